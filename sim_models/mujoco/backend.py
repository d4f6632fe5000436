"""MuJoCo backends (issue 3): the mechanism held or driven in MuJoCo, forces
read from MuJoCo's own constraint state.

- :func:`settle` — backend ``mujoco``: statics by settling with the crank
  locked; moving and friction cases by driving the input (``driven``).
- :func:`solve_at_pose` — backend ``mujoco_solve``: exact constraint forces at
  the analytic pose from MuJoCo's constraint Jacobian.
- :func:`sweep` — either backend over an array of θ12.

A ``mechanism = "linkage"`` case goes to :mod:`.linkage` (any planar linkage, issue 12).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from mechcheck.analytic.case import Case
from mechcheck.analytic.solution import Solution
from mechcheck.sim_models.coulomb import at_rest_reason
from mechcheck.sim_models.mujoco import solve as exact, sweep as sweeps
from mechcheck.sim_models.mujoco.dynamics import driven
from mechcheck.sim_models.mujoco.linkage import settle_linkage, solve_linkage_at_pose, sweep_linkage
from mechcheck.sim_models.mujoco.mjwarnings import noting_warnings
from mechcheck.sim_models.mujoco.settle import settle_static

__all__ = ["settle", "solve_at_pose", "sweep"]


def settle(case: Case) -> Solution:
    """The ``mujoco`` backend: settled statics, or a driven run for motion/friction.

    The harness calls it only at poses whose forces exist and are unique (the pose gate,
    :func:`mechcheck.run.gated`): elsewhere a soft model would settle to whatever its
    bending allows. A moving case is not run either where its Coulomb friction is at rest
    at the reading
    (ω = 0, α ≠ 0: :func:`~mechcheck.sim_models.coulomb.at_rest_reason`);
    measured: the run read the sense of its lead-in, 1.1e-2 off where the
    case's direction is the other one.
    """
    if case.mechanism == "linkage":
        return noting_warnings(lambda: settle_linkage(case))
    if case.kind == "static":
        return noting_warnings(lambda: settle_static(case))
    at_rest = "" if case.motion.is_static else at_rest_reason(case, case.motion.omega,
                                                              case.motion.alpha)
    if at_rest:
        return Solution(case.name, "mujoco", {}, status="indeterminate", message=at_rest,
                        diagnostics={"method": "driven"})
    return noting_warnings(lambda: driven(case))


def solve_at_pose(case: Case) -> Solution:
    """The ``mujoco_solve`` backend: exact constraint forces at the analytic pose."""
    if case.mechanism == "linkage":
        return noting_warnings(lambda: solve_linkage_at_pose(case))
    return noting_warnings(lambda: exact.solve_at_pose(case))


def sweep(case: Case, grid: ArrayLike, backend: str = "mujoco") -> list[Solution]:
    """Either backend over a sweep: θ12 (rad) of a four-bar or slider-crank
    (:func:`.sweep.sweep`), or a linkage's first driver (rad or m from the drawn pose,
    :func:`.linkage.sweep_linkage`)."""
    if case.mechanism == "linkage":
        return sweep_linkage(case, np.asarray(grid, dtype=float), backend)
    return sweeps.sweep(case, grid, backend)
