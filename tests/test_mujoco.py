"""Cross-checks of the MuJoCo backends against the analytic backend.

Expected values always come from :func:`mechcheck.analytic.forces.solve` (the
member-equilibrium matrix method), an independent method; never from MuJoCo.

Every comparison goes through :func:`mechcheck.testing.assert_solution_close`,
the one tolerance policy (compare/tolerance.py). The seed cases are the
built-in case files' (compare/cases/seeds.toml), loaded by name.
"""

from __future__ import annotations

import importlib
import io
import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings, strategies as st

import mechcheck
from mechcheck.analytic.case import Case, FourBarGeometry, Friction, Load, Mass, Motion, SliderCrankGeometry
from mechcheck.analytic.kinematics import pose_of
from mechcheck.analytic.linkage_backends import analytic_results
from mechcheck.analytic.presets import as_linkage, preset_case, redrawn
from mechcheck.analytic.solution import Solution
from mechcheck.sim_models.linkage_motion import driven_motion, lead_limit
from mechcheck.sim_models.mujoco import backend as _mujoco, settle as mj_settle
from mechcheck.sim_models.mujoco._fast import first_stops
from mechcheck.sim_models.mujoco.batch_settle import CHUNK, REFINE_CHUNK, RULES
from mechcheck.sim_models.mujoco.linkage_dynamics import DYNAMIC
from mechcheck.sim_models.mujoco.linkage_model import model_xml
from mechcheck.sim_models.mujoco.linkage_rig import LinkageRig
from mechcheck.sim_models.mujoco.settle import (
    EXTRAPOLATE_AFTER,
    FLOOR_WINDOW,
    REFINE_RTOL,
    SETTLE_RTOL,
    WOBBLE_RTOL,
    DecayWatch,
    Refinement,
    plain_passes_left,
    refinement_left,
    secant_slope,
)
from mechcheck.sweep import SweepTask, run_task
from mechcheck.testing import assert_solution_close

from .builtin import builtin
from .harness import solver, sweeper
from .mujoco_twins import StepWatch, remaining_change, vectorised_stops

#: The backend's functions as the harness calls them (a preset as its linkage).
settle = solver(_mujoco.settle, "mujoco")
solve_at_pose = solver(_mujoco.solve_at_pose, "mujoco_solve")
sweep = sweeper(_mujoco.sweep, {"mujoco": _mujoco.settle, "mujoco_solve": _mujoco.solve_at_pose},
                "mujoco")


def fourbar_e1() -> Case:
    """Seed E1 (Söylemez 6.3) with the loads in their stated directions."""
    return builtin("seed-E1-as-stated")


def slidercrank_e2(*, with_friction: bool = True) -> Case:
    """Seed E2: the centric slider-crank, with or without its joint friction."""
    return builtin("seed-E2-friction" if with_friction else "seed-E2-frictionless")


#: The seed cases whose MuJoCo models are committed as golden MJCF.
GOLDEN_CASES = ["seed-E1-as-stated", "seed-E2-frictionless", "seed-E2-friction"]

GOLDEN = Path(__file__).parent / "golden" / "mujoco"


def assert_close(sim: Solution) -> None:
    """The solution agrees with the analytic backend under the one tolerance policy, and
    MuJoCo raised no warning while computing it (the models are well posed)."""
    assert_solution_close(case_of[sim.case], sim, complete=True)
    assert "warnings" not in sim.diagnostics, sim.diagnostics["warnings"]


MASSES_4 = (Mass(2, 0.5, (0.04, 0.0), 3e-4), Mass(3, 0.8, (0.05, 0.01), 7e-4),
            Mass(4, 1.2, (0.06, 0.0), 1.5e-3))
MASSES_SC = (Mass(2, 0.4, (0.02, 0.0), 2e-4), Mass(3, 0.6, (0.1, 0.0), 2e-3), Mass(4, 0.9))


def tilted_slider(name: str, **changes: object) -> Case:
    """An offset slider-crank on a slide tilted 15°, loaded on the slider and the rod."""
    base = preset_case(name=name, geometry=SliderCrankGeometry(0.05, 0.2, 0.02),
                theta12=math.radians(40.0), ground_angle=math.radians(15.0),
                loads=(Load(4, (0.0, 0.0), (-200.0, 30.0)), Load(3, (0.1, 0.01), (5.0, -20.0))))
    return redrawn(base, **changes)


STATIC_CASES = [
    fourbar_e1(),
    slidercrank_e2(with_friction=False),
    tilted_slider("slider-offset-tilted"),
    tilted_slider("slider-left-branch", branch="left"),
    redrawn(fourbar_e1(), name="fourbar-crossed", branch="crossed"),
    redrawn(fourbar_e1(), name="fourbar-gravity", gravity=(0.0, -9.81), masses=MASSES_4,
                       ground_angle=math.radians(10.0)),
    redrawn(fourbar_e1(), name="fourbar-drive-on-4", drive_link=4),
]
DYNAMIC_CASES = [
    redrawn(fourbar_e1(), name="fourbar-dynamic", masses=MASSES_4, gravity=(0.0, -9.81),
                       motion=Motion(-10.0, 5.0)),
    redrawn(fourbar_e1(), name="fourbar-dynamic-drive-4", masses=MASSES_4, drive_link=4,
                       motion=Motion(-10.0, 5.0)),
    redrawn(fourbar_e1(), name="fourbar-dynamic-crossed", masses=MASSES_4, branch="crossed",
                       motion=Motion(8.0, -20.0)),
    tilted_slider("slider-dynamic", masses=MASSES_SC, gravity=(0.0, -9.81),
                  motion=Motion(-30.0, 10.0)),
]
FRICTION_CASES = [
    slidercrank_e2(),
    redrawn(fourbar_e1(), name="fourbar-friction", friction=Friction(
        mu=0.15, pin_radius={"A0": 0.01, "A": 0.012, "B": 0.008, "B0": 0.01}, direction=1)),
    tilted_slider("slider-friction-slide", friction=Friction(
        mu=0.1, pin_radius={"A0": 0.01, "A": 0.01, "B": 0.01}, slide_mu=0.12, direction=-1)),
    tilted_slider("slider-friction-moving", masses=MASSES_SC, motion=Motion(-3.0, 1.0),
                  friction=Friction(mu=0.1, pin_radius={"A": 0.01, "B": 0.01}, slide_mu=0.12,
                                    viscous={"A0": 0.02, "slide": 0.5})),
]
case_of = {c.name: c for c in STATIC_CASES + DYNAMIC_CASES + FRICTION_CASES}
ids = lambda cases: [c.name for c in cases]  # noqa: E731


@pytest.mark.parametrize("case", STATIC_CASES, ids=ids(STATIC_CASES))
def test_settled_statics_match_analytic(case: Case) -> None:
    """A mechanism held by MuJoCo's joint lock settles to the analytic static reactions and drive torque."""
    sim = settle(case)
    assert sim.diagnostics["method"] == "settle"
    assert_close(sim)


@pytest.mark.parametrize("case", STATIC_CASES + DYNAMIC_CASES + FRICTION_CASES,
                         ids=ids(STATIC_CASES + DYNAMIC_CASES + FRICTION_CASES))
def test_constraint_solve_is_exact(case: Case) -> None:
    """MuJoCo's constraint Jacobian at the analytic pose gives the rigid-body forces to rounding."""
    assert_close(solve_at_pose(case))


@pytest.mark.parametrize("case", DYNAMIC_CASES, ids=ids(DYNAMIC_CASES))
def test_driven_dynamics_match_dalembert(case: Case) -> None:
    """Driving the input through the prescribed motion gives the D'Alembert torque and reactions."""
    sim = settle(case)
    assert sim.diagnostics["method"] == "driven"
    assert_close(sim)


@pytest.mark.parametrize("case", FRICTION_CASES, ids=ids(FRICTION_CASES))
def test_driven_friction_matches_friction_circle(case: Case) -> None:
    """Friction emulated from MuJoCo's own reactions while driving gives the friction-circle drive torque."""
    assert_close(settle(case))


def test_exam_q3_rocker_drive_next_to_a_dead_point() -> None:
    """Exam Q3 (seed 002): the rocker drives 6.7° before a rocker dead point (dθ14/dθ12 = −0.062).

    It was ``not_settled`` (a crank ringing for ~700 steps on the soft drive
    equality of a massless rocker) and, when settled, 3e-2 off (the soft
    constraints' violation, magnified 1/0.062 = 16× in the crank). Now within
    the dynamic target, the time step refined by the convergence check.
    """
    case = builtin("seed-exam-Q3")
    sim = settle(case)
    assert sim.diagnostics["method"] == "driven"
    assert sim.diagnostics["timestep"] < DYNAMIC.timestep
    assert_solution_close(case, sim, complete=True)


def test_lead_in_stops_short_of_a_rocker_dead_point() -> None:
    """Exam Q3 runs as its linkage, driven at B0 with the rocker's rates at the instant,
    θ14 = θ14* + v·t + a·t²/2. Back in time the rocker turns towards its upper extreme (a
    dead point of the rocker drive), past which the linkage does not assemble: the guard
    refuses a lead-in that starts beyond it and passes the one the run used."""
    case = builtin("seed-exam-Q3")
    linkage = as_linkage(case)
    driver = linkage.linkage.drivers[0]
    # By hand, from the closed-form kinematics: the rocker's range about θ14* on a 0.005°
    # grid of the crank, and when the prescribed rocker motion reaches its top (t < 0).
    grid = case.preset.theta12 + np.radians(np.linspace(-180.0, 180.0, 72001))
    turned = pose_of(case, grid).links[4].angle - pose_of(case).links[4].angle[0]
    top = float(np.max(np.angle(np.exp(1j * turned))))
    v, a = driver.velocity, driver.acceleration
    reached = (v - math.sqrt(v * v + 2.0 * a * top)) / a
    assert -0.25 < reached < -0.15
    limit = lead_limit(linkage, driven_motion(linkage, 0.0),
                       float(analytic_results(linkage).condition[0]))
    beyond = math.ceil(1.2 * -reached / DYNAMIC.timestep)
    assert "does not assemble" in limit(beyond, DYNAMIC.timestep)
    sim = settle(case)
    used = int(sim.diagnostics["lead_steps"]) * float(sim.diagnostics["timestep"])
    assert used < -reached and not limit(int(sim.diagnostics["lead_steps"]),
                                         float(sim.diagnostics["timestep"]))


def test_stop_rule_estimates_what_is_still_to_come() -> None:
    """The settling stop rule judges the change still to come, not the last step's change."""
    fast = [1e-8 * 0.74**k for k in range(6)]  # an ordinary pose: r = 0.74
    assert remaining_change(fast) == pytest.approx(fast[-1] / 0.74**3 * 0.74 / 0.26)
    slow = [1e-10 * 0.999**k for k in range(6)]  # a tiny but slow decay: 1e-7 still to come
    assert remaining_change(slow) > SETTLE_RTOL
    dip = [4e-7, 2e-7, 9e-8, 1e-8]  # the turning point of an oscillation
    assert remaining_change(dip) > SETTLE_RTOL
    wobble = [5e-9, 3e-9, 5e-9, 3e-9]  # no decay: nothing to extrapolate
    assert remaining_change(wobble) == np.inf


def watch_until_settled(forces: np.ndarray, watch: DecayWatch | StepWatch | None = None
                        ) -> tuple[int, str]:
    """(index of the reading at which :class:`DecayWatch` (or ``watch``, a twin) first says
    settled, or −1; its rule)."""
    watch = DecayWatch() if watch is None else watch
    for i, f in enumerate(forces):
        if watch.settled(f):
            return i, watch.rule
    return -1, ""


def batch_until_settled(forces: np.ndarray, stops: Any = first_stops) -> tuple[int, str]:
    """The same from the batch settler's rule (:func:`.settle.first_stops`: compiled where
    numba is installed; ``stops``: another implementation), fed chunk by chunk with
    the pass's history as the settler feeds it: a refinement pass's first chunk short,
    then whole ones."""
    history = np.full((1, FLOOR_WINDOW - 1, forces.shape[1]), np.nan)
    starts = [0, *range(REFINE_CHUNK, len(forces), CHUNK)]
    for start, end in zip(starts, [*starts[1:], len(forces)], strict=True):
        chunk = forces[start:end][None]
        first, rule = stops(history, chunk, np.zeros(chunk.shape[:2]))
        if first[0] >= 0:
            return start + int(first[0]), RULES[rule[0]]
        history = np.concatenate([history, chunk], axis=1)[:, -(FLOOR_WINDOW - 1):]
    return -1, ""


STOP_RULES = {"per step": watch_until_settled, "batch": batch_until_settled,
              "batch, Python": lambda forces: batch_until_settled(forces, mj_settle.first_stops),
              "twin, per step": lambda forces: watch_until_settled(forces, StepWatch()),
              "twin, numpy": lambda forces: batch_until_settled(forces, vectorised_stops)}


def random_passes(rng: np.random.Generator, kind: int) -> tuple[np.ndarray, ...]:
    """A wave of up to 8 poses' pass readings (history, chunk, speed) around a random force
    vector: decaying (kind 0), on a rounding floor (1), with NaNs (2), rounded to a few
    digits (3); each pose's pass started somewhere in its history (NaN before)."""
    poses, steps, m = (int(v) for v in (rng.integers(1, 9), rng.integers(1, 17), rng.integers(1, 7)))
    base = rng.normal(size=(1, 1, m)) * 10 ** rng.uniform(-3, 3)
    k = np.arange(FLOOR_WINDOW - 1 + steps)[None, :, None]
    x = base + base * rng.normal(size=(poses, 1, m)) * 10.0 ** rng.uniform(-12, -4) \
        * rng.uniform(0.1, 1.0) ** k
    if kind == 1:
        x = x + 10.0 ** rng.uniform(-14, -8) * rng.choice([-1, 1], size=x.shape) * np.abs(base)
    elif kind == 2:
        x[rng.random(x.shape) < 0.02] = np.nan
    elif kind == 3:
        x = np.round(x, int(rng.integers(3, 12)))
    for p, cut in enumerate(rng.integers(0, FLOOR_WINDOW - 1, size=poses)):
        x[p, :cut] = np.nan
    speed = np.where(rng.random((poses, steps)) < 0.8, 0.0, 1.0)
    return x[:, :FLOOR_WINDOW - 1], x[:, FLOOR_WINDOW - 1:], speed


def test_the_stop_rules_are_the_vectorised_twins() -> None:
    """The stop rules (:func:`.settle.first_stops`), run as Python and compiled
    (:mod:`._fast.stop_kernel`, where numba is installed), give the numpy twin's first stop
    and rule exactly, on 2 000 random waves in which every rule fires."""
    stop_kernel = pytest.importorskip("mechcheck.sim_models.mujoco._fast.stop_kernel")
    rng = np.random.default_rng(13)
    fired = np.zeros(len(RULES), dtype=int)
    for trial in range(2000):
        history, readings, speed = random_passes(rng, trial % 4)
        first, rule = vectorised_stops(history, readings, speed)
        for stops in (stop_kernel.first_stops, mj_settle.first_stops):
            found = stops(history, readings, speed)
            np.testing.assert_array_equal(found[0], first, err_msg=f"trial {trial}")
            np.testing.assert_array_equal(found[1], rule, err_msg=f"trial {trial}")
        np.add.at(fired, rule[first >= 0], 1)
    assert fired.min() > 20, fired


#: Forces of the size of seed E1's next to its change point, N (F34 and the drive torque / scale).
E1_FORCES = np.array([-1798.6, -5.87, 0.0, 40.15])


@pytest.mark.parametrize("until_settled", STOP_RULES.values(), ids=STOP_RULES)
def test_stop_rule_accepts_the_rounding_floor(until_settled: Any) -> None:
    """Forces cycling on their rounding floor are settled once a floor window has shown it.

    The cycle is the one measured on seed E1 0.332° from its change point (second pass):
    F34_x repeats −5.5, −8.5, −25.9, −19.4, 0 (×1e-9 of the forces) for ever, so every window
    of four changes holds one of 1.7e-8 or 1.9e-8; the old rule waited for a window below 1e-8
    and ran out of steps.
    """
    cycle = np.array([-5.5, -8.5, -25.9, -19.4, 0.0]) * 1e-9
    wobble = np.tile(cycle, 40)
    forces = np.tile(E1_FORCES, (wobble.size, 1))
    forces[:, 0] *= 1.0 + wobble
    at, rule = until_settled(forces)
    assert (at, rule) == (FLOOR_WINDOW - 1, "floor")


@pytest.mark.parametrize("until_settled", STOP_RULES.values(), ids=STOP_RULES)
@pytest.mark.parametrize("half_period", [13, 18, 36])
def test_stop_rule_does_not_take_a_slow_swing_for_the_floor(half_period: int,
                                                            until_settled: Any) -> None:
    """A lightly damped mode (half-periods 13–36 steps at condition numbers 360–2100) is not
    judged settled at a turning point: when the rule fires, the forces are within the floor
    tolerance of where they end."""
    t = np.arange(20000)
    swing = 1e-5 * 0.98**t * np.cos(np.pi * t / half_period + 0.7)
    at, _ = until_settled(E1_FORCES * (1.0 + swing[:, None]))
    assert at > 0 and abs(swing[at]) <= 3 * WOBBLE_RTOL


@settings(max_examples=200, deadline=None)
@given(st.floats(1e-9, 1e-3), st.floats(0.3, 0.999), st.integers(2, 60), st.floats(0.0, 6.3),
       st.floats(0.0, 3e-8), st.integers(0, 2**32 - 1))
def test_batch_stop_rule_is_the_per_step_rule(amplitude: float, decay: float, half_period: int,
                                              phase: float, floor: float, seed: int) -> None:
    """The batch settler's rule fires at the same reading, by the same rule, as
    :class:`DecayWatch` reading one step at a time and as its plain-Python twin: damped
    swings of any rate and period on a rounding floor of any size (seed E1's forces)."""
    t = np.arange(3000)
    noise = np.random.default_rng(seed).uniform(-floor, floor, t.size)
    swing = amplitude * decay**t * np.cos(np.pi * t / half_period + phase) + noise
    forces = E1_FORCES * (1.0 + swing[:, None])
    expected = watch_until_settled(forces, StepWatch())
    assert batch_until_settled(forces) == watch_until_settled(forces) == expected


def test_refinement_counts_the_passes_still_to_come() -> None:
    """Passes that converge slowly (difference shrinking 0.9× per pass) are not done at a
    difference of 1e-7: 9× that is still to come. Quickly converging ones, and ones whose
    difference no longer shrinks (two readings of one equilibrium), are."""
    assert refinement_left([5e-8]) == 5e-8
    assert refinement_left([1e-5, 1e-6, 9e-8]) <= REFINE_RTOL
    assert refinement_left([1.1e-7, 9.9e-8]) == pytest.approx(9.9e-8 * 9.0)
    assert refinement_left([3e-9, 8e-9]) == 8e-9


def test_refinement_with_a_measured_contraction_needs_the_difference_it_implies() -> None:
    """Two passes agreeing to d are within d·c/(1 − c) of the fixed point only if the passes
    contract by c; a contraction measured earlier in the run (0.9) holds even where the
    last two differences happen to shrink fast or not at all."""
    assert refinement_left([1e-8], contraction=0.9) == pytest.approx(9e-8)
    assert refinement_left([1e-7, 1e-8], contraction=0.9) == pytest.approx(9e-8)
    assert refinement_left([3e-9, 8e-9], contraction=0.5) == 8e-9  # c/(1 − c) = 1
    assert refinement_left([5e-8], contraction=0.0) == 5e-8  # as without


#: A linear fixed-point iteration as the passes are next to a change point: a pass started
#: with ``carried`` holds (1 − c)(F* − carried) in its constraints.
FIXED_POINT = np.array([6.4e4, -28.5, 0.0, 5.5])


def held_by_a_pass(carried: np.ndarray, c: float) -> np.ndarray:
    return (1.0 - c) * (FIXED_POINT - carried)


@pytest.mark.parametrize("c", [0.3, 0.9, 0.99])
def test_secant_of_two_passes_measures_their_contraction(c: float) -> None:
    """On a linear iteration the secant of any two passes is exactly 1 − c (an identity),
    and carrying the held forces times 1/(1 − c) lands on the fixed point (Aitken)."""
    first = np.array([100.0, -1.0, 0.0, 0.3])
    second = first + 3.7 * held_by_a_pass(first, c)  # an extrapolated carry between them
    slope = secant_slope((first, held_by_a_pass(first, c)), (second, held_by_a_pass(second, c)))
    assert slope == pytest.approx(1.0 - c, rel=1e-12)
    landed = second + held_by_a_pass(second, c) / slope
    assert np.allclose(landed, FIXED_POINT, rtol=1e-12, atol=1e-9)


def test_passes_are_extrapolated_only_when_plain_ones_would_crawl() -> None:
    """Plain passes go on while they would converge within :data:`EXTRAPOLATE_AFTER` more
    (c = 0.01: one more); at c = 0.9 the next carry is extrapolated by 1/(1 − c) = 10, and
    the difference across it is not taken for a pass's."""
    scale = np.ones(FIXED_POINT.size)
    for c, expected in ((0.01, 1.0), (0.9, 10.0)):
        refinement = Refinement()
        carried = np.zeros(FIXED_POINT.size)
        factors = []
        for _ in range(2):
            total = carried + held_by_a_pass(carried, c)
            factors.append(refinement.factor(carried, total, scale))
            carried = carried + factors[-1] * (total - carried)
        assert factors == [1.0, pytest.approx(expected)]
        assert refinement.contraction == pytest.approx(c)
        assert refinement.extrapolated == (expected != 1.0)
        assert not refinement.converged(0.0) or expected == 1.0
    # Passes left at c = 0.5 from a pass holding 1e-4: 0.5ⁿ·1e-4 ≤ 1e-7 → n = log2(1000).
    assert plain_passes_left(1e-4, 0.5) == pytest.approx(math.log2(1000.0))


def test_steady_plain_passes_are_extrapolated_by_their_ratio() -> None:
    """Where no secant is measured (every carry below MEASURABLE_CARRY of the forces), plain
    passes whose differences shrink steadily, 0.77 a pass here, are extrapolated by
    1/(1 − 0.77) once three in a row show it (Aitken's Δ² on the differences); a ratio
    still changing (0.38, then 0.77) does not, and the count starts again after an
    extrapolated carry."""
    scale = np.ones(2)
    carried = np.array([0.0, 1.0])  # the same every pass: no carry to measure a secant across
    total = carried + np.array([3e-7, 0.0])  # held: 3e-7 of the largest force
    refinement = Refinement()
    factors = []
    for d in (1.7e-6, 6.6e-7, 5.1e-7, 3.9e-7):
        refinement.converged(d)
        factors.append(refinement.factor(carried, total, scale))
    assert factors[:3] == [1.0, 1.0, 1.0]  # 0.39 then 0.77: not steady yet
    c = 3.9e-7 / 5.1e-7
    assert factors[3] == pytest.approx(1.0 / (1.0 - c), rel=1e-12)
    assert refinement.contraction == pytest.approx(c) and refinement.extrapolated
    assert not refinement.converged(3.0e-7)  # across the extrapolated carry: no pass's
    assert refinement.steady_ratio() is None
    assert plain_passes_left(3e-7, c) > EXTRAPOLATE_AFTER  # why it was extrapolated


def test_a_batched_sweep_to_condition_number_ten_thousand_settles_every_pose() -> None:
    """Seed E1 batched towards its change point, δ from 0.2° to 0.0115° (condition numbers
    590 to 10 300): every pose settles within its tolerance. The pose at condition number
    8 600 was ``not_settled`` after 16 passes (its secant misread the contraction once,
    then its carries were too small to measure one; :data:`.settle.STEADY_RATIO`)."""
    case = fourbar_e1()
    theta = math.pi - np.radians(np.geomspace(0.2, 0.0115, 17))
    for t, sim in zip(theta, sweep(case, theta), strict=True):
        at = redrawn(case, theta12=float(t))
        assert sim.status == "ok", f"θ12 = {np.degrees(t):.4f}°: {sim.message}"
        assert_solution_close(at, sim, complete=True)


#: Seed E1 1.15e-2° from its change point: condition number 1.03e4 (issue 13's target 1e4).
REACH_DELTA = 0.0115


def test_settled_statics_reach_condition_number_ten_thousand() -> None:
    """Seed E1 at condition number 1.03e4 settles within the static target, alone and in a
    batch (it was ``not_settled`` from condition number ~5300: the passes contracted by
    0.5–0.9 each and ran out)."""
    case = redrawn(fourbar_e1(), theta12=math.pi - math.radians(REACH_DELTA))
    assert mechcheck.solve(case, "analytic").diagnostics["condition_number"] > 1e4
    for sim in (settle(case), *sweep(fourbar_e1(), [case.preset.theta12])):
        assert sim.status == "ok", sim.message
        assert sim.diagnostics["passes"] > 2
        assert_solution_close(case, sim, complete=True)


def test_sweep_next_to_the_change_point_settles_as_its_poses_alone() -> None:
    """A batched sweep of seed E1 towards its change point, δ from 0.2° to 0.0164°
    (condition numbers 2.2e3–2.7e4; past 1e4 a pose is judged as near-singular): every pose
    settles within its target, as each does alone. The poses between every 8th start from
    their settled neighbours' forces, and from condition number ~4200 on such a start ran
    its first pass out of steps (``not_settled``); such a pose is now settled again from
    nothing carried."""
    case = fourbar_e1()
    theta = math.pi - np.radians(np.geomspace(0.2, 0.0164, 15))
    for t, sim in zip(theta, sweep(case, theta), strict=True):
        at = redrawn(case, theta12=float(t))
        assert mechcheck.solve(at, "analytic").diagnostics["condition_number"] < 3e4
        assert sim.status == "ok", f"θ12 = {np.degrees(t):.4f}°: {sim.message}"
        assert_solution_close(at, sim, complete=True)


#: Seed E1 at θ12 = 180° − δ, δ from the near-toggle study (condition numbers 222, 546, 1345,
#: 3310).
NEAR_TOGGLE_DELTAS = np.geomspace(30.0, 1e-4, 15)[3:7]


@pytest.mark.parametrize("delta", NEAR_TOGGLE_DELTAS, ids=lambda d: f"{d:.3f}deg")
def test_settled_statics_near_the_change_point_do_not_depend_on_luck(delta: float) -> None:
    """Seed E1 0.817° and 0.332° from its change point (condition numbers 145 and 357) settle
    within the static target, as 2.01° and 0.135° do: they were ``not_settled`` (3000 steps on
    a rounding floor of 1–3e-8 that the stop rule only took below 1e-8)."""
    case = redrawn(fourbar_e1(), theta12=math.pi - math.radians(float(delta)))
    sim = settle(case)
    assert sim.status == "ok", sim.message
    assert_solution_close(case, sim, complete=True)


def test_settled_statics_are_monotonic_towards_the_change_point() -> None:
    """Approaching seed E1's change point from 2° to 0.1° (condition numbers 60–1200), every
    pose settles within the static target: no pose fails while a closer one passes."""
    case = fourbar_e1()
    theta = math.pi - np.radians(np.geomspace(2.0, 0.1, 14))
    for t, sim in zip(theta, sweep(case, theta), strict=True):
        assert sim.status == "ok", f"θ12 = {np.degrees(t):.4f}°: {sim.message}"
        assert_solution_close(redrawn(case, theta12=float(t)), sim, complete=True)


def test_settled_statics_next_to_the_change_point() -> None:
    """Seed E1 1° and 2° from its change point (condition numbers 119 and 59) meets the static
    target: a single settled state was 2e-5 off there (the soft constraints' bending)."""
    case = fourbar_e1()
    theta = np.radians([178.0, 179.0, 181.0, 182.0])
    for t, sim in zip(theta, sweep(case, theta), strict=True):
        assert sim.diagnostics["passes"] >= 2
        assert_solution_close(redrawn(case, theta12=float(t)), sim, complete=True)


def test_whole_cycle_sweep_is_within_tolerance() -> None:
    """A 1° sweep of seed E1: every pose but the change point within the policy's tolerance."""
    case = fourbar_e1()
    theta = np.radians(np.arange(360.0))
    sols = sweep(case, theta)
    assert [i for i, s in enumerate(sols) if s.status != "ok"] == [180]
    for t, sim in zip(theta, sols, strict=True):
        if sim.status == "ok":
            assert_solution_close(redrawn(case, theta12=float(t)), sim, complete=True)


def test_change_point_case_is_singular() -> None:
    """At the change point itself the pose gate keeps the case from MuJoCo (``mechcheck.solve``,
    as ``mechcheck run``): the analytic verdict, no forces."""
    for backend in ("mujoco", "mujoco_solve"):
        solution = mechcheck.solve(builtin("fourbar-change-point"), backend)
        assert solution.status == "singular" and "not run" in solution.message
        assert not solution.values


def test_seed_e1_drive_torque() -> None:
    """Seed E1 (Söylemez 6.3) settles to T12 = +2.90133 N·m CCW (SEEDS.md)."""
    assert settle(fourbar_e1()).values["T12"] == pytest.approx(2.90133, abs=1e-5)


def test_seed_e2_drive_torque() -> None:
    """Seed E2 driven clockwise with pin and slide friction needs T12 = −22.897 N·m (SEEDS.md)."""
    assert settle(slidercrank_e2()).values["T12"] == pytest.approx(-22.897, abs=1e-3)


def test_sweep_marks_change_point_singular() -> None:
    """Through the harness's sweep, the pose gate withholds E1's change point (θ12 = 180°)
    from MuJoCo, and MuJoCo's sweep of the other poses matches everywhere."""
    case = fourbar_e1()
    theta_deg = np.array([30.0, 120.0, 180.0, 250.0])
    for backend in ("mujoco", "mujoco_solve"):
        task = SweepTask(case, backend, theta_deg, 0, "")
        status = pd.read_parquet(io.BytesIO(run_task(task)[1]))
        assert list(status["status"]) == ["ok", "ok", "singular", "ok"]
        regular = np.radians(np.delete(theta_deg, 2))
        for t, solution in zip(regular, sweep(case, regular, backend), strict=True):
            assert_solution_close(redrawn(case, theta12=float(t)), solution, complete=True)


def test_unsettled_run_reports_no_forces(monkeypatch: pytest.MonkeyPatch) -> None:
    """With a step budget too small to settle, the backend says not_settled and reports no forces."""
    # The package exports the function ``settle``, which hides the module's name.
    settle_module = importlib.import_module("mechcheck.sim_models.mujoco.settle")
    monkeypatch.setattr(settle_module, "MAX_STEPS", 3)
    sim = settle(fourbar_e1())
    assert sim.status == "not_settled"
    assert not any(q.startswith(("F", "T")) for q in sim.values)


@pytest.mark.parametrize("name", GOLDEN_CASES)
def test_golden_xml_is_reproduced(name: str) -> None:
    """The committed MJCF of each seed case, built as its linkage, is exactly what the builder
    produces today."""
    assert model_xml(name, builtin(name).linkage) == (GOLDEN / f"{name}.xml").read_text()


def test_model_is_planar_fourbar() -> None:
    """The four-bar, built as its linkage, has three z-hinges, one loop connect and the
    crank's drive equality, and no contacts."""
    rig = LinkageRig(as_linkage(fourbar_e1()))
    model = rig.model
    assert model.nv == 3 and model.neq == 2 and len(rig.loop_eq) == 1
    assert np.allclose(model.jnt_axis, [0.0, 0.0, 1.0])
    assert list(rig.drive_eq) == ["A0"]


def test_geometry_types_unchanged() -> None:
    """The seed cases use the shared Case geometry types (no private copies)."""
    assert isinstance(fourbar_e1().preset.geometry, FourBarGeometry)
    assert isinstance(slidercrank_e2().preset.geometry, SliderCrankGeometry)


def test_mujoco_warnings_go_to_diagnostics_not_to_a_file(tmp_path: Path,
                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    """A MuJoCo warning raised while a Solution is computed lands in its ``warnings``
    diagnostic, and MuJoCo writes no MUJOCO_LOG.TXT into the working directory."""
    import mujoco

    from mechcheck.sim_models.mujoco.mjwarnings import noting_warnings

    monkeypatch.chdir(tmp_path)
    model = mujoco.MjModel.from_xml_string(
        '<mujoco><worldbody><body><joint type="hinge"/><geom size="0.1"/></body></worldbody></mujoco>')
    data = mujoco.MjData(model)

    def unstable() -> Solution:
        data.qfrc_applied[0] = math.nan  # MuJoCo warns: NaN in qacc
        mujoco.mj_step(model, data)
        return Solution("demo", "mujoco", {})

    solution = noting_warnings(unstable)
    assert "QACC" in str(solution.diagnostics["warnings"])
    assert list(tmp_path.iterdir()) == []
    assert "warnings" not in noting_warnings(lambda: Solution("demo", "mujoco", {})).diagnostics
