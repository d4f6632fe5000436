"""Loads into a linkage's MuJoCo model (:class:`RigLoads`): the loads and weights, the
emulated friction and the closures' dampers as xfrc_applied at the current pose, and the
carried constraint forces (:mod:`.settle`, why: :mod:`.rig`) — each connect's force as an
equal and opposite pair at its two sites, each driver's effort as ``qfrc_applied`` on its
joint.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from mechcheck.analytic.case import Case
from mechcheck.analytic.values import GROUND
from mechcheck.sim_models.mujoco import _fast
from mechcheck.sim_models.mujoco.linkage_build import RigModel
from mechcheck.sim_models.mujoco.linkage_members import far_share, far_site
from mechcheck.sim_models.mujoco.model import STATIC, Settings
from mechcheck.sim_models.mujoco.rig import LoadTable, cross_z, load_wrenches, rows_times

Array = NDArray[np.float64]


@dataclass(frozen=True)
class CarriedPairs:
    """The sites where carried connect forces act (see :meth:`LinkageRig.apply_carried`)."""

    sites: NDArray[np.int_]
    bodies: NDArray[np.int_]
    signs: Array
    rows: NDArray[np.int_]
    incidence: Array



class RigLoads(RigModel):
    """A rig's loads: the load table, and the constraint forces carried as loads."""

    def __init__(self, case: Case, settings: Settings = STATIC,
                 customize: Callable[[mujoco.MjSpec], None] | None = None) -> None:
        super().__init__(case, settings, customize)
        self.loads = self._load_table()
        self.incidence = np.zeros((self.model.nbody, self.loads.sites.size))
        self.incidence[self.loads.bodies, np.arange(self.loads.sites.size)] = 1.0
        self.body_forces = self.incidence @ self.loads.forces
        self.pairs = self._carried_layout()

    def _load_table(self) -> LoadTable:
        """The loads plus the weights m·g of the real masses (never fictitious ones); loads
        on the ground do nothing and are left out."""
        lk = self.linkage
        rows: list[tuple[int, int, tuple[float, float, float], float]] = []
        for i, load in enumerate(lk.loads):
            if load.link != GROUND:
                rows += self._load_rows(f"load{i}", load.link, load.at,
                                        (load.force[0], load.force[1], 0.0), load.torque)
        if lk.gravity != (0.0, 0.0):
            for i, mass in enumerate(lk.masses):
                if mass.link != GROUND:
                    rows += self._load_rows(f"weight{i}", mass.link, mass.com,
                                            (mass.mass * lk.gravity[0], mass.mass * lk.gravity[1],
                                             0.0), 0.0)
        return LoadTable(np.array([r[0] for r in rows], dtype=int),
                         np.array([r[1] for r in rows], dtype=int),
                         np.array([r[2] for r in rows], dtype=float).reshape(-1, 3),
                         np.array([r[3] for r in rows], dtype=float))

    def _load_rows(self, site: str, link: str, at: tuple[float, float],
                   force: tuple[float, float, float], torque: float
                   ) -> list[tuple[int, int, tuple[float, float, float], float]]:
        """A load's rows (site, body, force, couple): one, or on a split member its shares
        on the near and far bodies (:func:`.linkage_members.far_share`)."""
        parts = [(site, 1.0)]
        if link in self.member_ends:
            t = far_share(*self.member_ends[link], at)
            parts = [(site, 1.0 - t), (far_site(site), t)]
        out = []
        for name, share in parts:
            found = self._id(mujoco.mjtObj.mjOBJ_SITE, name)
            out.append((found, int(self.model.site_bodyid[found]),
                        (share * force[0], share * force[1], share * force[2]), share * torque))
        return out

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
                    bodies.append(int(self.model.site_bodyid[site]))
                    signs.append(sign)
                    rows.append(eq_rows)
        incidence = np.zeros((self.model.nbody, len(sites)))
        incidence[bodies, np.arange(len(sites))] = 1.0
        return CarriedPairs(np.array(sites, dtype=int), np.array(bodies, dtype=int),
                            np.array(signs), np.array(rows, dtype=int).reshape(-1, 3),
                            incidence)

    def apply_loads(self) -> None:
        """xfrc_applied from the current pose (:meth:`wrenches`), and the carried forces;
        first the gear meshes' tendons back on their lines of action (after MuJoCo's
        kinematics, which every caller has just run)."""
        d = self.data
        if self.meshes:
            self.aim_meshes()
        d.xfrc_applied[:] = self.wrenches(d.site_xpos[None], d.xipos[None], d.qvel[None])[0]
        if self.carried.any():
            self.apply_carried()
            self.apply_carried_meshes()

    def apply_carried_meshes(self) -> None:
        """Each gear mesh's carried tendon force as its pair: along the tendon on gear b's
        site, opposite on gear a's (where :meth:`aim_meshes` has just put them)."""
        m, d = self.model, self.data
        for mesh, row in zip(self.meshes, self.mesh_rows, strict=True):
            ends = [d.xpos[b] + d.xmat[b].reshape(3, 3) @ m.site_pos[s]
                    for s, b in zip(mesh.sites, mesh.bodies, strict=True)]
            u = (ends[1] - ends[0]) / np.linalg.norm(ends[1] - ends[0])
            for end, body, sign in zip(ends, mesh.bodies, (-1.0, 1.0), strict=True):
                if body:
                    force = sign * self.carried[row] * u
                    d.xfrc_applied[body, 0:3] += force
                    d.xfrc_applied[body, 5] += float(cross_z((end - d.xipos[body])[None], force[None])[0])

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
        carried = factor * self.data.efc_force[:self.nefc]
        # A member's equality is its spring (:mod:`.linkage_members`): its force is the
        # member's own at every pass, never a load.
        carried[self.member_rows] = 0.0
        self.carried = self.carried + carried

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

    def constraint_forces(self) -> Array:
        """The equality forces, carried ones included, drivers' torques as forces."""
        return self.total_constraint_forces() * self.efc_scale
