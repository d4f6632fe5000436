"""A linkage's compiled model and data, and where everything is in them: the bodies,
joints, sites and equalities by name, the constraint rows of each equality, each link's
rotation in qpos, the weights that make joint speeds point speeds. The pose is set here
(joint states, drivers' targets); loads go in through :mod:`.linkage_loads` and forces come
out through :mod:`.linkage_readout` (:class:`.linkage_rig.LinkageRig` is all three).
"""

from __future__ import annotations

from collections.abc import Callable

import mujoco
import numpy as np
from numpy.typing import NDArray

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage import Joint, LinearSpring
from mechcheck.analytic.linkage_backends import quantity_units
from mechcheck.analytic.linkage_kinematics import LinkagePose
from mechcheck.analytic.values import GROUND
from mechcheck.sim_models.mujoco.joint_kinds import MjJoint, builder_of
from mechcheck.sim_models.mujoco.linkage_members import (
    member_ends,
    set_member_stiffness,
    split_members,
    stretch_excess_along,
)
from mechcheck.sim_models.mujoco.linkage_mesh import MeshLine, mesh_of, site_names, tendon_name
from mechcheck.sim_models.mujoco.linkage_model import (
    CLOCK,
    LinkageTree,
    TreeJoint,
    body_name,
    build_spec,
    closure_sites,
    joint_damping,
    local,
    origin_of,
    spanning_tree,
)
from mechcheck.sim_models.mujoco.model import STATIC, Settings, place_frames_exactly
from mechcheck.sim_models.mujoco.settle import rounding_floor

Array = NDArray[np.float64]


def mj_joint_state(pose: LinkagePose, t: TreeJoint, mj: MjJoint) -> tuple[Array, Array, Array]:
    """qpos, qvel, qacc of one MuJoCo joint of tree joint ``t`` at an analytic pose: the
    joint's coordinate, or a free turn's rotation of the child relative to the parent."""
    if mj.coordinate:
        return pose.joint_coordinate(t.joint)
    child, parent = pose.angle(t.child), pose.angle(t.parent)
    turn = [(c - p) / mj.turn for c, p in zip(child, parent, strict=True)]
    return turn[0], turn[1], turn[2]


class RigModel:
    """One linkage Case's compiled model and data, with the index maps into them."""

    def __init__(self, case: Case, settings: Settings = STATIC,
                 customize: Callable[[mujoco.MjSpec], None] | None = None) -> None:
        """``customize`` edits the spec before it is compiled (the servo models of
        ``tests/turning/``)."""
        self.case = case
        self.settings = settings
        self.linkage = linkage = case.linkage
        self.tree: LinkageTree = spanning_tree(linkage)
        self.tree_joints = {t.joint.name: t for t in self.tree.tree}
        spec = build_spec(case.name, linkage, settings)
        if customize is not None:
            customize(spec)
        self.model = spec.compile()
        place_frames_exactly(self.model)
        #: The split members (:mod:`.linkage_members`) and their equalities, whose soft
        #: stiffness is E·A/L: a spring, not a constraint to hold rigidly.
        self.members = split_members(linkage)
        self.member_eqs = np.array(set_member_stiffness(self.model, self.members), dtype=int)
        self.rigid_eqs = np.setdiff1d(np.arange(self.model.neq), self.member_eqs)
        #: Each split member's near and far end (drawn), by name.
        self.member_ends = {m.name: member_ends(m, self.tree.parent_joint(m.name).joint.at,
                                                linkage.points) for m in self.members}
        #: What each split member's equality force exceeds its N by (its own loads).
        self.member_excess = np.array([stretch_excess_along(linkage, m) for m in self.members])
        self.data = mujoco.MjData(self.model)
        self.scale = linkage.scale
        self.units: dict[str, str] | None = quantity_units(linkage)
        self.moving_links = tuple(linkage.moving_links)  # looked up at every driven step
        self._name_maps()
        self.rotation = self._rotations()
        mujoco.mj_forward(self.model, self.data)
        self.nefc = int(self.data.nefc)  # constant: equalities only, no contacts or limits
        self._constraint_rows()
        self._weights()
        #: Constraint forces carried as loads (:mod:`.linkage_loads`), part of every force
        #: read.
        self.carried = np.zeros(self.nefc)
        #: Friction emulated from the reactions (:mod:`.linkage_friction`): xfrc_applied
        #: added to the loads, and each prismatic joint's friction force along its axis,
        #: which is part of its reported reaction.
        self.extra = np.zeros((self.model.nbody, 6))
        self.sliding: dict[str, float] = {}
        self.viscous = True
        #: Dampers on loop-closing joints (no MuJoCo joint to damp): couples −c·q̇ from
        #: MuJoCo's own joint rates, applied with the loads.
        self.closure_damping = {j.name: c for j in self.tree.closures
                                if (c := joint_damping(linkage, j)) > 0.0}
        self.phi_names = tuple(f"phi_{link}" for link in linkage.moving_links)
        self.origins = {link: origin_of(self.tree, linkage, link)
                        for link in (GROUND, *self.moving_links)}

    def _name_maps(self) -> None:
        """The bodies, tree joints' dofs, equalities and sites of the linkage's parts."""
        m, linkage = self.model, self.linkage
        obj = mujoco.mjtObj
        self.body = {GROUND: 0} | {link: self._id(obj.mjOBJ_BODY, body_name(link))
                                   for link in linkage.moving_links}
        self.dof = {t.joint.name: int(m.jnt_dofadr[self._id(obj.mjOBJ_JOINT, t.joint.name)])
                    for t in self.tree.tree}
        #: Each tree joint's MuJoCo joints (:mod:`.joint_kinds`) with their dof addresses:
        #: its coordinate's (``dof``) and, for a pin in a slot, its free turn's.
        self.mj_joints = {t.joint.name: self._joint_dofs(t) for t in self.tree.tree}
        self.hinge = np.array([m.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE
                               for j in range(m.njnt)])
        self.springs = [s for s in linkage.springs if isinstance(s, LinearSpring)]
        self.loop_eq = {j.name: self._id(obj.mjOBJ_EQUALITY, f"loop_{j.name}")
                        for j in self.tree.closures}
        self.drive_eq = {d.joint: self._id(obj.mjOBJ_EQUALITY, f"drive_{d.joint}")
                         for d in linkage.drivers}
        self.driver_eqs = np.array([self.drive_eq[d.joint] for d in linkage.drivers], dtype=int)
        self.loop_sites = {j.name: tuple(self._id(obj.mjOBJ_SITE, s) for s in closure_sites(j))
                           for j in self.tree.closures}
        self.point_sites = {p: self._id(obj.mjOBJ_SITE, f"point_{p}") for p in linkage.points}
        self.meshes = [self._mesh_line(j) for j in self.tree.meshes]

    def _mesh_line(self, joint: Joint) -> MeshLine:
        """A gear mesh's tendon, equality, sites and the gears' bodies and centres."""
        obj = mujoco.mjtObj
        links = joint.links
        centres = tuple(np.array([*local(self.tree, self.linkage, link, self.linkage.points[c])])
                        for link, c in zip(links, mesh_of(joint).centres, strict=True))
        ca, cb = (self.linkage.points[c] for c in mesh_of(joint).centres)
        return MeshLine(joint, self._id(obj.mjOBJ_EQUALITY, tendon_name(joint)),
                        self._id(obj.mjOBJ_TENDON, tendon_name(joint)),
                        (self._id(obj.mjOBJ_SITE, site_names(joint)[0]),
                         self._id(obj.mjOBJ_SITE, site_names(joint)[1])),
                        (self.body[links[0]], self.body[links[1]]), (centres[0], centres[1]),
                        np.subtract(cb, ca))

    def _joint_dofs(self, t: TreeJoint) -> tuple[tuple[MjJoint, int], ...]:
        """The MuJoCo joints of tree joint ``t``, each with its dof address."""
        return tuple((mj, int(self.model.jnt_dofadr[self._id(mujoco.mjtObj.mjOBJ_JOINT, mj.name)]))
                     for mj in builder_of(t.joint).joints(t.joint, t.sign))

    def _rotations(self) -> Array:
        """Each moving link's rotation as the signed sum of the hinges on its path from the
        ground (slides do not turn): phi = rotation @ qpos."""
        rotation = np.zeros((len(self.moving_links), self.model.nq))
        for k, link in enumerate(self.moving_links):
            while link != GROUND:
                t = self.tree.parent_joint(link)
                for mj, dof in self.mj_joints[t.joint.name]:
                    if mj.turn:
                        rotation[k, dof] = mj.turn
                link = t.parent
        return rotation

    def _constraint_rows(self) -> None:
        """Each equality's constraint rows (after a forward pass), the drivers' among them,
        and what scales their torques to forces."""
        self.loop_rows = {j: self.equality_rows(e) for j, e in self.loop_eq.items()}
        self.member_rows = np.array([self.equality_rows(e)[0] for e in self.member_eqs],
                                    dtype=int)
        self.mesh_rows = np.array([self.equality_rows(mesh.equality)[0] for mesh in self.meshes],
                                  dtype=int)
        # A switched-off driver (a servo model, ``customize``) has no constraint rows.
        self.drive_rows = {j: rows for j, e in self.drive_eq.items()
                           if (rows := self.equality_rows(e)).size}
        self.efc_scale = np.ones(self.nefc)
        for name, rows in self.drive_rows.items():
            joint = self.linkage.joint(name)
            if builder_of(joint).coordinate_is_angle(joint):
                self.efc_scale[rows] = 1.0 / self.scale  # torques as forces, for the stop rule
        self.drive_dofs = np.array([self.dof[j] for j in self.drive_rows], dtype=int)
        self.drive_first_rows = np.array([rows[0] for rows in self.drive_rows.values()],
                                         dtype=int)
        # A driven run's extra armature on each driven joint, subtracted from its effort.
        self.drive_armature = {j: float(self.model.dof_armature[self.dof[j]])
                               - self.settings.armature for j in self.drive_rows}

    def _weights(self) -> None:
        """The rounding floor, and joint speeds and pose errors as point speeds and lengths."""
        m = self.model
        #: The spread of forces the positions' rounding makes at rest (N, the settling's
        #: absolute allowance), from the model at the drawn pose: its sites' largest
        #: coordinate sets the grid they sit on.
        extent = max(self.scale, float(np.abs(self.data.site_xpos[:, :2]).max(initial=0.0)))
        self.rounding = rounding_floor(float(m.body_mass.max()), extent, self.settings.timestep)
        # Hinges times the size.
        self.weight = np.where(self.hinge[m.dof_jntid], self.scale, 1.0)
        clock = int(mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, CLOCK))
        self.clock: int | None = int(m.jnt_dofadr[clock]) if clock >= 0 else None
        if self.clock is not None:
            self.weight[self.clock] = 0.0  # the clock is time, not the mechanism

    def _id(self, kind: mujoco.mjtObj, name: str) -> int:
        found = int(mujoco.mj_name2id(self.model, kind, name))
        assert found >= 0, name
        return found

    def equality_rows(self, eq_id: int) -> NDArray[np.int_]:
        d = self.data
        return np.flatnonzero((d.efc_type[:d.nefc] == mujoco.mjtConstraint.mjCNSTR_EQUALITY)
                              & (d.efc_id[:d.nefc] == eq_id))

    # -- pose -------------------------------------------------------------------------
    def joint_states(self, pose: LinkagePose) -> tuple[Array, Array, Array]:
        """qpos, qvel, qacc (N, nq) of the tree joints from an analytic pose: used only to
        seed or prescribe the motion, never to read forces."""
        n = pose.q.shape[0]
        out = [np.zeros((n, self.model.nq)) for _ in range(3)]
        for t in self.tree.tree:
            for mj, dof in self.mj_joints[t.joint.name]:
                for array, value in zip(out, mj_joint_state(pose, t, mj), strict=True):
                    array[:, dof] = value
        return out[0], out[1], out[2]

    def set_state(self, qpos: Array, qvel: Array) -> None:
        """Put the model in a state (a seed): the gear meshes are held where they are."""
        self.data.qpos[:] = qpos
        self.data.qvel[:] = qvel
        if self.meshes:
            mujoco.mj_kinematics(self.model, self.data)
            self.aim_meshes(hold=True)

    def aim_meshes(self, hold: bool = False) -> None:
        """Every gear mesh's tendon on its current line of action (after MuJoCo's
        kinematics; :meth:`.linkage_mesh.MeshLine.aim`)."""
        for mesh in self.meshes:
            mesh.aim(self.model, self.data, hold)

    def joint_rates(self, qvel: Array) -> dict[str, float]:
        """Every joint's coordinate rate q̇ (LINKAGES.md) from joint velocities."""
        omega = dict(zip(self.moving_links, self.rotation @ qvel, strict=True))
        omega[GROUND] = 0.0
        return {j.name: float(qvel[self.dof[j.name]]) if j.name in self.dof
                else float(omega[j.links[1]] - omega[j.links[0]]) for j in self.linkage.joints}

    def set_timestep(self, dt: float) -> None:
        """Change the time step, with the constraints' time constant (as
        MuJoCo's stiffest 2·dt unless the settings fix it)."""
        self.model.opt.timestep = dt
        if self.settings.solref_timeconst is None:
            self.model.eq_solref[self.rigid_eqs, 0] = 2.0 * dt

    def set_targets(self, values: Array) -> None:
        """Hold each driven joint at its value (rad or m, from the drawn pose)."""
        self.model.eq_data[self.driver_eqs, 0] = values

    def without_viscous(self) -> None:
        """No damper anywhere (a quasi-static run: the analytic motion has no speed, so
        no viscous force; the simulated one is slow but not still)."""
        self.model.dof_damping[:] = 0.0
        self.model.tendon_damping[:] = 0.0
        self.viscous = False

    def total_constraint_forces(self) -> Array:
        """The equality forces, carried ones included."""
        return self.carried + self.data.efc_force[:self.nefc]

    # -- how settled ------------------------------------------------------------------
    def loop_violation(self) -> float:
        """Largest gap of a loop-closing joint (a gear mesh's: its tendon's stretch along
        the line of action), metres."""
        return float(self.loop_gaps(self.data.efc_pos[None])[0])

    def loop_gaps(self, efc_pos: Array) -> Array:
        """(N,): :meth:`loop_violation` of N states' ``efc_pos``."""
        gaps = [np.sqrt((efc_pos[:, rows] ** 2).sum(axis=1)) for rows in self.loop_rows.values()]
        gaps += [np.abs(efc_pos[:, row]) for row in self.mesh_rows]
        return np.max(gaps, axis=0) if gaps else np.zeros(efc_pos.shape[0])

    def joint_velocity(self) -> float:
        """Largest joint speed as a point speed (hinges times the size), m/s."""
        return float(np.abs(self.data.qvel * self.weight).max(initial=0.0))

    def pose_drift(self, theta12: float | None = None, qpos: Array | None = None) -> float:
        """Largest difference of the simulated joints from ``qpos``, as a length (m)."""
        assert qpos is not None
        return float(np.abs((self.data.qpos - qpos) * self.weight).max(initial=0.0))
