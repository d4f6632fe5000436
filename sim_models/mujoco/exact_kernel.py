"""The per-pose loops of ``mujoco_solve``'s batch (:func:`.linkage.exact_sweep`) in numba
(imported through :func:`mechcheck.sim_models.compiled.kernel` only where numba is
installed: the ``fast`` extra).

Pose for pose they do what the Python loops do (:meth:`.linkage_rig.LinkageRig.load_points`,
:func:`.linkage.constraint_equations`, :func:`.linkage.post_constraint`): the same arrays
written into the same MjData, the same MuJoCo functions called (through their C function
pointers, :mod:`.exact_compiled`), the same arrays copied out. Only the interpreter's
per-pose overhead is gone. ``d_*`` arguments are views of the MjData's own arrays.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numba import njit

Array = np.ndarray
Fn = Callable[[int, int], None]


@njit(cache=True)
def load_points(kinematics: Fn, m: int, d: int, qpos: Array, d_qpos: Array,
                d_sites: Array, d_centres: Array, sites: Array, centres: Array) -> None:
    """Each pose's site_xpos and xipos (rows of ``sites``, ``centres``) after mj_kinematics."""
    for i in range(qpos.shape[0]):
        d_qpos[:] = qpos[i]
        kinematics(m, d)
        sites[i] = d_sites
        centres[i] = d_centres


@njit(cache=True)
def equations(forward: Fn, mul_m: Any, m: int, d: int, qpos: Array, qvel: Array,
              qacc: Array, columns: Array, loads: Array, d_qpos: Array, d_qvel: Array,
              held: Array, d_xfrc: Array, d_jac: Array, d_pos: Array, d_smooth: Array,
              jac: Array, efc_pos: Array, smooth: Array, inertial: Array, rolling: bool,
              moving: bool) -> None:
    """Each pose's forward pass: its Jacobian, efc_pos, qfrc_smooth (and M·qacc)."""
    for i in range(qpos.shape[0]):
        d_qpos[:] = qpos[i]
        if rolling:
            d_qvel[:] = qvel[i]
        held[:] = columns[i]
        d_xfrc[:] = loads[i]
        forward(m, d)
        jac[i] = d_jac
        efc_pos[i] = d_pos
        smooth[i] = d_smooth
        if moving:
            mul_m(m, d, inertial[i].ctypes.data, qacc[i].ctypes.data)


@njit(cache=True)
def post(forward: Fn, kinematics: Fn, com_pos: Fn, com_vel: Fn, rne: Fn, m: int, d: int,
         qpos: Array, qvel: Array, qacc: Array, loads: Array, forces: Array, d_qpos: Array,
         d_qvel: Array, d_qacc: Array, d_xfrc: Array, d_force: Array, targets: Any,
         sources: Any, rolling: bool, tendons: bool, steady: bool) -> None:
    """Each pose's mj_rnePostConstraint with its constraint forces imposed; the ``sources``
    (flat views) copied into row i of ``targets``."""
    d_qacc[:] = 0.0
    for i in range(qpos.shape[0]):
        d_qpos[:] = qpos[i]
        if rolling:
            d_qvel[:] = qvel[i]
        d_xfrc[:] = loads[i]
        if tendons:
            forward(m, d)
        else:
            kinematics(m, d)
            com_pos(m, d)
            com_vel(m, d)
        d_force[:] = forces[i]
        if not steady:
            d_qacc[:] = qacc[i]
        rne(m, d)
        for k in range(len(targets)):
            targets[k][i] = sources[k]


@njit(cache=True)
def reads(set_state: Any, forward: Fn, rne: Fn, m: int, d: int, states: Array, spec: int,
          eq_data: Array, driver_eqs: Array, targets: Array, xfrc: Array, d_xfrc: Array,
          d_qfrc: Array, drive_dofs: Array, drives: Array, carried: Array, d_force: Array,
          d_pos: Array, out_force: Array, out_pos: Array, outs: Any, sources: Any) -> None:
    """:meth:`.batch_settle.BatchSettler.read`'s loop: each state set (``spec``), its drivers'
    targets, loads and drive forces, a forward pass and mj_rnePostConstraint; the captured
    arrays (:meth:`.linkage_rig.LinkageRig.capture`) copied into row k."""
    nefc = carried.size
    for k in range(states.shape[0]):
        set_state(m, d, states[k].ctypes.data, spec)
        for j in range(driver_eqs.size):
            eq_data[driver_eqs[j], 0] = targets[k, j]
        d_xfrc[:] = xfrc[k]
        for j in range(drive_dofs.size):
            d_qfrc[drive_dofs[j]] = drives[k, j]
        forward(m, d)
        rne(m, d)
        for i in range(len(outs)):
            outs[i][k] = sources[i]
        out_force[k] = d_force
        out_pos[k] = d_pos
        for j in range(nefc):
            out_force[k, j] += carried[j]
