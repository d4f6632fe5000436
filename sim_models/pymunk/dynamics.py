"""Driven runs: dynamic cases (ω, α ≠ 0) and friction cases, backend ``pymunk``.

The drive link is locked (GearJoint, ratio 1) to a kinematic "clock" body
whose angle follows the prescribed motion of link 2,
θ12(t) = θ12* + ω·τ + ½·α·τ² with τ = t − t*, so the crank reaches the case's
θ12 at t*. When the drive acts on the rocker the clock follows θ14(θ12(t))
from the closed-form kinematics: the motion is still prescribed through θ12
(CONVENTIONS.md), only the torque acts on link 4. Friction cases that are
static (ω = 0) are driven quasi-statically at ``QUASI_STATIC_OMEGA`` in the
case's ``direction``.

The run starts a short lead-in before t*, on the closed-form pose *and
velocities* (a seed, so there is no start-up shock), with the real masses
and inertias; massless links get ``driven_fictitious_mass`` (its inertia
force is the one modelling error left, bounded below). Loads, weights and
friction forces are applied inside pymunk's velocity integration, i.e. at the
pose the step's constraint impulses belong to. The reading at θ12* is
interpolated linearly in the crank angle the body actually had between the
two steps that bracket it.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pymunk

from analytic.case import Case
from analytic.kinematics import pose_of
from analytic.solution import Solution
from sim_models.pymunk.friction import (
    apply_viscous_pin_moments,
    sign,
    slide_friction_force,
    slide_speed,
    update_pin_friction,
)
from sim_models.pymunk.loads import apply_load_set
from sim_models.pymunk.model import Model, build_model, slide_axes
from sim_models.pymunk.readout import (
    Values,
    crank_angle,
    joint_separation,
    pose_drift,
    pose_values,
    reactions,
    residual_velocity,
)
from sim_models.pymunk.settings import SolverSettings
from sim_models.pymunk.verdict import singular_solution

BACKEND = "pymunk"

#: rad/s of the quasi-static drive of a static friction case. Slow enough that
#: the inertia forces of the (light) bodies, m·ω²·L, are ~1e-10 of the loads,
#: fast enough that every joint keeps a definite sense of relative motion.
QUASI_STATIC_OMEGA = 0.01

#: Settings of driven runs. dt is small because here, unlike in statics, the
#: integration error is part of the force (the reactions carry m·a): it is
#: O(ω·dt) per reading before interpolation. No damping: it would remove
#: momentum that the constraint forces must supply. error_bias = 0 corrects
#: the whole joint error every step (Chipmunk's bias coefficient is
#: 1 − error_bias^dt): at dt = 1e-4 any "per second" bias that is not ~0
#: corrects almost nothing per step, and the drifting loop then biases the
#: forces (measured: 0.9⁶⁰ → 7e-3, 1e-300 → 5e-5, 0 → 2e-6 on a slider-crank
#: at 20 rad/s). Massless links get 1 kg (well conditioned against real
#: masses of ~1 kg; its inertia force is removed by extrapolation, see
#: :func:`drive`).
DRIVEN = SolverSettings(dt=1.0e-4, iterations=100, error_bias=0.0, damping=1.0,
                        driven_fictitious_mass=1.0)

#: Lead-in, as the number of steps before t*: enough for the warm-started
#: solver to converge from a cold start (a few steps, see the settle runs)
#: and for the friction limits, which lag one step, to follow.
LEAD_STEPS = 400

#: A reading is trusted only if the forces vary smoothly through θ12*: the
#: second difference over the bracketing steps, relative to the force scale,
#: must be below this (a start-up transient or a solver not converged shows
#: up as step-to-step noise far above it).
SMOOTHNESS = 1.0e-5


@dataclass
class Drive:
    """The prescribed motion: crank angle θ12(t) and the drive link's angle at step times."""

    case: Case
    omega: float
    alpha: float
    t_star: float = 0.0

    def theta12(self, t: np.ndarray | float) -> np.ndarray:
        tau = np.asarray(t, dtype=float) - self.t_star
        return self.case.theta12 + self.omega * tau + 0.5 * self.alpha * tau * tau

    def drive_angles(self, t: np.ndarray) -> np.ndarray:
        """Angle of the drive link at times t: θ12(t), or θ14(θ12(t)) for a rocker drive."""
        th = np.atleast_1d(self.theta12(t))
        if self.case.drive_link == 2:
            return th
        return pose_of(self.case, th, omega=0.0, alpha=0.0).theta14


def drive_motion(case: Case) -> tuple[float, float]:
    """(ω, α) the crank is driven with: the case's, or a slow quasi-static turn."""
    if case.motion.is_static:
        return QUASI_STATIC_OMEGA * case.input_sense, 0.0
    return case.motion.omega, case.motion.alpha


def seed_state(model: Model, drive: Drive, t: float) -> None:
    """Closed-form pose and velocities at time t (the start of the lead-in)."""
    th = drive.theta12(t)
    w = drive.omega + drive.alpha * (t - drive.t_star)
    pose = pose_of(model.case, np.atleast_1d(th), omega=w, alpha=drive.alpha)
    for link, body in model.bodies.items():
        s = pose.links[link]
        body.angle = float(s.angle[0])
        body.position = (float(s.origin[0, 0]), float(s.origin[0, 1]))
        cog = body.local_to_world(body.center_of_gravity) - body.position
        # Velocity of the centre of gravity: v_origin + ω × r.
        body.velocity = (float(s.velocity[0, 0]) - float(s.omega[0]) * cog.y,
                         float(s.velocity[0, 1]) + float(s.omega[0]) * cog.x)
        body.angular_velocity = float(s.omega[0])
    model.driver.angle = float(drive.drive_angles(np.array([t]))[0])
    model.driver.angular_velocity = float(pose.links[model.case.drive_link].omega[0])
    model.drive.phase = 0.0


def install_force_callbacks(model: Model, extras: dict[int, tuple[float, float, float]]) -> None:
    """Apply loads (at the integrated pose) and this step's friction forces inside pymunk.

    ``extras[link] = (fx, fy, torque)`` holds friction forces computed before
    the step from the previous step's state; the slider's force acts at B.
    """
    case = model.case
    for link, body in model.bodies.items():
        mine = case.with_(loads=tuple(ld for ld in case.loads if ld.link == link),
                          masses=tuple(m for m in case.masses if m.link == link))

        def velocity(b: pymunk.Body, gravity: tuple[float, float], damping: float, dt: float,
                     link: int = link, mine: Case = mine) -> None:
            apply_load_set(mine, {link: b})
            fx, fy, tq = extras.get(link, (0.0, 0.0, 0.0))
            if fx or fy:
                b.apply_force_at_world_point((fx, fy), b.local_to_world((0.0, 0.0)))
            b.torque += tq
            pymunk.Body.update_velocity(b, gravity, damping, dt)

        body.velocity_func = velocity


def friction_extras(model: Model) -> tuple[dict[int, tuple[float, float, float]], float]:
    """Update the motor limits and compute this step's explicit friction forces.

    Returns the per-link extras and the slide force along u (part of F14).
    """
    update_pin_friction(model)
    extras: dict[int, tuple[float, float, float]] = {}
    torques = {link: b.torque for link, b in model.bodies.items()}
    apply_viscous_pin_moments(model)  # accumulates into body.torque; move it to extras
    for link, b in model.bodies.items():
        extras[link] = (0.0, 0.0, b.torque - torques[link])
        b.torque = torques[link]
    slide = 0.0
    if model.groove is not None:
        slide = slide_friction_force(model, sign(slide_speed(model)))
        (ux, uy), _ = slide_axes(model.case)
        _, _, tq = extras[4]
        extras[4] = (slide * ux, slide * uy, tq)
    return extras, slide


@dataclass(frozen=True)
class Reading:
    """One step's crank angle and reactions."""

    theta12: float
    values: Values


def interpolate(before: Reading, after: Reading, theta: float) -> Values:
    """Linear interpolation of two readings to crank angle θ."""
    span = after.theta12 - before.theta12
    w = (theta - before.theta12) / span if span else 0.0
    return {q: (1.0 - w) * before.values[q] + w * after.values[q] for q in before.values}


def roughness(readings: list[Reading], length: float) -> float:
    """Largest second difference of the last three readings, relative to the force scale."""
    a, b, c = (r.values for r in readings[-3:])
    scale = max(max(abs(v) / (length if q[0] in "TM" else 1.0) for q, v in c.items()), 1e-300)
    return max(abs(a[q] - 2 * b[q] + c[q]) / (length if q[0] in "TM" else 1.0)
               for q in c) / scale


def passed(theta: float, target: float, sense: float) -> bool:
    return (theta - target) * sense >= 0.0


def run_drive(model: Model, drive: Drive, on_step: Callable[[], None] | None = None
              ) -> tuple[list[Reading], int]:
    """Step from the lead-in until the crank passes θ12*; returns the readings and steps.

    The budget is four lead-ins: a crank that lags that far behind its clock
    has not followed the prescribed motion.
    """
    dt = model.settings.dt
    sense = sign(drive.omega) or sign(drive.alpha) or 1.0
    t0 = drive.t_star - LEAD_STEPS * dt
    budget = 4 * LEAD_STEPS
    targets = drive.drive_angles(t0 + dt * np.arange(1, budget + 1))
    seed_state(model, drive, t0)
    extras: dict[int, tuple[float, float, float]] = {}
    install_force_callbacks(model, extras)
    readings: list[Reading] = []
    for step in range(1, budget + 1):
        new_extras, slide = friction_extras(model)
        extras.clear()
        extras.update(new_extras)
        model.driver.angular_velocity = (float(targets[step - 1]) - model.driver.angle) / dt
        model.space.step(dt)
        if on_step is not None:
            on_step()
        readings.append(Reading(crank_angle(model), pose_values(model) | reactions(model, slide)))
        if step > LEAD_STEPS // 2 and passed(readings[-1].theta12, model.case.theta12, sense):
            return readings, step
    return readings, budget


def has_fictitious_inertia(case: Case) -> bool:
    """True when some link is massless or has zero inertia (it gets a fictitious one)."""
    return any(case.mass_of(k) is None or case.mass_of(k).inertia == 0.0  # type: ignore[union-attr]
               for k in (2, 3, 4))


def drive_once(case: Case, settings: SolverSettings) -> tuple[Solution, Values]:
    """One driven run; returns its Solution and the raw interpolated values."""
    start = time.perf_counter()
    model = build_model(case, settings, mass_mode="real", driver_kind="kinematic")
    omega, alpha = drive_motion(case)
    readings, steps = run_drive(model, Drive(case, omega, alpha))
    rough = roughness(readings, case.geometry.scale)
    diag: dict[str, float | str] = {
        "method": "driven", "steps": steps, "wall_time_s": time.perf_counter() - start,
        "residual_velocity": residual_velocity(model), "joint_separation": joint_separation(model),
        "pose_drift": pose_drift(model, crank_angle(model)), "roughness": rough,
        "drive_omega": omega, "dt": settings.dt, "iterations": settings.iterations,
    }
    crossed = len(readings) >= 2 and passed(readings[-1].theta12, case.theta12,
                                            sign(omega) or sign(alpha) or 1.0)
    if not crossed or not math.isfinite(rough) or rough > SMOOTHNESS:
        return Solution(case.name, BACKEND, {}, status="not_settled",
                        message=f"the driven run did not pass θ12 smoothly (roughness {rough:.3g}"
                                f", limit {SMOOTHNESS:g}): transient or solver not converged",
                        diagnostics=diag), {}
    values = interpolate(readings[-2], readings[-1], case.theta12)
    return Solution(case.name, BACKEND, values, diagnostics=diag), values


def drive(case: Case, settings: SolverSettings = DRIVEN) -> Solution:
    """The ``pymunk`` backend for dynamic and friction cases: drive through θ12 and read there.

    Fictitious inertia of massless links: with the motion prescribed, every
    reaction is affine in the fictitious masses and inertias, F(k) = F₀ + k·G
    when they are all scaled by k. A dynamic case with such links is
    therefore run twice, at k = 1 and k = 2, and reported as F₀ = 2·F(1) − F(2):
    the massless answer, from pymunk's numbers alone. In a quasi-static
    friction run the fictitious inertia force, m·ω²·L ≈ 1e-5 N, is left as is.
    """
    singular = singular_solution(case, BACKEND)
    if singular is not None:
        return singular
    first, values = drive_once(case, settings)
    if first.status != "ok" or case.motion.is_static or not has_fictitious_inertia(case):
        return first
    heavier = settings.with_(driven_fictitious_mass=2.0 * settings.driven_fictitious_mass)
    second, values2 = drive_once(case, heavier)
    if second.status != "ok":
        return second
    extrapolated = {q: 2.0 * values[q] - values2[q] for q in values}
    diag = dict(first.diagnostics)
    diag["wall_time_s"] = float(diag["wall_time_s"]) + float(second.diagnostics["wall_time_s"])
    diag["steps"] = int(diag["steps"]) + int(second.diagnostics["steps"])
    diag["fictitious_inertia_correction"] = max(
        abs(values[q] - extrapolated[q]) for q in values if q[0] in "FTM")
    return Solution(case.name, BACKEND, extrapolated, diagnostics=diag)
