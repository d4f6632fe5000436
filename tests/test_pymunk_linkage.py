"""The pymunk backends on any linkage (issue 12): the generic builder
(:mod:`mechcheck.sim_models.pymunk.linkage_model`) against the analytic linkage engine,
by the tolerance policy, held and driven; hand calculations for the springs' signs and
exam Q1; the verdicts for what it does not simulate."""

from __future__ import annotations

import io
import math
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from hypothesis import assume, example, given
from typer.testing import CliRunner

import mechcheck
from mechcheck.analytic.case import Case, Mass, Motion, SliderCrankGeometry
from mechcheck.analytic.linkage_backends import analytic_results, solve
from mechcheck.analytic.presets import preset_case
from mechcheck.analytic.solution import Solution, quantity_kind
from mechcheck.casefile import linkage_case
from mechcheck.cli import app
from mechcheck.linkage_file import LinkageCaseSpec
from mechcheck.sim_models.linkage_motion import is_driven
from mechcheck.sim_models.pymunk import backend as pm, linkage as pl, linkage_dynamics as pld
from mechcheck.sim_models.pymunk.settings import LINKAGE_SETTLE
from mechcheck.sweep import SweepTask, run_task
from mechcheck.testing import assert_solution_close
from mechcheck.tolerance import rule

from .builtin import builtin, builtin_cases, sliding_collar
from .strategies import carries_a_force, four_bar_table, inner_joints, linkage_tables
from .test_driven_friction import SENSED_RATE, coulomb_motion_unresolved
from .test_linkage_identities import SETTINGS, case_of
from .test_linkage_sweep import LINKAGES

LINKAGE_CASES = sorted(n for n, c in builtin_cases().items() if c.mechanism == "linkage")
STATIC = [n for n in LINKAGE_CASES if builtin(n).kind == "static" and n != "locking-fourbar"]
MOVING = [n for n in LINKAGE_CASES if builtin(n).kind != "static"]
DRIVEN = [n for n in MOVING if builtin(n).kind == "dynamic"]
FRICTION = [n for n in MOVING if builtin(n).kind == "friction"]
BACKENDS = {"pymunk": pm.settle, "pymunk_solve": pm.solve_at_pose}


def at_rest(case: Case) -> Case:
    """The case with its drivers held still and without friction: its statics, so that the
    built-in six-bars, the shaper, the boom and the five-bar are checked held too."""
    linkage = case.linkage
    drivers = tuple(replace(d, velocity=0.0, acceleration=0.0, sense=0) for d in linkage.drivers)
    return case.with_(name=f"{case.name}-at-rest",
                      geometry=replace(linkage, drivers=drivers, friction=None))


def table_case(table: dict[str, Any]) -> Case:
    return linkage_case(LinkageCaseSpec.model_validate(table))


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("name", STATIC)
def test_static_builtin_linkages_agree_with_analytic(name: str, backend: str) -> None:
    """Every static built-in linkage (springs, prismatic drivers, free coordinates included)
    gives every analytic quantity within the policy's tolerance."""
    case = builtin(name)
    assert_solution_close(case, BACKENDS[backend](case), complete=True)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("name", MOVING)
def test_moving_builtin_linkages_held_at_rest_agree_with_analytic(name: str, backend: str) -> None:
    case = at_rest(builtin(name))
    assert_solution_close(case, BACKENDS[backend](case), complete=True)


@pytest.mark.parametrize("name", DRIVEN)
def test_driven_builtin_linkages_agree_with_analytic(name: str) -> None:
    """``pymunk`` drives every frictionless moving built-in linkage through its prescribed
    motion (:mod:`mechcheck.sim_models.pymunk.linkage_dynamics`) and reads every analytic
    quantity within the policy's dynamic tolerance; the reading's lead-in and time step
    were judged converged on pymunk's own readings."""
    case = builtin(name)
    solution = pm.settle(case)
    assert_solution_close(case, solution, complete=True)
    d = solution.diagnostics
    assert d["method"] == "driven" and float(d["timestep_disagreement"]) <= 1e-4
    assert float(d["loop_violation"]) < 1e-5 * case.linkage.scale


@pytest.mark.parametrize("name", FRICTION)
def test_friction_builtin_linkages_agree_with_analytic(name: str) -> None:
    """Joint friction emulated from pymunk's own reactions and joint rates
    (:mod:`mechcheck.sim_models.pymunk.linkage_friction`): a moving case is driven through
    its motion, a static one with Coulomb friction through a slow motion in its drivers'
    senses; every analytic quantity within the policy's friction tolerance."""
    case = builtin(name)
    solution = pm.settle(case)
    assert_solution_close(case, solution, complete=True)
    assert solution.diagnostics["method"] == "driven"


def test_exam_q2_with_friction_is_the_hand_calculation() -> None:
    """Exam Q2 with μ = 0.1, driven: F = m ẍ + (k1 + k2) x + μ m g = 26 + 0.1·2·9.81 =
    27.962 N; the slide's friction μ·|N| comes from pymunk's own normal reaction and is
    part of F_slide (friction tolerance 1e-3)."""
    sim = pm.settle(builtin("exam-q2-friction"))
    assert sim.values["Q_slide"] == pytest.approx(2.0 * 3.0 + 500.0 * 0.040 + 0.1 * 2.0 * 9.81,
                                                  rel=1e-3)
    assert sim.values["F_slide_x"] == pytest.approx(-0.1 * 2.0 * 9.81, rel=1e-3)
    assert sim.values["F_slide_y"] == pytest.approx(2.0 * 9.81, rel=1e-3)


def off_line_masses_slider_crank() -> Case:
    """CI's derandomized draw (2026-11-26): an unloaded slider-crank, horizontal coupler,
    under g = 1 m/s² along +x, every point mass at the origin (off its link), slide μ = 0.25:
    a static friction case, driven quasi-statically."""
    table = {
        "name": "off-line-masses", "mechanism": "linkage", "gravity": [1.0, 0.0],
        "points": {"O2": [0.0, 0.0], "A": [-0.1040367091367856, 0.22732435670642043],
                   "B": [-0.6040367091367856, 0.22732435670642043]},
        "links": [{"name": "ground", "points": ["O2"]},
                  {"name": "crank", "points": ["O2", "A"]},
                  {"name": "coupler", "points": ["A", "B"]},
                  {"name": "slider", "points": ["B"]}],
        "joints": [{"name": "O2", "kind": "revolute", "links": ["ground", "crank"], "at": "O2"},
                   {"name": "A", "kind": "revolute", "links": ["crank", "coupler"], "at": "A"},
                   {"name": "B", "kind": "revolute", "links": ["coupler", "slider"], "at": "B"},
                   {"name": "slide", "kind": "prismatic", "links": ["ground", "slider"],
                    "at": "B", "axis": [1.0, 0.0]}],
        "drivers": [{"joint": "O2", "rotation": 0.0, "sense": "increasing"}],
        "masses": [{"link": "crank", "mass": 0.25, "com": [0.0, 0.0], "inertia": 0.0},
                   {"link": "coupler", "mass": 1.0, "com": [0.0, 0.0], "inertia": 0.0},
                   {"link": "slider", "mass": 1.0, "com": [0.0, 0.0], "inertia": 0.0}],
        "friction": {"mu": 0.25}}
    return linkage_case(LinkageCaseSpec.model_validate(table))


def test_a_reading_the_solver_has_not_converged_goes_to_more_iterations() -> None:
    """At 100 Gauss–Seidel iterations this case read the slide's normal force 0.070 N and
    its friction 0.043 N (not μ·N) against the analytic 0.455 and 0.114, status ``ok``: the
    same at every lead-in and time step, as warm starting carried each short solve into the
    next. Solving the last step again with more iterations exposes it, and the run goes on
    to 400: every quantity within the friction tolerance, and the friction is μ·|N| of
    pymunk's own normal force."""
    case = off_line_masses_slider_crank()
    assert case.kind == "friction"
    solution = mechcheck.solve(case, "pymunk")
    assert_solution_close(case, solution, complete=True)
    assert solution.diagnostics["iterations"] > pld.ITERATIONS[0]
    assert solution.diagnostics["solver_disagreement"] <= 1e-4
    normal, along = solution.values["F_slide_y"], solution.values["F_slide_x"]
    assert abs(along) == pytest.approx(0.25 * abs(normal), rel=1e-3)


def assert_reading_or_reason(case: Case, solution: Solution) -> None:
    """Every quantity within the policy's tolerance, or (docs/limitations.md) a
    ``not_settled`` verdict with its reason and no force, or ``indeterminate`` where a
    Coulomb joint's motion is confirmed at rest or reversing at the reading (README,
    pymunk, slow drives)."""
    if solution.status == "ok":
        assert_solution_close(case, solution, complete=True)
        return
    if solution.status == "indeterminate":
        # A draw of README's test command (2026-11-26): a six-bar whose slider sat at its
        # dead centre (coupler 1e-5 m off the slide's line), its slide slower than pymunk
        # resolves at the reading.
        assert coulomb_motion_unresolved(case, pld.DRIVEN.dt, SENSED_RATE), solution.message
    else:
        assert solution.status == "not_settled" and solution.message
    assert not any(q.startswith(("F_", "Q_", "M_", "S_")) for q in solution.values)


#: A draw of README's test command (2026-11-26): a slider at its dead centre, pymunk `indeterminate`.
SLIDER_AT_DEAD_CENTRE: dict[str, Any] = {
    "name": "random-linkage", "mechanism": "linkage", "gravity": [0.0, 0.0],
    "points": {"O2": [0.0, 0.0], "A": [0.25, 0.0], "B": [-0.75, 1e-05], "C": [-0.75, 1e-05],
               "D": [-0.25, 1e-05], "O6": [-0.25, -0.49999]},
    "links": [{"name": "ground", "points": ["O2", "O6"]},
              {"name": "crank", "points": ["O2", "A"]},
              {"name": "coupler", "points": ["A", "B", "C"]},
              {"name": "slider", "points": ["B"]},
              {"name": "link5", "points": ["C", "D"]},
              {"name": "output", "points": ["O6", "D"]}],
    "joints": [{"name": "O2", "kind": "revolute", "links": ["ground", "crank"], "at": "O2"},
               {"name": "A", "kind": "revolute", "links": ["crank", "coupler"], "at": "A"},
               {"name": "B", "kind": "revolute", "links": ["coupler", "slider"], "at": "B"},
               {"name": "slide", "kind": "prismatic", "links": ["ground", "slider"],
                "at": "B", "axis": [1.0, 0.0]},
               {"name": "C", "kind": "revolute", "links": ["coupler", "link5"], "at": "C"},
               {"name": "D", "kind": "revolute", "links": ["link5", "output"], "at": "D"},
               {"name": "O6", "kind": "revolute", "links": ["ground", "output"], "at": "O6"}],
    "drivers": [{"joint": "O2", "rotation": 0.0, "velocity": -1.0, "acceleration": 0.0}],
    "loads": [{"link": "crank", "at": [0.0, 0.0], "force": {"x": 0.0, "y": 0.0},
               "torque": 0.0}],
    "masses": [],
    "friction": {"mu": 0.25, "pin_radius": {"O2": 0.0}},
}


@SETTINGS
@given(linkage_tables(friction=True))
@example(SLIDER_AT_DEAD_CENTRE)
def test_random_friction_linkages_agree_with_analytic(table: dict[str, Any]) -> None:
    """Random linkages with friction circles, slide friction and viscous terms, driven in
    pymunk (moving, or quasi-statically with Coulomb friction): every quantity within the
    friction tolerance, or no number and the reason."""
    case = case_of(table)
    assume(case.kind == "friction" and is_driven(case) and pld.refusal(case) is None)
    reference = analytic_results(case)
    assume(bool(reference.pose.assembled[0]))
    solution = mechcheck.solve(case, "pymunk")
    assert_reading_or_reason(case, solution)


@pytest.mark.parametrize("name", MOVING)
def test_the_constraint_solve_refuses_moving_linkages_with_the_reason(name: str) -> None:
    case = builtin(name)
    solution = pm.solve_at_pose(case)
    assert solution.status == "not_applicable"
    assert case.kind in solution.message and "for statics" in solution.message
    assert not solution.values


def test_free_coordinates_are_not_driven() -> None:
    """Exam Q1's slider and bar are free coordinates (no driver): a driven run would have
    to settle them while it drives, which the driven model does not do; it says so."""
    free = builtin("exam-q1-slider-bar")
    assert pl.has_free_coordinates(free)
    why = pld.refusal(free)
    assert why is not None and "free coordinates" in why


@SETTINGS
@given(linkage_tables(friction=False, moving=True))
def test_random_driven_linkages_agree_with_analytic(table: dict[str, Any]) -> None:
    """Random moving linkages (LINKAGES.md tables), driven in pymunk, against the analytic
    engine: every quantity within the dynamic tolerance, or no number and the reason."""
    case = case_of(table)
    assume(pld.refusal(case) is None and case.kind == "dynamic")
    assume(bool(analytic_results(case).pose.assembled[0]))
    solution = mechcheck.solve(case, "pymunk")
    assert_reading_or_reason(case, solution)


def far_slider(com: tuple[float, float]) -> Case:
    """A random draw of the driven-friction test (2026-12-02, its friction, crank mass and
    crank loads taken away): a slider-crank (crank 0.894 m, rod 0.531 m, slide 0.0925 m
    off the crank's pivot) driven at ω = −21.8 rad/s, 0.6° from its outer limit position,
    whose one mass is a 4.5 kg slider with its centre of mass at ``com`` (m) from its pin."""
    return preset_case(name="far-slider", geometry=SliderCrankGeometry(0.894, 0.531, 0.0925),
                       theta12=0.055, masses=(Mass(4, 4.5, com, 0.0),), motion=Motion(-21.8))


def test_a_driven_mass_far_off_its_pin_gives_no_number_in_pymunk() -> None:
    """docs/limitations.md, "A driven mass far off its joints": with the slider's centre of
    mass 0.52 m from its pin, pymunk's readings at its two smallest time steps still differ
    by more than the time-step rule allows, so it gives no number and says why. The place
    of the mass is the cause: at the pin, the same case reads within the dynamic tolerance
    (its forces are the same: the slider only translates); MuJoCo reads the far one."""
    far = far_slider((-0.48, 0.19))
    assert math.hypot(-0.48, 0.19) == pytest.approx(0.516, abs=1e-3)
    solution = mechcheck.solve(far, "pymunk")
    assert solution.status == "not_settled", solution.message
    assert "time step not converged" in solution.message
    assert "TIMESTEP_AGREEMENT_RTOL" in solution.message
    assert not any(quantity_kind(q) != "pose" for q in solution.values)
    at_pin = far_slider((0.0, 0.0))
    assert_solution_close(at_pin, mechcheck.solve(at_pin, "pymunk"), complete=True)
    assert_solution_close(far, mechcheck.solve(far, "mujoco"), complete=True)


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_locking_linkage_gets_the_analytic_verdict_and_no_numbers(backend: str) -> None:
    """Behind the pose gate (``mechcheck.solve``, as ``mechcheck run``): not run."""
    solution = mechcheck.solve(builtin("locking-fourbar"), backend)
    assert solution.status == "no_solution"
    assert "locks at rotation" in solution.message and "not run" in solution.message
    assert not solution.values


def test_a_redundant_linkage_gets_the_analytic_verdict_and_no_numbers() -> None:
    """A parallelogram with a third parallel bar: Gruebler 0, mobility 1, one constraint
    redundant, so the reactions are not unique (``indeterminate``), not simulated."""
    names = ["O2", "A", "O4", "B", "O6", "C"]
    xy = [[0.0, 0.0], [0.0, 1.0], [1.0, 0.0], [1.0, 1.0], [2.0, 0.0], [2.0, 1.0]]

    def pin(name: str, a: str, b: str) -> dict[str, Any]:
        return {"name": name, "kind": "revolute", "links": [a, b], "at": name}

    case = table_case({
        "name": "triple-parallelogram", "mechanism": "linkage",
        "points": dict(zip(names, xy, strict=True)),
        "links": [{"name": "ground", "points": ["O2", "O4", "O6"]},
                  {"name": "crank", "points": ["O2", "A"]},
                  {"name": "coupler", "points": ["A", "B", "C"]},
                  {"name": "rocker", "points": ["O4", "B"]},
                  {"name": "bar", "points": ["O6", "C"]}],
        "joints": [pin("O2", "ground", "crank"), pin("A", "crank", "coupler"),
                   pin("B", "coupler", "rocker"), pin("O4", "ground", "rocker"),
                   pin("C", "coupler", "bar"), pin("O6", "ground", "bar")],
        "drivers": [{"joint": "O2", "rotation": 20.0}],
        "loads": [{"link": "coupler", "at": "B", "force": {"x": 0.0, "y": -100.0}}],
    })
    for backend in BACKENDS:
        solution = mechcheck.solve(case, backend)
        assert solution.status == "indeterminate" and not solution.values, solution.message
        assert "redundant" in solution.message


def arm(springs: list[dict[str, Any]], rotation: float = 30.0) -> Case:
    """A unit arm O→A on the ground, driven to ``rotation`` degrees, loaded only by springs."""
    return table_case({
        "name": "arm", "mechanism": "linkage",
        "points": {"O": [0.0, 0.0], "A": [1.0, 0.0], "P": [1.0, 1.0]},
        "links": [{"name": "ground", "points": ["O", "P"]}, {"name": "arm", "points": ["O", "A"]}],
        "joints": [{"name": "O", "kind": "revolute", "links": ["ground", "arm"], "at": "O"}],
        "drivers": [{"joint": "O", "rotation": rotation}],
        "springs": springs,
    })


@pytest.mark.parametrize("backend", BACKENDS)
def test_torsion_spring_sign_by_hand(backend: str) -> None:
    """k = 2 N·m/rad relaxed at −10°, arm turned +30°: S = 2·(40° in rad) = 1.3963 N·m,
    acting −S on the arm, so the driver holds Q = +S; the pin carries nothing.
    (pymunk's rotary spring measures a − b: its rest angle must be −q0.)"""
    case = arm([{"name": "t", "joint": "O", "stiffness": 2.0, "free_rotation": -10.0}])
    s = BACKENDS[backend](case)
    expected = 2.0 * math.radians(40.0)
    tol = rule(backend, "torque", "static").rtol
    assert s.values["S_t"] == pytest.approx(expected, rel=tol)
    assert s.values["Q_O"] == pytest.approx(expected, rel=tol)
    assert math.hypot(s.values["F_O_x"], s.values["F_O_y"]) <= tol * expected


@pytest.mark.parametrize("backend", BACKENDS)
def test_linear_spring_sign_by_hand(backend: str) -> None:
    """Spring from P = (1, 1) on the ground to A = (1, 0) on the unturned arm: L = 1 m,
    L0 = 0.5 m, k = 100 N/m, so S = 50 N pulls A up (+y). On the arm: the pin force is
    (0, −50) N, and the driver holds Q = −(1 m × 50 N) = −50 N·m."""
    case = arm([{"name": "s", "ends": [["ground", "P"], ["arm", "A"]], "stiffness": 100.0,
                 "free_length": 0.5}], rotation=0.0)
    s = BACKENDS[backend](case)
    tol = rule(backend, "force", "static").rtol
    assert s.values["S_s"] == pytest.approx(50.0, rel=tol)
    assert s.values["Q_O"] == pytest.approx(-50.0, rel=tol)
    assert s.values["F_O_y"] == pytest.approx(-50.0, rel=tol)
    assert abs(s.values["F_O_x"]) <= tol * 50.0


EXAM_Q1_HAND = {"q_slide": 10.0 / 500.0, "phi_bar": math.atan(2 * 10.0 / (3.0 * 9.81)),
                "S_spring": 10.0}


@pytest.mark.parametrize("x, phi_deg", [(0.0, 0.0), (-0.1, -60.0), (0.15, 80.0), (0.02, 150.0)])
def test_exam_q1_equilibrium_is_found_by_settling_from_other_poses(x: float, phi_deg: float) -> None:
    """Exam Q1 (seed 002): x = F/k, φ = atan(2F/(mg)), S = F, however it starts (the drawn
    pose, either side, or upside-down); never from the answer."""
    case = builtin("exam-q1-slider-bar")
    phi = math.radians(phi_deg)
    # slider: translated by x; bar: turned by φ about A = origin, then translated by x.
    seed = np.array([x, 0.0, 0.0, x, 0.0, phi])
    s = pl.settle(case, seed=seed)
    assert_solution_close(case, s, complete=True)
    for quantity, expected in EXAM_Q1_HAND.items():
        tol = rule("pymunk", "pose" if quantity != "S_spring" else "force", "static").rtol
        assert s.values[quantity] == pytest.approx(expected, rel=tol), quantity


def test_space_damping_is_not_used_because_it_scales_the_springs() -> None:
    """The model damps velocities itself; Space.damping stays 1 (see linkage_model)."""
    case = builtin("bonnet-hold")
    model = pl.build_linkage_model(case, LINKAGE_SETTLE, analytic_results(case).pose.q[0])
    assert model.space.damping == 1.0


def test_diagnostics_say_how_the_numbers_were_got() -> None:
    s: Solution = pm.settle(at_rest(builtin("watt-ii-demo")))
    d = s.diagnostics
    assert d["method"] == "settle" and int(d["steps"]) > 0
    assert float(d["loop_violation"]) < 1e-9 and float(d["pose_drift"]) < 1e-9
    assert float(d["residual_velocity"]) <= 1e-9 * at_rest(builtin("watt-ii-demo")).linkage.scale


def loaded_case(table: dict[str, Any]) -> Case:
    """A random case whose joints carry some reaction.

    Where every reaction is exactly zero (e.g. only a couple on the crank, which the
    driver takes), the policy judges them against the 0.01 N force floor, i.e. to 1e-11 N
    at 1e-9, below the rounding of pymunk's solve at a condition of 1e3 (3e-11 N seen);
    such a case checks no reaction anyway.
    """
    case = case_of(table)
    reactions = [abs(v) for q, v in solve(case).values.items() if q.startswith("F_")]
    assume(max(reactions, default=0.0) > 0.0)
    return case


@SETTINGS
@given(linkage_tables(friction=False, moving=False))
def test_random_static_linkages_by_the_constraint_solve(table: dict[str, Any]) -> None:
    """Random assemblable four-bars, slider-cranks and six-bars with loads, weights and
    springs: pymunk's constraint solve at the analytic pose gives every quantity."""
    case = loaded_case(table)
    assert_solution_close(case, pm.solve_at_pose(case), complete=True)


@SETTINGS
@given(linkage_tables(friction=False, moving=False))
def test_random_static_linkages_by_settling(table: dict[str, Any]) -> None:
    """The same random linkages, held and settled by simulation. Left out: draws where no
    joint between two moving links carries a force (docs/limitations.md; below)."""
    case = loaded_case(table)
    assume(carries_a_force(solve(case), inner_joints(case.linkage)))
    assert_solution_close(case, pm.settle(case), complete=True)


#: A draw of README's test command (2026-11-26): the only load, 0.125 N, on the crank's
#: ground pin; every other joint carries nothing.
LOAD_ON_THE_GROUND_PIN = four_bar_table(
    {"O2": [0.0, 0.0], "A": [0.20532771839798078, 0.0], "O4": [0.5, 0.0],
     "B": [0.35266385919899035, -0.47779918544705063]},
    drivers=[{"joint": "O2", "rotation": 0.001953125}],
    loads=[{"link": "crank", "at": [0.0, 0.0], "force": {"x": 0.0, "y": 0.125},
            "torque": 0.0}])


def test_a_load_straight_into_the_ground_gives_no_wrong_number() -> None:
    """docs/limitations.md: with nothing between two moving links carrying a force,
    pymunk's forces there chatter about zero (3e-10 N here, against a 0.125 N load) and its
    settling need not stop. It then says ``not_settled`` with no number, never a wrong one;
    the random test above leaves such draws out."""
    case = linkage_case(LinkageCaseSpec.model_validate(LOAD_ON_THE_GROUND_PIN))
    reference = solve(case)
    assert reference.values["F_O2_y"] == pytest.approx(-0.125, rel=1e-12)  # the load, by hand
    assert not carries_a_force(reference, inner_joints(case.linkage))
    solution = pm.settle(case)
    if solution.status == "ok":
        assert_solution_close(case, solution, complete=True)
    else:
        assert solution.status == "not_settled" and solution.message
        assert not any(q.startswith(("F_", "Q_", "M_", "S_")) for q in solution.values)


def test_an_unloaded_linkage_settles_to_zero_forces() -> None:
    """No load: every reaction is zero; the run must still stop (rounding noise of the
    error correction is below its force floor) rather than report not_settled."""
    case = at_rest(builtin("watt-ii-demo"))
    bare = case.with_(geometry=replace(case.linkage, loads=(), masses=()))
    s = pm.settle(bare)
    assert s.status == "ok", s.message
    forces = [abs(v) for q, v in s.values.items() if q.startswith(("F_", "Q_"))]
    assert forces and max(forces) <= 1e-9


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_linkage_sweep_with_continuation_agrees_pose_by_pose(backend: str) -> None:
    """The Watt six-bar held at crank angles across its range, in one Space (warm-started
    from pose to pose): each pose as its own case through the analytic backend."""
    case = at_rest(builtin("watt-ii-demo"))
    values = np.radians([-200.0, -150.0, -100.0, -50.0, 0.0, 50.0, 100.0])
    solutions = pm.sweep(case, values, backend)
    driver = case.linkage.drivers[0]
    for value, solution in zip(values, solutions, strict=True):
        at = case.with_(geometry=replace(case.linkage, drivers=(replace(driver, value=value),)))
        assert solution.diagnostics["driver"] == value
        assert_solution_close(at, solution, complete=True)


def test_a_sweep_reports_the_analytic_verdict_where_the_linkage_locks() -> None:
    """Through the harness's sweep: the pose gate keeps the locked pose from pymunk."""
    case = at_rest(builtin("watt-ii-demo"))
    task = SweepTask(case, "pymunk", np.array([0.0, 120.0]), 0, "")
    status = pd.read_parquet(io.BytesIO(run_task(task)[1]))
    assert list(status["status"]) == ["ok", "no_solution"]


def test_next_to_a_lock_a_held_linkage_that_leaves_its_assembly_is_not_settled() -> None:
    """0.5° before the Watt six-bar's lock (108.06°) its other assembly is 25 mm away and
    the loaded soft joints give way to it: the run must not report that pose's forces."""
    case = at_rest(builtin("watt-ii-demo"))
    driver = case.linkage.drivers[0]
    near = case.with_(geometry=replace(case.linkage,
                                       drivers=(replace(driver, value=math.radians(107.5)),)))
    solution = pm.settle(near)
    if solution.status == "ok":  # it held: then its numbers must be right
        assert_solution_close(near, solution, complete=True)
    else:
        assert solution.status == "not_settled" and "assembly" in solution.message


def test_an_unstable_free_equilibrium_is_not_settled_for_but_solved_at() -> None:
    """A collar sliding freely on a pinned bar has only unstable equilibria (the analytic
    backend ends on one and says so). Settling cannot measure it; the constraint solve at
    that pose can."""
    up = sliding_collar()
    settled = pm.settle(up)
    assert settled.status == "not_applicable" and "unstable" in settled.message
    assert_solution_close(up, pm.solve_at_pose(up), complete=True)


def test_the_sweep_command_runs_linkages_through_pymunk(tmp_path: Path) -> None:
    """`mechcheck sweep` on the seed-E1 linkage: pymunk and pymunk_solve give rows that
    pass against the analytic sweep, pose by pose."""
    out = tmp_path / "sweep"
    result = CliRunner().invoke(app, [
        "sweep", str(LINKAGES / "seed_e1_fourbar.toml"), "-q", "--workers", "0", "--out",
        str(out), "--driver", "-60:60:30", "-b", "pymunk", "-b", "pymunk_solve"])
    assert result.exit_code == 0, result.output
    status = pd.read_parquet(out / "status")
    assert set(status["status"]) == {"ok"}
    comparison = pd.read_parquet(out / "comparison.parquet")
    assert {"pymunk", "pymunk_solve"} <= set(comparison["backend"].astype(str))
    assert comparison["passed"].all()
