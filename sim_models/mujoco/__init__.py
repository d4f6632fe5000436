"""MuJoCo backends (issue 3): the mechanism held or driven in MuJoCo, forces
read from MuJoCo's own constraint state.

- :func:`settle` — backend ``mujoco``: statics by settling with the crank
  locked; moving and friction cases by driving the input (``driven``).
- :func:`solve_at_pose` — backend ``mujoco_solve``: exact constraint forces at
  the analytic pose from MuJoCo's constraint Jacobian.
- :func:`sweep` — either backend over an array of θ12.
"""

from __future__ import annotations

from analytic.case import Case
from analytic.equilibrium import condition
from analytic.kinematics import pose_of
from analytic.solution import Solution
from sim_models.mujoco.dynamics import driven
from sim_models.mujoco.settle import settle_static
from sim_models.mujoco.solve import solve_at_pose
from sim_models.mujoco.sweep import SWEEP_SINGULAR_CONDITION, singular_solution, sweep

__all__ = ["settle", "solve_at_pose", "sweep"]


def settle(case: Case) -> Solution:
    """The ``mujoco`` backend: settled statics, or a driven run for motion/friction.

    A pose at a change point (condition number beyond the line the analytic
    backend and :func:`sweep` withhold forces at) is not simulated: its forces
    do not exist, and a soft model would settle to whatever its bending allows.
    """
    cond = float(condition(case, pose_of(case))[0])
    if not cond <= SWEEP_SINGULAR_CONDITION:
        return singular_solution(case, "mujoco", cond)
    if case.kind == "static":
        return settle_static(case)
    return driven(case)
