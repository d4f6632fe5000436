"""Driven linkages in MuJoCo (the four-bar and slider-crank among them, as their linkage):
every driver follows its prescribed motion by forward simulation, and the forces are read at
the instant.

The model (:func:`.linkage_model.build_spec` with a clock) has a heavy clock hinge turning
at 1 rad/s, so its angle is the time t, 0 at the instant read; each driver's joint
equality is the polynomial q = q* + v·t + a·t²/2 of it, so the prescribed position,
speed and acceleration hold at every step and the equality's velocity error is zero on the
prescribed motion. Its force is the driver's effort Q, less the driven joint's armature
times MuJoCo's q̈ (:func:`.linkage_model.drive_armature`).

The run starts ``steps·dt`` before the instant at rest relative to the prescribed motion:
the analytic pose and joint velocities there (the analytic side prescribes the motion and
seeds the start, nothing more). The rules that judge the reading are both simulators'
(:mod:`mechcheck.sim_models.convergence`): the lead-in is doubled until two readings
agree, never through a pose whose condition number grows past ``LEAD_CONDITION_GROWTH``
times the instant's (or that does not assemble), then the time step is halved until two
readings agree. A massless link gets a fictitious mass and every reading is the massless
limit 2·F(k) − F(2k) of the model as built and one with twice the fictitious inertia.

Coulomb friction (:mod:`.linkage_friction`) is applied every step from the current
massless-limit reactions, on both models alike (:func:`read_drive`), with the senses of
the simulator's own joint velocities; viscous friction is MuJoCo's joint damping.
A static case with Coulomb friction is a quasi-static motion: the heavy settling
masses driven at :data:`QUASI_STATIC_SPEED` (rad/s or m/s) in each driver's
``sense``, without dampers (the analytic motion has no speed), extrapolated to no
fictitious inertia like any other.

Why the time step must be refined, not fixed: a soft constraint holds its force with a
violation ∝ R·f·(2·dt)² (R grows as the links touching it get lighter), and MuJoCo leaves
out the constraints' J̇·v, which the same stiffness makes up with a violation ∝ dt². The
pose error this makes is magnified near a dead point by the inverse transmission ratio
(the four-bar of exam Q3, driven at its rocker: the crank follows at 16 times the rocker's
angle; 3.7e-3 of the forces at dt = 2.5e-5 s with massless links at 1e-5 of the real
masses, 1.7e-5 at 1e-2, against ~1e-5 on ordinary cases, measured).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import mujoco
import numpy as np

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage_backends import quantity_units
from mechcheck.analytic.linkage_forces import LinkageResults
from mechcheck.analytic.linkage_kinematics import solve_pose
from mechcheck.analytic.solution import Solution
from mechcheck.analytic.values import GROUND
from mechcheck.sim_models.convergence import (
    Convergence,
    converge,
    converge_stretch,
    driven_verdict,
    inertia_correction,
    massless_limit,
    stretch_timestep,
)
from mechcheck.sim_models.diagnostics import RunDiagnostics
from mechcheck.sim_models.inertia import link_extent, real_inertial
from mechcheck.sim_models.linkage_motion import (
    Motion,
    at_first_driver,
    at_rest_reason,
    coulomb_joints,
    driven_motion,
    lead_limit,
    prescribed_motion,
    self_locking_note,
)
from mechcheck.sim_models.mujoco import _fast
from mechcheck.sim_models.mujoco.joint_kinds import builder_of
from mechcheck.sim_models.mujoco.linkage_friction import apply_friction, clear_friction
from mechcheck.sim_models.mujoco.linkage_mesh import pushing
from mechcheck.sim_models.mujoco.linkage_model import spanning_tree
from mechcheck.sim_models.mujoco.linkage_rig import LinkageRig, Snapshot
from mechcheck.sim_models.mujoco.model import INERTIA_FLOOR_FRACTION, Settings

#: Dynamics: first time step 2.5e-5 s (refined by halving). With dt = 1e-3 the
#: clock-driven torque was 2–4e-2 off (SIMULATORS.md): the soft constraint's time constant
#: 2·dt must be short against the motion. The driven joint gets an armature
#: (:data:`.model.DRIVE_ARMATURE_INERTIA`).
DYNAMIC = Settings(timestep=2.5e-5, masses="real", clock=True, drive_armature=True)
#: Quasi-static friction runs use the heavy settling masses (:data:`.model.SETTLE_MASS`).
QUASI_STATIC = Settings(timestep=1e-3, masses="settle", clock=True)
#: Driver speed of a quasi-static run, rad/s or m/s: the inertia forces of the 1 t links,
#: m·ω²·L ≈ 1e-4 N, stay ~1e-6 of the loads.
QUASI_STATIC_SPEED = 1e-3
#: Fixed-point passes at the final instant so that the friction loads match the reactions
#: they were computed from.
FINAL_FRICTION_PASSES = 5


def turns(case: Case, link: str) -> bool:
    """True when a link can rotate: a joint that turns (a revolute joint, a pin in a slot)
    lies on its path to the ground."""
    tree = spanning_tree(case.linkage)
    while link != GROUND:
        t = tree.parent_joint(link)
        if builder_of(t.joint).turns(t.joint):
            return True
        link = t.parent
    return False


def has_fictitious_inertia(case: Case, settings: Settings) -> bool:
    """True when a moving body has inertia the Case does not (see
    :func:`.linkage_model.model_inertial`); a body that cannot turn may have any inertia."""
    if settings.masses == "settle":
        return True
    for link in case.linkage.moving_links:
        real = real_inertial(case.linkage, link)
        if real is None:
            return True
        floor = INERTIA_FLOOR_FRACTION * real.mass * link_extent(case.linkage, link) ** 2
        if real.inertia < floor and turns(case, link):
            return True
    return False


@dataclass(frozen=True)
class LinkageRigs:
    """The model as built and, with fictitious inertia, one with twice of it."""

    base: LinkageRig
    doubled: LinkageRig | None = None

    @property
    def members(self) -> tuple[LinkageRig, ...]:
        return (self.base,) if self.doubled is None else (self.base, self.doubled)

    @property
    def runs(self) -> int:
        return len(self.members)


def driven_rigs(case: Case, motion: Motion) -> LinkageRigs:
    settings = QUASI_STATIC if motion.quasi_static else DYNAMIC
    rigs = [LinkageRig(case, settings)]
    if has_fictitious_inertia(case, settings):
        rigs.append(LinkageRig(case, replace(settings, fictitious_scale=2.0)))
    for rig in rigs:
        if motion.quasi_static:
            rig.without_viscous()
        for k, driver in enumerate(case.linkage.drivers):
            eq = rig.drive_eq[driver.joint]
            rig.model.eq_data[eq, :3] = (motion.value[k], motion.velocity[k],
                                         0.5 * motion.acceleration[k])
    return LinkageRigs(rigs[0], rigs[1] if len(rigs) > 1 else None)


def start_run(rig: LinkageRig, motion: Motion, steps: int, dt: float) -> None:
    """At t = −steps·dt on the prescribed motion: the analytic pose and joint velocities
    there, the clock at that time and turning at 1 rad/s."""
    m, d = rig.model, rig.data
    mujoco.mj_resetData(m, d)
    rig.set_timestep(dt)
    clear_friction(rig)
    t0 = -steps * dt
    values, velocities, accelerations = motion.at(np.array([t0]))
    pose = solve_pose(rig.linkage, values, velocities, accelerations)
    qpos, qvel, _ = rig.joint_states(pose)
    assert rig.clock is not None
    qpos[0, rig.clock], qvel[0, rig.clock] = t0, 1.0
    rig.set_state(qpos[0], qvel[0])


def forward(rig: LinkageRig) -> None:
    """A forward pass with the loads at the current positions."""
    m, d = rig.model, rig.data
    mujoco.mj_kinematics(m, d)
    rig.apply_loads()
    mujoco.mj_forward(m, d)


def massless_reading(rigs: LinkageRigs) -> dict[str, float]:
    """The current values of the models, free of fictitious inertia."""
    values = rigs.base.read()
    if rigs.doubled is None:
        return values
    return massless_limit(values, rigs.doubled.read(), rigs.base.units)


def massless_reactions(rigs: LinkageRigs) -> dict[str, float]:
    """The efforts and reactions alone, free of fictitious inertia: what a step's friction
    needs (:meth:`.linkage_rig.LinkageRig.reactions`)."""
    values = rigs.base.reactions()
    if rigs.doubled is None:
        return values
    return massless_limit(values, rigs.doubled.reactions(), rigs.base.units)


def with_friction(rigs: LinkageRigs,
                  reading: Callable[[LinkageRigs], dict[str, float]] = massless_reading
                  ) -> dict[str, float]:
    """Read the massless limit (``reading``: everything, or at every step the reactions
    alone) and set the friction it gives on every model, with the senses of MuJoCo's own
    joint velocities; returns the reading."""
    values = reading(rigs)
    rates = rigs.base.joint_rates(rigs.base.data.qvel)
    for rig in rigs.members:
        apply_friction(rig, values, rates)
    return values


def read_drive(rigs: LinkageRigs, motion: Motion, steps: int, dt: float,
               friction: bool) -> dict[str, float]:
    """Simulate to the instant and return the values there, free of fictitious inertia:
    the models run in step and share the friction of the extrapolated reactions, so they
    differ by their inertia alone."""
    for rig in rigs.members:
        start_run(rig, motion, steps, dt)
    run_steps(rigs, steps, friction)
    return read_instant(rigs, friction)


def run_steps(rigs: LinkageRigs, steps: int, friction: bool,
              loads: list[PointLoads] | None = None) -> None:
    """Step the models in lockstep, each step's friction from the massless-limit reactions;
    ``loads``: each model's loads applied by :class:`PointLoads` (else by the rig)."""
    for _ in range(steps):
        for k, rig in enumerate(rigs.members):
            if loads is None:
                forward(rig)
            else:
                loaded_forward(rig, loads[k])
        if friction:
            with_friction(rigs, massless_reactions)
        for rig in rigs.members:
            mujoco.mj_Euler(rig.model, rig.data)


class PointLoads:
    """A rig's xfrc_applied at its current pose when it is the loads and the friction alone
    (:meth:`.linkage_loads.RigLoads.wrenches` without a gear mesh, a carried force or a
    closure's damper, :func:`plain`), summed per body by ``bincount``: a long run applies it
    at every step, where the general path's small-array calls cost three times MuJoCo's
    forward pass. The same sums, in another order (rounding apart)."""

    def __init__(self, rig: LinkageRig) -> None:
        table = rig.loads
        self.sites, self.bodies = table.sites, table.bodies
        self.fx, self.fy = table.forces[:, 0].copy(), table.forces[:, 1].copy()
        self.torques = np.asarray(table.torques, dtype=float)
        self.base = np.zeros((rig.model.nbody, 6))
        self.base[:, 0:3] = rig.body_forces

    def apply(self, rig: LinkageRig) -> None:
        d = rig.data
        wrench = self.base + rig.extra
        if self.sites.size:
            arm = d.site_xpos[self.sites] - d.xipos[self.bodies]
            moment = arm[:, 0] * self.fy - arm[:, 1] * self.fx + self.torques
            wrench[:, 5] += np.bincount(self.bodies, moment, minlength=len(wrench))
        d.xfrc_applied[:] = wrench


def plain(rig: LinkageRig) -> bool:
    """The rig's loads are the point loads and the friction alone (:class:`PointLoads`)."""
    return not (rig.meshes or rig.carried.any() or (rig.closure_damping and rig.viscous))


def read_instant(rigs: LinkageRigs, friction: bool) -> dict[str, float]:
    """The values at the models' current state, free of fictitious inertia; with friction,
    after :data:`FINAL_FRICTION_PASSES` passes that match it to the reactions."""
    values: dict[str, float] = {}
    for _ in range(FINAL_FRICTION_PASSES if friction else 1):
        for rig in rigs.members:
            forward(rig)
        values = with_friction(rigs) if friction else massless_reading(rigs)
    return values


#: What a continuous run measured at a pose, besides its values, by name (the diagnostics
#: of :func:`stretch_solution`).
Measured = dict[str, float]


def read_stretch(rigs: LinkageRigs, motion: Motion, lead: int, dt: float, interval: float,
                 poses: int, friction: bool, reference: np.ndarray
                 ) -> list[tuple[dict[str, float], Measured]]:
    """One run through ``poses`` poses ``interval`` seconds apart, the first after ``lead``
    steps of ``dt``: each pose's values (as :func:`read_drive`) read at the step that
    reaches it, and what the run measured there (steps so far, the clock's speed error,
    the loop's gap, the pose's distance from the analytic ``reference`` qpos)."""
    per_pose = round(interval / dt)
    steps = np.full(poses, per_pose, dtype=np.int64)
    steps[0] = lead
    if not friction and all(map(plain, rigs.members)):
        return plain_readings(rigs, motion, dt, steps, reference)
    for rig in rigs.members:
        start_run(rig, motion, lead, dt)
    base = rigs.base
    loads = [PointLoads(rig) for rig in rigs.members] if all(map(plain, rigs.members)) else None
    out = []
    for k, done in enumerate(np.cumsum(steps).tolist()):
        run_steps(rigs, int(steps[k]), friction, loads)
        values = read_instant(rigs, friction)
        out.append((values, measured(rigs, values, done, base.data.qvel,
                                     base.loop_violation(), base.data.qpos, reference[k],
                                     base.read)))
    return out


def measured(rigs: LinkageRigs, values: dict[str, float], steps: int, qvel: np.ndarray,
             gap: float, qpos: np.ndarray, reference: np.ndarray,
             base_values: Callable[[], dict[str, float]]) -> Measured:
    """What a continuous run measured at a pose: its steps so far, the clock's speed error,
    the loop's gap, the pose's distance from the analytic ``reference`` qpos, the
    fictitious inertia the massless limit ``values`` removed from the base model's
    reading (``base_values()``)."""
    base = rigs.base
    assert base.clock is not None
    return {"steps": float(steps),
            "residual_velocity": abs(float(qvel[base.clock]) - 1.0),
            "loop_violation": gap,
            "pose_drift": turned_drift(base, qpos, reference),
            "fictitious_inertia_correction": (inertia_correction(base_values(), values,
                                                                 base.scale, base.units)
                                              if rigs.doubled is not None else 0.0)}


def plain_readings(rigs: LinkageRigs, motion: Motion, dt: float, steps: np.ndarray,
                   reference: np.ndarray) -> list[tuple[dict[str, float], Measured]]:
    """:func:`read_stretch` of models whose loads are :class:`PointLoads` and no Coulomb
    friction: the models do not share anything, so each runs the whole stretch on its own
    (:func:`plain_stretch`), capturing MuJoCo's arrays at each pose, and the read-out reads
    every pose at once."""
    base = rigs.base
    snaps = [plain_stretch(rig, motion, dt, steps) for rig in rigs.members]
    columns = [rig.values(snap) for rig, snap in zip(rigs.members, snaps, strict=True)]
    gaps = base.loop_gaps(snaps[0].efc_pos)
    out = []
    for k, done in enumerate(np.cumsum(steps).tolist()):
        read = [{q: float(column[q][k]) for q in column} for column in columns]
        values = (read[0] if rigs.doubled is None
                  else massless_limit(read[0], read[1], base.units))
        out.append((values, measured(rigs, values, done, snaps[0].qvel[k],
                                     float(gaps[k]), snaps[0].qpos[k], reference[k],
                                     read[0].copy)))
    return out


def plain_stretch(rig: LinkageRig, motion: Motion, dt: float, steps: np.ndarray) -> Snapshot:
    """One model's run from ``steps[0]·dt`` before the instant, read after each ``steps[k]``
    steps: MuJoCo's arrays at each reading (:meth:`.linkage_readout.RigReadout.capture`).
    Compiled where it can be (:func:`._fast.drive`: the same calls, the same numbers)."""
    snapshot = rig.snapshot(len(steps))
    loads = PointLoads(rig)
    start_run(rig, motion, int(steps[0]), dt)
    if _fast.drive(rig, loads, steps, snapshot):
        return snapshot
    start_run(rig, motion, int(steps[0]), dt)
    m, d = rig.model, rig.data
    for k, count in enumerate(steps.tolist()):
        for _ in range(count):
            loaded_forward(rig, loads)
            mujoco.mj_Euler(m, d)
        loaded_forward(rig, loads)
        mujoco.mj_rnePostConstraint(m, d)
        rig.capture(snapshot, k)
    return snapshot


def loaded_forward(rig: LinkageRig, loads: PointLoads) -> None:
    """A forward pass with ``loads`` at the current positions: MuJoCo's position stage
    (the kinematics among it), the loads from the positions it found, the rest of the pass
    (the loads enter only after the position stage)."""
    m, d = rig.model, rig.data
    mujoco.mj_fwdPosition(m, d)
    loads.apply(rig)
    mujoco.mj_forwardSkip(m, d, mujoco.mjtStage.mjSTAGE_POS, 0)


def turned_drift(rig: LinkageRig, qpos: np.ndarray, reference: np.ndarray) -> float:
    """:meth:`.linkage_build.LinkageRig.pose_drift` of ``qpos`` from ``reference`` with every
    hinge's difference taken modulo a turn: a continuous run's hinges count the turns it
    has made."""
    gap = qpos - reference
    turning = rig.hinge[rig.model.dof_jntid]
    gap = np.where(turning, np.remainder(gap + np.pi, 2.0 * np.pi) - np.pi, gap)
    return float(np.abs(gap * rig.weight).max(initial=0.0))


def drive_stretch(case: Case, values: np.ndarray, results: LinkageResults
                  ) -> list[Solution] | None:
    """The ``mujoco`` backend at the poses ``values`` of a continuous sweep (the case at the
    first, turning at constant speed; ``results`` their analytic analysis): one run read at
    each pose as it passes (:func:`read_stretch`), judged by
    :func:`~mechcheck.sim_models.convergence.converge_stretch`. None where the poses are to
    be run one by one: a gear mesh (its side is chosen per run), a Coulomb joint at rest or
    reversing at a pose, or a lead-in that does not converge."""
    start = time.perf_counter()
    # The Coulomb joints do not depend on the driver's value: a case without any needs no
    # case per pose to ask.
    if coulomb_joints(case) and any(at_rest_reason(at_first_driver(case, v), DYNAMIC.timestep)
                                    for v in values):
        return None
    motion = prescribed_motion(case)
    rigs = driven_rigs(case, motion)
    if rigs.base.meshes:
        return None
    friction = case.has_coulomb_friction
    interval = abs(float(values[1] - values[0]) / float(motion.velocity[0]))
    reference = rigs.base.joint_states(results.pose)[0]

    def read(lead: int, dt: float, poses: int) -> list[tuple[dict[str, float], dict[str, float]]]:
        return read_stretch(rigs, motion, lead, dt, interval, poses, friction, reference)

    outs = converge_stretch(read, lead_limit(case, motion, float(results.condition[0])),
                            stretch_timestep(DYNAMIC.timestep, interval), rigs.base.scale,
                            rigs.runs, len(values), rigs.base.units)
    if outs is None:
        return None
    share = (time.perf_counter() - start) / len(values)
    return [stretch_solution(case, rigs, out, results.take(np.array([k])), share)
            for k, out in enumerate(outs)]


def stretch_solution(case: Case, rigs: LinkageRigs, out: Convergence, results: LinkageResults,
                     share: float) -> Solution:
    """A pose of a continuous run with its diagnostics (those of :func:`driven_solution`,
    measured at the step that reached it)."""
    run = out.run
    units = rigs.base.units or {}
    diagnostics = RunDiagnostics(
        "driven", out.total_steps, share, run["residual_velocity"], run["loop_violation"],
        run["pose_drift"],
    ).as_dict(lead_disagreement=out.lead_disagreement, lead_steps=out.lead_steps,
              timestep=out.dt, timestep_disagreement=out.timestep_disagreement,
              fictitious_runs=rigs.runs,
              fictitious_inertia_correction=run["fictitious_inertia_correction"])
    return driven_verdict(case.name, "mujoco", out, diagnostics, units, case.linkage.scale,
                          lambda: out.verdict() + self_locking_note(results))


def drive_linkage(case: Case, results: LinkageResults) -> Solution:
    """The ``mujoco`` backend for a driven linkage, or a static one with Coulomb friction
    (method ``driven``); ``results`` is the analytic pose analysis (verdicts, the instant's
    condition number)."""
    start = time.perf_counter()
    at_rest = at_rest_reason(case, DYNAMIC.timestep)
    if at_rest:
        return Solution(case.name, "mujoco", {}, status="indeterminate", message=at_rest,
                        diagnostics={"method": "driven"}, units=quantity_units(case.linkage))
    motion = driven_motion(case, QUASI_STATIC_SPEED)
    rigs = driven_rigs(case, motion)
    friction = case.has_coulomb_friction
    units = rigs.base.units

    def read(steps: int, dt: float) -> dict[str, float]:
        # A gear mesh's tendon on the side of its line of action where it pushes.
        return pushing([rig.meshes for rig in rigs.members],
                       lambda: read_drive(rigs, motion, steps, dt, friction), lambda v: v)

    limit = lead_limit(case, motion, float(results.condition[0]))
    out = converge(read, limit, rigs.base.settings.timestep, rigs.base.scale, rigs.runs, units)
    return driven_solution(case, rigs, out, results, time.perf_counter() - start)


def driven_solution(case: Case, rigs: LinkageRigs, out: Convergence, results: LinkageResults,
                    elapsed: float) -> Solution:
    """The reading with its diagnostics; the pose drift is the last run's pose at the instant
    against the analytic one (the same rule as pymunk's: a run that left its assembly gives
    no forces)."""
    rig = rigs.base
    units = rig.units or {}
    diagnostics = RunDiagnostics(
        "driven", out.total_steps, elapsed,
        abs(float(rig.data.qvel[rig.clock]) - 1.0) if rig.clock is not None else 0.0,
        rig.loop_violation(), rig.pose_drift(qpos=rig.joint_states(results.pose)[0][0]),
    ).as_dict(lead_disagreement=out.lead_disagreement, lead_steps=out.lead_steps,
              timestep=out.dt, timestep_disagreement=out.timestep_disagreement,
              fictitious_runs=rigs.runs, fictitious_inertia_correction=(
                  inertia_correction(rig.read(), out.values, rig.scale, units)
                  if rigs.doubled is not None else 0.0))
    return driven_verdict(case.name, "mujoco", out, diagnostics, units, case.linkage.scale,
                          lambda: out.verdict() + self_locking_note(results))
