"""Driven sweeps as one continuous motion: a linkage turning its first driver at constant
speed over an evenly spaced whole turn is run once and read at each pose as it passes; the
readings are those of the per-pose driven runs, and the analytic answer, within the dynamic
tolerance. Any other sweep runs pose by pose and says why."""

from __future__ import annotations

from dataclasses import replace
from importlib import import_module
from pathlib import Path

import numpy as np
import pytest

from mechcheck import load_cases, solve
from mechcheck.analytic.case import Case
from mechcheck.analytic.solution import Solution
from mechcheck.sim_models.linkage_motion import at_first_driver, continuous_reason, grid_step
from mechcheck.testing import assert_solution_close

ROOT = Path(__file__).resolve().parents[1]
USERS = Path("/work/shared/cases/users")
WHITWORTH = next((p for p in (ROOT / "compare" / "cases" / "users" / "whitworth.toml",
                              USERS / "whitworth.toml") if p.exists()), None)
BACKENDS = ("mujoco", "pymunk")


def turning(case: Case, omega: float = 10.0, alpha: float = 0.0) -> Case:
    """``case`` with its first driver turning at ``omega`` rad/s (accelerating at ``alpha``)."""
    linkage = case.linkage
    first = replace(linkage.drivers[0], velocity=omega, acceleration=alpha)
    return replace(case, geometry=replace(linkage, drivers=(first, *linkage.drivers[1:])))


def seed_fourbar() -> Case:
    """Seed E1 (Söylemez 6.3) as a linkage, massless, its crank turning at 10 rad/s."""
    path = ROOT / "compare" / "cases" / "linkages" / "seed_e1_fourbar.toml"
    return turning(next(c for c in load_cases(path) if c.name == "e1-linkage"))


def whitworth() -> Case:
    """The user's Whitworth quick-return, crank turning at 10 rad/s (its own file)."""
    if WHITWORTH is None:
        pytest.skip("the Whitworth case file is not here")
    return next(c for c in load_cases(WHITWORTH) if c.name == "whitworth-running")


def sweep(case: Case, grid: np.ndarray, backend: str) -> list[Solution]:
    """The simulator's own sweep of the case's first driver, behind the pose gate."""
    found: list[Solution] = import_module(f"mechcheck.sim_models.{backend}.backend").sweep(
        case, grid, backend)
    return found


def test_an_evenly_spaced_whole_turn_at_constant_speed_is_one_motion() -> None:
    """Only a constant-speed turn of the first driver over poses on an evenly spaced grid of a
    whole turn (some left out by the gate) is one continuous motion; each other sweep is
    refused with its reason."""
    case = seed_fourbar()
    turn = np.radians(np.arange(0.0, 360.0, 30.0))
    assert grid_step(turn) == pytest.approx(np.radians(30.0), rel=1e-12)
    assert continuous_reason(case, turn) == ""
    assert continuous_reason(case, np.delete(turn, 4)) == ""  # a pose the gate withheld
    uneven = np.radians(np.arange(0.0, 350.0, 7.0))  # 7° does not divide a turn
    assert "not on an evenly spaced grid of a whole turn" in continuous_reason(case, uneven)
    assert "not on an evenly spaced grid" in continuous_reason(case, turn[[0, 1, 3]] + [0, 0, 0.1])
    assert "accelerate" in continuous_reason(turning(case, alpha=5.0), turn)
    assert "quasi-static" in continuous_reason(turning(case, omega=0.0), turn)


@pytest.mark.slow
@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize(("make", "degrees"), [
    # crank at 60°, 120°, 150°: drawn at 60°, it locks at its change point 120° on (θ12 = 180°)
    (seed_fourbar, (0.0, 60.0, 90.0)),
    (whitworth, (0.0, 150.0, 300.0)),     # crank at 60°, 210°, 360°
], ids=["seed-E1-fourbar", "whitworth"])
def test_a_continuous_sweep_reads_what_per_pose_runs_read(make: object, degrees: tuple[float, ...],
                                                          backend: str) -> None:
    """Over a whole turn in 30° steps, the readings of the one continuous run at the chosen
    poses agree with the analytic answer and with that pose's own driven run, within the
    dynamic tolerance."""
    assert callable(make)
    case = make()
    grid = np.radians(np.arange(0.0, 360.0, 30.0))
    solutions = sweep(case, grid, backend)
    for value in degrees:
        swept = solutions[round(value / 30.0)]
        assert str(swept.diagnostics["sweep_run"]).startswith("continuous"), swept.diagnostics
        at_pose = at_first_driver(case, np.radians(value))
        assert_solution_close(at_pose, swept)
        assert_solution_close(at_pose, swept, reference=solve(at_pose, backend))


@pytest.mark.slow
def test_a_sweep_of_an_accelerating_driver_runs_pose_by_pose_and_says_so() -> None:
    """A crank that accelerates is not one constant-speed motion: each pose is its own driven
    run (the same reading as solved alone), and its diagnostics say why."""
    case = turning(seed_fourbar(), alpha=20.0)
    grid = np.radians(np.arange(0.0, 360.0, 180.0))
    swept = sweep(case, grid, "mujoco")[0]
    assert swept.diagnostics["sweep_run"] == (
        "per pose: the drivers accelerate: the prescribed motion is not one constant-speed "
        "motion through the poses")
    alone = solve(at_first_driver(case, 0.0), "mujoco")
    assert swept.values == pytest.approx(alone.values, rel=1e-12)
