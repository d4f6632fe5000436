"""Driven linkages in pymunk (backend ``pymunk``): a moving linkage case, every
coordinate driven, or a static one with Coulomb friction driven quasi-statically.

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
the model as built and with twice that inertia, F₀ = 2·F(k) − F(2k); the two run in
lockstep (:class:`Twins`). Joint friction is applied from pymunk's own reactions and joint
rates (:mod:`.linkage_friction`, :meth:`Twins.step_with_friction`), the same on both
models, from their extrapolated reactions.

Not modelled here (``not_applicable`` with the reason): free coordinates in a moving
linkage, and spring dampers (Chipmunk damps a spring implicitly, which is not the
analytic c·v under a prescribed motion).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, replace
from functools import cache

import numpy as np
import pymunk

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage_backends import quantity_units
from mechcheck.analytic.linkage_forces import LinkageResults
from mechcheck.analytic.linkage_kinematics import Array, solve_pose
from mechcheck.analytic.solution import Solution, quantity_kind
from mechcheck.sim_models.convergence import (
    Convergence,
    converge,
    converge_stretch,
    disagreement,
    driven_verdict,
    inertia_correction,
    left_assembly,
    massless_limit,
    stretch_timestep,
)
from mechcheck.sim_models.diagnostics import RunDiagnostics
from mechcheck.sim_models.linkage_motion import (
    Motion,
    at_first_driver,
    at_rest_reason,
    driven_motion,
    has_free_coordinates,
    lead_limit,
    prescribed_motion,
    self_locking_note,
)
from mechcheck.sim_models.pymunk.linkage import loop_violations, pose_drifts, pose_table
from mechcheck.sim_models.pymunk.linkage_friction import (
    Diverged,
    JointLoads,
    apply_joint_friction,
    friction_loads,
    joint_rate,
    joint_rates,
    with_sliding,
)
from mechcheck.sim_models.pymunk.linkage_model import (
    LinkageModel,
    build_linkage_model,
    coordinates,
    gyration_radius,
    has_fictitious_inertia,
    move_lock,
    place,
)
from mechcheck.sim_models.pymunk.loads import LoadLike, MassLike, apply_forces
from mechcheck.sim_models.pymunk.readout import Values
from mechcheck.sim_models.pymunk.settings import SolverSettings
from mechcheck.sim_models.pymunk.slow_mode import RATIO_STEPS, steady_ratio, step_ratio

BACKEND = "pymunk"

#: rad/s (or m/s) of the quasi-static drive of a static case with Coulomb friction, fast
#: enough that every joint keeps a definite sense of relative motion. Every link's inertia
#: is fictitious in such a run and extrapolated away (:func:`.linkage_model.driven_inertial`):
#: with the real masses' inertia kept, m·ω²·L was the size of a random six-bar's 5e-4 N
#: reactions (read twice as large, 2026-11-26).
QUASI_STATIC_OMEGA = 0.01

#: rad/s (a prismatic joint's m/s per the linkage's length scale): a Coulomb joint slower
#: than this at the reading is at rest for pymunk. Its joint rates are measured on bodies
#: whose velocities also carry the error correction of its constraints (``error_bias`` 0:
#: the whole residual joint error, over one step), so below this the sense each Coulomb
#: term takes from them is noise. Measured (2026-11-26): random friction cases driven at
#: 1.2e-7 rad/s read joint rates 1e-13 to 3e-3 rad/s off the prescribed ones; a four-bar
#: with μ = 0.25 at B0 read T12 = +0.0367 at ω = −1e-8 rad/s and −0.0592 at −1.2e-7
#: against −0.0451 (MuJoCo right at both), right from 1e-6 on; a slider-crank was erratic
#: up to 1e-6 and right from 3e-6 on.
SENSED_RATE = 1e-5

#: Settings of driven runs. dt is small because here, unlike in statics, the integration
#: error is part of the force (the reactions carry m·a); the reading is checked against
#: dt/2 (:func:`~mechcheck.sim_models.convergence.halve_timestep`). No damping: it would
#: remove momentum that the constraint forces must supply. error_bias = 0 corrects the
#: whole joint error every step (Chipmunk's bias coefficient is 1 − error_bias^dt): at
#: dt = 1e-4 any "per second" bias that is not ~0 corrects almost nothing per step, and the
#: drifting loop then biases the forces (measured on a slider-crank at 20 rad/s:
#: 0.9⁶⁰ → 7e-3, 1e-300 → 5e-5, 0 → 2e-6). ``iterations`` is the first rung of
#: :data:`ITERATIONS`.
DRIVEN = SolverSettings(dt=1.0e-4, iterations=100, error_bias=0.0, damping=1.0)

#: Passes per step of a run with friction: the step under the loads of its predicted
#: state, then once more under the loads of the state that pass made. One correction
#: leaves the loads' error at the friction's feedback gain times the prediction's O(dt²)
#: error; the time-step check measures what is left.
FRICTION_PASSES = 2

BodyState = tuple[pymunk.Body, float, tuple[float, float], tuple[float, float], float]


def snapshot(bodies: Iterable[pymunk.Body]) -> list[BodyState]:
    """The bodies' angle, position and velocities (to repeat a step)."""
    return [(b, b.angle, (b.position.x, b.position.y), (b.velocity.x, b.velocity.y),
             b.angular_velocity) for b in bodies]


def restore(saved: list[BodyState]) -> None:
    """Put the bodies back where :func:`snapshot` found them (angle first: pymunk
    rotates about the centre of gravity)."""
    for body, angle, position, velocity, spin in saved:
        body.angle = angle
        body.position = position
        body.velocity = velocity
        body.angular_velocity = spin


def predicted(history: list[Values]) -> Values | None:
    """The next step's state extrapolated linearly from the last two (error O(dt²))."""
    if not history:
        return None
    if len(history) == 1:
        return history[-1]
    last, before = history[-1], history[-2]
    return {q: 2.0 * v - before[q] for q, v in last.items()}


def refusal(case: Case) -> str | None:
    """Why a moving linkage case (or a static one with Coulomb friction) is not driven
    here, or None."""
    linkage = case.linkage
    if has_free_coordinates(case):
        return ("a moving linkage with free coordinates: pymunk drives every coordinate or "
                "holds a static one, not both")
    if any(spring.damping for spring in linkage.springs if hasattr(spring, "damping")):
        return ("a spring with a damper: Chipmunk damps springs implicitly, which is not the "
                "analytic c·v under a prescribed motion")
    return None


def install_loads(model: LinkageModel, friction: JointLoads) -> None:
    """Each body applies its link's loads, real weights and joint friction (``friction``,
    read when the step runs) inside its velocity integration, at the pose the step's
    impulses belong to."""
    linkage = model.linkage
    for link, body in model.bodies.items():
        loads = [ld for ld in linkage.loads if ld.link == link]
        masses = [m for m in linkage.masses if m.link == link]

        def velocity(b: pymunk.Body, gravity: tuple[float, float], damping: float, dt: float,
                     link: str = link, loads: Sequence[LoadLike] = loads,
                     masses: Sequence[MassLike] = masses) -> None:
            apply_forces(loads, masses, linkage.gravity, {link: b})
            apply_joint_friction(model, link, b, friction)
            pymunk.Body.update_velocity(b, gravity, damping, dt)

        body.velocity_func = velocity


def drive_to(model: LinkageModel, values: Array) -> None:
    """Move every driver's lock to ``values`` (d,): a gear's phase, a held slide's anchor."""
    for driver, value in zip(model.linkage.drivers, values, strict=True):
        move_lock(model, model.linkage.joint(driver.joint), float(value))


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
    #: What the massless extrapolation removed from the base model's reading, N.
    correction: float = 0.0
    #: How far the last step's reading moves when that step is solved again with
    #: :data:`SOLVER_CHECK_FACTOR` times the iterations (relative, as the convergence checks).
    solver_disagreement: float = 0.0
    #: The bodies' largest distance from the prescribed pose at the instant, in any of the
    #: twins (m, :func:`.linkage.pose_drifts`).
    drift: float = 0.0


@dataclass
class Twins:
    """The models a driven run steps in lockstep: the case as built and, when it has
    fictitious inertia, the same with twice of it; both take the same joint friction
    (``friction``, set before each step)."""

    models: list[LinkageModel]
    friction: JointLoads
    viscous: bool

    @property
    def base(self) -> LinkageModel:
        return self.models[0]

    def reactions(self) -> dict[str, float]:
        """The last step's reactions, free of fictitious inertia (prismatic friction
        included)."""
        return self.reading()[0]

    def reading(self) -> tuple[dict[str, float], float]:
        """:meth:`reactions`, and what the extrapolation removed from the base model's
        (:func:`~mechcheck.sim_models.convergence.inertia_correction`)."""
        units = quantity_units(self.base.linkage)
        read = [with_sliding(m, m.readout.values(), self.friction) for m in self.models]
        if len(read) == 1:
            return read[0], 0.0
        limit = massless_limit(read[0], read[1], units)
        return limit, inertia_correction(read[0], limit, self.base.linkage.scale, units)

    def step(self, loads: JointLoads, dt: float) -> Values:
        """One step of every model under the friction ``loads``; the state it makes: the
        reactions and the joint rates centred on the step's pose (the mean of the rates
        before and after: the velocity change of a step is centred on its pose)."""
        before = joint_rates(self.base)
        self.friction.clear()
        self.friction.update(loads)
        for model in self.models:
            model.space.step(dt)
        after = joint_rates(self.base)
        state = self.reactions() | {q: 0.5 * (v + after[q]) for q, v in before.items()}
        if not all(math.isfinite(v) for v in state.values()):
            raise Diverged("a reaction or a joint rate became non-finite")
        return state

    def step_with_friction(self, history: list[Values], dt: float) -> None:
        """One step whose friction is that of its own reactions and rates: taken under the
        loads of the state predicted from the last two (error O(dt²)), then repeated from
        the same start under the loads of the state that made, FRICTION_PASSES in all
        (the four-bar's scheme, :mod:`.friction`); appends the step's state to ``history``."""
        guess = predicted(history)
        loads = friction_loads(self.base, guess, self.viscous) if guess is not None else {}
        saved = [snapshot(m.bodies.values()) for m in self.models]
        for attempt in range(FRICTION_PASSES):
            if attempt:
                for bodies in saved:
                    restore(bodies)
                loads = friction_loads(self.base, history.pop(), self.viscous)
            history.append(self.step(loads, dt))
        del history[:-2]


def run_drive(twins: Twins, motion: Motion, steps: int, dt: float) -> DriveEnd:
    """Step from ``steps·dt`` before the instant to it; how the last step ended, and how far
    its reading moves when that step is solved again with more iterations
    (:func:`resolve_last_step`)."""
    linkage = twins.base.linkage
    values = start_drive(twins, motion, steps, dt, 0)
    history: list[Values] = []
    before_last = advance(twins, values, 0, steps, history, dt)
    instant = solve_pose(linkage, *motion.at(np.zeros(1)))
    return drive_end(twins, motion, 0.0, instant.q, before_last, dt)


def start_drive(twins: Twins, motion: Motion, steps: int, dt: float, after: int) -> Array:
    """Place the twins ``steps·dt`` before the instant on the prescribed motion (the analytic
    pose, its velocities half a step later); the drivers' values at every step from there
    to ``after`` steps past the instant, and two more."""
    linkage = twins.base.linkage
    times = dt * np.arange(-steps, after + 2, dtype=float)  # t0 … t* + (after + 1)·dt
    values, _, _ = motion.at(times)
    start = solve_pose(linkage, *motion.at(times[:1]))
    half = solve_pose(linkage, *motion.at(times[:1] + 0.5 * dt))
    for model in twins.models:
        place(model, start.q[0])
        set_velocities(model, half.qdot[0])
    return values


Saved = tuple[list[list[BodyState]], list[Values]]


def advance(twins: Twins, values: Array, first: int, last: int, history: list[Values],
            dt: float) -> Saved:
    """Steps ``first`` … ``last − 1`` of a run whose drivers' values per step are
    ``values``; the state before the last of them (to solve it again)."""
    before_last: Saved = ([], [])
    for n in range(first, last):
        for model in twins.models:
            drive_to(model, values[n + 2])  # the position the next update must reach
        if n == last - 1:
            before_last = [snapshot(m.bodies.values()) for m in twins.models], list(history)
        step_once(twins, history, dt)
    return before_last


def drive_end(twins: Twins, motion: Motion, t: float, instant: Array, before_last: Saved,
              dt: float) -> DriveEnd:
    """The reading of the step that reached the time ``t`` of the motion, whose analytic
    pose is ``instant`` (1, 3n); the models are left as the check of its solve
    (:func:`resolve_last_step`) leaves them."""
    linkage = twins.base.linkage
    base = twins.base
    # The velocities now are those of half a step past the instant.
    _, prescribed, _ = motion.at(np.array([t + 0.5 * dt]))
    q = coordinates(base)
    pose = {k: float(v[0]) for k, v in pose_table(linkage, q[None, :]).items()}
    reactions_now, correction = twins.reading()
    rate_error = float(np.abs(driver_rates(base) - prescribed[0]).max(initial=0.0))
    # Every twin's: one that left the assembly spoils the extrapolation of both.
    radius = np.array([gyration_radius(linkage, link) for link in linkage.moving_links])
    simulated = np.array([coordinates(m) for m in twins.models])
    drift = float(pose_drifts(radius, simulated,
                              turned_like(simulated, np.repeat(instant, len(twins.models),
                                                               axis=0))).max())
    unsolved = resolve_last_step(twins, *before_last, reactions_now, dt)
    return DriveEnd(pose | reactions_now, q, rate_error, correction, unsolved, drift)


def turned_like(q: Array, reference: Array) -> Array:
    """``reference`` (M, 3n) with each body's angle moved by whole turns to the nearest of
    ``q``'s: a long run's bodies count the turns they have made."""
    out = np.array(reference, dtype=float)
    gap = q[:, 2::3] - out[:, 2::3]
    out[:, 2::3] += 2.0 * np.pi * np.round(gap / (2.0 * np.pi))
    return out


def run_stretch(twins: Twins, motion: Motion, lead: int, dt: float, per_pose: int,
                instants: Array) -> list[DriveEnd]:
    """One run through the poses ``instants`` (M, 3n, analytic, each ``per_pose`` steps
    after the last), the first after ``lead`` steps of ``dt``: at the step that reaches each
    pose, its reading as :func:`run_drive` takes it. The run then goes on from that step as
    it was taken (the check of its solve undone, bodies and friction history; the
    constraints keep its better warm start)."""
    poses = len(instants)
    values = start_drive(twins, motion, lead, dt, (poses - 1) * per_pose)
    history: list[Values] = []
    ends = []
    for k in range(poses):
        first = 0 if k == 0 else lead + (k - 1) * per_pose
        before_last = advance(twins, values, first, lead + k * per_pose, history, dt)
        taken = [snapshot(m.bodies.values()) for m in twins.models], list(history)
        ends.append(drive_end(twins, motion, k * per_pose * dt, instants[k:k + 1],
                              before_last, dt))
        for bodies in taken[0]:
            restore(bodies)
        history[:] = taken[1]
    return ends


def step_once(twins: Twins, history: list[Values], dt: float) -> None:
    """One step of every model (with friction, :meth:`Twins.step_with_friction`)."""
    if twins.base.linkage.friction is None:
        for model in twins.models:
            model.space.step(dt)
    else:
        twins.step_with_friction(history, dt)


#: The last step of a driven run is solved again with this many times the iterations. In a
#: moving run warm starting carries the impulses of a step that stopped short into the next
#: one, which stops short again: a random slider-crank (quasi-static, slide friction, point
#: masses off their links) read its slide's normal force 0.070 N against 0.455 at 100
#: iterations, the same at every lead-in and time step; 400 read it right (2026-11-26).
SOLVER_CHECK_FACTOR = 4


def resolve_last_step(twins: Twins, saved: list[list[BodyState]], history: list[Values],
                      reading: dict[str, float], dt: float) -> float:
    """How far ``reading`` moves when the last step is taken again from the same state
    (``saved`` bodies, friction ``history``) with :data:`SOLVER_CHECK_FACTOR` times the
    iterations, relative to the largest force (torques over the length scale); the
    models are left as that step leaves them."""
    for model, bodies in zip(twins.models, saved, strict=True):
        restore(bodies)
        model.space.iterations *= SOLVER_CHECK_FACTOR
    try:
        step_once(twins, history, dt)
    finally:
        for model in twins.models:
            model.space.iterations //= SOLVER_CHECK_FACTOR
    linkage = twins.base.linkage
    return disagreement(twins.reading()[0], reading, linkage.scale, quantity_units(linkage))


def driver_rates(model: LinkageModel) -> Array:
    """Each driver's rate from the bodies' own velocities (:func:`.linkage_friction.joint_rate`)."""
    return np.array([joint_rate(model, model.linkage.joint(d.joint))
                     for d in model.linkage.drivers])


#: Gauss–Seidel iterations per step, tried in turn until the lead-in converges. Mass
#: ratios slow the solver: the crank shaper (8 kg links, a 0.4 kg block of 1e-4 kg·m²
#: on the slot) needs 1000 where the other built-in linkages agree at 100; at 100 its
#: readings wander by 10 % from lead to lead, and with twice the fictitious inertia diverge.
#: The Whitworth quick-return turning at 10 rad/s (``cases/users/whitworth.toml``, a 20 kg
#: ram on 1–3 kg links) at 210° (condition number about 250) still moved by 1.3e-4 of the
#: forces when its last step was solved again at 1600 (the rule: 1e-4); at 6400, 1.4e-8.
#: The raising scissor lift (``cases/users/scissor_lift.toml``) 60 mm down its stroke
#: (condition number 248) is stable from 25 600 on (:data:`STABLE_STEP_CONTRACTION`) and
#: meets the iteration rule at 102 400; 280 and 285 mm up it (condition numbers 284 and 406)
#: a stable step needs about 126 000 and 329 000, and both read at 409 600; 64 mm down it
#: (544) is stable at 409 600, where its last step solved again moved the reading by 2.3e-4
#: of the forces (the rule: 1e-4), and meets the rule at 1 638 400 (2.3e-7).
ITERATIONS = (100, 400, 1600, 6400, 25600, 102400, 409600, 1638400)
#: Past this many iterations a step, a further rung runs only where more iterations are what
#: the run lacks (:func:`next_rung`): a rung costs about as much as all the rungs before it.
PLAIN_ITERATIONS = 1600
#: A driven run is stable only where one step's Gauss–Seidel leaves at most this fraction of
#: the constraint solve's slowest mode. Chipmunk starts each step's solve from the last
#: step's impulses and, with ``error_bias`` 0 (:data:`DRIVEN`), corrects the whole joint
#: error within it. For one mode that a step's solve leaves the fraction ρ of, the position
#: error, velocity and impulse then follow a linear map per step whose spectral radius is
#: below 1 only for ρ < 1/2 (0.84 at ρ = 0.3, 1.11 at 0.7, 1.15 at 0.9): above it the
#: reactions oscillate from step to step, grow, and the run leaves its assembly. Measured on
#: the raising scissor lift at −60 mm (:func:`iteration_contraction`): ρ = 0.87 at 1600
#: iterations and 0.57 at 6400 (the twin with doubled fictitious inertia 0.91 and 0.70); its
#: reactions grew 1.12× a step at both (the map: 1.15 and 1.11), and held at 25 600 (ρ =
#: 0.11 and 0.24). At −10 mm (0.47 at 1600) they rang on and the lead-in did not converge
#: within its budget. A quarter keeps the map's radius below 0.8.
STABLE_STEP_CONTRACTION = 0.25
#: The steps over which :func:`iteration_contraction` follows the step ratio; it goes on past
#: the first ratio that holds still (:func:`.slow_mode.steady_ratio`), which can be a faster
#: mode's: the scissor lift 265 mm up its stroke, at 100 iterations a step, read 0.9966
#: after 40 steps and 0.9943, steady, from 80; 280 mm up it (the slower twin) read 0.948,
#: steady, at step 23 and 0.9989 from about 160: a stable step needs about 2 600
#: iterations by the first and 126 000 by the second.
CONTRACTION_STEPS = 400
#: A step's change of the impulses this small, relative to them, is their rounding.
ROUNDING = 1.0e-12


#: Past :data:`PLAIN_ITERATIONS`, a rung runs only where its iterations × the square of the
#: linkage's joints stay within this. A step's Gauss–Seidel work grows with iterations ×
#: joints (measured: 13 ns per iteration and joint on the scissor lift's 10 joints, 25 on a
#: chain of 64 four-bar loops); the second factor of joints keeps a large linkage, each of
#: whose steps already costs joints-fold, off the rungs whose steps take a tenth of a
#: second. The scissor lift's 10 joints and the Whitworth's 7 reach 1 638 400 (0.2 s a
#: step); 100 joints reach 6400, and a chain of 64 four-bar loops (193 joints) stays at 1600
#: (8 ms a step), as does any linkage of more than 160 joints.
ITERATION_BUDGET = 1.65e8


def rungs(joints: int) -> list[int]:
    """The rungs of :data:`ITERATIONS` a linkage of ``joints`` joints may run
    (:data:`ITERATION_BUDGET`)."""
    return [n for n in ITERATIONS
            if n <= PLAIN_ITERATIONS or n * joints ** 2 <= ITERATION_BUDGET]


def next_rung(out: Convergence | None, iterations: int, contraction: Callable[[], float],
              joints: int) -> int | None:
    """The rung of :data:`ITERATIONS` to run after a run at ``iterations`` that did not
    converge (``out``; None where its lead-in reached no reading), or None: below
    :data:`PLAIN_ITERATIONS` the next; from there the next where the iteration rule alone
    failed, and else the first whose step leaves at most :data:`STABLE_STEP_CONTRACTION` of
    the slowest mode where this one left more (``contraction()``: per iteration, measured
    when asked): the run was unstable, and more iterations are what it lacks. Past
    :data:`PLAIN_ITERATIONS` only rungs within :data:`ITERATION_BUDGET` for a linkage of
    ``joints`` joints."""
    higher = [n for n in rungs(joints) if n > iterations]
    if not higher:
        return None
    if iterations < PLAIN_ITERATIONS or (out is not None and out.solver_only_failed):
        return higher[0]
    per_iteration = contraction()
    if per_iteration ** iterations <= STABLE_STEP_CONTRACTION:
        return None
    return next((n for n in higher if per_iteration ** n <= STABLE_STEP_CONTRACTION), None)


def iteration_contraction(case: Case, q: Array) -> float:
    r"""The fraction of the constraint solve's slowest mode that one Gauss–Seidel iteration
    leaves at the pose ``q`` (3n,) of ``case`` (its drivers' values), in the slower of the
    driven twins (:func:`slowest_ratio`, per step of :data:`ITERATIONS`\[0], to the power
    1/N). Measured on the scissor lift at −60 mm: the per-iteration contraction of 100, 400,
    1600 and 6400 iterations a step agreed within 0.2 % of its gap to 1."""
    twins = build_twins(case, driven_motion(case, QUASI_STATIC_OMEGA), DRIVEN.dt, ITERATIONS[0])
    drivers = np.array([d.value for d in case.linkage.drivers])
    return max(slowest_ratio(m, q, drivers) for m in twins.models) ** (1.0 / ITERATIONS[0])


def slowest_ratio(model: LinkageModel, q: Array, drivers: Array) -> float:
    """How much the slowest mode of ``model``'s constraint solve shrinks per step: the model
    is put back on the pose ``q`` at rest (its drivers at ``drivers``) before every step, so
    its accumulated impulses are the iterates of one linear fixed-point map, and the ratio of
    consecutive steps' changes (:func:`.slow_mode.step_ratio`) settles on each mode's in turn
    as the faster ones die out (:func:`.slow_mode.steady_ratio`): the last one it settles on
    within :data:`CONTRACTION_STEPS` is the slowest's. Where the changes reach the impulses'
    rounding (:data:`ROUNDING`) before any settles, every mode is fast: their mean ratio
    since the first step."""
    iterates: list[np.ndarray] = []
    ratios: list[float] = []
    steady: float | None = None
    for _ in range(CONTRACTION_STEPS):
        place(model, q)
        drive_to(model, drivers)
        model.space.step(DRIVEN.dt)
        iterates.append(np.array(model.readout.accumulated()))
        if len(iterates) < 3:
            continue
        change, before = iterates[-1] - iterates[-2], iterates[-2] - iterates[-3]
        ratios.append(abs(step_ratio(change, before)))
        steady = steady_ratio(ratios) or steady
        if np.abs(change).max() <= ROUNDING * np.abs(iterates[-1]).max():
            break
    if steady is not None:
        return steady
    first = float(np.abs(iterates[1] - iterates[0]).max())
    last = float(np.abs(iterates[-1] - iterates[-2]).max())
    if last <= ROUNDING * np.abs(iterates[-1]).max() and first > 0.0:
        return float((last / first) ** (1.0 / (len(iterates) - 2)))
    return max(ratios[-RATIO_STEPS:], default=0.0)


def build(case: Case, scale: float, dt: float, iterations: int,
          friction: JointLoads, quasi_static: bool) -> LinkageModel:
    settings = replace(DRIVEN, fictitious_scale=scale, dt=dt, iterations=iterations,
                       quasi_static=quasi_static)
    model = build_linkage_model(case, settings, np.zeros(3 * len(case.linkage.moving_links)),
                                driven=True)
    install_loads(model, friction)
    return model


def build_twins(case: Case, motion: Motion, dt: float, iterations: int) -> Twins:
    """Fresh models (the step is part of the settings every impulse is divided by)."""
    friction: JointLoads = {}
    slow = motion.quasi_static
    scales = (1.0, 2.0) if has_fictitious_inertia(case.linkage, slow) else (1.0,)
    return Twins([build(case, k, dt, iterations, friction, slow) for k in scales], friction,
                 viscous=not slow)


def read_drive(case: Case, motion: Motion, steps: int, dt: float, iterations: int) -> DriveEnd:
    """One reading, free of fictitious inertia (:class:`Twins`); a run that diverges, or
    that leaves the assembly it was started on (:func:`left_assembly`), reads NaN forces,
    which no convergence rule accepts: the next rung of :data:`ITERATIONS` runs instead.

    Gauss–Seidel that stops short of the constraint solve can throw a linkage onto its
    other assembly within tens of steps, and runs that agree there are another linkage's:
    the crank shaper turned 160° (condition number 31) flipped its output dyad (link5
    1.3 rad over, the ram 0.135 m off) after 37 steps at 100 iterations and 86 at 400
    (time step 1e-4 s), and held at 1600; its lead-ins at 400 iterations then agreed to
    1e-7 on the flipped linkage."""
    twins = build_twins(case, motion, dt, iterations)
    units = quantity_units(case.linkage)
    try:
        end = run_drive(twins, motion, steps, dt)
    except Diverged:
        return DriveEnd(dict.fromkeys(units, math.nan), coordinates(twins.base), math.nan)
    return withheld(end, units, case.linkage.scale)


def withheld(end: DriveEnd, units: dict[str, str], scale: float) -> DriveEnd:
    """``end`` with NaN forces where its run left the assembly it was started on
    (:func:`left_assembly`): no convergence rule accepts them."""
    if not left_assembly(end.drift, scale):
        return end
    kinds = {q: quantity_kind(q, units.get(q)) for q in end.values}
    return replace(end, values={q: v if kinds[q] == "pose" else math.nan
                                for q, v in end.values.items()})


def read_stretch(case: Case, motion: Motion, lead: int, dt: float, interval: float,
                 instants: Array, iterations: int) -> list[DriveEnd]:
    """:func:`run_stretch` on fresh twins, as :func:`read_drive` reads one pose: a run that
    diverges reads NaN from there on, a pose where it had left the assembly NaN forces."""
    twins = build_twins(case, motion, dt, iterations)
    units = quantity_units(case.linkage)
    ends: list[DriveEnd] = []
    try:
        ends = run_stretch(twins, motion, lead, dt, round(interval / dt), instants)
    except Diverged:
        lost = DriveEnd(dict.fromkeys(units, math.nan), coordinates(twins.base), math.nan)
        ends = [lost] * len(instants)
    return [withheld(end, units, case.linkage.scale) for end in ends]


def drive_stretch(case: Case, values: Array, results: LinkageResults
                  ) -> list[Solution | None] | None:
    """The ``pymunk`` backend at the poses ``values`` of a continuous sweep (the case at the
    first, turning at constant speed; ``results`` their analytic analysis): one run read at
    each pose as it passes (:func:`run_stretch`), judged by
    :func:`~mechcheck.sim_models.convergence.converge_stretch`, at each rung of
    :data:`ITERATIONS` in turn (:func:`climb`). None where the poses are to be run one by
    one: a refused case, or a Coulomb joint at rest or reversing at a pose; None for a pose
    that no rung's lead-in reached."""
    start = time.perf_counter()
    if refusal(case) is not None or any(at_rest_reason(at_first_driver(case, v), DRIVEN.dt,
                                                       SENSED_RATE) for v in values):
        return None
    runs = 2 if has_fictitious_inertia(case.linkage, False) else 1
    interval = abs(float(values[1] - values[0]) / float(case.linkage.drivers[0].velocity))
    found: list[Rung | None] = [None] * len(values)
    contraction = [cache(lambda k=k: iteration_contraction(
        at_first_driver(case, float(values[k])), np.asarray(results.pose.q)[k]))
        for k in range(len(values))]
    want = dict.fromkeys(range(len(values)), ITERATIONS[0])  # the rung each pose runs next
    steps = 0
    while want:
        iterations = min(want.values())
        pending = [k for k, n in want.items() if n == iterations]
        for group in np.split(np.array(pending, dtype=int),
                              np.flatnonzero(np.diff(pending) != 1) + 1):
            steps += climb(case, values, results, group, iterations, interval, runs, found)
        for k in pending:
            f = found[k]
            out = f[0] if f is not None and f[2] == iterations else None
            rung = None if out is not None and out.converged else next_rung(
                out, iterations, contraction[k], len(case.linkage.joints))
            if rung is None:
                del want[k]
            else:
                want[k] = rung
    share = (time.perf_counter() - start) / len(values)
    solutions: list[Solution | None] = []
    for k, f in enumerate(found):
        if f is not None:
            f[0].total_steps = steps // len(values)
        solutions.append(None if f is None else driven_solution(
            case, results.take(np.array([k])), f[0], f[1], (runs, f[2], contraction[k]), share))
    return solutions


#: A pose's reading at a rung of :data:`ITERATIONS`: its convergence, its run's end, the rung.
Rung = tuple[Convergence, DriveEnd, int]


def climb(case: Case, values: Array, results: LinkageResults, group: Array, iterations: int,
          interval: float, runs: int, found: list[Rung | None]) -> int:
    """One rung for the consecutive poses ``group`` (indices into ``values``) not yet
    converged: a run from a lead-in to the first of them through the rest
    (:func:`~mechcheck.sim_models.convergence.converge_stretch`), each pose's reading put in
    ``found``; a rung whose lead-in does not converge leaves them as they were. Returns the
    steps it took."""
    at = at_first_driver(case, float(values[group[0]]))
    motion = prescribed_motion(at)
    instants = np.asarray(results.pose.q)[group]
    units = quantity_units(case.linkage)
    ends: dict[tuple[float, int], DriveEnd] = {}  # by time step and pose

    def read(lead: int, dt: float, poses: int) -> list[tuple[dict[str, float], dict[str, float]]]:
        got = read_stretch(at, motion, lead, dt, interval, instants[:poses], iterations)
        ends.update(((dt, k), e) for k, e in enumerate(got))
        return [(e.values, {"steps": float(lead + k * round(interval / dt))})
                for k, e in enumerate(got)]

    outs = converge_stretch(read, lead_limit(at, motion, float(results.condition[group[0]])),
                            stretch_timestep(DRIVEN.dt, interval), case.linkage.scale, runs,
                            len(group), units)
    if outs is None:
        return 0
    for j, k in enumerate(group.tolist()):
        end = ends[(outs[j].dt, j)]
        outs[j].solver_disagreement = end.solver_disagreement
        found[k] = (outs[j], end, iterations)
    return outs[0].total_steps * len(outs)


def drive_at_timestep(case: Case, dt: float, lead_time: float) -> Solution:
    """One driven run of ``lead_time`` seconds at the fixed time step ``dt``, with no lead-in
    or time-step refinement: how the reading's error depends on the step (the rigid-joints
    study). The reading is the run's, converged or not."""
    start = time.perf_counter()
    steps = max(1, round(lead_time / dt))
    end = read_drive(case, driven_motion(case, QUASI_STATIC_OMEGA), steps, dt, DRIVEN.iterations)
    return Solution(case.name, BACKEND, end.values, units=quantity_units(case.linkage),
                    diagnostics={"method": "driven", "steps": steps, "timestep": dt,
                                 "wall_time_s": time.perf_counter() - start})


def drive_linkage(case: Case, results: LinkageResults) -> Solution:
    """The ``pymunk`` backend for a moving linkage (method ``driven``); ``results`` is the
    analytic pose analysis of the instant (its condition number bounds the lead-in)."""
    start = time.perf_counter()
    units = quantity_units(case.linkage)
    why = refusal(case)
    if why is not None:
        return Solution(case.name, BACKEND, {}, status="not_applicable", units=units,
                        message=f"a {case.kind} linkage case: {why}")
    at_rest = at_rest_reason(case, DRIVEN.dt, SENSED_RATE)
    if at_rest:
        return Solution(case.name, BACKEND, {}, status="indeterminate", message=at_rest,
                        diagnostics={"method": "driven"}, units=units)
    motion = driven_motion(case, QUASI_STATIC_OMEGA)
    runs = 2 if has_fictitious_inertia(case.linkage, motion.quasi_static) else 1
    scale = case.linkage.scale
    last: list[DriveEnd] = []
    limit = lead_limit(case, motion, float(results.condition[0]))
    steps = 0  # of every attempt
    contraction = cache(lambda: iteration_contraction(case, results.pose.q[0]))
    rung: int | None = ITERATIONS[0]
    while rung is not None:
        iterations = rung

        def read(steps: int, dt: float, iterations: int = iterations) -> dict[str, float]:
            last[:] = [read_drive(case, motion, steps, dt, iterations)]
            return last[0].values

        out = converge(read, limit, DRIVEN.dt, scale, runs, units)
        out.solver_disagreement = last[0].solver_disagreement
        steps += out.total_steps
        rung = None if out.converged else next_rung(out, iterations, contraction,
                                                           len(case.linkage.joints))
    out.total_steps = steps
    return driven_solution(case, results, out, last[0], (runs, iterations, contraction),
                           time.perf_counter() - start)


#: How a driven reading was made: the runs per reading (2 with fictitious inertia to remove),
#: the Gauss–Seidel iterations a step, and the contraction per iteration (:func:`next_rung`).
Made = tuple[int, int, Callable[[], float]]


def driven_solution(case: Case, results: LinkageResults, out: Convergence, end: DriveEnd,
                    made: Made, elapsed: float) -> Solution:
    linkage = case.linkage
    units = quantity_units(linkage)
    radius = np.array([gyration_radius(linkage, link) for link in linkage.moving_links])
    q = end.q[None, :]
    runs, iterations, contraction = made
    diagnostics = RunDiagnostics(
        "driven", out.total_steps, elapsed, end.rate_error, float(loop_violations(linkage, q)[0]),
        float(pose_drifts(radius, q, results.pose.q[:1])[0]),
    ).as_dict(lead_disagreement=out.lead_disagreement, lead_steps=out.lead_steps,
              timestep=out.dt, timestep_disagreement=out.timestep_disagreement,
              fictitious_runs=runs, iterations=iterations,
              fictitious_inertia_correction=end.correction,
              solver_disagreement=end.solver_disagreement)
    return driven_verdict(case.name, BACKEND, out, diagnostics, units, linkage.scale,
                          lambda: unconverged(out, end, linkage.scale)
                          + instability(iterations, contraction(), len(linkage.joints))
                          + self_locking_note(results))


def instability(iterations: int, per_iteration: float, joints: int) -> str:
    """What a run at ``iterations`` a step lacked, where one step left more of the constraint
    solve's slowest mode than a stable run may (:data:`STABLE_STEP_CONTRACTION`), or ``""``;
    ``joints``: the linkage's, which bound its last rung (:func:`rungs`)."""
    left = per_iteration ** iterations
    if left <= STABLE_STEP_CONTRACTION:
        return ""
    needed = (math.log(STABLE_STEP_CONTRACTION) / math.log(per_iteration)
              if 0.0 < per_iteration < 1.0 else math.inf)
    return (f"; one step's Gauss–Seidel left {left:.2f} of the constraint solve's slowest mode "
            f"at {iterations} iterations (stable: ≤ {STABLE_STEP_CONTRACTION}, "
            f"STABLE_STEP_CONTRACTION): a stable run needs about {needed:.3g} iterations a "
            f"step; this linkage's ladder ends at {rungs(joints)[-1]} (ITERATIONS within "
            "ITERATION_BUDGET)")


def unconverged(out: Convergence, end: DriveEnd, scale: float) -> str:
    """Why a driven run gives no number: its last run left the assembly (at the most
    Gauss–Seidel iterations tried, :func:`read_drive`), or a convergence check failed."""
    left = left_assembly(end.drift, scale)
    if not left:
        return out.verdict()
    if out.lead_limit:   # the lead-in could not be made long enough: that, not the solver
        return f"{left}; {out.verdict()}"
    return (f"{left}; pymunk's Gauss–Seidel solve did not hold the linkage (the last run: "
            f"{out.lead_steps} steps of {out.dt:.3g} s)")
