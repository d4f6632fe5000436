"""Verdicts that withhold forces: singular poses on a driven run's lead-in, and runs that did
not settle."""

from __future__ import annotations

import numpy as np

from mechcheck.analytic.case import Case
from mechcheck.analytic.forces import solve_poses
from mechcheck.analytic.solution import Solution
from mechcheck.sim_models.pymunk.model import Model
from mechcheck.sim_models.pymunk.readout import pose_values


def singular_mask(case: Case, theta12: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(singular?, condition number) per θ12: a property of the pose, not of any force.

    Uses the analytic backend's condition number of the equilibrium matrix,
    which depends on the geometry only; none of its forces are used.
    """
    results = solve_poses(case.with_(friction=None, loads=(), masses=(),
                                     motion=type(case.motion)()), theta12)
    return results.singular, results.condition


def unsettled_solution(model: Model, backend: str, diag: dict[str, float | str]) -> Solution:
    """``not_settled``: the budget ran out; the pose is reported, no forces."""
    return not_settled(model.case.name, backend, pose_values(model), diag)


def not_settled(case: str, backend: str, pose: dict[str, float], diag: dict[str, float | str],
                units: dict[str, str] | None = None) -> Solution:
    """``not_settled`` for any model: the pose it reached, its diagnostics, no forces."""
    return Solution(case, backend, pose, status="not_settled",
                    message=f"did not settle within {diag['steps']} steps "
                            f"(residual velocity {diag['residual_velocity']:.3g} m/s, "
                            f"force change {diag['force_change']:.3g})",
                    diagnostics=diag, units=units or {})
