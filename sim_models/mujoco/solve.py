"""The ``mujoco_solve`` method: constraint forces at the analytic pose from MuJoCo's own
constraint Jacobian — an exactness check of the model itself (used by
:func:`mechcheck.sim_models.mujoco.linkage.exact_solution`).

With qpos, qvel, qacc set to the prescribed motion, the equations of motion
M·qacc = qfrc_smooth + Jᵀ·f hold for the true constraint forces f, where J's
rows are the loop-closing connects and the drivers' joint equalities. The rigid forces
are the least-squares solution of Jᵀ f = M·qacc − qfrc_smooth (the connect's z row is empty in a planar model,
so the minimum-norm solution leaves it zero). Without the empty rows Jᵀ is square at a
held pose, and solved directly (`lstsq` costs 30× more than the rest of the solve for
these 3×3 to 9×9 systems); least squares only where it is not square or is singular.
This is the inverse dynamics of the closed loop; ``mj_inverse`` cannot be used, its soft inverse splits the
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
    f = rigid_forces(jac, rhs)
    d.efc_force[:d.nefc] = f
    d.qfrc_constraint[:] = jac.T @ f
    d.qacc[:] = qacc
    return float(np.abs(jac.T @ f - rhs).max(initial=0.0))


def rigid_forces(jac: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """The minimum-norm least-squares f of Jᵀ f = rhs: rows of J that are empty (a
    connect's z row in a planar model) get 0, and the rest is solved directly when it is
    square and regular."""
    f = np.zeros(jac.shape[0])
    rows = np.flatnonzero(np.any(jac, axis=1))
    if rows.size == jac.shape[1]:
        try:
            f[rows] = np.linalg.solve(jac[rows].T, rhs)
            return f
        except np.linalg.LinAlgError:
            pass
    if rows.size:
        f[rows] = np.linalg.lstsq(jac[rows].T, rhs, rcond=None)[0]
    return f


def batch_rigid_forces(jac: np.ndarray, rhs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`rigid_forces` of N systems at once (``jac`` (N, nefc, nv), ``rhs`` (N, nv)),
    and each one's residual max|Jᵀ f − rhs|. The rows empty at every pose are left out;
    when the rest is square the stack is solved in one call, otherwise (or if one pose is
    singular) pose by pose."""
    forces = np.zeros(jac.shape[:2])
    rows = np.flatnonzero(np.any(jac, axis=(0, 2)))
    square = jac[:, rows].transpose(0, 2, 1)
    try:
        if rows.size != jac.shape[2]:
            raise np.linalg.LinAlgError("not square")
        forces[:, rows] = np.linalg.solve(square, rhs[..., None])[..., 0]
    except np.linalg.LinAlgError:
        forces = np.array([rigid_forces(j, r) for j, r in zip(jac, rhs, strict=True)])
    residual = np.abs(np.einsum("nij,ni->nj", jac, forces) - rhs).max(axis=1, initial=0.0)
    return forces, residual
