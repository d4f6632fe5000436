"""The ``mujoco_solve`` backend: constraint forces at the analytic pose from
MuJoCo's own constraint Jacobian — an exactness check of the model itself.

With qpos, qvel, qacc set to the prescribed motion, the equations of motion
M·qacc = qfrc_smooth + Jᵀ·f hold for the true constraint forces f, where J's
rows are the loop connect (F34) and the drive's joint equality (the drive
torque, on link 2 or link 4). The rigid forces are the least-squares solution
of Jᵀ f = M·qacc − qfrc_smooth (the connect's z row is empty in a planar model,
so the minimum-norm solution leaves it zero). This is the inverse dynamics of
the closed loop; ``mj_inverse`` cannot be used, its soft inverse splits the
loop forces meaninglessly (SIMULATORS.md).

The forces are written back into MuJoCo (efc_force, qfrc_constraint, qacc)
and read the same way as after settling, through ``mj_rnePostConstraint``.
Friction couples depend on the reactions, so with friction the solve is
repeated with the couples from the previous reactions until they stop changing.
"""

from __future__ import annotations

import time

import mujoco
import numpy as np

from mechcheck.analytic.case import Case
from mechcheck.analytic.solution import Solution
from mechcheck.sim_models.diagnostics import RunDiagnostics
from mechcheck.sim_models.mujoco.friction import friction_loads, relative_speeds
from mechcheck.sim_models.mujoco.model import EXACT, zero_fictitious_masses
from mechcheck.sim_models.mujoco.rig import Rig

#: The friction fixed point stops when no reaction changes by more than this
#: fraction of the largest. Each pass contracts by about μ·r/L (≈ 0.03 on the
#: seeds), so 1e-14 is reached in ~10 passes.
FRICTION_RTOL = 1e-14
FRICTION_MAX_PASSES = 200


def constraint_solve(rig: Rig, qacc: np.ndarray) -> dict[str, float]:
    """Solve Jᵀ f = M·qacc − qfrc_smooth at the current qpos/qvel and read the forces."""
    m, d = rig.model, rig.data
    mujoco.mj_kinematics(m, d)  # load points and centres of mass for the loads
    mujoco.mj_comPos(m, d)
    rig.apply_loads()
    mujoco.mj_forward(m, d)
    full_qacc = np.zeros(m.nv)
    full_qacc[rig.joint_addresses()] = qacc
    impose_rigid_forces(m, d, full_qacc)
    return rig.read()


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


def friction_senses(rig: Rig, case: Case) -> dict[str, float]:
    """Relative speeds whose signs friction opposes at the case's own pose: the
    prescribed motion, or a unit quasi-static motion in friction.direction when
    the case is static. (A sweep reuses one rig for many poses, so the pose must
    come from ``case``, not from the case the rig was built for.)"""
    omega = case.motion.omega if case.motion.omega else float(case.input_sense)
    _, qvel, _ = rig.qpos_at(case.theta12, omega=omega, alpha=0.0)
    return relative_speeds(rig, qvel)


def solve_with_friction(rig: Rig, case: Case, qvel: np.ndarray,
                        qacc: np.ndarray) -> tuple[dict[str, float], int]:
    """Fixed point: friction couples from the reactions, reactions from the couples."""
    senses = friction_senses(rig, case)
    speeds = relative_speeds(rig, qvel)
    values = constraint_solve(rig, qacc)
    for passes in range(1, FRICTION_MAX_PASSES + 1):
        rig.set_extra(*friction_loads(rig, values, senses, speeds))
        new = constraint_solve(rig, qacc)
        change = max(abs(new[q] - values[q]) for q in new)
        size = max(abs(v) for q, v in new.items() if q[0] in "FTM")
        values = new
        if change <= FRICTION_RTOL * size:
            return values, passes
    return values, FRICTION_MAX_PASSES


def exact_rig(case: Case) -> Rig:
    """A rig for the exact solve: the Case's own masses, massless links massless."""
    rig = Rig(case, EXACT)
    zero_fictitious_masses(case, rig.model, rig.layout)
    return rig


def solve_at_pose(case: Case, rig: Rig | None = None) -> Solution:
    """The ``mujoco_solve`` backend: exact constraint forces at the analytic pose.

    ``rig`` (from :func:`exact_rig` of a case differing only in θ12) is reused by sweeps.
    """
    start = time.perf_counter()
    rig = rig or exact_rig(case)
    qpos, qvel, qacc = rig.qpos_at(case.theta12)
    return solve_state(case, rig, qpos, qvel, qacc, start)


def solve_state(case: Case, rig: Rig, qpos: np.ndarray, qvel: np.ndarray, qacc: np.ndarray,
                start: float) -> Solution:
    """The exact solve at a given (analytic) joint state; ``start`` times it."""
    rig.set_extra(np.zeros(rig.model.nbody), np.zeros((rig.model.nbody, 3)))
    rig.set_state(qpos, qvel)
    rig.set_lock(qpos[0] if case.drive_link == 2 else qpos[2])
    passes = 0
    if case.has_friction:
        values, passes = solve_with_friction(rig, case, qvel, qacc)
    else:
        values = constraint_solve(rig, qacc)
    # At the analytic pose and velocities by construction: nothing left to move or drift.
    diagnostics = RunDiagnostics("constraint_solve", passes, time.perf_counter() - start,
                                 0.0, rig.loop_violation(), 0.0).as_dict()
    return Solution(case.name, "mujoco_solve", values, diagnostics=diagnostics)
