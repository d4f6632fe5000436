"""The ``mujoco`` backend for moving cases: drive the input through the
prescribed motion by forward simulation and read the forces at θ12.

A heavy "clock" hinge (armature :data:`~.model.CLOCK_ARMATURE`) carries the
prescribed motion φ(t) = θ12(t) − θ12*; a joint equality ties the driven link
to it — the crank as θ12 = θ12* + φ, or for ``drive_link = 4`` the rocker as
θ14 = p(φ), a quartic fitted to the analytic θ14(θ12) over the run (the
motion is still prescribed through θ12). The equality's force is then the
drive torque on that link, and the reactions come from cfrc_int as in statics.

The run starts T before the instant with the analytic pose and velocities of
θ12(−T) (a consistent seed) and ends exactly at t = 0. Only the soft
constraints' start-up transient (a few time constants 2·dt) separates the
answer from the steady motion, so the run is repeated with twice the lead
time; it is accepted when the two answers agree within
:data:`LEAD_AGREEMENT_RTOL` (the transient has died), else the lead keeps
doubling up to :data:`MAX_LEAD_STEPS`. Leads stay short (0.1 rad at
ω = 10 rad/s) so that a run never sweeps through a change point.

Friction (:mod:`.friction`) is emulated from the current reactions every step
with the senses of the simulator's own joint velocities. A static friction case
is a quasi-static motion: heavy fictitious links driven at
:data:`QUASI_STATIC_SPEED` in the stated sense.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import mujoco
import numpy as np

from analytic.case import Case
from analytic.equilibrium import condition
from analytic.kinematics import pose_of
from analytic.solution import Solution, quantity_kind
from sim_models.mujoco.friction import friction_loads, relative_speeds
from sim_models.mujoco.model import Settings
from sim_models.mujoco.rig import Rig

#: Dynamics: 1e-4 s. With dt = 1e-3 the clock-driven torque was 2–4e-2 off
#: (SIMULATORS.md): the soft constraint's time constant 2·dt must be short
#: against the motion.
DYNAMIC = Settings(timestep=2.5e-5, masses="real", clock=True)
#: Quasi-static friction runs use the heavy settling masses (see model.SETTLE_MASS).
QUASI_STATIC = Settings(timestep=1e-3, masses="settle", clock=True)
#: Input speed of a quasi-static run, rad/s: the inertia forces of the 1 t
#: links, m·ω²·L ≈ 1e-4 N, stay ~1e-6 of the loads.
QUASI_STATIC_SPEED = 1e-3

#: First lead time, in steps, and the most it may grow to.
LEAD_STEPS = 50
MAX_LEAD_STEPS = 1600
#: Runs with lead N and 2N agree to this fraction of the largest force (or
#: torque/scale): the start-up transient has died. 100× below the 1e-3 target.
LEAD_AGREEMENT_RTOL = 1e-5
#: Fixed-point passes at the final instant so that the friction couples match
#: the reactions they were computed from.
FINAL_FRICTION_PASSES = 5
#: Forward passes at the seeded state that carry its constraint forces before
#: the first step: the soft constraints hold 1 − R/(A + R) ≈ 0.9999 of a force
#: at zero violation, so each pass leaves 1e-4 of the last; three reach rounding.
WARM_START_PASSES = 3


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
    are exact at every step (not only at the instant); a single polynomial
    fitted over the whole lead-in was off by up to 1e-4 rad at its ends, which
    started every run with a constraint violation.
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


def start_run(rig: Rig, drive: Drive, coupling: np.ndarray) -> None:
    """Seed the analytic state at θ12(−T), set the clock going, and carry the
    constraint forces of that state (:data:`WARM_START_PASSES`)."""
    m, d = rig.model, rig.data
    mujoco.mj_resetData(m, d)
    rig.set_extra(np.zeros(m.nbody), np.zeros((m.nbody, 3)))  # no friction left from a last run
    phi0 = drive.start_offset()
    qpos, qvel, _ = rig.qpos_at(drive.theta12 + phi0, drive.start_speed(), drive.alpha)
    rig.set_state(qpos, qvel)
    clock = rig.layout.qpos["clock"]
    d.qpos[clock] = phi0
    d.qvel[clock] = drive.start_speed()
    # The clock's own inertia times α keeps it on the prescribed acceleration.
    rig.clock_force = m.dof_armature[clock] * drive.alpha
    rig.reset_carried()
    for _ in range(WARM_START_PASSES):
        forward(rig, coupling)
        rig.carry()


def forward(rig: Rig, coupling: np.ndarray) -> None:
    """A forward pass at the current state with the drive polynomial ``coupling``;
    the loads (and carried forces) are placed at the current positions."""
    m, d = rig.model, rig.data
    m.eq_data[rig.layout.drive_eq, :5] = coupling
    mujoco.mj_kinematics(m, d)
    rig.apply_loads()
    mujoco.mj_forward(m, d)


def apply_friction(rig: Rig, values: dict[str, float]) -> None:
    """Friction couples from the current reactions and the simulator's own velocities.

    In a quasi-static run Coulomb senses come from the actual (slow) velocities;
    viscous terms use them too, which is right for a real motion and negligible
    (c·1e-3) for a quasi-static one, whose analytic value has ω = 0.
    """
    qvel = rig.data.qvel[rig.joint_addresses()]
    speeds = relative_speeds(rig, qvel)
    viscous_speeds = speeds if rig.case.motion.omega or rig.case.motion.alpha else {
        k: 0.0 for k in speeds}
    rig.set_extra(*friction_loads(rig, values, speeds, viscous_speeds))


def run_drive(rig: Rig, drive: Drive, friction: bool) -> dict[str, float]:
    """Simulate to the instant and return the values there."""
    m, d = rig.model, rig.data
    coupling = coupling_table(rig.case, drive)
    start_run(rig, drive, coupling[0])
    values: dict[str, float] = {}
    for k in range(drive.steps):
        forward(rig, coupling[k])
        if friction:
            values = rig.read()
            apply_friction(rig, values)
        mujoco.mj_Euler(m, d)
        rig.carry()
    for _ in range(FINAL_FRICTION_PASSES if friction else 1):
        forward(rig, coupling[-1])
        values = rig.read()
        if friction:
            apply_friction(rig, values)
    return values


def disagreement(a: dict[str, float], b: dict[str, float], length: float) -> float:
    """Largest difference of forces (and torques/length) relative to the largest of them."""
    def vector(v: dict[str, float]) -> np.ndarray:
        return np.array([x / length if quantity_kind(q) == "torque" else x
                         for q, x in v.items() if quantity_kind(q) != "pose"])
    va, vb = vector(a), vector(b)
    return float(np.abs(va - vb).max()) / max(float(np.abs(vb).max()), 1e-300)


def drive_motion(case: Case) -> tuple[Settings, float, float]:
    """Model settings, ω and α of the run: the Case's motion, or a slow quasi-static
    one in friction.direction for a static friction case."""
    if case.motion.is_static:
        return QUASI_STATIC, case.input_sense * QUASI_STATIC_SPEED, 0.0
    return DYNAMIC, case.motion.omega, case.motion.alpha


def driven(case: Case, rig: Rig | None = None) -> Solution:
    """The ``mujoco`` backend for a moving or friction case (method ``driven``).

    ``rig`` (built with :func:`drive_motion`'s settings for a case differing
    only in θ12) is reused by sweeps.
    """
    start = time.perf_counter()
    settings, omega, alpha = drive_motion(case)
    rig = rig or Rig(case, settings)
    steps = LEAD_STEPS
    total = steps
    previous = run_drive(rig, Drive(case.theta12, omega, alpha, steps, settings.timestep),
                         case.has_friction)
    while True:
        steps *= 2
        total += steps
        values = run_drive(rig, Drive(case.theta12, omega, alpha, steps, settings.timestep),
                           case.has_friction)
        residual = disagreement(values, previous, rig.scale)
        previous = values
        if not np.isfinite(residual):
            residual = np.inf
            break
        if residual <= LEAD_AGREEMENT_RTOL or steps >= MAX_LEAD_STEPS:
            break
    diagnostics: dict[str, float | str] = {
        "method": "driven", "steps": total, "wall_time_s": time.perf_counter() - start,
        "residual_velocity": abs(float(rig.data.qvel[rig.layout.qpos["clock"]]) - omega),
        "loop_violation": rig.loop_violation(), "pose_drift": rig.pose_drift(case.theta12),
        "lead_disagreement": residual, "lead_steps": steps, "timestep": settings.timestep,
    }
    if residual > LEAD_AGREEMENT_RTOL:
        pose = {q: v for q, v in values.items() if quantity_kind(q) == "pose"}
        return Solution(case.name, "mujoco", pose, status="not_settled",
                        message=f"start-up transient still {residual:.1e} of the forces after "
                                f"{steps} lead steps", diagnostics=diagnostics)
    return Solution(case.name, "mujoco", values, diagnostics=diagnostics)
