"""The ``mujoco`` backend for moving cases: drive the input through the
prescribed motion by forward simulation and read the forces at θ12.

A heavy "clock" hinge (armature :data:`~.model.CLOCK_ARMATURE`) carries the
prescribed motion φ(t) = θ12(t) − θ12*; a joint equality ties the driven link
to it — the crank as θ12 = θ12* + φ, or for ``drive_link = 4`` the rocker as
θ14 = p(φ), the analytic θ14(θ12* + φ) expanded to second order about the
clock's angle at every step (:func:`coupling_table`; the motion is still
prescribed through θ12). The equality's force is then the drive torque on that
link (less the driven hinge's armature torque, see
:data:`~.model.DRIVE_ARMATURE_INERTIA`), and the reactions come from cfrc_int
as in statics.

The run starts T before the instant with the analytic pose and velocities of
θ12(−T) (a consistent seed) and ends exactly at t = 0. Two numerical errors
separate the answer from the rigid motion, and each is driven below its
threshold by a convergence check, never by a fixed setting:

- the soft constraints' start-up transient: the run is repeated with twice
  the lead time until two answers agree within :data:`~mechcheck.sim_models.convergence.LEAD_AGREEMENT_RTOL`.
  The lead-in may not pass a pose whose condition number exceeds
  :data:`LEAD_CONDITION_GROWTH` times the instant's — a change point, or for a
  rocker drive a rocker dead point, where the driven link cannot move the
  crank and the crank's sense is undetermined;
- the time discretisation: a soft constraint holds its force with a violation
  ∝ R·f·(2·dt)² (R grows as the links touching it get lighter: massless links
  carry only a fictitious fraction of the real masses), and MuJoCo leaves out the
  constraints' J̇·v, which the same stiffness makes up with a violation ∝ dt².
  The pose error this makes is magnified by the inverse transmission ratio
  near a dead point (exam Q3: the crank follows the rocker at
  1/|dθ14/dθ12| = 16 times its angle; 3.7e-3 of the forces at dt = 2.5e-5 s
  with massless links at 1e-5 of the real masses, 1.7e-5 at 1e-2, against
  ~1e-5 on ordinary cases). The run is repeated with half the step
  (and as many lead steps) until two answers agree within
  :data:`~mechcheck.sim_models.convergence.TIMESTEP_AGREEMENT_RTOL`.

Friction (:mod:`.friction`) is emulated from the current reactions every step
with the senses of the simulator's own joint velocities. A static friction case
is a quasi-static motion: heavy fictitious links driven at
:data:`QUASI_STATIC_SPEED` in the stated sense.

Fictitious inertia. MuJoCo refuses massless moving bodies, so a massless link
gets :data:`~.model.FICTITIOUS_MASS_FRACTION` of the real masses, and every
link of a quasi-static run :data:`~.model.SETTLE_MASS`; their inertia forces
were reported as reactions (3e-3 of the force floor on an unloaded massless
four-bar, 1.6e-2 on an unloaded quasi-static slider-crank). The motion is
prescribed by the clock, so it does not depend on the masses, and the
reactions, the solution of Jᵀλ = M(k)·q̈ + c(k) − loads, are affine in the
fictitious inertia k: F(k) = F₀ + k·G. Every reading of such a model is
therefore the same drive run on the model as built and on one with twice the
fictitious inertia (:func:`driven_rigs`), reported as F₀ = 2·F(k) − F(2k)
(:func:`massless_limit`), and the convergence checks below judge that
extrapolated reading. The pin moments μ·r·|F| are not linear in k, so the two
models run in step and both take their friction from the extrapolated
reactions (:func:`read_drive`): friction is then the same load on both and the
extrapolation stays exact. The
driven hinge's armature is no fictitious inertia: it is subtracted exactly
(:meth:`.rig.Rig.read`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import mujoco
import numpy as np

from mechcheck.analytic.case import Case
from mechcheck.analytic.equilibrium import condition
from mechcheck.analytic.kinematics import pose_of
from mechcheck.analytic.solution import Solution, quantity_kind
from mechcheck.sim_models.convergence import (
    LEAD_AGREEMENT_RTOL,
    LEAD_CONDITION_GROWTH,
    Convergence,
    halve_timestep,
    lengthen_lead,
    massless_limit,
)
from mechcheck.sim_models.diagnostics import RunDiagnostics
from mechcheck.sim_models.mujoco.friction import friction_loads, relative_speeds
from mechcheck.sim_models.mujoco.model import Settings, has_fictitious_inertia
from mechcheck.sim_models.mujoco.rig import Rig

#: Dynamics: first time step 2.5e-5 s (refined by halving, see the module doc).
#: With dt = 1e-3 the clock-driven torque was 2–4e-2 off (SIMULATORS.md): the
#: soft constraint's time constant 2·dt must be short against the motion. The
#: driven hinge gets an armature (model.DRIVE_ARMATURE_INERTIA).
DYNAMIC = Settings(timestep=2.5e-5, masses="real", clock=True, drive_armature=True)
#: Quasi-static friction runs use the heavy settling masses (see model.SETTLE_MASS).
QUASI_STATIC = Settings(timestep=1e-3, masses="settle", clock=True)
#: Input speed of a quasi-static run, rad/s: the inertia forces of the 1 t
#: links, m·ω²·L ≈ 1e-4 N, stay ~1e-6 of the loads.
QUASI_STATIC_SPEED = 1e-3

#: Fixed-point passes at the final instant so that the friction couples match
#: the reactions they were computed from.
FINAL_FRICTION_PASSES = 5


@dataclass(frozen=True)
class Drive:
    """The prescribed input motion: at the instant, θ12*, ω, α; lead time T."""

    theta12: float
    omega: float
    alpha: float
    steps: int
    dt: float

    @property
    def lead(self) -> float:
        return self.steps * self.dt

    def start_speed(self) -> float:
        return self.omega - self.alpha * self.lead

    def clock_angles(self) -> np.ndarray:
        """φ at each of the ``steps + 1`` forward passes, as MuJoCo's semi-implicit
        Euler integration of the clock produces them (speed first, then angle),
        ending exactly on φ = 0."""
        k = np.arange(1, self.steps + 1)
        speeds = self.start_speed() + k * self.alpha * self.dt
        phi = np.concatenate([[0.0], np.cumsum(speeds * self.dt)])
        return phi - phi[-1]

    def start_offset(self) -> float:
        """φ at the start (see :meth:`clock_angles`)."""
        return float(self.clock_angles()[0])


def coupling_table(case: Case, drive: Drive) -> np.ndarray:
    """The drive equality's polynomial (ascending coefficients φ⁰…φ⁴) at every
    forward pass of the run, shape (steps + 1, 5).

    For the crank it is θ12 = θ12* + φ throughout. For the rocker it is the
    analytic θ14(θ12* + φ) expanded to second order about the clock's angle φ_k
    at that pass, so the rocker's prescribed position, speed and acceleration
    are exact at every step (not only at the instant). A single quartic fitted
    over the lead-in started runs with a violation of the drive equality:
    1.8e-5 rad for exam Q3's 1600-step lead-in, 0.16 rad for
    fourbar-dynamic-drive4's 800-step one, whose fitting range reached a rocker
    dead point (measured).
    """
    phi = drive.clock_angles()
    table = np.zeros((phi.size, 5))
    if case.drive_link == 2:
        table[:, 0] = drive.theta12
        table[:, 1] = 1.0
        return table
    rocker = pose_of(case, drive.theta12 + phi, omega=1.0, alpha=0.0).links[4]
    value, slope, half_curvature = rocker.angle, rocker.omega, 0.5 * rocker.alpha
    table[:, 0] = value - slope * phi + half_curvature * phi**2
    table[:, 1] = slope - 2.0 * half_curvature * phi
    table[:, 2] = half_curvature
    return table


def lead_in_condition(case: Case, drive: Drive) -> tuple[float, float]:
    """(largest condition number, θ12 where it occurs) over the run's lead-in."""
    theta = drive.theta12 + drive.clock_angles()
    cond = condition(case, pose_of(case, theta))
    cond = np.where(np.isfinite(cond), cond, np.inf)
    worst = int(np.argmax(cond))
    return float(cond[worst]), float(theta[worst])


def start_run(rig: Rig, drive: Drive) -> None:
    """Seed the analytic state at θ12(−T) and set the clock going."""
    m, d = rig.model, rig.data
    mujoco.mj_resetData(m, d)
    rig.set_timestep(drive.dt)
    rig.set_extra(np.zeros(m.nbody), np.zeros((m.nbody, 3)))  # no friction left from a last run
    phi0 = drive.start_offset()
    qpos, qvel, _ = rig.qpos_at(drive.theta12 + phi0, drive.start_speed(), drive.alpha)
    rig.set_state(qpos, qvel)
    clock = rig.layout.qpos["clock"]
    d.qpos[clock] = phi0
    d.qvel[clock] = drive.start_speed()
    # The clock's own inertia times α keeps it on the prescribed acceleration.
    d.qfrc_applied[clock] = m.dof_armature[clock] * drive.alpha


def forward(rig: Rig, coupling: np.ndarray) -> None:
    """A forward pass at the current state with the drive polynomial ``coupling``;
    the loads are placed at the current positions (mj_kinematics first: after
    mj_Euler the positions in mjData are still those before the step)."""
    m, d = rig.model, rig.data
    m.eq_data[rig.layout.drive_eq, :5] = coupling
    mujoco.mj_kinematics(m, d)
    rig.apply_loads()
    mujoco.mj_forward(m, d)


def apply_friction(rigs: DrivenRigs, values: dict[str, float]) -> None:
    """Friction couples from the reactions ``values`` and the simulator's own velocities,
    set on every model of the drive alike.

    In a quasi-static run Coulomb senses come from the actual (slow) velocities;
    viscous terms use them too, which is right for a real motion and negligible
    (c·1e-3) for a quasi-static one, whose analytic value has ω = 0.
    """
    rig = rigs.base
    qvel = rig.data.qvel[rig.joint_addresses()]
    speeds = relative_speeds(rig, qvel)
    viscous_speeds = speeds if rig.case.motion.omega or rig.case.motion.alpha else {
        k: 0.0 for k in speeds}
    loads = friction_loads(rig, values, speeds, viscous_speeds)
    for member in rigs.members:
        member.set_extra(*loads)


@dataclass(frozen=True)
class DrivenRigs:
    """The model as built (``base``) and, when it has inertia the Case does not,
    the same model with twice that fictitious inertia (``doubled``)."""

    base: Rig
    doubled: Rig | None = None

    @property
    def members(self) -> tuple[Rig, ...]:
        return (self.base,) if self.doubled is None else (self.base, self.doubled)

    @property
    def runs(self) -> int:
        """Simulator runs per reading."""
        return len(self.members)


def driven_rigs(case: Case) -> DrivenRigs:
    """The rigs a driven run of ``case`` (or of a case differing only in θ12) uses."""
    settings, _, _ = drive_motion(case)
    if not has_fictitious_inertia(case, settings):
        return DrivenRigs(Rig(case, settings))
    return DrivenRigs(Rig(case, settings), Rig(case, replace(settings, fictitious_scale=2.0)))


def massless_reading(rigs: DrivenRigs) -> dict[str, float]:
    """The current values of the models, free of fictitious inertia (see the module doc)."""
    values = rigs.base.read()
    return values if rigs.doubled is None else massless_limit(values, rigs.doubled.read())


def read_drive(rigs: DrivenRigs, drive: Drive, friction: bool) -> dict[str, float]:
    """Simulate to the instant and return the values there, free of fictitious inertia.

    The models run in step and friction on both comes from the massless-limit
    reactions: the two then differ by their inertia alone, so F₀ = 2·F(k) − F(2k)
    holds however large the fictitious part is. (Friction from each model's own
    reactions made it nonlinear in k: a massless slider-crank whose rod carries
    7.8 N of real load and 50 N of fictitious inertia read T12 5 % off.)
    """
    coupling = coupling_table(rigs.base.case, drive)
    for rig in rigs.members:
        start_run(rig, drive)
    for k in range(drive.steps):
        for rig in rigs.members:
            forward(rig, coupling[k])
        if friction:
            apply_friction(rigs, massless_reading(rigs))
        for rig in rigs.members:
            mujoco.mj_Euler(rig.model, rig.data)
    values: dict[str, float] = {}
    for _ in range(FINAL_FRICTION_PASSES if friction else 1):
        for rig in rigs.members:
            forward(rig, coupling[-1])
        values = massless_reading(rigs)
        if friction:
            apply_friction(rigs, values)
    return values


def drive_motion(case: Case) -> tuple[Settings, float, float]:
    """Model settings, ω and α of the run: the Case's motion, or a slow quasi-static
    one in friction.direction for a static friction case."""
    if case.motion.is_static:
        return QUASI_STATIC, case.input_sense * QUASI_STATIC_SPEED, 0.0
    return DYNAMIC, case.motion.omega, case.motion.alpha


def converge_lead(rigs: DrivenRigs, case: Case, omega: float, alpha: float,
                  dt: float) -> Convergence:
    """Double the lead time until the start-up transient has died (or may not grow)."""
    friction = case.has_friction
    instant = float(condition(case, pose_of(case, np.array([case.theta12])))[0])

    def read(steps: int, step: float) -> dict[str, float]:
        return read_drive(rigs, Drive(case.theta12, omega, alpha, steps, step), friction)

    def limit(steps: int, step: float) -> str:
        worst, where = lead_in_condition(case, Drive(case.theta12, omega, alpha, steps, step))
        if not worst <= LEAD_CONDITION_GROWTH * instant:
            return (f"a longer lead-in would pass θ12 = {np.degrees(where):.2f}°, "
                    f"condition number {worst:.3g} against {instant:.3g} at the instant "
                    "(a change point, or the rocker dead point of a rocker drive)")
        return ""

    return lengthen_lead(read, limit, dt, rigs.base.scale, rigs.runs)


def refine_timestep(rigs: DrivenRigs, case: Case, omega: float, alpha: float,
                    out: Convergence) -> Convergence:
    """Halve the time step until two runs agree, keeping the number of lead steps
    (:func:`halve_timestep`)."""

    def read(steps: int, dt: float) -> dict[str, float]:
        return read_drive(rigs, Drive(case.theta12, omega, alpha, steps, dt), case.has_friction)

    return halve_timestep(read, out, rigs.base.scale, rigs.runs)


def fictitious_correction(rigs: DrivenRigs, values: dict[str, float]) -> float:
    """The largest change the extrapolation made to the base run's last reading:
    the fictitious inertia removed, N (torques divided by the mechanism's scale)."""
    if rigs.doubled is None:
        return 0.0
    base, length = rigs.base.read(), rigs.base.scale
    return max(abs(base[q] - v) / (length if quantity_kind(q) == "torque" else 1.0)
               for q, v in values.items() if quantity_kind(q) != "pose")


def driven(case: Case, rigs: DrivenRigs | None = None) -> Solution:
    """The ``mujoco`` backend for a moving or friction case (method ``driven``).

    ``rigs`` (from :func:`driven_rigs` for a case differing only in θ12) are
    reused by sweeps.
    """
    start = time.perf_counter()
    settings, omega, alpha = drive_motion(case)
    rigs = rigs or driven_rigs(case)
    rig = rigs.base
    out = converge_lead(rigs, case, omega, alpha, settings.timestep)
    if out.lead_disagreement <= LEAD_AGREEMENT_RTOL:
        out = refine_timestep(rigs, case, omega, alpha, out)
    values = out.values
    diagnostics = RunDiagnostics(
        "driven", out.total_steps, time.perf_counter() - start,
        abs(float(rig.data.qvel[rig.layout.qpos["clock"]]) - omega), rig.loop_violation(),
        rig.pose_drift(case.theta12),
    ).as_dict(lead_disagreement=out.lead_disagreement, lead_steps=out.lead_steps,
              timestep=out.dt, timestep_disagreement=out.timestep_disagreement,
              fictitious_inertia_correction=fictitious_correction(rigs, values))
    if not out.converged:
        pose = {q: v for q, v in values.items() if quantity_kind(q) == "pose"}
        return Solution(case.name, "mujoco", pose, status="not_settled",
                        message=out.verdict(), diagnostics=diagnostics)
    return Solution(case.name, "mujoco", values, diagnostics=diagnostics)
