"""MuJoCo's driven readings of massless links carry no fictitious inertia (issue 10 item 8).

MuJoCo refuses massless moving bodies, so the driven backend gives massless
links a fictitious inertia, and a quasi-static friction run heavy fictitious
links; the backend extrapolates its readings to zero fictitious inertia.
Expected values come from the analytic backend (every force of an unloaded
massless mechanism is exactly zero), compared under the one tolerance policy.
"""

from __future__ import annotations

import math

import numpy as np

from mechcheck.analytic.case import Case, FourBarGeometry, Friction, Load, Motion, SliderCrankGeometry
from mechcheck.analytic.presets import preset_case, redrawn
from mechcheck.analytic.solution import FORCE_FLOOR_N, Solution, quantity_kind
from mechcheck.sim_models.mujoco import backend as _mujoco
from mechcheck.testing import assert_solution_close
from mechcheck.tolerance import rule

from .closed_form import forces
from .harness import solver, sweeper

#: The backend's functions as the harness calls them (a preset as its linkage).
settle = solver(_mujoco.settle, "mujoco")
sweep = sweeper(_mujoco.sweep, {"mujoco": _mujoco.settle, "mujoco_solve": _mujoco.solve_at_pose},
                "mujoco")

#: The seed four-bar's links, metres (a1..a4 = 140, 80, 100, 120 mm).
SEED_FOURBAR = FourBarGeometry(0.140, 0.080, 0.100, 0.120)
SLIDER_CRANK = SliderCrankGeometry(a2=0.1, a3=0.3)


def unloaded_fourbar() -> Case:
    return preset_case("fourbar-unloaded-massless", SEED_FOURBAR, math.radians(60.0),
                motion=Motion(omega=5.0))


def unloaded_slidercrank() -> Case:
    return preset_case("slidercrank-unloaded-massless", SLIDER_CRANK, math.radians(50.0),
                motion=Motion(omega=5.0))


def unloaded_friction_slidercrank() -> Case:
    return preset_case("slidercrank-unloaded-friction", SLIDER_CRANK, math.radians(50.0),
                friction=Friction(mu=0.1, pin_radius={"A": 0.01}, direction=1))


def driven(case: Case) -> Solution:
    """The ``mujoco`` backend's driven run, checked to have been one and to be free of warnings."""
    sim = settle(case)
    assert sim.diagnostics["method"] == "driven"
    assert "warnings" not in sim.diagnostics, sim.diagnostics["warnings"]
    return sim


def largest_force(solution: Solution) -> float:
    return max(abs(v) for q, v in solution.values.items() if quantity_kind(q) == "force")


def test_unloaded_massless_fourbar_in_motion_has_no_forces() -> None:
    """A massless, unloaded four-bar turning at 5 rad/s needs no force anywhere."""
    case = unloaded_fourbar()
    assert largest_force(forces.solve(case)) == 0.0
    assert_solution_close(case, driven(case), complete=True)


def test_unloaded_massless_slidercrank_in_motion_has_no_forces() -> None:
    """A massless, unloaded slider-crank turning at 5 rad/s needs no force anywhere."""
    case = unloaded_slidercrank()
    assert largest_force(forces.solve(case)) == 0.0
    assert_solution_close(case, driven(case), complete=True)


def test_unloaded_friction_slidercrank_has_no_forces() -> None:
    """With no load every reaction, and so every friction moment μ·r·|F|, is zero, even
    though the quasi-static run drives heavy fictitious links."""
    case = unloaded_friction_slidercrank()
    assert largest_force(forces.solve(case)) == 0.0
    assert_solution_close(case, driven(case), complete=True)


def test_unloaded_massless_fourbar_reads_zero_over_a_sweep() -> None:
    """Over half a turn a massless, unloaded four-bar in motion reads zero forces at every pose."""
    case = unloaded_fourbar()
    angles = np.radians(np.arange(10.0, 180.0, 20.0))
    for theta, sim in zip(angles, sweep(case, angles), strict=True):
        assert_solution_close(redrawn(case, theta12=float(theta)), sim, complete=True)


def test_fictitious_inertia_of_a_loaded_massless_fourbar_is_removed() -> None:
    """A massless four-bar at 10 rad/s under 1 N loads carries a fictitious inertia worth
    more than the dynamic tolerance (m_f·ω²·L ≈ 1e-2 kg · 100 s⁻² · 0.1 m ≈ 0.1 N), and
    its reading still matches the massless D'Alembert answer within that tolerance."""
    case = preset_case("fourbar-massless-light-loads", SEED_FOURBAR, math.radians(60.0),
                loads=(Load(4, at=(0.09, 0.0), force=(0.3, 1.0)),
                       Load(3, at=(0.05, 0.02), force=(-0.5, 0.0))),
                motion=Motion(omega=10.0, alpha=20.0))
    sim = driven(case)
    tolerance = rule("mujoco", "force", "dynamic").rtol
    scale = max(largest_force(forces.solve(case)), FORCE_FLOOR_N)
    # The correction made is far beyond the tolerance: without it the case would fail.
    assert float(sim.diagnostics["fictitious_inertia_correction"]) > 10.0 * tolerance * scale
    assert_solution_close(case, sim, complete=True)


def test_lightly_loaded_quasi_static_friction_reads_no_inertia() -> None:
    """A slider-crank with pin and slide friction under a 0.05 N load, driven quasi-statically
    on heavy fictitious links, gives the static friction-circle answer: the links' inertia
    (~1e-4 N, 2e-3 of the load) is not part of the reading."""
    case = preset_case("slidercrank-friction-light-load", SLIDER_CRANK, math.radians(50.0),
                loads=(Load(4, force=(-0.05, 0.0)),),
                friction=Friction(mu=0.1, pin_radius={"A0": 0.01, "A": 0.01, "B": 0.01},
                                  slide_mu=0.12, direction=1))
    assert_solution_close(case, driven(case), complete=True)
