"""The per-pose loops of ``mujoco_solve``'s batch (:func:`..linkage.exact_sweep`) and of a
settled sweep's reads (:meth:`..batch_settle.BatchSettler.read`) in numba (imported through
:func:`mechcheck.sim_models.compiled.kernel` only where numba is installed: the ``fast``
extra).

Pose for pose they do what the Python loops do (:meth:`..linkage_loads.RigLoads.load_points`,
:func:`..linkage.constraint_equations`, :func:`..linkage.post_constraint`, the read): the
same arrays written into the same MjData, the same MuJoCo functions called (through their
C function pointers, :mod:`.pointers`), the same arrays copied out. Only the interpreter's
per-pose overhead is gone.
"""

from __future__ import annotations

from numba import njit

from mechcheck.sim_models.mujoco._fast.plans import (
    Capture,
    EquationsPlan,
    MjCalls,
    PointsPlan,
    PostPlan,
    ReadsPlan,
)


@njit(cache=True)
def load_points(mj: MjCalls, p: PointsPlan) -> None:
    """Each pose's site_xpos and xipos (rows of ``p.sites``, ``p.centres``) after mj_kinematics."""
    for i in range(p.qpos.shape[0]):
        p.d_qpos[:] = p.qpos[i]
        mj.kinematics(mj.m, mj.d)
        p.sites[i] = p.d_sites
        p.centres[i] = p.d_centres


@njit(cache=True)
def equations(mj: MjCalls, p: EquationsPlan) -> None:
    """Each pose's forward pass: its Jacobian, efc_pos, qfrc_smooth (and M·qacc)."""
    for i in range(p.qpos.shape[0]):
        p.d_qpos[:] = p.qpos[i]
        if p.rolling:
            p.d_qvel[:] = p.qvel[i]
        p.held[:] = p.columns[i]
        p.d_xfrc[:] = p.loads[i]
        mj.forward(mj.m, mj.d)
        p.jac[i] = p.d_jac
        p.efc_pos[i] = p.d_pos
        p.smooth[i] = p.d_smooth
        if p.moving:
            mj.mul_m(mj.m, mj.d, p.inertial[i].ctypes.data, p.qacc[i].ctypes.data)


@njit(cache=True)
def post(mj: MjCalls, p: PostPlan) -> None:
    """Each pose's mj_rnePostConstraint with its constraint forces imposed; the ``sources``
    (flat views) copied into row i of ``targets``."""
    p.d_qacc[:] = 0.0
    for i in range(p.qpos.shape[0]):
        p.d_qpos[:] = p.qpos[i]
        if p.rolling:
            p.d_qvel[:] = p.qvel[i]
        p.d_xfrc[:] = p.loads[i]
        if p.tendons:
            mj.forward(mj.m, mj.d)
        else:
            mj.kinematics(mj.m, mj.d)
            mj.com_pos(mj.m, mj.d)
            mj.com_vel(mj.m, mj.d)
        p.d_force[:] = p.forces[i]
        if not p.steady:
            p.d_qacc[:] = p.qacc[i]
        mj.rne(mj.m, mj.d)
        for k in range(len(p.targets)):
            p.targets[k][i] = p.sources[k]


@njit(cache=True)
def reads(mj: MjCalls, p: ReadsPlan) -> None:
    """The settled reads: each state set (``spec``), its drivers' targets, loads and drive
    forces, a forward pass and mj_rnePostConstraint; the captured arrays copied into row k,
    the equality forces with the carried ones added."""
    for k in range(p.states.shape[0]):
        mj.set_state(mj.m, mj.d, p.states[k].ctypes.data, p.spec)
        for j in range(p.driver_eqs.size):
            p.eq_data[p.driver_eqs[j], 0] = p.targets[k, j]
        p.d_xfrc[:] = p.xfrc[k]
        for j in range(p.drive_dofs.size):
            p.d_qfrc[p.drive_dofs[j]] = p.drives[k, j]
        mj.forward(mj.m, mj.d)
        mj.rne(mj.m, mj.d)
        capture(p.capture, k)


@njit(cache=True)
def capture(c: Capture, k: int) -> None:
    """The captured arrays copied into row k, the equality forces with the carried ones
    added."""
    for i in range(len(c.outs)):
        c.outs[i][k] = c.sources[i]
    c.out_force[k] = c.d_force
    c.out_pos[k] = c.d_pos
    for j in range(c.carried.size):
        c.out_force[k, j] += c.carried[j]
