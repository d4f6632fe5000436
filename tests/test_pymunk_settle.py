"""The settling loop in bulk (:mod:`mechcheck.sim_models.pymunk.bulk`) does what the plain
per-body loop did, and its stop rule stops where that loop's did.

The reference here is the straightforward loop through pymunk's public properties: damp
each body's velocities, apply each load with ``apply_force_at_world_point``, step, read
every constraint's impulse into a named table, measure the residual velocity body by
body and compare the tables of consecutive steps. The bulk loop reads and writes the
bodies through pymunk's batch iterators, computes the loads' torque in closed form and
compares impulses; it must take the same number of steps to the same verdict and
forces. The two differ only in the rounding of the loads' torque, so the forces agree
to the policy's rounding tolerance (the analytic family's).
"""

from __future__ import annotations

import math

import numpy as np
import pymunk
import pytest

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage_backends import analytic_results, quantity_units
from mechcheck.analytic.solution import FORCE_FLOOR_N
from mechcheck.sim_models.pymunk.forces import accumulated_impulse, torque_on_b
from mechcheck.sim_models.pymunk.linkage import (
    axis_now,
    free_start,
    has_free_coordinates,
    rounding_floor,
    settle_run,
    solve_run,
)
from mechcheck.sim_models.pymunk.linkage_model import (
    LinkageModel,
    apply_loads,
    build_linkage_model,
    coordinates,
    damp,
    place,
)
from mechcheck.sim_models.pymunk.readout import Values
from mechcheck.sim_models.pymunk.settings import LINKAGE_SETTLE, LINKAGE_SOLVE, SolverSettings
from mechcheck.tolerance import rule

from .builtin import builtin

#: The two loops differ only in rounding (the loads' torque in closed form): the policy's
#: tolerance for the same equations solved another way.
ROUNDING = rule("analytic", "force", "static").rtol

#: Static linkages with every kind of joint, load and spring the builder makes: a pin
#: four-bar with loads, a slider-crank (groove), springs on a held and on a free linkage,
#: a held slide (the boom's cylinder) and free coordinates with a groove and a spring.
STATIC = ["e1-linkage", "e2-linkage-frictionless", "e1-linkage-driven-from-90", "bonnet-hold",
          "bonnet-free", "boom-hold-drawn", "exam-q1-slider-bar"]
#: Those held by their drivers alone: ``pymunk_solve`` re-poses the analytic pose of the
#: drivers (free coordinates settle instead).
HELD = ["e1-linkage", "e2-linkage-frictionless", "e1-linkage-driven-from-90", "bonnet-hold",
        "boom-hold-drawn"]


def start(case: Case) -> np.ndarray:
    """Where a run starts: the analytic pose when every coordinate is driven, else the drawn
    pose (:func:`~mechcheck.sim_models.pymunk.linkage.settle`)."""
    return free_start(case) if has_free_coordinates(case) else analytic_results(case).pose.q[0]


def model_of(case: Case, settings: SolverSettings = LINKAGE_SETTLE) -> LinkageModel:
    return build_linkage_model(case, settings, start(case))


def force_on_b(constraint: pymunk.Constraint, dt: float) -> tuple[float, float]:
    """Force vector (N) a pivot or groove applied to its body b during the last step."""
    j = accumulated_impulse(constraint)
    assert isinstance(j, tuple)
    return j[0] / dt, j[1] / dt


def plain_reactions(model: LinkageModel) -> Values:
    """Every reaction read constraint by constraint through :mod:`.forces` (the loop's
    readings before the bulk readout)."""
    dt, out = model.settings.dt, {}
    for joint in model.linkage.joints:
        name = joint.name
        if joint.kind == "revolute":
            out[f"F_{name}_x"], out[f"F_{name}_y"] = force_on_b(model.pins[name], dt)
            continue
        if name in model.held:
            fx, fy = force_on_b(model.held[name], dt)
            ux, uy = axis_now(model, joint)
            along = fx * ux + fy * uy
            out[f"Q_{name}"] = along
            fx, fy = fx - along * ux, fy - along * uy
        else:
            fx, fy = force_on_b(model.grooves[name], dt)
        out[f"F_{name}_x"], out[f"F_{name}_y"] = fx, fy
        out[f"M_{name}"] = torque_on_b(model.locks[name], dt)
    for name, gear in model.drives.items():
        out[f"Q_{name}"] = torque_on_b(gear, dt)
    for name, spring in model.springs.items():
        out[f"S_{name}"] = -spring.impulse / dt
    return out


def plain_change(new: Values, old: Values, model: LinkageModel, floor: float) -> float:
    """Largest change of a force (or couple / size) as a fraction of the largest one."""
    units = quantity_units(model.linkage)
    per = {q: model.linkage.scale if units[q] == "N*m" else 1.0 for q in new}
    scale = max(max(abs(v) / per[q] for q, v in new.items()), floor)
    return max(abs(new[q] - old[q]) / per[q] for q in new) / scale


def plain_settle(model: LinkageModel, floor: float) -> tuple[Values, int, bool]:
    """The settling loop through public properties: (last reading, steps, settled)."""
    s, previous, calm = model.settings, None, 0
    values: Values = {}
    for n in range(1, s.max_steps + 1):
        damp(model)
        apply_loads(model)
        model.space.step(s.dt)
        values = plain_reactions(model)
        velocity = max(abs(b.velocity) + abs(b.angular_velocity) * model.radius[k]
                       for k, b in model.bodies.items())
        change = plain_change(values, previous, model, floor) if previous else math.inf
        previous = values
        calm = calm + 1 if velocity <= s.settle_speed * model.linkage.scale \
            and change <= s.settle_force_change else 0
        if calm >= s.settle_patience:
            return values, n, True
    return values, s.max_steps, False


def plain_solve(model: LinkageModel, q: np.ndarray) -> tuple[Values, int, bool]:
    """The constraint solve through public properties: re-pose, load, step, compare."""
    s, previous, calm = model.settings, None, 0
    values: Values = {}
    for n in range(1, s.max_steps + 1):
        place(model, q)
        apply_loads(model)
        model.space.step(s.dt)
        values = plain_reactions(model)
        change = plain_change(values, previous, model, FORCE_FLOOR_N) if previous else math.inf
        previous = values
        calm = calm + 1 if change <= s.settle_force_change else 0
        if calm >= s.settle_patience:
            return values, n, True
    return values, s.max_steps, False


def assert_same_forces(fast: Values, plain: Values) -> None:
    assert list(fast) == list(plain)  # the same quantities, in the same order
    scale = max(abs(v) for v in plain.values())
    for q, v in plain.items():
        assert fast[q] == pytest.approx(v, rel=ROUNDING, abs=ROUNDING * scale), q


@pytest.mark.parametrize("name", STATIC)
def test_bulk_settling_stops_where_the_plain_loop_did(name: str) -> None:
    """The bulk loop takes the same steps to the same verdict and forces as the plain loop."""
    case = builtin(name)
    fast, plain = model_of(case), model_of(case)
    run = settle_run(fast)
    values, steps, settled = plain_settle(plain, rounding_floor(plain))
    assert (run.steps, run.settled) == (steps, settled)
    assert_same_forces(run.values, values)
    assert coordinates(fast) == pytest.approx(coordinates(plain), rel=ROUNDING, abs=1e-15)


@pytest.mark.parametrize("name", HELD)
def test_bulk_solve_stops_where_the_plain_loop_did(name: str) -> None:
    """The constraint solve (re-posed every step) in bulk matches the plain loop step for step."""
    case = builtin(name)
    assert not has_free_coordinates(case)
    q = analytic_results(case).pose.q[0]
    fast, plain = model_of(case, LINKAGE_SOLVE), model_of(case, LINKAGE_SOLVE)
    run = solve_run(fast, q)
    values, steps, settled = plain_solve(plain, q)
    assert (run.steps, run.settled) == (steps, settled)
    assert_same_forces(run.values, values)


def test_an_exhausted_budget_is_not_settled_at_the_same_step() -> None:
    """With a budget too small to settle, both loops stop at it, unsettled, on the same reading."""
    case = builtin("exam-q1-slider-bar")  # free coordinates: thousands of steps to settle
    tight = LINKAGE_SETTLE.with_(max_steps=40)
    fast, plain = model_of(case, tight), model_of(case, tight)
    run = settle_run(fast)
    values, steps, settled = plain_settle(plain, rounding_floor(plain))
    assert (run.steps, run.settled) == (steps, settled) == (40, False)
    assert_same_forces(run.values, values)


@pytest.mark.parametrize("name", ["e1-linkage", "bonnet-hold", "boom-hold-drawn"])
def test_load_terms_equal_the_applied_loads(name: str) -> None:
    """At any angle, the closed-form force and torque per body equal what pymunk accumulates
    from ``apply_force_at_world_point`` for every load and weight."""
    case = builtin(name)
    model = model_of(case)
    rng = np.random.default_rng(13)
    q = start(case).copy()
    for _ in range(5):
        q[2::3] = rng.uniform(-math.pi, math.pi, q[2::3].size)
        place(model, q)
        apply_loads(model)
        torque = model.loads.torques(q[2::3].tolist())
        size = max(float(np.abs(model.loads.force).max()), 1.0)
        for k, body in enumerate(model.bodies.values()):
            assert tuple(body.force) == pytest.approx(tuple(model.loads.force[k]),
                                                      rel=ROUNDING, abs=ROUNDING * size)
            assert body.torque == pytest.approx(torque[k], rel=ROUNDING,
                                                abs=ROUNDING * size * model.linkage.scale)
        model.space.step(model.settings.dt)  # clears the forces for the next angles


def test_bulk_reads_and_places_as_the_properties_do() -> None:
    """Bulk reads give each body's public position, angle and velocities; bulk placing puts
    the origin where the position setter (after the angle) does."""
    case = builtin("bonnet-free")
    model = model_of(case)
    damp(model)
    apply_loads(model)
    model.space.step(model.settings.dt)
    state = model.bulk.read()
    for k, body in enumerate(model.bodies.values()):
        assert list(state[k]) == [body.position.x, body.position.y, body.angle,
                                  body.velocity.x, body.velocity.y, body.angular_velocity]
    q = start(case) + 0.1
    place(model, q)
    twin = model_of(case)
    for k, body in enumerate(twin.bodies.values()):
        body.angle = float(q[3 * k + 2])
        body.position = (float(q[3 * k]), float(q[3 * k + 1]))
    assert coordinates(model).tolist() == coordinates(twin).tolist()
