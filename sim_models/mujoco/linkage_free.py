"""Free coordinates of a static linkage (fewer drivers than degrees of freedom) settled to
their equilibrium under MuJoCo's own dynamics (issue 12).

The analytic side seeds nothing but the start: the drawn pose (``qpos = 0``), or a pose
the caller gives, and the drivers' held values. From there MuJoCo moves the linkage under
its loads, weights and springs, with viscous damping on every joint that no driver holds,
until it is at rest; the forces are read at rest, where the dampers exert nothing, so they
change the path to the equilibrium and never the equilibrium. Where it came to rest is
reported in the pose quantities.

Damping and time step come from MuJoCo's own model at the start pose, never from the
answer: each free joint's stiffness K_j is the curvature of the potential that MuJoCo's
forces give (a central difference of ``qfrc_smooth`` — springs, loads, weights — in that
joint alone), its inertia M_jj the diagonal of MuJoCo's mass matrix; the damper is
:data:`DAMPING_RATIO` × critical for that uncoupled mode, 2·√(K_j·M_jj), and the time step
resolves the fastest uncoupled mode with :data:`STEPS_PER_PERIOD` steps.

Settling and its stop rules are :mod:`.settle`'s (the refinement passes carry the
constraint forces and go on from where the last pass stopped), watched on every force the
reading reports: the constraint forces, the springs' tensions and the tree joints'
reactions (a linkage with no loop and no driver, like exam Q1, has no constraint force).

An equilibrium the analytic side finds unstable cannot be reached by settling (any
disturbance leaves it): such a case gets a verdict, not a number.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace

import mujoco
import numpy as np

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage_backends import quantity_units
from mechcheck.analytic.linkage_forces import LinkageResults
from mechcheck.analytic.solution import FORCE_FLOOR_N, Solution
from mechcheck.sim_models.mujoco.linkage_rig import Array, LinkageRig
from mechcheck.sim_models.mujoco.settle import settle_refined, settled_solution

#: Damping ratio of each free joint's damper (1 = critical for its uncoupled mode).
DAMPING_RATIO = 1.0
#: Time steps per period of the fastest uncoupled mode (as exam Q1's model).
STEPS_PER_PERIOD = 60.0
#: A joint's stiffness is taken as at least this fraction of the largest: a joint at
#: a pose where the potential is flat (or curves down) still gets a damper.
STIFFNESS_FLOOR_FRACTION = 1e-2
#: Finite-difference step of the stiffness, as a fraction of the scale (hinges: rad).
STIFFNESS_STEP = 1e-6
#: Step budget of each settling pass (the first moves the linkage to its equilibrium).
FREE_MAX_STEPS = 30_000

UNSTABLE = ("the equilibrium pose of the free coordinates is unstable (analytic: stable = "
            "no): settling moves away from it, so the mujoco backend cannot find it")


class FreeLinkageRig(LinkageRig):
    """A :class:`LinkageRig` whose stop rule watches every reported force (see the
    module doc)."""

    def constraint_forces(self) -> Array:
        m, d = self.model, self.data
        mujoco.mj_rnePostConstraint(m, d)
        moving = d.cfrc_int[1:]
        return np.concatenate([super().constraint_forces(), self.spring_tensions(),
                               moving[:, 3:5].ravel(), moving[:, 2] / self.scale])


def free_joints(rig: LinkageRig) -> np.ndarray:
    """The dof addresses of the tree joints no driver holds (a pin in a slot's turn is
    never held)."""
    held = set(rig.drive_rows)
    return np.array([dof for j, joints in rig.mj_joints.items() for mj, dof in joints
                     if not (mj.coordinate and j in held)], dtype=int)


def generalised_loads(rig: LinkageRig, qpos: Array) -> Array:
    """MuJoCo's smooth generalised forces at rest in ``qpos`` (springs, loads, weights)."""
    m, d = rig.model, rig.data
    d.qpos[:] = qpos
    d.qvel[:] = 0.0
    mujoco.mj_kinematics(m, d)
    mujoco.mj_comPos(m, d)
    rig.apply_loads()
    mujoco.mj_forward(m, d)
    return d.qfrc_smooth.copy()


def stiffnesses(rig: LinkageRig, qpos: Array, dofs: np.ndarray) -> Array:
    """Each joint's own stiffness −∂Q_j/∂q_j at ``qpos`` (central difference), floored
    at :data:`STIFFNESS_FLOOR_FRACTION` of the largest (never zero)."""
    out = np.zeros(dofs.size)
    for k, dof in enumerate(dofs):
        h = STIFFNESS_STEP * (1.0 if rig.hinge[rig.model.dof_jntid[dof]] else rig.scale)
        step = np.zeros_like(qpos)
        step[dof] = h
        plus, minus = generalised_loads(rig, qpos + step), generalised_loads(rig, qpos - step)
        out[k] = abs(plus[dof] - minus[dof]) / (2.0 * h)
    largest = float(out.max(initial=0.0))
    # An unloaded linkage has no stiffness: a unit force per unit length sets the pace.
    floor = STIFFNESS_FLOOR_FRACTION * largest if largest > 0.0 else FORCE_FLOOR_N
    return np.maximum(out, floor)


def tune(rig: LinkageRig, qpos: Array) -> None:
    """Dampers on the free joints and the time step, from MuJoCo's model at ``qpos``."""
    m, d = rig.model, rig.data
    dofs = free_joints(rig)
    if dofs.size == 0:
        return
    k = stiffnesses(rig, qpos, dofs)
    full = np.zeros((m.nv, m.nv))
    d.qpos[:] = qpos
    mujoco.mj_forward(m, d)
    mujoco.mj_fullM(m, d, full)
    inertia = np.diag(full)[dofs]
    m.dof_damping[dofs] = m.dof_damping[dofs] + 2.0 * DAMPING_RATIO * np.sqrt(k * inertia)
    fastest = float(np.sqrt(k / inertia).max())
    rig.set_timestep(2.0 * math.pi / (STEPS_PER_PERIOD * fastest))


def settle_free(case: Case, results: LinkageResults, start: dict[str, float] | None = None,
                rig: LinkageRig | None = None) -> Solution:
    """The ``mujoco`` backend for a static linkage with free coordinates, started at rest
    with the joint coordinates ``start`` (joint name → rad or m from the drawn pose; the
    others, and by default all, at the drawn pose) and the drivers held."""
    tic = time.perf_counter()
    if results.stable is not None and results.stable[0] == 0.0:
        return Solution(case.name, "mujoco", {}, status="not_applicable", message=UNSTABLE,
                        units=quantity_units(case.linkage))
    rig = rig or FreeLinkageRig(case)
    qpos = np.zeros(rig.model.nq)
    for joint, value in (start or {}).items():
        qpos[rig.dof[joint]] = value  # a tree joint's qpos is its coordinate
    mujoco.mj_resetData(rig.model, rig.data)
    rig.set_targets(np.array([d.value for d in case.linkage.drivers]))
    rig.reset_carried()
    tune(rig, qpos)
    rig.set_state(qpos, np.zeros_like(qpos))

    def restart() -> None:  # go on from where the last pass came to rest
        rig.data.qvel[:] = 0.0

    result = settle_refined(rig, qpos, restart=restart, max_steps=FREE_MAX_STEPS)
    out = settled_solution(rig, qpos, result, time.perf_counter() - tic)
    # Settled as any static case (method "settle"); the free coordinates found their own rest.
    diagnostics = {**out.diagnostics, "free_coordinates": "settled from the drawn pose",
                   "timestep": float(rig.model.opt.timestep)}
    return replace(out, diagnostics=diagnostics)
