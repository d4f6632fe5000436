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

from mechcheck.sim_models.protocol import held_and_exact

SIMULATOR = held_and_exact("mujoco", "mechcheck.sim_models.mujoco.backend",
                           "MuJoCo, held until settled (statics) or driven (dynamics, friction)",
                           "MuJoCo's constraint forces at the exact analytic pose",
                           "mechcheck.sim_models.mujoco.softness:stiffness_study")
BACKENDS = SIMULATOR.backends
