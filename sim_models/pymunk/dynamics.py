"""Driven runs: dynamic cases (ω, α ≠ 0) and friction cases, backend ``pymunk``.

The drive link is locked (GearJoint, ratio 1) to a kinematic "clock" body
whose angle follows the prescribed motion of link 2,
θ12(t) = θ12* + ω·τ + ½·α·τ² with τ = t − t*, so the crank reaches the case's
θ12 at t*. When the drive acts on the rocker the clock follows θ14(θ12(t))
from the closed-form kinematics: the motion is still prescribed through θ12
(CONVENTIONS.md), only the torque acts on link 4. Friction cases that are
static (ω = 0) are driven quasi-statically at ``QUASI_STATIC_OMEGA`` in the
case's ``direction``.

A run starts a lead-in of n steps before t*, on the closed-form pose *and
velocities* (a seed, so there is no start-up shock), with the real masses
and inertias; massless links get ``driven_fictitious_mass`` (its inertia
force is removed by extrapolation, see :func:`drive`). Loads, weights and
friction forces are applied inside pymunk's velocity integration, i.e. at the
pose the step's constraint impulses belong to. The reading is taken where the
crank actually passes θ12* next to t* (:func:`reading_at`).

Nothing about a run is a fixed step count (see :data:`LEAD_MIN`): the
lead-in and the solver iterations grow until the readings are free of
start-up noise (:func:`lead_ladder`), and the time step halves until two
successive readings agree (:func:`drive_once`). Both are judged on pymunk's
own readings only; the analytic side supplies the prescribed motion, the
seed, and the geometry's condition number that keeps the lead-in clear of
dead points (:func:`lead_window`). What cannot be met within the budgets is
reported ``not_settled`` with the reason, never as forces.

Why the drive-on-link-4 cases need this. With the torque on the rocker, the
rocker cannot move the crank where crank and coupler are in line
(dθ14/dθ12 = 0, a dead point of the rocker drive), and next to such a point
the loop is ill-conditioned: the crank is barely held, warm-started
Gauss–Seidel at 100 iterations no longer keeps up with the motion, and the
forces of a run that crosses the point, or starts near it, oscillate by
O(100 %) from step to step. fourbar-dynamic-drive4's old 400-step lead-in
started 5.6° on the far side of such a point (θ12 ≈ 223.7°, 327 steps
before t*). seed-exam-Q3 reads 6.8° of crank rotation short of one
(θ12 ≈ 36.8°; at θ12* crank and coupler are 8.6° from in line), where the
forces vary so fast (by 100 % within ~200 steps) that their genuine second
difference per step, 1.4e-4, failed the old smoothness test, which took it
for noise (the reading itself was 8e-5 off). A third defect showed on the
way: the closed-form θ14 jumps by 2π at θ12 = 180°, and the clock followed
the jump (see :meth:`Drive.link_angles`).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass

import numpy as np
import pymunk

from mechcheck.analytic.case import Case
from mechcheck.analytic.kinematics import pose_of
from mechcheck.analytic.solution import FORCE_FLOOR_N, Solution
from mechcheck.sim_models.coulomb import coulomb_reversal as sense_change
from mechcheck.sim_models.pymunk.friction import (
    Diverged,
    FrictionLoads,
    State,
    apply_friction,
    friction_loads,
    speeds,
)
from mechcheck.sim_models.pymunk.loads import apply_load_set
from mechcheck.sim_models.pymunk.model import Model, build_model, has_fictitious_inertia
from mechcheck.sim_models.pymunk.readout import (
    Values,
    crank_angle,
    loop_violation,
    pose_drift,
    pose_values,
    reactions,
    residual_velocity,
)
from mechcheck.sim_models.pymunk.settings import SolverSettings
from mechcheck.sim_models.pymunk.verdict import singular_mask

BACKEND = "pymunk"

#: rad/s of the quasi-static drive of a static friction case. Slow enough that
#: the inertia forces of the (light) bodies, m·ω²·L, are ~1e-10 of the loads,
#: fast enough that every joint keeps a definite sense of relative motion.
QUASI_STATIC_OMEGA = 0.01

#: Settings of driven runs. dt is small because here, unlike in statics, the
#: integration error is part of the force (the reactions carry m·a); the
#: reading is checked against dt/2 (:data:`STEP_AGREEMENT`). No damping: it
#: would remove momentum that the constraint forces must supply. error_bias = 0
#: corrects the whole joint error every step (Chipmunk's bias coefficient is
#: 1 − error_bias^dt): at dt = 1e-4 any "per second" bias that is not ~0
#: corrects almost nothing per step, and the drifting loop then biases the
#: forces (measured: 0.9⁶⁰ → 7e-3, 1e-300 → 5e-5, 0 → 2e-6 on a slider-crank
#: at 20 rad/s). Massless links get 1 kg (well conditioned against real
#: masses of ~1 kg; its inertia force is removed by extrapolation, see
#: :func:`drive`). ``iterations`` is the first rung of :func:`lead_ladder`.
DRIVEN = SolverSettings(dt=1.0e-4, iterations=100, error_bias=0.0, damping=1.0,
                        driven_fictitious_mass=1.0)

#: First lead-in (steps before t*) and the most it may grow to. A driven
#: run is never read after a fixed number of steps: the prescribed motion
#: fixes *when* the reading is taken (at t*, where the crank passes θ12*), and
#: what is adaptive is how long the start-up transient is given. An attempt is
#: accepted only if its readings were free of noise (SMOOTHNESS) over the
#: SMOOTH_READINGS steps up to the reading, i.e. the transient had died and the
#: solver kept up; otherwise the lead-in and the iterations double, within
#: LEAD_MAX / MAX_ITERATIONS and the regular window (:func:`lead_window`), and
#: when those are spent the run reports ``not_settled`` with the reason, never
#: forces. Measured: once the solver keeps up, a seeded run's transient dies
#: within ~10–40 steps, so most cases are accepted at the first rung.
LEAD_MIN = 50
LEAD_MAX = 1600

#: Solver iterations per step may double with the lead-in up to this. Near a
#: dead point of the drive the loop is ill-conditioned and warm-started
#: Gauss–Seidel at 100 iterations does not keep up with the motion: measured
#: on fourbar-dynamic-drive4 (dθ14/dθ12 = 0.14 at the reading) the forces
#: oscillate by O(100 %) step to step at 100 iterations and are smooth from
#: 200 on.
MAX_ITERATIONS = 1600

#: The lead-in stays where the mechanism is no harder for the solver than at
#: the reading: the equilibrium's condition number (geometry only, the one
#: the singular verdict uses) at most this multiple of its value at θ12*.
#: This keeps the run clear of a dead point of the rocker drive (there the
#: rocker cannot move the crank, which then goes its own way, and next to it
#: the start-up transient does not die) and of a change point (where a
#: crank-driven rocker may fold onto the other branch).
WINDOW_CONDITION = 2.0

#: Noise criterion. The smooth part of a force sampled every step has a k-th
#: difference of about F·(dt/T)^k, T the time over which it varies;
#: step-to-step noise of amplitude σ (a start-up transient, a solver that does
#: not keep up) gives ~2^k·σ. The 4th difference separates the two by far:
#: on the fast-varying seed-exam-Q3 reading the 2nd difference is 1.4e-4 but
#: the 4th is 1.4e-7; the other driven cases give ≤ 1e-7 and runs that have
#: not settled 7e-4 … 1. The limit bounds the noise left in a reading to
#: ~1e-6 of the force scale, 1000× below the 1e-3 dynamic target.
SMOOTHNESS = 1.0e-5

#: The noise criterion must hold over this many consecutive steps ending at
#: the reading: longer than the few steps the joint-error correction
#: (error_bias = 0: dead-beat) takes, so a transient that is still dying out
#: is not taken for a smooth run.
SMOOTH_READINGS = 20

#: Readings the noise criterion needs: SMOOTH_READINGS 4th differences.
NOISE_SPAN = SMOOTH_READINGS + 4

#: rad: at t* the crank must be this close to θ12* (measured ≤ 3e-6 when it
#: follows its clock); farther means the loop did not follow the motion.
TRACKING_LIMIT = 1.0e-4

#: Step-size check. The integration error of a driven reading falls as dt²
#: (measured 4–6× per halving next to rocker dead points), so a reading is
#: repeated at dt/2 and accepted when the two differ by at most this fraction
#: of the force scale: the finer one, which is reported, is then ~1/3 of that,
#: 1e-4, 10× below the 1e-3 dynamic target. Otherwise dt keeps halving down to
#: DRIVEN.dt / MAX_REFINEMENT (also when a reading is not smooth: next to a
#: dead point the forces can vary within ~10 steps of 1e-4 s, measured on
#: seed-exam-Q3 at θ12 = 35°, and a finer step resolves them).
STEP_AGREEMENT = 3.0e-4
MAX_REFINEMENT = 4

#: Passes per step of a run with friction: the step under the loads of its
#: predicted state, then once more under the loads of the state that pass
#: made (:mod:`~mechcheck.sim_models.pymunk.friction`). One correction leaves
#: the loads' error at the friction's feedback gain times the prediction's
#: O(dt²) error; the time-step check (STEP_AGREEMENT) measures what is left.
FRICTION_PASSES = 2


@dataclass
class Drive:
    """The prescribed motion: crank angle θ12(t) and the links' closed-form angles along it."""

    case: Case
    omega: float
    alpha: float
    t_star: float = 0.0

    def theta12(self, t: np.ndarray | float) -> np.ndarray:
        tau = np.asarray(t, dtype=float) - self.t_star
        return self.case.theta12 + self.omega * tau + 0.5 * self.alpha * tau * tau

    def link_angles(self, t: np.ndarray, anchor: int) -> dict[int, np.ndarray]:
        """Closed-form angles of links 2–4 at the times ``t``, continuous along them.

        The closed form gives each angle modulo 2π (θ14 = f ∓ acos(…) with
        f = atan2(B, A) jumps by 2π where B changes sign, e.g. at θ12 = 180°),
        and a clock told to follow such a jump turns the rocker a full
        revolution in one step. So the angles are unwrapped along ``t`` (a
        step turns a link far less than π) and shifted by whole turns so that
        ``t[anchor]`` keeps the closed form's own value: the run then ends on
        the reported convention.
        """
        pose = pose_of(self.case, np.atleast_1d(self.theta12(t)), omega=0.0, alpha=0.0)
        out = {}
        for link, state in pose.links.items():
            smooth = np.unwrap(state.angle)
            out[link] = smooth + (state.angle[anchor] - smooth[anchor])
        return out


def drive_motion(case: Case) -> tuple[float, float]:
    """(ω, α) the crank is driven with: the case's, or a slow quasi-static turn."""
    if case.motion.is_static:
        return QUASI_STATIC_OMEGA * case.input_sense, 0.0
    return case.motion.omega, case.motion.alpha


def seed_state(model: Model, drive: Drive, t: float, angles: dict[int, float]) -> None:
    """Closed-form pose and velocities at time t (the start of the lead-in).

    ``angles`` are the links' angles at t on the run's continuous branch
    (:meth:`Drive.link_angles`); they differ from the closed form's by whole turns.
    """
    th = drive.theta12(t)
    w = drive.omega + drive.alpha * (t - drive.t_star)
    pose = pose_of(model.case, np.atleast_1d(th), omega=w, alpha=drive.alpha)
    for link, body in model.bodies.items():
        s = pose.links[link]
        body.angle = angles[link]
        body.position = (float(s.origin[0, 0]), float(s.origin[0, 1]))
        cog = body.local_to_world(body.center_of_gravity) - body.position
        # Velocity of the centre of gravity: v_origin + ω × r.
        body.velocity = (float(s.velocity[0, 0]) - float(s.omega[0]) * cog.y,
                         float(s.velocity[0, 1]) + float(s.omega[0]) * cog.x)
        body.angular_velocity = float(s.omega[0])
    model.driver.angle = angles[model.case.drive_link]
    model.driver.angular_velocity = float(pose.links[model.case.drive_link].omega[0])
    model.drive.phase = 0.0


def install_force_callbacks(model: Model, extras: dict[int, tuple[float, float, float]]) -> None:
    """Apply loads (at the integrated pose) and this step's friction forces inside pymunk.

    ``extras[link] = (fx, fy, torque)`` holds the friction forces of the step
    (:func:`~mechcheck.sim_models.pymunk.friction.apply_friction`); the slider's force acts at B.
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


def combined_reactions(models: list[Model], slide: float) -> tuple[Values, Values]:
    """The reactions of one step, free of fictitious inertia (see :func:`drive`), and the
    base model's own.

    ``models`` is the case as built and, when it has massless links, the same
    with twice their fictitious inertia; every friction load is the same on
    both, so F₀ = 2·F(1) − F(2) holds exactly as without friction.
    """
    values = [reactions(m, slide) for m in models]
    if len(values) == 1:
        return values[0], values[0]
    return {q: 2.0 * v - values[1][q] for q, v in values[0].items()}, values[0]


def predicted(history: list[State]) -> State | None:
    """The next step's state extrapolated linearly from the last two (error O(dt²))."""
    if not history:
        return None
    if len(history) == 1:
        return history[-1]
    last, before = history[-1], history[-2]
    return {q: 2.0 * v - before[q] for q, v in last.items()}


def step_models(models: list[Model], extras: list[dict[int, tuple[float, float, float]]],
                loads: FrictionLoads, rate: float) -> tuple[Values, Values, State]:
    """One step of every model under ``loads``; returns the reactions, the base model's own
    (:func:`combined_reactions`) and the state they make."""
    dt = models[0].settings.dt
    for model, mine in zip(models, extras, strict=True):
        if model.case.friction is not None:
            apply_friction(model, loads, mine)
        model.driver.angular_velocity = rate
        model.space.step(dt)
    values, raw = combined_reactions(models, loads.slide)
    state = values | speeds(models[0])
    if not all(math.isfinite(v) for v in (*state.values(), *raw.values())):
        raise Diverged("a reaction or speed became non-finite")
    return values, raw, state


@dataclass(frozen=True)
class Reading:
    """One step's crank angle and values (pose and reactions)."""

    theta12: float
    values: Values
    correction: float = 0.0  # largest force (N) or torque (N·m) the fictitious-inertia twin removed
    raw: Values | None = None  # the base model's own reactions when a twin ran beside it


@dataclass(frozen=True)
class Window:
    """The longest lead-in (steps before t*) on a regular stretch of the motion, and its limit."""

    steps: int
    reason: str
    condition: float  # the equilibrium's condition number at θ12*


def lead_window(case: Case, drive: Drive, dt: float, budget: int = LEAD_MAX) -> Window:
    """How far before t* the prescribed motion may start (kinematics and geometry only).

    At every step time of the longest lead-in the equilibrium's condition
    number must stay within WINDOW_CONDITION× its value at θ12*. A reversal
    of ω inside the lead-in is allowed: the reading is taken at t*.
    """
    t = drive.t_star - dt * np.arange(budget + 1)
    _, condition = singular_mask(case, drive.theta12(t))
    limit = WINDOW_CONDITION * condition[0]
    worse = np.nonzero(~(condition <= limit))[0]
    if not worse.size:
        return Window(budget, f"it reached the lead-in budget ({budget} steps)",
                      float(condition[0]))
    n = int(worse[0])
    return Window(n - 1, f"the equilibrium's condition number rises from {condition[0]:.3g} at "
                         f"θ12* past {limit:.3g} {n} steps before it (θ12 = "
                         f"{math.degrees(float(drive.theta12(t[n]))):.2f}°), "
                         f"{singularity_ahead(case, drive, t, condition, n)}",
                  float(condition[0]))


def singularity_ahead(case: Case, drive: Drive, t: np.ndarray, condition: np.ndarray,
                      n: int) -> str:
    """Name what the lead-in approaches from step n on: a rocker-drive dead point or a change point.

    It is the first peak of the condition number at or after step n; a dead
    point of the rocker drive is where dθ14/dθ12 changes sign there.
    """
    bad = ~np.isfinite(condition)
    finite = np.where(bad, np.finfo(float).max, condition)  # inf − inf would warn (a change point)
    rising = np.nonzero(bad[n:] | (np.append(np.diff(finite[n:]), -1.0) < 0.0))[0]
    m = n + int(rising[0])
    where = f"θ12 ≈ {math.degrees(float(drive.theta12(t[m]))):.2f}°, {m} steps before θ12*"
    if case.drive_link == 4:
        near = t[max(m - 2, 0):m + 3]
        ratio = pose_of(case, np.atleast_1d(drive.theta12(near)), omega=1.0, alpha=0.0).links[4].omega
        if np.nanmin(ratio) < 0.0 < np.nanmax(ratio):
            return (f"approaching a dead point of the rocker drive at {where} (crank and coupler "
                    "in line, dθ14/dθ12 = 0: the rocker cannot drive the crank there)")
    return f"approaching a change point or toggle of the loop at {where}"


def interpolate(a: Reading, b: Reading, c: Reading, theta: float) -> Values:
    """The values where the crank passed θ between readings b and c (a, b, c consecutive).

    The crossing's fraction w of the step comes from the crank angles
    (linear); the values are interpolated quadratically in time through the
    three readings (equal steps), which leaves an error of the order of their
    third difference rather than the second (next to a dead point the forces
    vary fast, see SMOOTHNESS).
    """
    span = c.theta12 - b.theta12
    w = (theta - b.theta12) / span if span else 0.0
    return {q: b.values[q] + 0.5 * w * (c.values[q] - a.values[q])
            + 0.5 * w * w * (c.values[q] - 2.0 * b.values[q] + a.values[q]) for q in c.values}


def reading_at(readings: list[Reading], lead: int, theta: float) -> tuple[Values, int]:
    """The reading at θ12* and how many of ``readings`` it draws on.

    It is where the crank passes θ12* within a step of t*, else at t* itself.
    ``readings[i]`` is step i + 1, step ``lead`` ends at t*. The crank follows
    its clock to ~1e-6 rad; interpolating to where it actually passes θ12*
    removes that. When it does not pass θ12* within a step of t* (it is
    momentarily at rest there, ω(t*) = 0, or moves less per step than its
    tracking error), the reading at t* is taken as it is. The step past t*
    is drawn on (and judged, :func:`lead_ladder`) only when the crank passes
    θ12* during it.
    """
    for k in (lead, lead - 1):  # a crossing between steps k and k + 1
        if k < 2 or k >= len(readings):
            continue
        a, b, c = readings[k - 2], readings[k - 1], readings[k]
        if b.theta12 != c.theta12 and (b.theta12 - theta) * (c.theta12 - theta) <= 0.0:
            return interpolate(a, b, c, theta), k + 1
    return dict(readings[lead - 1].values), lead


def _force_table(rows: list[Values], length: float) -> np.ndarray:
    """Forces and torques / length of the readings, one row per reading (N)."""
    names = [q for q in rows[-1] if q[0] in "FTM"]
    return np.array([[r[q] / (length if q[0] in "TM" else 1.0) for q in names] for r in rows])


def _relative_difference(rows: list[Values], order: int, length: float) -> float:
    table = _force_table(rows, length)
    scale = max(float(np.abs(table[-1]).max()), FORCE_FLOOR_N)  # an unloaded case is smooth too
    return float(np.abs(np.diff(table, n=order, axis=0)).max()) / scale


def roughness(readings: list[Reading], length: float) -> float:
    """Largest 4th difference of the forces over the last SMOOTH_READINGS steps, relative to their scale.

    Judged on the reported forces and on the base model's own: a solver that
    does not keep up shows in both, but where the fictitious inertia carries
    all the force (an unloaded massless case, whose reported forces are 0) only
    in the latter (measured: such a slider-crank next to its limit position,
    read at 100 iterations, was 2.2e-3 rad off in θ13 with 0 roughness).
    ``inf`` when there are fewer than NOISE_SPAN readings (nothing to judge).
    """
    if len(readings) < NOISE_SPAN:
        return math.inf
    last = readings[-NOISE_SPAN:]
    return max(_relative_difference([r.values for r in last], 4, length),
               _relative_difference([r.raw or r.values for r in last], 4, length))


def curvature(readings: list[Reading], length: float) -> float:
    """Last 2nd difference of the forces relative to their scale (diagnostic: how fast they vary)."""
    return (_relative_difference([r.values for r in readings[-3:]], 2, length)
            if len(readings) >= 3 else math.inf)


def force_change(new: Values, old: Values, length: float) -> float:
    """Largest difference of forces (torques / length) between two readings, relative to their scale."""
    names = [q for q in new if q[0] in "FTM"]
    unit = {q: length if q[0] in "TM" else 1.0 for q in names}
    scale = max(max(abs(new[q]) / unit[q] for q in names), FORCE_FLOOR_N)
    return max(abs(new[q] - old[q]) / unit[q] for q in names) / scale


def run_drive(models: list[Model], drive: Drive, lead: int,
              on_step: Callable[[], None] | None = None) -> list[Reading]:
    """Step from ``lead`` steps before t* to one step past it; returns every step's reading.

    ``models`` run in lockstep (the case and, with massless links, its twice
    heavier twin, see :func:`combined_reactions`). With friction every step
    is taken FRICTION_PASSES times from the same start: first with the loads
    of the predicted state, then with those of the state the last pass made
    (:mod:`~mechcheck.sim_models.pymunk.friction`). Raises :class:`Diverged`
    when a number goes non-finite.
    """
    base = models[0]
    dt = base.settings.dt
    t0 = drive.t_star - lead * dt
    steps = lead + 1
    angles = drive.link_angles(t0 + dt * np.arange(steps + 1), anchor=lead)
    targets = angles[base.case.drive_link][1:]
    extras: list[dict[int, tuple[float, float, float]]] = []
    for model in models:
        seed_state(model, drive, t0, {link: float(a[0]) for link, a in angles.items()})
        extras.append({})
        install_force_callbacks(model, extras[-1])
    passes = FRICTION_PASSES if base.case.friction is not None else 1
    history: list[State] = []
    readings: list[Reading] = []
    for step in range(1, steps + 1):
        rate = (float(targets[step - 1]) - base.driver.angle) / dt
        guess = predicted(history)
        loads = friction_loads(base.case, guess) if guess is not None else FrictionLoads()
        saved = [snapshot((*m.bodies.values(), m.driver)) for m in models] if passes > 1 else []
        for attempt in range(passes):
            if attempt:
                for bodies in saved:
                    restore(bodies)
                loads = friction_loads(base.case, history.pop())
            values, raw, state = step_models(models, extras, loads, rate)
            history.append(state)
        if on_step is not None:
            on_step()
        twin = len(models) > 1
        correction = max(abs(v - values[q]) for q, v in raw.items()) if twin else 0.0
        readings.append(Reading(crank_angle(base), pose_values(base) | values, correction,
                                raw if twin else None))
        del history[:-2]
    return readings


@dataclass(frozen=True)
class Rung:
    """One attempt's lead-in (steps before t*) and solver iterations per step."""

    lead: int
    iterations: int


def next_rung(rung: Rung, window: Window, settings: SolverSettings) -> Rung | None:
    """Twice the lead-in and the iterations, within their limits; None when both are spent."""
    most = max(MAX_ITERATIONS, settings.iterations)
    if rung.lead >= window.steps and rung.iterations >= most:
        return None
    return Rung(min(2 * rung.lead, window.steps), min(2 * rung.iterations, most))


@dataclass
class Driven:
    """The outcome of a driven reading at one dt: values (empty unless ok) and how it went."""

    ok: bool
    values: Values
    rung: Rung
    diagnostics: dict[str, float | str]
    message: str = ""


def lead_ladder(case: Case, settings: SolverSettings, first: Rung | None = None) -> Driven:
    """One reading at ``settings.dt``, with the lead-in and iterations grown until it is smooth.

    Attempts start at ``first`` (default LEAD_MIN steps, ``settings.iterations``)
    and climb :func:`next_rung` until one passes the noise criterion with the
    crank on θ12* at t*.
    """
    start = time.perf_counter()
    omega, alpha = drive_motion(case)
    drive = Drive(case, omega, alpha)
    window = lead_window(case, drive, settings.dt)
    rung = first or Rung(LEAD_MIN, settings.iterations)
    rung = Rung(min(rung.lead, window.steps), rung.iterations)
    diag: dict[str, float | str] = {"method": "driven", "drive_omega": omega, "dt": settings.dt,
                                    "lead_window": window.steps,
                                    "condition_number": window.condition}
    if window.steps < NOISE_SPAN:
        diag["wall_time_s"] = time.perf_counter() - start
        return Driven(False, {}, rung, diag,
                      f"no room for a lead-in: the prescribed motion is regular for only "
                      f"{window.steps} steps of {settings.dt:g} s before θ12* (at least "
                      f"{NOISE_SPAN} are needed to judge the start-up transient) because "
                      f"{window.reason}")
    length = case.geometry.scale
    attempts = steps = 0
    diverged = ""
    while True:
        attempts += 1
        models = build_models(case, settings.with_(iterations=rung.iterations))
        try:
            readings = run_drive(models, drive, rung.lead)
            diverged = ""
        except Diverged as error:
            readings, diverged = [], str(error)
        steps += len(readings) * len(models)
        used = reading_at(readings, rung.lead, case.theta12) if readings else None
        rough = roughness(readings[:used[1]], length) if used else math.inf
        tracking = readings[rung.lead - 1].theta12 - case.theta12 if readings else math.inf
        if rough <= SMOOTHNESS and abs(tracking) <= TRACKING_LIMIT:
            break
        climbed = next_rung(rung, window, settings)
        if climbed is None:
            break
        rung = climbed
    model = models[0]
    diag |= {
        "steps": steps, "attempts": attempts, "lead_steps": rung.lead,
        "iterations": rung.iterations, "wall_time_s": time.perf_counter() - start,
        "roughness": rough, "tracking_error": tracking,
    }
    if readings:
        diag |= {
            "residual_velocity": residual_velocity(model),
            "loop_violation": loop_violation(model),
            "pose_drift": pose_drift(model, crank_angle(model)),
            "curvature": curvature(readings, length),
            "fictitious_inertia_correction": readings[rung.lead - 1].correction,
        }
    if rough <= SMOOTHNESS and abs(tracking) <= TRACKING_LIMIT:
        assert used is not None
        return Driven(True, used[0], rung, diag)
    if diverged:
        what = (f"the simulation diverged ({diverged}) even at {rung.iterations} solver "
                "iterations per step")
    elif rough > SMOOTHNESS:
        what = (f"step-to-step noise {rough:.3g} in the forces over the last {SMOOTH_READINGS} "
                f"steps (4th difference, limit {SMOOTHNESS:g}): the start-up transient did not "
                "die or the solver did not keep up")
    else:
        what = (f"the crank was {tracking:.3g} rad from θ12 at t* (limit {TRACKING_LIMIT:g}): "
                "the loop did not follow the prescribed motion")
    limited = (f"; the lead-in could not be longer because {window.reason}"
               if rung.lead >= window.steps else "")
    return Driven(False, {}, rung, diag,
                  f"the driven run did not pass θ12 smoothly after "
                  f"{attempts} attempt(s) (lead-in up to {rung.lead} steps, up to "
                  f"{rung.iterations} solver iterations per step; condition number "
                  f"{window.condition:.3g} at θ12*): {what}{limited}")


def drive_once(case: Case, settings: SolverSettings, first: Rung | None = None
               ) -> tuple[Solution, Values, Rung]:
    """One driven reading, converged in the time step; returns Solution, values and first rung.

    A reading (:func:`lead_ladder`) is taken at ``settings.dt``, then at dt/2,
    dt/4, … (each starting from the previous level's lead-in time and
    iterations), down to dt / MAX_REFINEMENT. The first reading that agrees
    within STEP_AGREEMENT with the one at twice its step is reported. A level
    whose readings were not smooth is passed over (a finer step both removes
    integration noise and resolves forces that vary fast next to a dead
    point), but it cannot serve as the check of the next one. ``first`` is the
    first rung at ``settings.dt``; the rung returned is the last one tried
    there (where a second run of the same case can start).
    """
    length = case.geometry.scale
    wall, steps = 0.0, 0
    rung = first
    coarsest = first or Rung(LEAD_MIN, settings.iterations)
    previous: Driven | None = None
    tried: list[str] = []
    refinement = 1
    while True:
        dt = settings.dt / refinement
        run = lead_ladder(case, settings.with_(dt=dt), rung)
        wall += float(run.diagnostics["wall_time_s"])
        steps += int(run.diagnostics.get("steps", 0))
        diag = run.diagnostics | {"wall_time_s": wall, "steps": steps}
        if refinement == 1:
            coarsest = run.rung
        if run.ok and previous is not None and previous.ok:
            change = force_change(run.values, previous.values, length)
            diag["step_change"] = change
            if change <= STEP_AGREEMENT:
                return (Solution(case.name, BACKEND, run.values, diagnostics=diag), run.values,
                        coarsest)
            tried.append(f"dt = {dt:g} s: smooth, but {change:.3g} of the force scale from the "
                         f"reading at dt = {2 * dt:g} s (limit {STEP_AGREEMENT:g})")
        elif run.ok:
            tried.append(f"dt = {dt:g} s: smooth")
        else:
            tried.append(f"dt = {dt:g} s: {run.message}")
        if refinement >= MAX_REFINEMENT:
            break
        previous, rung = run, Rung(2 * run.rung.lead, run.rung.iterations)
        refinement *= 2
    return (Solution(case.name, BACKEND, {}, status="not_settled",
                     message="no driven reading converged in the time step (condition number "
                             f"{float(diag.get('condition_number', math.nan)):.3g} at θ12*): "
                             + "; ".join(tried), diagnostics=diag),
            {}, coarsest)


def build_models(case: Case, settings: SolverSettings) -> list[Model]:
    """The models a driven run steps in lockstep: the case with its real masses and, when
    it is moving and some link has fictitious mass or inertia (a massless link, or a
    near-point mass: :func:`~mechcheck.sim_models.pymunk.model.added_inertia`),
    the same with twice all of it."""
    models = [build_model(case, settings, mass_mode="real", driver_kind="kinematic")]
    if not case.motion.is_static and has_fictitious_inertia(case, settings):
        heavier = settings.with_(fictitious_scale=2.0 * settings.fictitious_scale)
        models.append(build_model(case, heavier, mass_mode="real", driver_kind="kinematic"))
    return models


def coulomb_reversal(case: Case, settings: SolverSettings) -> str:
    """Why no driven reading can be judged: a Coulomb term's relative motion reverses (or
    stops) where the reading is judged; empty when none does.

    A reading is accepted only when it is smooth over the NOISE_SPAN steps up
    to it at two successive time steps, the finer at most ``settings.dt / 2``
    (:func:`drive_once`). A Coulomb force reversing inside that stretch jumps
    by twice its size there: no smooth reading exists, however fine the step.
    The step after t* counts too: where the crank is nearly at rest at t*
    its tracking error (~1e-7 rad) can put the crossing of θ12* into that
    step, and the reading then draws on it (measured: ω = −6e-8 rad/s,
    α = 168 rad/s², a reversal 4e-10 s after t*, was ``not_settled``).
    Kinematics only (the prescribed motion); no force enters.
    """
    omega, alpha = drive_motion(case)
    dt = settings.dt / 2.0
    joint, what = sense_change(case, omega, alpha, dt * np.arange(-NOISE_SPAN, 2), NOISE_SPAN)
    if not joint:
        return ""
    if what.startswith("reverses"):
        what = f"reverses within {NOISE_SPAN * dt:.3g} s before the reading or one step after it"
    return (f"the relative motion of the Coulomb friction at {joint} {what} (prescribed "
            f"motion ω = {omega:g} rad/s, α = {alpha:g} rad/s²): its friction force "
            f"jumps by twice its size there, inside the {NOISE_SPAN} steps of "
            f"{dt:g} s over which a driven reading must be smooth, so no reading can "
            "be told from noise")


def drive(case: Case, settings: SolverSettings = DRIVEN) -> Solution:
    """The ``pymunk`` backend for dynamic and friction cases: drive through θ12 and read there.

    Fictitious inertia of massless links: with the motion prescribed, every
    reaction is affine in the fictitious masses and inertias, F(k) = F₀ + k·G
    when they are all scaled by k, as long as every other load is the same.
    A dynamic case with such links is therefore run at k = 1 and k = 2 in
    lockstep (:func:`build_models`), every step's friction loads taken from
    the combination F₀ = 2·F(1) − F(2) and applied to both, and F₀ is what
    is read and judged: the massless answer, from pymunk's numbers alone.
    Friction taken from each run's own reactions is not affine in k (μ·|F(k)|),
    and the fictitious inertia forces are no small part of them (1 kg links at
    16.6 rad/s: ~1000 N against ~130 N of load on a random slider-crank), so
    extrapolating two independent runs was 39 % off there. In a quasi-static
    friction run the fictitious inertia force, m·ω²·L ≈ 1e-5 N, is left as is.
    """
    why = coulomb_reversal(case, settings)
    if why:
        return Solution(case.name, BACKEND, {}, status="indeterminate", message=why,
                        diagnostics={"method": "driven"})
    solution, _, _ = drive_once(case, settings)
    return solution
