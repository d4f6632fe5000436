"""Cross-checks of the pymunk backends against the analytic backend (an independent method).

Relative error measure: |sim − ref| / max(|ref|, scale), scale = the largest
|ref| among the case's quantities of the same kind (forces, or torques).
Expected values always come from ``mechcheck.analytic.forces``, never from pymunk.
"""

from __future__ import annotations

import io
import math

import numpy as np
import pandas as pd
import pytest

import mechcheck
from mechcheck.analytic.case import Case, Friction, Load, Mass, Motion, SliderCrankGeometry
from mechcheck.analytic.kinematics import pose_of
from mechcheck.analytic.linkage_kinematics import solve_pose
from mechcheck.analytic.presets import as_linkage, preset_case, redrawn
from mechcheck.analytic.solution import Solution
from mechcheck.casefile import builtin_case_files, load_cases
from mechcheck.sim_models.convergence import LEAD_AGREEMENT_RTOL, TIMESTEP_AGREEMENT_RTOL
from mechcheck.sim_models.linkage_motion import driven_motion
from mechcheck.sim_models.pymunk import backend as _pymunk
from mechcheck.sweep import SweepTask, run_task
from mechcheck.testing import assert_solution_close

from .builtin import builtin
from .closed_form.forces import solve_poses
from .harness import solver, sweeper

#: The backend's functions as the harness calls them (a preset as its linkage).
settle = solver(_pymunk.settle, "pymunk")
solve_at_pose = solver(_pymunk.solve_at_pose, "pymunk_solve")
sweep = sweeper(_pymunk.sweep, {"pymunk": _pymunk.settle, "pymunk_solve": _pymunk.solve_at_pose},
                "pymunk")

MASSES = (Mass(2, 1.0, (0.04, 0.0), 1e-3), Mass(3, 2.0, (0.05, 0.01), 2e-3),
          Mass(4, 1.5, (0.06, 0.0), 2e-3))


def e1() -> Case:
    """Seed E1 (SEEDS.md, Söylemez 6.3), loads as stated: T12 = +2.90133 N·m."""
    return builtin("seed-E1-as-stated")


def e2() -> Case:
    """Seed E2 slider-crank with friction, crank clockwise: T12 = −22.897 N·m."""
    return builtin("seed-E2-friction")


def assert_agrees(sol: Solution, case: Case) -> None:
    """Every quantity of ``sol`` agrees with the analytic backend under the one tolerance policy."""
    assert_solution_close(case, sol, complete=True)


def slider_offset_tilted() -> Case:
    return preset_case(name="slider-offset-tilted", geometry=SliderCrankGeometry(0.1, 0.35, offset=0.04),
                theta12=2.0, ground_angle=0.3,
                loads=(Load(4, force=(-80.0, 10.0)), Load(3, at=(0.1, 0.02), force=(5.0, -30.0),
                                                         torque=1.5)))


STATIC_CASES = {
    "E1-fourbar": e1,
    "E1-crossed": lambda: redrawn(e1(), name="E1-crossed", branch="crossed"),
    "E1-tilted-ground": lambda: redrawn(e1(), name="E1-tilted", ground_angle=0.4, theta12=1.5),
    "slider-offset-tilted": slider_offset_tilted,
    "slider-left": lambda: redrawn(slider_offset_tilted(), name="slider-left", branch="left"),
    "E2-frictionless": lambda: redrawn(e2(), name="E2-frictionless", friction=None),
    "gravity-masses": lambda: redrawn(e1(), name="E1-gravity", gravity=(0.0, -9.81), masses=MASSES),
    "drive-on-link-4": lambda: redrawn(e1(), name="E1-T14", drive_link=4),
}


@pytest.mark.parametrize("make", STATIC_CASES.values(), ids=STATIC_CASES.keys())
def test_settled_statics_match_analytic(make: object) -> None:
    """A mechanism held by simulation until settled carries the analytic reactions and drive torque."""
    case = make()  # type: ignore[operator]
    sol = settle(case)
    assert_agrees(sol, case)
    assert sol.diagnostics["method"] == "settle"
    assert float(sol.diagnostics["pose_drift"]) < 1e-9 * case.scale


@pytest.mark.parametrize("make", STATIC_CASES.values(), ids=STATIC_CASES.keys())
def test_constraint_solve_at_pose_matches_analytic(make: object) -> None:
    """pymunk's own constraint solver at the exact pose reproduces the statics to rounding."""
    case = make()  # type: ignore[operator]
    sol = solve_at_pose(case)
    assert_agrees(sol, case)
    assert sol.backend == "pymunk_solve"


def test_seed_e1_drive_torque_is_ccw_2_901() -> None:
    """The settled E1 needs the seed's +2.90133 N·m (CCW) on the crank: the sign convention holds."""
    assert settle(e1()).values["T12"] == pytest.approx(2.90133, rel=1e-5)


DRIVEN_CASES = {
    "fourbar-masses-omega": lambda: redrawn(e1(), name="dyn", masses=MASSES, motion=Motion(-10.0)),
    "fourbar-accel-gravity": lambda: redrawn(e1(), name="dyn-acc", masses=MASSES, gravity=(0, -9.81),
                                                motion=Motion(-10.0, 50.0)),
    "fourbar-drive-link-4": lambda: redrawn(e1(), name="dyn-T14", masses=MASSES, drive_link=4,
                                               motion=Motion(-10.0, 50.0)),
    "fourbar-massless-crank": lambda: redrawn(e1(), name="dyn-massless", masses=MASSES[1:],
                                                 motion=Motion(-10.0)),
    "slider-masses": lambda: redrawn(e2(), name="sc-dyn", friction=None, motion=Motion(20.0),
                                        masses=(Mass(2, 2.0, (0.1, 0.0), 0.01),
                                                Mass(3, 4.0, (0.3, 0.0), 0.2), Mass(4, 3.0))),
    # ω = 0 at θ12*: the crank is momentarily at rest there, read at t* by time.
    "fourbar-from-rest": lambda: redrawn(e1(), name="dyn-rest", masses=MASSES, gravity=(0, -9.81),
                                            motion=Motion(0.0, 50.0)),
    # ω(t) = 0.5 + 200·τ reverses 2.5 ms before θ12*, inside the lead-in.
    "fourbar-omega-reverses": lambda: redrawn(e1(), name="dyn-rev", masses=MASSES,
                                                 gravity=(0, -9.81), motion=Motion(0.5, 200.0)),
}


@pytest.mark.parametrize("make", DRIVEN_CASES.values(), ids=DRIVEN_CASES.keys())
def test_driven_dynamics_match_analytic(make: object) -> None:
    """Driving the input through θ12 with the prescribed ω, α gives the D'Alembert reactions and torque."""
    case = make()  # type: ignore[operator]
    sol = settle(case)
    assert_agrees(sol, case)
    assert sol.diagnostics["method"] == "driven"


def builtin_case(name: str) -> Case:
    """A case of the built-in suite (compare/cases/*.toml), by name."""
    return next(c for c in load_cases(*builtin_case_files()) if c.name == name)


@pytest.mark.parametrize("name", ["seed-exam-Q3", "fourbar-dynamic-drive4"])
def test_builtin_rocker_driven_dynamics_match_analytic(name: str) -> None:
    """The built-in drive-on-link-4 cases with inertia, gravity, ω and α agree with D'Alembert.

    Both read near a dead point of the rocker drive: seed-exam-Q3 6.8° of
    crank rotation short of one (forces varying fast, which the old
    smoothness test took for noise), fourbar-dynamic-drive4 with one 327 steps
    before θ12*, inside the old 400-step lead-in. Both used to come back
    ``not_settled``.
    """
    case = builtin_case(name)
    sol = settle(case)
    assert_agrees(sol, case)
    assert sol.diagnostics["method"] == "driven"
    assert float(sol.diagnostics["lead_disagreement"]) <= LEAD_AGREEMENT_RTOL
    assert float(sol.diagnostics["timestep_disagreement"]) <= TIMESTEP_AGREEMENT_RTOL


def test_lead_in_stops_short_of_the_rocker_dead_point() -> None:
    """fourbar-dynamic-drive4, driven at B0 as a linkage, has a rocker dead point (where
    dθ14/dθ12 changes sign, θ12 ≈ 223.7°) shortly before the instant: the rocker's motion
    cannot be continued back past it. The run's lead-in ends where the linkage still
    assembles along the prescribed rocker motion."""
    case = builtin_case("fourbar-dynamic-drive4")
    sol = settle(case)
    linkage = as_linkage(case)
    motion = driven_motion(linkage, 0.0)
    lead = float(sol.diagnostics["lead_steps"]) * float(sol.diagnostics["timestep"])
    along = solve_pose(linkage.linkage, motion.at(np.linspace(-lead, 0.0, 200))[0])
    assert along.assembled.all()
    # By hand (the crank's motion, θ12 + ω·t + α·t²/2): the dead point is 300–400 steps of
    # 1e-4 s before the instant, so a lead-in twice as long as the run's would pass it.
    t = -1e-4 * np.arange(400)
    theta = case.preset.theta12 + case.preset.motion.omega * t + 0.5 * case.preset.motion.alpha * t**2
    ratio = pose_of(case, theta, omega=1.0, alpha=0.0).links[4].omega
    assert 300 < int(np.argmax(ratio <= 0.0)) < 400


def test_reading_next_to_a_rocker_dead_point_is_withheld_with_the_reason() -> None:
    """1.2° short of the dead point there is no room for a lead-in: no forces, and it says why."""
    case = redrawn(builtin_case("fourbar-dynamic-drive4"), theta12=math.radians(222.5))
    sol = settle(case)
    assert sol.status == "not_settled"
    assert not any(q[0] in "FTM" for q in sol.values)
    # Driven at B0, the rocker's motion cannot be continued back past its dead point.
    assert "lead-in would start where the linkage does not assemble" in sol.message


def test_rocker_clock_is_continuous_where_the_closed_form_theta14_wraps() -> None:
    """The closed-form θ14 jumps by 2π at θ12 = 180°; a lead-in across it still follows the rocker."""
    case = redrawn(builtin_case("fourbar-dynamic-drive4"), theta12=math.radians(180.5),
                                                        motion=Motion(12.0, 0.0))
    jump = np.diff(pose_of(case, np.radians([179.9, 180.1]), omega=0.0, alpha=0.0).theta14)
    assert abs(abs(float(jump[0])) - 2 * math.pi) < 0.1
    assert_agrees(settle(case), case)


FRICTION_CASES = {
    "E2-pins-and-slide": e2,
    "fourbar-pins-ccw": lambda: redrawn(e1(),
        name="E1-friction", friction=Friction(mu=0.2, direction=1,
                                              pin_radius={"A0": 0.01, "A": 0.01, "B": 0.01,
                                                          "B0": 0.01})),
    "slider-tilted-pin-and-slide": lambda: redrawn(slider_offset_tilted(),
        name="sc-friction", friction=Friction(mu=0.15, pin_radius={"A": 0.02}, slide_mu=0.3,
                                              direction=1)),
    "fourbar-viscous-dynamic": lambda: redrawn(e1(),
        name="E1-viscous", masses=MASSES, motion=Motion(-10.0),
        friction=Friction(viscous={"A0": 0.05, "A": 0.02, "B0": 0.03})),
    "E2-coulomb-dynamic": lambda: redrawn(e2(),
        name="E2-dynamic", motion=Motion(-3.0),
        masses=(Mass(3, 1.0, (0.4, 0.0), 0.05), Mass(4, 2.0))),
}


@pytest.mark.parametrize("make", FRICTION_CASES.values(), ids=FRICTION_CASES.keys())
def test_friction_drive_torque_matches_friction_circle(make: object) -> None:
    """Driving slowly with μ·r·|F| pin motors and μ·|N| on the slide gives the friction-circle torque."""
    case = make()  # type: ignore[operator]
    assert_agrees(settle(case), case)


def test_e2_friction_raises_torque_from_frictionless() -> None:
    """Friction makes E2's clockwise drive torque larger in magnitude (−22.90 vs −18.78 N·m)."""
    with_friction = settle(e2()).values["T12"]
    assert with_friction == pytest.approx(-22.897, rel=1e-4)
    assert settle(redrawn(e2(), friction=None)).values["T12"] == pytest.approx(-18.783, rel=1e-4)


def test_sweep_keeps_the_change_point_from_pymunk_and_agrees_elsewhere() -> None:
    """Through the harness's sweep, the pose gate withholds the E1 change point (θ12 = 180°)
    from pymunk, and the continuation sweep of the other poses matches everywhere."""
    theta_deg = np.arange(0.0, 360.0, 10.0)
    status = pd.read_parquet(io.BytesIO(run_task(SweepTask(e1(), "pymunk", theta_deg, 0, ""))[1]))
    assert list(status.loc[status["status"] != "ok", "theta12"]) == [180.0]
    assert status.set_index("theta12").loc[180.0, "status"] == "singular"
    sols = sweep(e1(), np.radians(np.delete(theta_deg, 18)))
    for theta, sol in zip(np.delete(theta_deg, 18), sols, strict=True):
        assert_agrees(sol, redrawn(e1(), theta12=math.radians(theta)))


def test_sweep_with_constraint_solve_backend() -> None:
    """The re-posed constraint solve keeps rounding-level agreement along a continuation sweep."""
    theta = np.radians(np.arange(5.0, 360.0, 30.0))
    for k, sol in enumerate(sweep(e1(), theta, backend="pymunk_solve")):
        assert_agrees(sol, redrawn(e1(), theta12=float(theta[k])))


def test_budget_exhausted_reports_not_settled_without_forces() -> None:
    """A run stopped by its step budget says not_settled and withholds every force."""
    from mechcheck.sim_models.pymunk.settings import LINKAGE_SETTLE

    sol = settle(e1(), LINKAGE_SETTLE.with_(max_steps=3))
    assert sol.status == "not_settled"
    assert not any(q[0] in "FTM" for q in sol.values)


def test_singular_pose_is_withheld() -> None:
    """At the E1 change point statics is singular, so no force is reported."""
    sol = mechcheck.solve(redrawn(e1(), theta12=math.pi), "pymunk")
    assert sol.status == "singular" and not sol.values and "not run" in sol.message


def test_constraint_solve_declines_motion() -> None:
    """The fixed-pose solve cannot represent velocities, so a dynamic case is not_applicable."""
    assert solve_at_pose(redrawn(e1(), masses=MASSES, motion=Motion(5.0))).status == "not_applicable"


@pytest.mark.slow
def test_full_cycle_sweep_of_e1() -> None:
    """Over a 360-pose continuation sweep every regular pose settles within the static target."""
    theta = np.radians(np.arange(360.0))
    regular = theta[~solve_poses(e1(), theta).singular]  # the harness sweeps only these
    assert len(regular) >= 355
    for t, sol in zip(regular, sweep(e1(), regular), strict=True):
        assert_agrees(sol, redrawn(e1(), theta12=float(t)))
