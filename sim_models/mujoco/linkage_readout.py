"""Forces out of a linkage's MuJoCo model (:class:`RigReadout`), in the quantities of
LINKAGES.md, from MuJoCo's own state only:

- ``Q_<joint>``: the force of the driver's joint equality. Its Jacobian row is +1 on the
  joint's coordinate q (:mod:`.linkage_model` orients every tree joint so), so the force
  is the effort conjugate to q: a couple on ``links[1]`` or a force along the axis;
- a loop-closing revolute joint's ``F_<joint>``: the force of its ``connect``, whose first
  site is on ``links[1]``;
- a tree joint's reaction: ``cfrc_int`` of its child body after ``mj_rnePostConstraint``
  (the spatial force of the parent on the child's subtree, moment about the subtree's
  centre of mass), turned into the force by ``links[0]`` on ``links[1]``; for a sliding
  joint (prismatic, pin in a slot: :mod:`.joint_kinds`) with the emulated friction along
  the axis, less the driver's effort along it, and a prismatic joint's moment about ``at``.
  MuJoCo 4's RNE sees the loads (``xfrc_applied``), the connect forces and the spatial
  tendons' pull on their sites (measured: the springs' reactions agree with the analytic
  ones to 1e-15; a correction for a tendon's pull, needed if it acted only in joint
  space, made them 3e-3 to 0.8 wrong);
- ``S_<spring>``: k(L − L0) + c·L̇ of MuJoCo's tendon length and speed with the model's
  own stiffness, spring length and damping; a torsional spring's from the hinge's qpos.

The read-out is vectorised over states (:class:`Snapshot`): a sweep captures every pose
and reads them at once, by gathers planned once per rig (:class:`ReadPlan`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage import Joint, TorsionSpring
from mechcheck.sim_models.mujoco.joint_kinds import builder_of
from mechcheck.sim_models.mujoco.linkage_build import RigModel
from mechcheck.sim_models.mujoco.model import STATIC, Settings
from mechcheck.sim_models.mujoco.rig import cross_z, rows_times

Array = NDArray[np.float64]


#: What the read-out reads of MjData (:class:`Snapshot`).
SNAPSHOT_FIELDS = ("efc_force", "efc_pos", "qacc", "qpos", "qvel", "cfrc_int", "subtree_com", "xpos",
                   "xmat", "site_xpos", "ten_length", "ten_velocity")


@dataclass(frozen=True)
class Snapshot:
    """The MjData arrays the read-out needs, for N states (leading axis)."""

    efc_force: Array
    efc_pos: Array
    qacc: Array
    qpos: Array
    qvel: Array
    cfrc_int: Array
    subtree_com: Array
    xpos: Array
    xmat: Array
    site_xpos: Array
    ten_length: Array
    ten_velocity: Array


def one_state(columns: dict[str, Array]) -> dict[str, float]:
    """The (1,) columns of one state's read-out as floats."""
    return dict(zip(columns, np.concatenate(list(columns.values())).tolist(), strict=True))


@dataclass(frozen=True)
class ReadPlan:
    """Where each quantity of the read-out is in MuJoCo's arrays
    (:meth:`LinkageRig.values`): index arrays, planned once per rig."""

    order: tuple[str, ...]
    effort_names: tuple[str, ...]
    effort_rows: NDArray[np.int_]
    effort_dofs: NDArray[np.int_]
    effort_armature: Array
    pin_names: tuple[str, ...]
    pin_bodies: NDArray[np.int_]
    pin_signs: Array
    loop_names: tuple[str, ...]
    loop_rows: NDArray[np.int_]
    slides: tuple[Joint, ...]
    point_names: tuple[str, ...]
    point_sites: NDArray[np.int_]
    joint_names: tuple[str, ...]
    joint_rows: Array



class RigReadout(RigModel):
    """A rig's read-out: every quantity from one state or many."""

    def __init__(self, case: Case, settings: Settings = STATIC,
                 customize: Callable[[mujoco.MjSpec], None] | None = None) -> None:
        super().__init__(case, settings, customize)
        #: The arrays :meth:`capture` copies (views of ``data``, which lives as long as the
        #: rig), but the constraint arrays.
        self.sources = [(field, getattr(self.data, field)) for field in SNAPSHOT_FIELDS
                        if not field.startswith("efc_")]
        self.single = {field: source[None] for field, source in self.sources}
        self.plan = read_plan(self)
        #: The arrays of ``data`` the read-out reads besides the state and the constraint
        #: forces: all a sweep copies per pose (:meth:`capture`, :func:`.linkage.exact_sweep`).
        self.derived = [(field, source) for field, source in self.sources
                        if field in self._derived_fields()]
        self.captured = [(field, source) for field, source in self.sources
                         if field in ("qpos", "qvel", "qacc")] + self.derived

    def snapshot(self, n: int = 1) -> Snapshot:
        """Room for the read-out arrays of ``n`` states (:meth:`capture`, :meth:`values`)."""
        shapes = {field: source.shape for field, source in self.sources}
        shapes |= {"efc_force": (self.nefc,), "efc_pos": (self.nefc,)}
        return Snapshot(*(np.zeros((n, *shapes[field])) for field in SNAPSHOT_FIELDS))

    def capture(self, snapshot: Snapshot, i: int = 0) -> None:
        """Copy what the read-out needs of the current data (after a forward pass and
        ``mj_rnePostConstraint``) into row ``i`` of ``snapshot``; the equality forces with
        the carried ones."""
        d = self.data
        for field, source in self.captured:  # the rest is never read (:meth:`values`)
            getattr(snapshot, field)[i] = source
        # The constraint arrays live in MuJoCo's arena, laid out anew by each forward pass.
        snapshot.efc_force[i] = d.efc_force
        snapshot.efc_pos[i] = d.efc_pos
        snapshot.efc_force[i, :self.nefc] += self.carried

    def read(self) -> dict[str, float]:
        """Every quantity from the current data (call after a forward pass)."""
        mujoco.mj_rnePostConstraint(self.model, self.data)
        return one_state(self.values(self.current()))

    def current(self) -> Snapshot:
        """The current data as a Snapshot of one state: views, no copies (but the
        equality forces, with the carried ones added)."""
        return Snapshot(efc_force=self.total_constraint_forces()[None],
                        efc_pos=self.data.efc_pos[None], **self.single)

    def values(self, s: Snapshot) -> dict[str, Array]:
        """Every quantity of the states in ``s``, each an (N,) array: the read-out of
        LINKAGES.md from MuJoCo's own arrays, vectorised over states (a sweep captures
        every pose and reads them at once), by gathers planned once (:class:`ReadPlan`)."""
        out = self._efforts_and_reactions(s)
        out.update(self._springs(s))
        out.update(self._pose_columns(s.qpos, s.site_xpos))
        out.update(self._mesh_columns(s))
        out.update(self._member_columns(s))
        return {name: out[name] for name in self.plan.order}

    def _member_columns(self, s: Snapshot) -> dict[str, Array]:
        """Each split member's tension N (:mod:`.linkage_members`): minus its tendon
        equality's force (the force along the tendon's length, which a tension shortens),
        less what that exceeds N by where the member carries loads off its middle."""
        forces = -s.efc_force[:, self.member_rows] - self.member_excess
        return {f"N_{member.name}": forces[:, k] for k, member in enumerate(self.members)}

    def _mesh_columns(self, s: Snapshot) -> dict[str, Array]:
        """Each gear mesh's tooth force (its tendon equality's force along its sites) and
        rolled arc (:meth:`.linkage_mesh.MeshLine.readings`)."""
        out: dict[str, Array] = {}
        if not self.meshes:
            return out
        forces = s.efc_force[:, self.mesh_rows]
        index = {link: k for k, link in enumerate(self.moving_links)}
        for k, mesh in enumerate(self.meshes):
            gear_a = mesh.joint.links[0]
            phi_a = (rows_times(s.qpos, self.rotation[index[gear_a]][None])[:, 0]
                     if gear_a in index else np.zeros(len(s.qpos)))
            out.update(mesh.readings(forces[:, k], s.site_xpos, s.xpos, s.xmat, phi_a))
        return out

    def reactions(self) -> dict[str, float]:
        """The drivers' efforts and the joints' reactions alone from the current data (after
        a forward pass): what friction is computed from at every step of a driven run."""
        mujoco.mj_rnePostConstraint(self.model, self.data)
        return one_state(self._efforts_and_reactions(self.current()))

    def _efforts_and_reactions(self, s: Snapshot) -> dict[str, Array]:
        plan = self.plan
        total = s.efc_force[:, :self.nefc]
        efforts = total[:, plan.effort_rows] - plan.effort_armature * s.qacc[:, plan.effort_dofs]
        pins = s.cfrc_int[:, plan.pin_bodies, 3:5] * plan.pin_signs[:, None]
        out = dict(zip(plan.effort_names, efforts.T, strict=True))
        out.update(zip(plan.pin_names, pins.reshape(len(pins), -1).T, strict=True))
        out.update(zip(plan.loop_names, total[:, plan.loop_rows].T, strict=True))
        for joint in plan.slides:
            effort = out.get(f"Q_{joint.name}")
            out.update(self._slide_reaction(s, joint, effort))
        return out

    def _slide_reaction(self, s: Snapshot, joint: Joint,
                        effort: Array | None) -> dict[str, Array]:
        """A sliding tree joint's reaction (a prismatic joint, a pin in a slot): the force
        and, if its kind has a couple, the moment about ``at``, by links[0] on links[1]
        (the tree joint's sign)."""
        name = joint.name
        t = self.tree_joints[name]
        child = self.body[t.child]
        f = s.cfrc_int[:, child, 3:5]
        u = self._axis_of(s.xmat, joint)
        # The driver's effort is reported as Q, not in F; emulated friction along the axis
        # is applied as a load, but it is part of the joint's reaction.
        along = self.sliding.get(name, 0.0) - (0.0 if effort is None else effort)
        out = {f"F_{name}_x": t.sign * f[:, 0] + along * u[:, 0],
               f"F_{name}_y": t.sign * f[:, 1] + along * u[:, 1]}
        if builder_of(joint).couple:
            point = self._point_on(s.xpos, s.xmat, joint.links[1], self.linkage.points[joint.at])
            # cfrc_int's moment is about the centre of mass of the body's kinematic tree.
            c = s.subtree_com[:, self.model.body_rootid[child], :2]
            out[f"M_{name}"] = t.sign * (s.cfrc_int[:, child, 2] + cross_z(c - point, f))
        return out

    def _derived_fields(self) -> set[str]:
        """What :meth:`values` reads of ``data`` besides qpos, qvel, qacc and the constraint
        arrays: the pins' cfrc_int, the points' sites, a slide's frames and subtree centre,
        the tendons' lengths and speeds."""
        plan = self.plan
        fields = {"cfrc_int"} if plan.pin_names or plan.slides else set()
        fields |= {"site_xpos"} if plan.point_names else set()
        fields |= {"xpos", "xmat", "subtree_com"} if plan.slides else set()
        fields |= {"site_xpos", "xpos", "xmat"} if self.meshes else set()
        return fields | ({"ten_length", "ten_velocity"} if self.springs else set())

    def point_on(self, link: str, drawn: tuple[float, float]) -> Array:
        """Current global (x, y) of a point fixed to ``link`` that was at ``drawn``."""
        d = self.data
        return self._point_on(d.xpos[None], d.xmat[None], link, drawn)[0]

    def _point_on(self, xpos: Array, xmat: Array, link: str,
                  drawn: tuple[float, float]) -> Array:
        """(N, 2): the point of ``link`` drawn at ``drawn`` in N states' body frames."""
        b = self.body[link]
        o = self.origins[link]
        r = np.array([drawn[0] - o[0], drawn[1] - o[1], 0.0])
        return (xpos[:, b] + xmat[:, b].reshape(-1, 3, 3) @ r)[:, :2]

    def axis_of(self, joint: Joint) -> Array:
        """A prismatic joint's current sliding direction (fixed in links[0])."""
        return self._axis_of(self.data.xmat[None], joint)[0]

    def _axis_of(self, xmat: Array, joint: Joint) -> Array:
        assert joint.axis is not None
        b0 = self.body[joint.links[0]]
        return (xmat[:, b0].reshape(-1, 3, 3) @ np.array([*joint.axis, 0.0]))[:, :2]

    def spring_tensions(self) -> Array:
        """Each linear spring's tension from MuJoCo's tendon length and speed."""
        d = self.data
        return self._tensions(d.ten_length[None], d.ten_velocity[None])[0]

    def _tensions(self, length: Array, velocity: Array) -> Array:
        m = self.model
        return (m.tendon_stiffness * (length - m.tendon_lengthspring[:, 0])
                + m.tendon_damping * velocity)

    def _springs(self, s: Snapshot) -> dict[str, Array]:
        out: dict[str, Array] = {}
        if not self.linkage.springs:
            return out
        tensions = self._tensions(s.ten_length, s.ten_velocity)
        for k, linear in enumerate(self.springs):
            out[f"S_{linear.name}"] = tensions[:, k]
        for torsion in self.linkage.springs:
            if isinstance(torsion, TorsionSpring):
                dof = self.dof[torsion.joint]  # = its qpos address (hinges and slides only)
                out[f"S_{torsion.name}"] = (
                    torsion.stiffness * (s.qpos[:, dof] - torsion.free_rotation)
                    + (torsion.damping * s.qvel[:, dof] if self.viscous else 0.0))
        return out

    def _pose_columns(self, qpos: Array, site_xpos: Array) -> dict[str, Array]:
        plan = self.plan
        # Positions in the file's frame: the model is built about the reference point.
        points = (site_xpos[:, plan.point_sites, :2] + self.linkage.offset).reshape(len(qpos), -1)
        out = dict(zip(plan.point_names, points.T, strict=True))
        out.update(zip(self.phi_names, rows_times(qpos, self.rotation).T, strict=True))
        out.update(zip(plan.joint_names, rows_times(qpos, plan.joint_rows).T, strict=True))
        return out


def quantity_order(rig: RigModel) -> tuple[str, ...]:
    """Every quantity of the read-out, in the order of LINKAGES.md."""
    linkage = rig.linkage
    order = [f"Q_{j}" for j in rig.drive_rows]
    for joint in linkage.joints:
        order += builder_of(joint).reaction_names(joint)
    order += [f"S_{spring.name}" for spring in linkage.springs]
    order += [f"N_{member.name}" for member in rig.members]
    order += [f"{axis}_{p}" for p in rig.point_sites for axis in "xy"]
    order += [f"phi_{link}" for link in linkage.moving_links]
    return tuple(order + [f"q_{joint.name}" for joint in linkage.joints])


def joint_coordinate_rows(rig: RigModel) -> Array:
    """q of every joint as rows on qpos: a tree joint's coordinate, a closure's relative
    rotation."""
    linkage = rig.linkage
    rows = np.zeros((len(linkage.joints), rig.model.nq))
    index = {link: k for k, link in enumerate(linkage.moving_links)}

    def rotation(link: str) -> Array | float:
        return rig.rotation[index[link]] if link in index else 0.0

    for k, joint in enumerate(linkage.joints):
        if joint.name in rig.dof:
            rows[k, rig.dof[joint.name]] = 1.0
        else:
            rows[k] = rotation(joint.links[1]) - rotation(joint.links[0])
    return rows


def read_plan(rig: RigModel) -> ReadPlan:
    """Where each quantity of ``rig``'s read-out is in MuJoCo's arrays."""
    drivers = list(rig.drive_rows)
    pins = [t for t in rig.tree.tree if not builder_of(t.joint).slide_readout]
    loops = list(rig.loop_rows)
    return ReadPlan(
        order=quantity_order(rig),
        effort_names=tuple(f"Q_{j}" for j in drivers),
        effort_rows=np.array([rig.drive_rows[j][0] for j in drivers], dtype=int),
        effort_dofs=np.array([rig.dof[j] for j in drivers], dtype=int),
        effort_armature=np.array([rig.drive_armature[j] for j in drivers]),
        pin_names=tuple(f"F_{t.joint.name}_{a}" for t in pins for a in "xy"),
        pin_bodies=np.array([rig.body[t.child] for t in pins], dtype=int),
        pin_signs=np.array([float(t.sign) for t in pins]),
        loop_names=tuple(f"F_{j}_{a}" for j in loops for a in "xy"),
        loop_rows=np.array([rig.loop_rows[j][k] for j in loops for k in (0, 1)], dtype=int),
        slides=tuple(t.joint for t in rig.tree.tree if builder_of(t.joint).slide_readout),
        point_names=tuple(f"{a}_{p}" for p in rig.point_sites for a in "xy"),
        point_sites=np.array(list(rig.point_sites.values()), dtype=int),
        joint_names=tuple(f"q_{j.name}" for j in rig.linkage.joints),
        joint_rows=joint_coordinate_rows(rig),
    )
