"""MuJoCo backends: the mechanism held or driven in MuJoCo, forces read from MuJoCo's own
constraint state (:mod:`.backend`).

- ``mujoco``: statics by settling with the drivers held; moving and friction cases driven
  through their prescribed motion;
- ``mujoco_solve``: exact constraint forces at the analytic pose from MuJoCo's constraint
  Jacobian.

Nothing here imports MuJoCo, so that listing the backends stays light: the functions
(``settle``, ``solve_at_pose``, ``sweep``) are in :mod:`.backend`.
"""

from __future__ import annotations

from mechcheck.analytic.contract import Backend
from mechcheck.sim_models.protocol import Simulator

_HERE = "mechcheck.sim_models.mujoco.backend"

BACKENDS = (
    Backend("mujoco", f"{_HERE}:settle", "settled",
            "MuJoCo, held until settled (statics) or driven (dynamics, friction)",
            sweep=f"{_HERE}:sweep", requires="mujoco"),
    Backend("mujoco_solve", f"{_HERE}:solve_at_pose", "exact_solve",
            "MuJoCo's constraint forces at the exact analytic pose",
            sweep=f"{_HERE}:sweep", requires="mujoco"),
)

SIMULATOR = Simulator("mujoco", BACKENDS, "mechcheck.sim_models.mujoco.softness:stiffness_study",
                      requires="mujoco")
