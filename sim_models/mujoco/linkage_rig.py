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
from mechcheck.sim_models.mujoco.rig import LoadTable, cross_z, parent_force, xfrc_of_loads

Array = NDArray[np.float64]


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
                if t.joint.kind == "revolute":
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
            if linkage.joint(joint).kind == "revolute":
                self.efc_scale[rows] = 1.0 / self.scale  # torques as forces, for the stop rule
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
        omega = dict(zip(self.linkage.moving_links, self.rotation @ qvel, strict=True))
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
        for driver, value in zip(self.linkage.drivers, values, strict=True):
            self.model.eq_data[self.drive_eq[driver.joint], 0] = value

    # -- loads ------------------------------------------------------------------------
    def apply_loads(self) -> None:
        """xfrc_applied from the current pose (see :func:`.rig.xfrc_of_loads`)."""
        xfrc_of_loads(self.data, self.loads, self.incidence, self.body_forces,
                      np.zeros(self.model.nbody))
        if self.extra.any():
            self.data.xfrc_applied[:] += self.extra
        if self.closure_damping and self.viscous:
            self.apply_closure_damping()
        if self.carried.any():
            self.apply_carried()

    def apply_closure_damping(self) -> None:
        """The couple −c·q̇ of each damper on a loop-closing joint on its second link, and
        its opposite on the first, from the current joint velocities."""
        rates = self.joint_rates(self.data.qvel)
        for name, c in self.closure_damping.items():
            i, j = self.linkage.joint(name).links
            for link, share in ((j, 1.0), (i, -1.0)):
                if link != GROUND:
                    self.data.xfrc_applied[self.body[link], 5] -= share * c * rates[name]

    def reset_carried(self) -> None:
        self.carried = np.zeros(self.nefc)
        self.data.qfrc_applied[:] = 0.0

    def carry(self) -> None:
        self.carried = self.carried + self.data.efc_force[:self.nefc]

    def apply_carried(self) -> None:
        """Each connect's carried force as a pair at its sites, each driver's as a
        generalised force on its joint (arrays from :meth:`_carried_layout`)."""
        d = self.data
        pairs = self.pairs
        if pairs.sites.size:
            f = self.carried[pairs.rows] * pairs.signs[:, None]
            arm = d.site_xpos[pairs.sites] - d.xipos[pairs.bodies]
            d.xfrc_applied[:, 0:3] += pairs.incidence @ f
            d.xfrc_applied[:, 5] += pairs.incidence @ cross_z(arm, f)
        d.qfrc_applied[self.drive_dofs] = self.carried[self.drive_first_rows]

    def total_constraint_forces(self) -> Array:
        return self.carried + self.data.efc_force[:self.nefc]

    def constraint_forces(self) -> Array:
        """The equality forces, carried ones included, drivers' torques as forces."""
        return self.total_constraint_forces() * self.efc_scale

    # -- read-out ---------------------------------------------------------------------
    def point_on(self, link: str, drawn: tuple[float, float]) -> Array:
        """Current global (x, y) of a point fixed to ``link`` that was at ``drawn``."""
        d, b = self.data, self.body[link]
        o = origin_of(self.tree, self.linkage, link)
        r = np.array([drawn[0] - o[0], drawn[1] - o[1], 0.0])
        return (d.xpos[b] + d.xmat[b].reshape(3, 3) @ r)[:2]

    def spring_tensions(self) -> Array:
        """Each linear spring's tension from MuJoCo's tendon length and speed."""
        m, d = self.model, self.data
        return (m.tendon_stiffness * (d.ten_length - m.tendon_lengthspring[:, 0])
                + m.tendon_damping * d.ten_velocity)

    def read(self) -> dict[str, float]:
        """Every quantity from the current data (call after a forward pass)."""
        m, d = self.model, self.data
        mujoco.mj_rnePostConstraint(m, d)
        total = self.total_constraint_forces()
        efforts = {j: float(total[rows[0]] - self.drive_armature[j] * d.qacc[self.dof[j]])
                   for j, rows in self.drive_rows.items()}
        values = {f"Q_{j}": q for j, q in efforts.items()}
        for joint in self.linkage.joints:
            values.update(self._reaction(joint, total, efforts.get(joint.name, 0.0)))
        values.update(self._springs())
        values.update(self.pose_values())
        return {k: float(v) for k, v in values.items()}

    def _reaction(self, joint: Joint, total: Array, effort: float) -> dict[str, float]:
        name = joint.name
        if name in self.loop_rows:
            f = total[self.loop_rows[name]]
            return {f"F_{name}_x": float(f[0]), f"F_{name}_y": float(f[1])}
        t = self.tree_joints[name]
        if joint.kind == "revolute":  # a force at the pin: its moment is not needed
            f = t.sign * self.data.cfrc_int[self.body[t.child], 3:5]
            return {f"F_{name}_x": float(f[0]), f"F_{name}_y": float(f[1])}
        point = self.point_on(joint.links[1], self.linkage.points[joint.at])
        f, moment = parent_force(self.model, self.data, self.body[t.child], point)
        f, moment = t.sign * f, t.sign * moment  # by links[0] on links[1]
        u = self.axis_of(joint)
        # The driver's effort is reported as Q, not in F; emulated friction along the axis
        # is applied as a load, but it is part of the joint's reaction.
        f = f + (self.sliding.get(name, 0.0) - effort) * u
        return {f"M_{name}": moment, f"F_{name}_x": float(f[0]), f"F_{name}_y": float(f[1])}

    def axis_of(self, joint: Joint) -> Array:
        """A prismatic joint's current sliding direction (fixed in links[0])."""
        assert joint.axis is not None
        b0 = self.body[joint.links[0]]
        return (self.data.xmat[b0].reshape(3, 3) @ np.array([*joint.axis, 0.0]))[:2]

    def without_viscous(self) -> None:
        """No damper anywhere (a quasi-static run: the analytic motion has no speed, so
        no viscous force; the simulated one is slow but not still)."""
        self.model.dof_damping[:] = 0.0
        self.model.tendon_damping[:] = 0.0
        self.viscous = False

    def _springs(self) -> dict[str, float]:
        d = self.data
        out: dict[str, float] = {}
        tensions = self.spring_tensions()
        for k, linear in enumerate(self.springs):
            out[f"S_{linear.name}"] = float(tensions[k])
        for torsion in self.linkage.springs:
            if isinstance(torsion, TorsionSpring):
                dof = self.dof[torsion.joint]  # = its qpos address (hinges and slides only)
                out[f"S_{torsion.name}"] = float(
                    torsion.stiffness * (d.qpos[dof] - torsion.free_rotation)
                    + (torsion.damping * d.qvel[dof] if self.viscous else 0.0))
        return out

    def pose_values(self) -> dict[str, float]:
        d = self.data
        out: dict[str, float] = {}
        for p, site in self.point_sites.items():
            out[f"x_{p}"], out[f"y_{p}"] = float(d.site_xpos[site, 0]), float(d.site_xpos[site, 1])
        phi = dict(zip(self.linkage.moving_links, self.rotation @ d.qpos, strict=True))
        phi[GROUND] = 0.0
        for link in self.linkage.moving_links:
            out[f"phi_{link}"] = float(phi[link])
        for joint in self.linkage.joints:
            if joint.name in self.dof:
                out[f"q_{joint.name}"] = float(d.qpos[self.dof[joint.name]])
            else:
                out[f"q_{joint.name}"] = float(phi[joint.links[1]] - phi[joint.links[0]])
        return out

    # -- how settled ------------------------------------------------------------------
    def loop_violation(self) -> float:
        """Largest gap of a loop-closing joint, metres."""
        d = self.data
        return max((float(np.linalg.norm(d.efc_pos[rows])) for rows in self.loop_rows.values()),
                   default=0.0)

    def joint_velocity(self) -> float:
        """Largest joint speed as a point speed (hinges times the size), m/s."""
        return float(np.abs(self.data.qvel * self.weight).max(initial=0.0))

    def pose_drift(self, theta12: float | None = None, qpos: Array | None = None) -> float:
        """Largest difference of the simulated joints from ``qpos``, as a length (m)."""
        assert qpos is not None
        return float(np.abs((self.data.qpos - qpos) * self.weight).max(initial=0.0))
