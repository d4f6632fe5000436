"""A compiled model with its data, and the three things every method does to it:
put it in a pose, apply the Case's loads, read the forces back.

Forces are read from MuJoCo's own state only:

- the drive torque is the force of the ``drive`` joint equality (its Jacobian
  row is +1 on the driven joint, so the force *is* the torque on that link);
- F34 is the force of the ``loop_B`` connect, whose first site is on link 4;
- F12, F23 and F14 (and M14 of a slider) come from ``cfrc_int`` after
  ``mj_rnePostConstraint``: the spatial force of the parent body on the child,
  whose moment MuJoCo refers to the subtree's centre of mass, shifted here to
  the joint point.

Carried constraint forces (settled statics, :mod:`.settle`). A soft constraint
holds a force f only with a violation r ∝ R·f (R its regulariser), so the
settled mechanism is bent by nanometres; next to a change point the forces are
so sensitive to the pose that this costs 2e-5 of them (seed E1 at θ12 = 179°,
condition number 119; the error grows as the cube of the condition number).
:meth:`Rig.carry` therefore moves the constraint forces of a settled state out
of the constraints into explicit loads — the loop force as an equal and
opposite pair at the two B sites (``xfrc_applied``, so ``cfrc_int`` sees it),
the holding torque on the held hinge (a joint torque, which is what a drive
is) — and the mechanism settles again: the constraints now hold only what is
left, and their violation, and the bending, shrink with it. Every reported
force is the carried part plus MuJoCo's current ``efc_force``.

A driven run may give the driven hinge an armature (:data:`.model.Settings`
``drive_armature``); its torque I_a·q̈ is then part of the equality's force
and is subtracted, with MuJoCo's own q̈, from the drive torque read here.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from mechcheck.analytic.case import Case
from mechcheck.analytic.kinematics import pose_of
from mechcheck.sim_models.mujoco.model import STATIC, Layout, Settings, compile_model

Array = NDArray[np.float64]


@dataclass
class LoadTable:
    """Every external load as arrays: site (point), body, global force, pure moment."""

    sites: NDArray[np.int_]
    bodies: NDArray[np.int_]
    forces: Array   # (k, 3)
    torques: Array  # (k,)


def load_table(case: Case, model: mujoco.MjModel, layout: Layout) -> LoadTable:
    """The Case's loads plus the weights m·g of the real masses (never the fictitious ones)."""
    sites, bodies, forces, torques = [], [], [], []
    for i, load in enumerate(case.loads):
        sites.append(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, f"load{i}"))
        bodies.append(layout.body[load.link])
        forces.append((load.force[0], load.force[1], 0.0))
        torques.append(load.torque)
    if case.gravity != (0.0, 0.0):
        for m in case.masses:
            sites.append(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SITE, f"weight{m.link}"))
            bodies.append(layout.body[m.link])
            forces.append((m.mass * case.gravity[0], m.mass * case.gravity[1], 0.0))
            torques.append(0.0)
    return LoadTable(np.array(sites, dtype=int), np.array(bodies, dtype=int),
                     np.array(forces, dtype=float).reshape(-1, 3), np.array(torques, dtype=float))


def cross_z(r: Array, f: Array) -> Array:
    """z-component of r × f for arrays of (.., ≥2) vectors."""
    return r[..., 0] * f[..., 1] - r[..., 1] * f[..., 0]


def parent_force(m: mujoco.MjModel, d: mujoco.MjData, body: int,
                 point: Array) -> tuple[Array, float]:
    """(force, moment about ``point``) of the parent body on ``body`` from cfrc_int (after
    mj_rnePostConstraint), whose moment MuJoCo refers to the centre of mass of the body's
    kinematic tree."""
    f = d.cfrc_int[body, 3:5]
    c = d.subtree_com[m.body_rootid[body], :2]
    return f.copy(), float(d.cfrc_int[body, 2] + cross_z(c - point, f))


def xfrc_of_loads(d: mujoco.MjData, loads: LoadTable, incidence: Array, body_forces: Array,
                  extra_torque: Array) -> None:
    """Write ``xfrc_applied``: each body's loads (``body_forces``, summed through
    ``incidence``) with their moments about its centre of mass from the current site
    positions, the loads' own couples and ``extra_torque``.

    MuJoCo applies xfrc_applied at the body's centre of mass, so a force at p carries
    the moment (p − x_com) × F. Loads given as qfrc_applied would be invisible to
    cfrc_int (SIMULATORS.md).
    """
    xfrc = d.xfrc_applied
    xfrc[:, 0:3] = body_forces
    xfrc[:, 3:5] = 0.0  # planar: no moments about x or y
    xfrc[:, 5] = extra_torque
    if loads.sites.size:
        arm = d.site_xpos[loads.sites] - d.xipos[loads.bodies]
        xfrc[:, 5] += incidence @ (cross_z(arm, loads.forces) + loads.torques)


class Rig:
    """One Case's compiled model and data, with loads, pose and force read-out."""

    def __init__(self, case: Case, settings: Settings = STATIC) -> None:
        self.case = case
        self.settings = settings
        self.model, self.layout = compile_model(case, settings)
        self.data = mujoco.MjData(self.model)
        self.loads = load_table(case, self.model, self.layout)
        self.four_bar = case.mechanism == "four_bar"
        self.output_joint = "B0" if self.four_bar else "slide"
        self.scale = case.geometry.scale
        self.units: dict[str, str] | None = None  # the four-bar's names carry their units
        # Body × load incidence: sums each load onto its body in one product.
        self.incidence = np.zeros((self.model.nbody, self.loads.sites.size))
        self.incidence[self.loads.bodies, np.arange(self.loads.sites.size)] = 1.0
        # Extra couples (friction) per body, and extra forces at pin B (slide friction).
        self.extra_torque = np.zeros(self.model.nbody)
        self.extra_force = np.zeros((self.model.nbody, 3))
        self.body_forces = self.incidence @ self.loads.forces
        self.efc_scale = self._efc_scale()
        self.drive_armature = settings.drive_armature_of(case)
        self.loop_rows = self.equality_rows(self.layout.loop_eq)
        self.drive_rows = self.equality_rows(self.layout.drive_eq)
        self.loop_sites = (mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_SITE, "B_on_4"),
                           mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_SITE, "B_on_3"))
        # Carried constraint forces: the loop force on link 4 (global x, y, z) and
        # the drive's torque, in the constraint rows' order (see the module doc).
        self.nefc = int(self.data.nefc)  # constant: equalities only, no contacts or limits
        self.carried = np.zeros(self.nefc)

    # -- pose -------------------------------------------------------------------
    def qpos_at(self, theta12: float, omega: float | None = None,
                alpha: float | None = None) -> tuple[Array, Array, Array]:
        """qpos, qvel, qacc of the mechanism's joints from the analytic kinematics
        (ω, α of link 2 default to the Case's motion).

        Used only to seed or prescribe the motion; forces are never taken from it.
        """
        q, v, a = self.states(np.array([theta12]), omega, alpha)
        return q[0], v[0], a[0]

    def states(self, theta12: Array, omega: float | None = None,
               alpha: float | None = None) -> tuple[Array, Array, Array]:
        """:meth:`qpos_at` vectorised over θ12: arrays of shape (N, 3)."""
        p = pose_of(self.case, theta12, omega=omega, alpha=alpha)
        l2, l3, l4 = p.links[2], p.links[3], p.links[4]
        if self.four_bar:
            out = (l4.angle, l4.omega, l4.alpha)
        else:
            assert p.s14 is not None and p.s14_dot is not None and p.s14_ddot is not None
            out = (p.s14, p.s14_dot, p.s14_ddot)
        q = np.stack([l2.angle, l3.angle - l2.angle, out[0]], axis=1)
        v = np.stack([l2.omega, l3.omega - l2.omega, out[1]], axis=1)
        a = np.stack([l2.alpha, l3.alpha - l2.alpha, out[2]], axis=1)
        return q, v, a

    def joint_addresses(self) -> list[int]:
        return [self.layout.qpos["A0"], self.layout.qpos["A"], self.layout.qpos[self.output_joint]]

    def set_state(self, qpos: Array, qvel: Array) -> None:
        idx = self.joint_addresses()
        self.data.qpos[idx] = qpos
        self.data.qvel[idx] = qvel

    def set_timestep(self, dt: float) -> None:
        """Change the time step at run time, with the constraints' time constant
        (2·dt unless the settings fix it; MuJoCo reads solref at every step)."""
        self.model.opt.timestep = dt
        if self.settings.solref_timeconst is None:
            self.model.eq_solref[:, 0] = 2.0 * dt

    def set_lock(self, target: float) -> None:
        """Hold the driven joint at ``target`` (rad) through the joint equality."""
        self.model.eq_data[self.layout.drive_eq, 0] = target

    # -- loads ------------------------------------------------------------------
    def apply_loads(self) -> None:
        """xfrc_applied from the current pose: each force at its body-fixed point
        (:func:`xfrc_of_loads`), and the slide friction's force at pin B."""
        d = self.data
        xfrc = d.xfrc_applied
        xfrc_of_loads(d, self.loads, self.incidence, self.body_forces, self.extra_torque)
        # Extra forces (slide friction) act at pin B, the slider's origin.
        b4 = self.layout.body[4]
        if self.extra_force[b4].any():
            xfrc[b4, 5] += cross_z(d.xpos[b4] - d.xipos[b4], self.extra_force[b4])
        if self.carried.any():
            self.apply_carried()

    # -- carried constraint forces ----------------------------------------------
    def reset_carried(self) -> None:
        """Nothing carried: the constraints hold every force themselves."""
        self.carried = np.zeros(self.nefc)
        self.data.qfrc_applied[self.layout.drive_dof] = 0.0

    def carry(self) -> None:
        """Add the constraint forces of the last forward pass to the carried ones."""
        self.carried = self.carried + self.data.efc_force[:self.nefc]

    def apply_carried(self) -> None:
        """The carried forces as loads: the loop pair at the B sites (moments about
        each centre of mass from the current positions), the drive torque on the
        held hinge. Only for a rig without a clock (the drive's row is then +1 on
        the held joint alone)."""
        assert not self.layout.clock, "carried forces are for held (clockless) rigs"
        d, body = self.data, self.layout.body
        f = self.carried[self.loop_rows]
        for b, site, sign in ((body[4], self.loop_sites[0], 1.0),
                              (body[3], self.loop_sites[1], -1.0)):
            d.xfrc_applied[b, 0:3] += sign * f
            d.xfrc_applied[b, 5] += sign * cross_z(d.site_xpos[site] - d.xipos[b], f)
        d.qfrc_applied[self.layout.drive_dof] = self.carried[self.drive_rows[0]]

    def total_constraint_forces(self) -> Array:
        """Carried plus current constraint forces, N (and N·m for the drive's row)."""
        return self.carried + self.data.efc_force[:self.nefc]

    def set_extra(self, torque: Array, force: Array) -> None:
        """Extra couples (per body, N·m) and slider forces (per body, N) on top of the loads."""
        self.extra_torque = torque
        self.extra_force = force
        self.body_forces = self.incidence @ self.loads.forces + force[:, 0:3]

    def constraint_forces(self) -> Array:
        """The equality forces, carried ones included, as one vector in N (the drive
        torque divided by the scale)."""
        return self.total_constraint_forces() * self.efc_scale

    # -- read-out ---------------------------------------------------------------
    def _efc_scale(self) -> Array:
        """1 for force rows, 1/scale for the drive's torque row (constant row layout)."""
        mujoco.mj_forward(self.model, self.data)
        scale = np.ones(self.data.nefc)
        scale[self.equality_rows(self.layout.drive_eq)] = 1.0 / self.scale
        return scale

    def equality_rows(self, eq_id: int) -> NDArray[np.int_]:
        d = self.data
        return np.flatnonzero((d.efc_type[:d.nefc] == mujoco.mjtConstraint.mjCNSTR_EQUALITY)
                              & (d.efc_id[:d.nefc] == eq_id))

    def parent_force(self, link: int, point: Array) -> tuple[Array, float]:
        """(force, moment about ``point``) of the parent body on ``link`` from cfrc_int."""
        return parent_force(self.model, self.data, self.layout.body[link], point)

    def read(self) -> dict[str, float]:
        """Every quantity from the current data (call after a forward pass)."""
        m, d = self.model, self.data
        mujoco.mj_rnePostConstraint(m, d)
        lay = self.layout
        q = d.qpos
        values = {"theta13": float(q[lay.qpos["A0"]] + q[lay.qpos["A"]])}
        f12, _ = self.parent_force(2, d.xpos[lay.body[2], :2])
        f23, _ = self.parent_force(3, d.xpos[lay.body[3], :2])
        total = self.total_constraint_forces()
        loop = total[self.loop_rows]
        f14, m14 = self.parent_force(4, d.xpos[lay.body[4], :2])
        # Slide friction is applied as an external force, but it is part of the
        # guide's reaction on the slider (F14 is the guide's whole force).
        f14 = f14 + self.extra_force[lay.body[4], :2]
        drive = total[self.drive_rows]
        values.update({"F12_x": f12[0], "F12_y": f12[1], "F23_x": f23[0], "F23_y": f23[1],
                       "F34_x": loop[0], "F34_y": loop[1], "F14_x": f14[0], "F14_y": f14[1]})
        if self.four_bar:
            values["theta14"] = float(q[lay.qpos["B0"]])
        else:
            values["s14"] = float(q[lay.qpos["slide"]])
            values["M14"] = m14
        dof = lay.drive_dof
        values[f"T1{self.case.drive_link}"] = float(drive[0] - self.drive_armature * d.qacc[dof])
        return {k: float(v) for k, v in values.items()}

    def loop_violation(self) -> float:
        """|B on link 3 − B on link 4|, metres."""
        return float(np.linalg.norm(self.data.efc_pos[self.equality_rows(self.layout.loop_eq)]))

    def joint_velocity(self) -> float:
        """Largest joint speed, as a point speed (rad/s × scale, m/s) — comparable across joints."""
        idx = self.joint_addresses()
        v = np.abs(self.data.qvel[idx])
        if not self.four_bar:
            v[2] /= self.scale
        return float(v.max() * self.scale)

    def pose_drift(self, theta12: float | None = None, qpos: Array | None = None) -> float:
        """Largest difference of the simulated pose from the analytic one (at
        ``theta12``, or given as joint coordinates ``qpos``), as a length (m).

        Angles are weighted by the mechanism's scale, the slider coordinate as is.
        """
        if qpos is None:
            assert theta12 is not None
            qpos, _, _ = self.qpos_at(theta12)
        q = qpos
        sim = self.data.qpos[self.joint_addresses()]
        diff = np.abs(sim - q)
        diff[:2] *= self.scale
        if self.four_bar:
            diff[2] *= self.scale
        return float(diff.max())
