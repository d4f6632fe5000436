"""Driven linkages in pymunk (backend ``pymunk``): a moving linkage case, every
coordinate driven, no joint friction.

The model is the linkage builder's (:mod:`.linkage_model`) with the links' real
inertia; each driver's lock follows the prescribed motion. Its targets are moved
every step and its error correction is complete (``error_bias`` 0, :data:`DRIVEN`),
so the velocity solve of a step makes the *next* position update land on the
prescribed value: a Chipmunk step first moves the bodies with their velocities,
then solves the constraints at that pose for the velocities of the step after.
A step's impulses therefore belong to the pose it has just reached, and the
velocity change they make is centred on it. Loads and real weights are applied
inside the velocity integration (``velocity_func``), i.e. at that same pose.

The run starts ``steps·dt`` before the instant on the analytic pose there, with the
analytic velocities half a step later (a seed: the prescribed motion and its start,
nothing more), and its reading is the step that reaches the instant. The reading is
judged by the rules both simulators share (:mod:`mechcheck.sim_models.convergence`):
the lead-in doubles until two readings agree, then the time step halves until two
agree. A massless link (or a point mass) gets fictitious inertia, removed by running
the model as built and with twice that inertia, F₀ = 2·F(k) − F(2k).

Not modelled here (``not_applicable`` with the reason): joint friction, free
coordinates in a moving linkage, and spring dampers (Chipmunk damps a spring
implicitly, which is not the analytic c·v under a prescribed motion).
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np
import pymunk

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage_backends import quantity_units
from mechcheck.analytic.linkage_forces import LinkageResults
from mechcheck.analytic.linkage_kinematics import Array, solve_pose
from mechcheck.analytic.solution import Solution, quantity_kind
from mechcheck.sim_models.convergence import (
    LEAD_AGREEMENT_RTOL,
    Convergence,
    halve_timestep,
    lengthen_lead,
    massless_limit,
)
from mechcheck.sim_models.diagnostics import RunDiagnostics
from mechcheck.sim_models.linkage_motion import Motion, lead_limit, prescribed_motion
from mechcheck.sim_models.pymunk.dynamics import DRIVEN
from mechcheck.sim_models.pymunk.linkage import (
    axis_now,
    has_free_coordinates,
    loop_violations,
    pose_drifts,
    pose_table,
    reactions,
)
from mechcheck.sim_models.pymunk.linkage_model import (
    LinkageModel,
    along,
    build_linkage_model,
    coordinates,
    gyration_radius,
    has_fictitious_inertia,
    place,
)
from mechcheck.sim_models.pymunk.loads import LoadLike, MassLike, apply_forces

BACKEND = "pymunk"


def refusal(case: Case) -> str | None:
    """Why a moving linkage case is not driven here, or None."""
    linkage = case.linkage
    if case.has_friction:
        return ("joint friction on a linkage is not modelled in the pymunk linkage model "
                "yet (it is in MuJoCo's)")
    if has_free_coordinates(case):
        return ("a moving linkage with free coordinates: pymunk drives every coordinate or "
                "holds a static one, not both")
    if any(spring.damping for spring in linkage.springs if hasattr(spring, "damping")):
        return ("a spring with a damper: Chipmunk damps springs implicitly, which is not the "
                "analytic c·v under a prescribed motion")
    return None


def install_loads(model: LinkageModel) -> None:
    """Each body applies its link's loads and real weights inside its velocity integration,
    at the pose the step's impulses belong to."""
    linkage = model.linkage
    for link, body in model.bodies.items():
        loads = [ld for ld in linkage.loads if ld.link == link]
        masses = [m for m in linkage.masses if m.link == link]

        def velocity(b: pymunk.Body, gravity: tuple[float, float], damping: float, dt: float,
                     link: str = link, loads: Sequence[LoadLike] = loads,
                     masses: Sequence[MassLike] = masses) -> None:
            apply_forces(loads, masses, linkage.gravity, {link: b})
            pymunk.Body.update_velocity(b, gravity, damping, dt)

        body.velocity_func = velocity


def drive_to(model: LinkageModel, values: Array) -> None:
    """Move every driver's lock to ``values`` (d,): a gear's phase, a held slide's anchor."""
    linkage = model.linkage
    for driver, value in zip(linkage.drivers, values, strict=True):
        joint = linkage.joint(driver.joint)
        if joint.kind == "revolute":
            model.drives[joint.name].phase = float(value)
        else:
            model.held[joint.name].anchor_a = along(joint, linkage.points[joint.at], float(value))


def set_velocities(model: LinkageModel, qdot: Array) -> None:
    """Every body's velocities from q̇ (3n,) of the link origins: pymunk's linear velocity
    is its centre of gravity's, v_origin + ω × (R·cog)."""
    for k, body in enumerate(model.bodies.values()):
        vx, vy, w = (float(x) for x in qdot[3 * k:3 * k + 3])
        c, s = math.cos(body.angle), math.sin(body.angle)
        gx, gy = body.center_of_gravity
        rx, ry = c * gx - s * gy, s * gx + c * gy
        body.velocity = (vx - w * ry, vy + w * rx)
        body.angular_velocity = w


@dataclass(frozen=True)
class DriveEnd:
    """Where a run ended: its values, the bodies' coordinates (3n,) and the largest
    error of a driver's rate against the prescribed one (rad/s or m/s)."""

    values: dict[str, float]
    q: Array
    rate_error: float


def driver_rates(model: LinkageModel) -> Array:
    """Each driver's rate from the bodies' own velocities: ω_b − ω_a, or the slide speed of
    ``at`` on links[1] relative to links[0] along the axis."""
    linkage = model.linkage
    rates = []
    for driver in linkage.drivers:
        joint = linkage.joint(driver.joint)
        a, b = (model.body(link) for link in joint.links)
        if joint.kind == "revolute":
            rates.append(b.angular_velocity - a.angular_velocity)
            continue
        point = b.local_to_world(linkage.points[joint.at])
        relative = b.velocity_at_world_point(point) - a.velocity_at_world_point(point)
        ux, uy = axis_now(model, joint)
        rates.append(relative.x * ux + relative.y * uy)
    return np.array(rates)


def run_drive(model: LinkageModel, motion: Motion, steps: int, dt: float) -> DriveEnd:
    """Step from ``steps·dt`` before the instant to it; how the last step ended."""
    linkage = model.linkage
    times = dt * np.arange(-steps, 2, dtype=float)  # t0 … t* + dt
    values, _, _ = motion.at(times)
    start = solve_pose(linkage, *motion.at(times[:1]))
    half = solve_pose(linkage, *motion.at(times[:1] + 0.5 * dt))
    place(model, start.q[0])
    set_velocities(model, half.qdot[0])
    for n in range(steps):
        drive_to(model, values[n + 2])  # the position the next update must reach
        model.space.step(dt)
    q = coordinates(model)
    # The velocities now are those of half a step past the instant.
    _, prescribed, _ = motion.at(np.array([0.5 * dt]))
    pose = {k: float(v[0]) for k, v in pose_table(linkage, q[None, :]).items()}
    return DriveEnd(pose | reactions(model), q,
                    float(np.abs(driver_rates(model) - prescribed[0]).max(initial=0.0)))


#: Gauss–Seidel iterations per step, tried in turn until the lead-in converges. Mass
#: ratios slow the solver: the crank shaper (8 kg links, a 0.4 kg block of 1e-4 kg·m²
#: on the slot) needs 1000 where the other built-in linkages agree at 100; at 100 its
#: readings wander by 10 % from lead to lead, and with twice the fictitious inertia diverge.
ITERATIONS = (100, 400, 1600)


def build(case: Case, scale: float, dt: float, iterations: int) -> LinkageModel:
    settings = replace(DRIVEN, fictitious_scale=scale, dt=dt, iterations=iterations)
    model = build_linkage_model(case, settings, np.zeros(3 * len(case.linkage.moving_links)),
                                driven=True)
    install_loads(model)
    return model


def read_drive(case: Case, motion: Motion, steps: int, dt: float, iterations: int) -> DriveEnd:
    """One reading, free of fictitious inertia: the model as built and, when it has
    fictitious inertia, one with twice of it (fresh models: the step is part of the
    settings every impulse is divided by)."""
    end = run_drive(build(case, 1.0, dt, iterations), motion, steps, dt)
    if not has_fictitious_inertia(case.linkage):
        return end
    doubled = run_drive(build(case, 2.0, dt, iterations), motion, steps, dt)
    return replace(end, values=massless_limit(end.values, doubled.values,
                                              quantity_units(case.linkage)))


def drive_linkage(case: Case, results: LinkageResults) -> Solution:
    """The ``pymunk`` backend for a moving linkage (method ``driven``); ``results`` is the
    analytic pose analysis of the instant (its condition number bounds the lead-in)."""
    start = time.perf_counter()
    units = quantity_units(case.linkage)
    why = refusal(case)
    if why is not None:
        return Solution(case.name, BACKEND, {}, status="not_applicable", units=units,
                        message=f"a {case.kind} linkage case: {why}")
    motion = prescribed_motion(case)
    runs = 2 if has_fictitious_inertia(case.linkage) else 1
    scale = case.linkage.scale
    last: list[DriveEnd] = []
    limit = lead_limit(case, motion, float(results.condition[0]))
    spent = 0  # steps of the attempts with fewer iterations
    for iterations in ITERATIONS:

        def read(steps: int, dt: float, iterations: int = iterations) -> dict[str, float]:
            last[:] = [read_drive(case, motion, steps, dt, iterations)]
            return last[0].values

        out = lengthen_lead(read, limit, DRIVEN.dt, scale, runs, units)
        if out.lead_disagreement <= LEAD_AGREEMENT_RTOL:
            out = halve_timestep(read, out, scale, runs, units)
            break
        spent += out.total_steps
    out.total_steps += spent
    return driven_solution(case, results, out, last[0], runs, iterations,
                           time.perf_counter() - start)


def driven_solution(case: Case, results: LinkageResults, out: Convergence, end: DriveEnd,
                    runs: int, iterations: int, elapsed: float) -> Solution:
    linkage = case.linkage
    units = quantity_units(linkage)
    radius = np.array([gyration_radius(linkage, link) for link in linkage.moving_links])
    q = end.q[None, :]
    diagnostics = RunDiagnostics(
        "driven", out.total_steps, elapsed, end.rate_error, float(loop_violations(linkage, q)[0]),
        float(pose_drifts(radius, q, results.pose.q[:1])[0]),
    ).as_dict(lead_disagreement=out.lead_disagreement, lead_steps=out.lead_steps,
              timestep=out.dt, timestep_disagreement=out.timestep_disagreement,
              fictitious_runs=runs, iterations=iterations)
    if not out.converged:
        pose = {k: v for k, v in out.values.items() if quantity_kind(k, units.get(k)) == "pose"}
        return Solution(case.name, BACKEND, pose, status="not_settled", message=out.verdict(),
                        diagnostics=diagnostics, units=units)
    return Solution(case.name, BACKEND, out.values, diagnostics=diagnostics, units=units)
