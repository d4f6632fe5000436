"""The ``mujoco_solve`` method: constraint forces at the analytic pose from MuJoCo's own
constraint Jacobian — an exactness check of the model itself (used by
:func:`mechcheck.sim_models.mujoco.linkage.exact_solution`).

With qpos, qvel, qacc set to the prescribed motion, the equations of motion
M·qacc = qfrc_smooth + Jᵀ·f hold for the true constraint forces f, where J's
rows are the loop-closing connects and the drivers' joint equalities. The rigid forces
are the least-squares solution of Jᵀ f = M·qacc − qfrc_smooth (the connect's z row is empty in a planar model,
so the minimum-norm solution leaves it zero). This is the inverse dynamics of
the closed loop; ``mj_inverse`` cannot be used, its soft inverse splits the
loop forces meaninglessly (SIMULATORS.md).

The forces are written back into MuJoCo (efc_force, qfrc_constraint, qacc)
and read the same way as after settling, through ``mj_rnePostConstraint``.
Friction couples depend on the reactions, so with friction the solve is
repeated with the couples from the previous reactions until they stop changing.
"""

from __future__ import annotations

import mujoco
import numpy as np

#: The friction fixed point stops when no reaction changes by more than this
#: fraction of the largest. Each pass contracts by about μ·r/L (≈ 0.03 on the
#: seeds), so 1e-14 is reached in ~10 passes.
FRICTION_RTOL = 1e-14
FRICTION_MAX_PASSES = 200


def impose_rigid_forces(m: mujoco.MjModel, d: mujoco.MjData, qacc: np.ndarray) -> float:
    """After a forward pass: the constraint forces f that make the motion ``qacc``
    rigid-body exact, Jᵀ f = M·qacc − qfrc_smooth (least squares; armature excluded,
    the exact model's is not the Case's), written into efc_force, qfrc_constraint and
    qacc for :func:`mujoco.mj_rnePostConstraint`. Returns the equations' residual,
    N or N·m (0 when the forces balance; a pose that is no equilibrium of its free
    coordinates leaves one)."""
    inertial = np.zeros(m.nv)
    mujoco.mj_mulM(m, d, inertial, qacc)
    inertial -= m.dof_armature * qacc
    jac = d.efc_J[:d.nefc * m.nv].reshape(d.nefc, m.nv)
    rhs = inertial - d.qfrc_smooth
    f = np.linalg.lstsq(jac.T, rhs, rcond=None)[0] if d.nefc else np.zeros(0)
    d.efc_force[:d.nefc] = f
    d.qfrc_constraint[:] = jac.T @ f
    d.qacc[:] = qacc
    return float(np.abs(jac.T @ f - rhs).max(initial=0.0))
