"""MuJoCo backends, on any linkage (:mod:`.linkage`). Forces are read from MuJoCo's own
constraint state.

- :func:`settle` — backend ``mujoco``: statics by settling with the drivers held; moving
  and Coulomb-friction cases driven along their motion (:mod:`.linkage_dynamics`).
- :func:`solve_at_pose` — backend ``mujoco_solve``: exact constraint forces at the analytic
  pose from MuJoCo's constraint Jacobian (:mod:`.solve`).
- :func:`sweep` — either backend over the first driver.
- :func:`simulate` — backend ``mujoco`` on a trajectory case: the linkage moving freely on a
  ladder of time steps and integrators (:mod:`.trajectory`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from mechcheck.analytic.case import Case
from mechcheck.analytic.solution import Solution
from mechcheck.analytic.trajectory import Trajectory
from mechcheck.sim_models.linkage_motion import gated_sweep
from mechcheck.sim_models.mujoco.linkage import settle_linkage, solve_linkage_at_pose, sweep_linkage
from mechcheck.sim_models.mujoco.mjwarnings import noting_warnings
from mechcheck.sim_models.mujoco.trajectory import simulate_case

__all__ = ["settle", "simulate", "solve_at_pose", "sweep"]


def settle(case: Case) -> Solution:
    """The ``mujoco`` backend: a linkage held until settled (statics), or driven along its
    prescribed motion (moving and Coulomb-friction cases)."""
    return noting_warnings(lambda: settle_linkage(case))


def solve_at_pose(case: Case) -> Solution:
    """The ``mujoco_solve`` backend: exact constraint forces at the analytic pose."""
    return noting_warnings(lambda: solve_linkage_at_pose(case))


def sweep(case: Case, grid: ArrayLike, backend: str = "mujoco") -> list[Solution]:
    """Either backend over a sweep of a linkage's first driver (rad or m from the drawn
    pose, :func:`.linkage.sweep_linkage`), behind the pose gate
    (:func:`~mechcheck.sim_models.linkage_motion.gated_sweep`)."""
    return gated_sweep(case, np.asarray(grid, dtype=float), backend,
                       lambda values, results: sweep_linkage(case, values, backend, results))


def simulate(case: Case) -> tuple[Trajectory, ...]:
    """The ``mujoco`` backend on a trajectory case: one run per rung of its ladder of time
    steps and integrators, the finest last (:func:`.trajectory.simulate_case`)."""
    return simulate_case(case)
