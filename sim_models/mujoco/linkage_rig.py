"""A linkage's compiled model and data: put it in a pose, apply the loads, read the forces
back in the quantities of LINKAGES.md, with the interface :mod:`.settle` drives (loads in
and forces out: :mod:`.rig`).

Forces are read from MuJoCo's own state only:

- ``Q_<joint>``: the force of the driver's joint equality. Its Jacobian row is +1 on the
  joint's coordinate q (:mod:`.linkage_model` orients every tree joint so), so the force
  is the effort conjugate to q: a couple on ``links[1]`` or a force along the axis;
- a loop-closing revolute joint's ``F_<joint>``: the force of its ``connect``, whose first
  site is on ``links[1]``;
- a tree joint's reaction: ``cfrc_int`` of its child body after ``mj_rnePostConstraint``
  (the spatial force of the parent on the child's subtree, moment about the subtree's
  centre of mass), turned into the force by ``links[0]`` on ``links[1]`` and, for a
  prismatic joint, its moment about ``at``, less the driver's effort along the axis.
  MuJoCo 4's RNE sees the loads (``xfrc_applied``), the connect forces and the spatial
  tendons' pull on their sites (measured: the springs' reactions agree with the analytic
  ones to 1e-15; a correction for a tendon's pull, needed if it acted only in joint
  space, made them 3e-3 to 0.8 wrong);
- ``S_<spring>``: k(L − L0) + c·L̇ of MuJoCo's tendon length and speed with the model's
  own stiffness, spring length and damping; a torsional spring's from the hinge's qpos.

Carried constraint forces (:mod:`.settle`, why: :mod:`.rig`): the forces of a settled
state can be moved into explicit loads — each connect's force as an equal and opposite
pair at its two sites, each driver's effort as ``qfrc_applied`` on its joint.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage import Joint, LinearSpring, TorsionSpring
from mechcheck.analytic.linkage_backends import quantity_units
from mechcheck.analytic.linkage_kinematics import LinkagePose
from mechcheck.analytic.values import GROUND
from mechcheck.sim_models.mujoco import _fast
from mechcheck.sim_models.mujoco.linkage_model import (
    CLOCK,
    LinkageTree,
    body_name,
    build_spec,
    closure_sites,
    joint_damping,
    origin_of,
    spanning_tree,
)
from mechcheck.sim_models.mujoco.model import STATIC, Settings, place_frames_exactly
from mechcheck.sim_models.mujoco.rig import LoadTable, cross_z, load_wrenches, rows_times
from mechcheck.sim_models.mujoco.settle import rounding_floor

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


@dataclass(frozen=True)
class CarriedPairs:
    """The sites where carried connect forces act (see :meth:`LinkageRig.apply_carried`)."""

    sites: NDArray[np.int_]
    bodies: NDArray[np.int_]
    signs: Array
    rows: NDArray[np.int_]
    incidence: Array


class LinkageRig:
    """One linkage Case's compiled model and data, with loads, pose and force read-out."""

    def __init__(self, case: Case, settings: Settings = STATIC,
                 customize: Callable[[mujoco.MjSpec], None] | None = None) -> None:
        """``customize`` edits the spec before it is compiled (the servo models of
        :mod:`.locks` and :mod:`.turning`)."""
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
        self.data = mujoco.MjData(self.model)
        #: The arrays :meth:`capture` copies (views of ``data``, which lives as long as the
        #: rig), but the constraint arrays.
        self.sources = [(field, getattr(self.data, field)) for field in SNAPSHOT_FIELDS
                        if not field.startswith("efc_")]
        self.single = {field: source[None] for field, source in self.sources}
        self.scale = linkage.scale
        self.units: dict[str, str] | None = quantity_units(linkage)
        m = self.model
        self.body = {GROUND: 0} | {link: self._id(mujoco.mjtObj.mjOBJ_BODY, body_name(link))
                                   for link in linkage.moving_links}
        self.dof = {t.joint.name: int(m.jnt_dofadr[self._id(mujoco.mjtObj.mjOBJ_JOINT,
                                                             t.joint.name)])
                    for t in self.tree.tree}
        self.hinge = np.array([m.jnt_type[j] == mujoco.mjtJoint.mjJNT_HINGE
                               for j in range(m.njnt)])
        # Each moving link's rotation is the signed sum of the hinges on its path from the
        # ground (slides do not turn): phi = rotation @ qpos.
        self.rotation = np.zeros((len(linkage.moving_links), m.nq))
        for k, link in enumerate(linkage.moving_links):
            while link != GROUND:
                t = self.tree.parent_joint(link)
                if t.joint.kind.rotates:
                    self.rotation[k, self.dof[t.joint.name]] = t.sign
                link = t.parent
        self.loads = self._load_table()
        self.incidence = np.zeros((m.nbody, self.loads.sites.size))
        self.incidence[self.loads.bodies, np.arange(self.loads.sites.size)] = 1.0
        self.body_forces = self.incidence @ self.loads.forces
        self.springs = [s for s in linkage.springs if isinstance(s, LinearSpring)]
        self.loop_eq = {j.name: self._id(mujoco.mjtObj.mjOBJ_EQUALITY, f"loop_{j.name}")
                        for j in self.tree.closures}
        self.drive_eq = {d.joint: self._id(mujoco.mjtObj.mjOBJ_EQUALITY, f"drive_{d.joint}")
                         for d in linkage.drivers}
        self.driver_eqs = np.array([self.drive_eq[d.joint] for d in linkage.drivers], dtype=int)
        self.loop_sites = {j.name: tuple(self._id(mujoco.mjtObj.mjOBJ_SITE, s)
                                         for s in closure_sites(j)) for j in self.tree.closures}
        self.point_sites = {p: self._id(mujoco.mjtObj.mjOBJ_SITE, f"point_{p}")
                            for p in linkage.points}
        mujoco.mj_forward(m, self.data)
        self.nefc = int(self.data.nefc)  # constant: equalities only, no contacts or limits
        self.loop_rows = {j: self.equality_rows(e) for j, e in self.loop_eq.items()}
        # A switched-off driver (a servo model, ``customize``) has no constraint rows.
        self.drive_rows = {j: rows for j, e in self.drive_eq.items()
                           if (rows := self.equality_rows(e)).size}
        self.efc_scale = np.ones(self.nefc)
        for joint, rows in self.drive_rows.items():
            if linkage.joint(joint).kind.rotates:
                self.efc_scale[rows] = 1.0 / self.scale  # torques as forces, for the stop rule
        #: The spread of forces the positions' rounding makes at rest (N, the settling's
        #: absolute allowance), from the model at the drawn pose: its sites' largest
        #: coordinate sets the grid they sit on.
        extent = max(self.scale, float(np.abs(self.data.site_xpos[:, :2]).max(initial=0.0)))
        self.rounding = rounding_floor(float(m.body_mass.max()), extent, settings.timestep)
        self.carried = np.zeros(self.nefc)
        self.pairs = self._carried_layout()
        self.drive_dofs = np.array([self.dof[j] for j in self.drive_rows], dtype=int)
        self.drive_first_rows = np.array([rows[0] for rows in self.drive_rows.values()],
                                         dtype=int)
        # Joint speeds and pose errors as point speeds and lengths: hinges times the size.
        self.weight = np.where(self.hinge[m.dof_jntid], self.scale, 1.0)
        clock = int(mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, CLOCK))
        self.clock: int | None = int(m.jnt_dofadr[clock]) if clock >= 0 else None
        if self.clock is not None:
            self.weight[self.clock] = 0.0  # the clock is time, not the mechanism
        # A driven run's extra armature on each driven joint, subtracted from its effort.
        self.drive_armature = {j: float(m.dof_armature[self.dof[j]]) - settings.armature
                               for j in self.drive_rows}
        #: Friction emulated from the reactions (:mod:`.linkage_friction`): xfrc_applied
        #: added to the loads, and each prismatic joint's friction force along its axis,
        #: which is part of its reported reaction.
        self.extra = np.zeros((m.nbody, 6))
        self.sliding: dict[str, float] = {}
        self.viscous = True
        #: Dampers on loop-closing joints (no MuJoCo joint to damp): couples −c·q̇ from
        #: MuJoCo's own joint rates, applied with the loads.
        self.closure_damping = {j.name: c for j in self.tree.closures
                                if (c := joint_damping(linkage, j)) > 0.0}
        self.phi_names = tuple(f"phi_{link}" for link in linkage.moving_links)
        # Looked up at every step of a driven run: computed once.
        self.moving_links = tuple(linkage.moving_links)
        self.origins = {link: origin_of(self.tree, linkage, link)
                        for link in (GROUND, *self.moving_links)}
        self.plan = self._read_plan()
        #: The arrays of ``data`` the read-out reads besides the state and the constraint
        #: forces: all a sweep copies per pose (:meth:`capture`, :func:`.linkage.exact_sweep`).
        self.derived = [(field, source) for field, source in self.sources
                        if field in self._derived_fields()]
        self.captured = [(field, source) for field, source in self.sources
                         if field in ("qpos", "qvel", "qacc")] + self.derived

    def _id(self, kind: mujoco.mjtObj, name: str) -> int:
        found = int(mujoco.mj_name2id(self.model, kind, name))
        assert found >= 0, name
        return found

    def _load_table(self) -> LoadTable:
        """The loads plus the weights m·g of the real masses (never fictitious ones); loads
        on the ground do nothing and are left out."""
        lk = self.linkage
        sites, bodies, forces, torques = [], [], [], []
        for i, load in enumerate(lk.loads):
            if load.link != GROUND:
                sites.append(self._id(mujoco.mjtObj.mjOBJ_SITE, f"load{i}"))
                bodies.append(self.body[load.link])
                forces.append((load.force[0], load.force[1], 0.0))
                torques.append(load.torque)
        if lk.gravity != (0.0, 0.0):
            for i, mass in enumerate(lk.masses):
                if mass.link != GROUND:
                    sites.append(self._id(mujoco.mjtObj.mjOBJ_SITE, f"weight{i}"))
                    bodies.append(self.body[mass.link])
                    forces.append((mass.mass * lk.gravity[0], mass.mass * lk.gravity[1], 0.0))
                    torques.append(0.0)
        return LoadTable(np.array(sites, dtype=int), np.array(bodies, dtype=int),
                         np.array(forces, dtype=float).reshape(-1, 3),
                         np.array(torques, dtype=float))

    def _carried_layout(self) -> CarriedPairs:
        """Where carried connect forces act, as a load table: one row per site of a
        connect on a moving link, with its constraint rows (``rows``: x, y, z), its sign
        (+ on ``links[1]``, the first site) and a body × site incidence."""
        sites, bodies, signs, rows = [], [], [], []
        for name, eq_rows in self.loop_rows.items():
            links = self.linkage.joint(name).links
            for link, site, sign in ((links[1], self.loop_sites[name][0], 1.0),
                                     (links[0], self.loop_sites[name][1], -1.0)):
                if link != GROUND:
                    sites.append(site)
                    bodies.append(self.body[link])
                    signs.append(sign)
                    rows.append(eq_rows)
        incidence = np.zeros((self.model.nbody, len(sites)))
        incidence[bodies, np.arange(len(sites))] = 1.0
        return CarriedPairs(np.array(sites, dtype=int), np.array(bodies, dtype=int),
                            np.array(signs), np.array(rows, dtype=int).reshape(-1, 3),
                            incidence)

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
            for array, value in zip(out, pose.joint_coordinate(t.joint), strict=True):
                array[:, self.dof[t.joint.name]] = value
        return out[0], out[1], out[2]

    def set_state(self, qpos: Array, qvel: Array) -> None:
        self.data.qpos[:] = qpos
        self.data.qvel[:] = qvel

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
            self.model.eq_solref[:, 0] = 2.0 * dt

    def set_targets(self, values: Array) -> None:
        """Hold each driven joint at its value (rad or m, from the drawn pose)."""
        self.model.eq_data[self.driver_eqs, 0] = values

    # -- loads ------------------------------------------------------------------------
    def apply_loads(self) -> None:
        """xfrc_applied from the current pose (:meth:`wrenches`), and the carried forces."""
        d = self.data
        d.xfrc_applied[:] = self.wrenches(d.site_xpos[None], d.xipos[None], d.qvel[None])[0]
        if self.carried.any():
            self.apply_carried()

    def wrenches(self, site_xpos: Array, xipos: Array, qvel: Array) -> Array:
        """(N, nbody, 6): the xfrc_applied of N states: the loads
        (:func:`.rig.load_wrenches`), the emulated friction (``extra``) and the couples −c·q̇
        of the dampers on loop-closing joints, on the joint's second link and opposite on
        its first, from the states' joint velocities."""
        out = load_wrenches(site_xpos, xipos, self.loads, self.incidence, self.body_forces)
        out += self.extra
        if self.closure_damping and self.viscous:
            omega = rows_times(qvel, self.rotation)
            spin = {link: omega[:, k] for k, link in enumerate(self.moving_links)}
            still = np.zeros(qvel.shape[0])
            for name, c in self.closure_damping.items():
                i, j = self.linkage.joint(name).links
                rate = spin.get(j, still) - spin.get(i, still)
                for link, share in ((j, 1.0), (i, -1.0)):
                    if link != GROUND:
                        out[:, self.body[link], 5] -= share * c * rate
        return out

    def reset_carried(self) -> None:
        self.carried = np.zeros(self.nefc)
        self.data.qfrc_applied[:] = 0.0

    def carry(self, factor: float = 1.0) -> None:
        """The constraints' forces carried as loads from now on, times ``factor`` (an
        extrapolated pass, :class:`.settle.Refinement`)."""
        self.carried = self.carried + factor * self.data.efc_force[:self.nefc]

    def apply_carried(self) -> None:
        """The carried forces added to the loads (:meth:`carried_loads` at the current
        pose)."""
        d = self.data
        pairs = self.pairs
        arm = d.site_xpos[pairs.sites] - d.xipos[pairs.bodies]
        xfrc, qfrc = self.carried_loads(self.carried, arm)
        d.xfrc_applied[:] += xfrc
        d.qfrc_applied[self.drive_dofs] = qfrc

    def carried_loads(self, carried: Array, arm: Array) -> tuple[Array, Array]:
        """Each connect's carried force as a pair at its sites (xfrc_applied to add, with
        ``arm`` = each pair site's position from its body's centre of mass), each driver's
        as a generalised force on its joint (qfrc_applied of ``drive_dofs``); arrays from
        :meth:`_carried_layout`. Leading dimensions of ``carried`` (…, nefc) and ``arm``
        (…, pairs, 3) are states: the loads of many at once."""
        pairs = self.pairs
        xfrc = np.zeros((*carried.shape[:-1], self.model.nbody, 6))
        if pairs.sites.size:
            f = carried[..., pairs.rows] * pairs.signs[:, None]
            xfrc[..., 0:3] = pairs.incidence @ f
            xfrc[..., 5] = rows_times(cross_z(arm, f), pairs.incidence)
        return xfrc, carried[..., self.drive_first_rows]

    def load_points(self, qpos: Array) -> tuple[Array, Array]:
        """(site_xpos, xipos) of MuJoCo's kinematics at each pose of ``qpos`` (N, nq);
        compiled where it can be."""
        m, d = self.model, self.data
        found = _fast.load_points(m, d, qpos)
        if found is not None:
            return found
        sites = np.empty((len(qpos), *d.site_xpos.shape))
        centres = np.empty((len(qpos), *d.xipos.shape))
        for i, q in enumerate(qpos):
            d.qpos[:] = q
            mujoco.mj_kinematics(m, d)
            sites[i], centres[i] = d.site_xpos, d.xipos
        return sites, centres

    def total_constraint_forces(self) -> Array:
        return self.carried + self.data.efc_force[:self.nefc]

    def constraint_forces(self) -> Array:
        """The equality forces, carried ones included, drivers' torques as forces."""
        return self.total_constraint_forces() * self.efc_scale

    # -- read-out ---------------------------------------------------------------------
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

    def spring_tensions(self) -> Array:
        """Each linear spring's tension from MuJoCo's tendon length and speed."""
        d = self.data
        return self._tensions(d.ten_length[None], d.ten_velocity[None])[0]

    def _tensions(self, length: Array, velocity: Array) -> Array:
        m = self.model
        return (m.tendon_stiffness * (length - m.tendon_lengthspring[:, 0])
                + m.tendon_damping * velocity)

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
        return {name: out[name] for name in self.plan.order}

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
        """A prismatic tree joint's reaction: force and moment about ``at``, by links[0] on
        links[1] (the tree joint's sign)."""
        name = joint.name
        t = self.tree_joints[name]
        child = self.body[t.child]
        point = self._point_on(s.xpos, s.xmat, joint.links[1], self.linkage.points[joint.at])
        # cfrc_int's moment is about the centre of mass of the body's kinematic tree.
        f = s.cfrc_int[:, child, 3:5]
        c = s.subtree_com[:, self.model.body_rootid[child], :2]
        moment = t.sign * (s.cfrc_int[:, child, 2] + cross_z(c - point, f))
        u = self._axis_of(s.xmat, joint)
        # The driver's effort is reported as Q, not in F; emulated friction along the axis
        # is applied as a load, but it is part of the joint's reaction.
        along = self.sliding.get(name, 0.0) - (0.0 if effort is None else effort)
        f = t.sign * f + np.asarray(along)[..., None] * u
        return {f"M_{name}": moment, f"F_{name}_x": f[:, 0], f"F_{name}_y": f[:, 1]}

    def _derived_fields(self) -> set[str]:
        """What :meth:`values` reads of ``data`` besides qpos, qvel, qacc and the constraint
        arrays: the pins' cfrc_int, the points' sites, a slide's frames and subtree centre,
        the tendons' lengths and speeds."""
        plan = self.plan
        fields = {"cfrc_int"} if plan.pin_names or plan.slides else set()
        fields |= {"site_xpos"} if plan.point_names else set()
        fields |= {"xpos", "xmat", "subtree_com"} if plan.slides else set()
        return fields | ({"ten_length", "ten_velocity"} if self.springs else set())

    def _read_plan(self) -> ReadPlan:
        linkage = self.linkage
        drivers = list(self.drive_rows)
        pins = [t for t in self.tree.tree if t.joint.kind.pins]
        loops = list(self.loop_rows)
        slides = [t.joint for t in self.tree.tree if not t.joint.kind.pins]
        order = [f"Q_{j}" for j in drivers]
        for joint in linkage.joints:
            order += ([f"M_{joint.name}"] if not joint.kind.pins else []) \
                + [f"F_{joint.name}_x", f"F_{joint.name}_y"]
        order += [f"S_{spring.name}" for spring in linkage.springs]
        order += [f"{axis}_{p}" for p in self.point_sites for axis in "xy"]
        order += [f"phi_{link}" for link in linkage.moving_links]
        order += [f"q_{joint.name}" for joint in linkage.joints]
        # q of every joint: a tree joint's coordinate, a closure's relative rotation.
        rows = np.zeros((len(linkage.joints), self.model.nq))
        index = {link: k for k, link in enumerate(linkage.moving_links)}
        for k, joint in enumerate(linkage.joints):
            if joint.name in self.dof:
                rows[k, self.dof[joint.name]] = 1.0
            else:
                i, j = joint.links
                rows[k] = (self.rotation[index[j]] if j in index else 0.0) \
                    - (self.rotation[index[i]] if i in index else 0.0)
        return ReadPlan(
            order=tuple(order),
            effort_names=tuple(f"Q_{j}" for j in drivers),
            effort_rows=np.array([self.drive_rows[j][0] for j in drivers], dtype=int),
            effort_dofs=np.array([self.dof[j] for j in drivers], dtype=int),
            effort_armature=np.array([self.drive_armature[j] for j in drivers]),
            pin_names=tuple(f"F_{t.joint.name}_{a}" for t in pins for a in "xy"),
            pin_bodies=np.array([self.body[t.child] for t in pins], dtype=int),
            pin_signs=np.array([float(t.sign) for t in pins]),
            loop_names=tuple(f"F_{j}_{a}" for j in loops for a in "xy"),
            loop_rows=np.array([self.loop_rows[j][k] for j in loops for k in (0, 1)],
                               dtype=int),
            slides=tuple(slides),
            point_names=tuple(f"{a}_{p}" for p in self.point_sites for a in "xy"),
            point_sites=np.array(list(self.point_sites.values()), dtype=int),
            joint_names=tuple(f"q_{j.name}" for j in linkage.joints),
            joint_rows=rows,
        )

    def axis_of(self, joint: Joint) -> Array:
        """A prismatic joint's current sliding direction (fixed in links[0])."""
        return self._axis_of(self.data.xmat[None], joint)[0]

    def _axis_of(self, xmat: Array, joint: Joint) -> Array:
        assert joint.axis is not None
        b0 = self.body[joint.links[0]]
        return (xmat[:, b0].reshape(-1, 3, 3) @ np.array([*joint.axis, 0.0]))[:, :2]

    def without_viscous(self) -> None:
        """No damper anywhere (a quasi-static run: the analytic motion has no speed, so
        no viscous force; the simulated one is slow but not still)."""
        self.model.dof_damping[:] = 0.0
        self.model.tendon_damping[:] = 0.0
        self.viscous = False

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

    def pose_values(self) -> dict[str, float]:
        d = self.data
        return one_state(self._pose_columns(d.qpos[None], d.site_xpos[None]))

    def _pose_columns(self, qpos: Array, site_xpos: Array) -> dict[str, Array]:
        plan = self.plan
        # Positions in the file's frame: the model is built about the reference point.
        points = (site_xpos[:, plan.point_sites, :2] + self.linkage.offset).reshape(len(qpos), -1)
        out = dict(zip(plan.point_names, points.T, strict=True))
        out.update(zip(self.phi_names, rows_times(qpos, self.rotation).T, strict=True))
        out.update(zip(plan.joint_names, rows_times(qpos, plan.joint_rows).T, strict=True))
        return out

    # -- how settled ------------------------------------------------------------------
    def loop_violation(self) -> float:
        """Largest gap of a loop-closing joint, metres."""
        return float(self.loop_gaps(self.data.efc_pos[None])[0])

    def loop_gaps(self, efc_pos: Array) -> Array:
        """(N,): :meth:`loop_violation` of N states' ``efc_pos``."""
        gaps = [np.sqrt((efc_pos[:, rows] ** 2).sum(axis=1)) for rows in self.loop_rows.values()]
        return np.max(gaps, axis=0) if gaps else np.zeros(efc_pos.shape[0])

    def joint_velocity(self) -> float:
        """Largest joint speed as a point speed (hinges times the size), m/s."""
        return float(np.abs(self.data.qvel * self.weight).max(initial=0.0))

    def pose_drift(self, theta12: float | None = None, qpos: Array | None = None) -> float:
        """Largest difference of the simulated joints from ``qpos``, as a length (m)."""
        assert qpos is not None
        return float(np.abs((self.data.qpos - qpos) * self.weight).max(initial=0.0))
