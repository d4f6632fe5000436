"""Exam Q1 and Q2 of seed 002 as pymunk models: Q1 settles, Q2 is driven.

Both spaces use ``Space.gravity = (0, −g)`` (every body is a real mass with
its real weight), no collision shapes (nothing collides), and a constant dt
per run, because every force is read as an accumulated impulse divided by
the dt of the step that produced it. Force *vectors* come from the solver's
accumulated impulses through :func:`mechcheck.sim_models.pymunk.forces.force_on_b`
(``Constraint.impulse`` is only a magnitude); that reader checks its struct
layout against pymunk's public values before the first read.

Q1 (:func:`settle_q1`). The slider is a body of infinite moment (it only
translates) held on the line y = 0 by a :class:`pymunk.GrooveJoint` to the
static body: the groove's impulse is the slide's normal force. The spring is
a :class:`pymunk.DampedSpring` of rest length 0 from the origin to the
slider, i.e. the force −k·(x, y) on the slider, unstretched at x = 0; its
signed impulse along the spring is read back as the spring force. The bar
hangs from the slider on a :class:`pymunk.PivotJoint` at A (body a = slider,
body b = bar, so the pivot's impulse on b is the pin force by the slider on
the bar). F is applied at B's current position every step. The motion is
damped by the spring's own damping (slider x) and a
:class:`pymunk.DampedRotarySpring` of zero stiffness on the bar, both roughly
critical; neither exerts anything at rest. ``Space.damping`` is *not* used:
Chipmunk applies a spring's impulse before it damps the velocities, so space
damping scales the spring force itself (measured: 0.86·k·x at damping^dt =
0.86, the slider settled 16 % too far out). The run starts from a pose the
caller chooses (default x = 0, φ = 0), never the analytic equilibrium, and
stops when it has settled or its step budget is spent (``not_settled``).

Q2 (:func:`drive_q2`). The mass (infinite moment) is held on y = 0 by a
groove to the static body (the normal force N) and tied in x to a kinematic
driver by a second groove, vertical and fixed to the driver: its impulse is
horizontal and is the drive force F. The driver is placed on the prescribed
x(t) every step and given the velocity (x(t_{n+1}) − x(t_n))/dt, so the mass
ends each step with that velocity and starts the next one exactly on the
path. The springs are two DampedSprings from walls at ∓:data:`WALL_DISTANCE`
with rest length equal to that distance (unstretched at x = 0). Pymunk has
no Coulomb friction without colliding shapes, so friction is a force
−μ·N·sign(ẋ) applied to the mass before each step, N being the surface
groove's normal impulse / dt of the previous step and ẋ the mass's own
velocity (the same emulation the slider-crank backend uses on its slide).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
import pymunk
from numpy.typing import ArrayLike, NDArray

from mechcheck.analytic.exam import (
    Q1_DAMPING_RATIO as DAMPING_RATIO,
    Q1_FORCE_CHANGE_RTOL as FORCE_CHANGE_RTOL,
    Q1_VELOCITY_TOL as VELOCITY_TOL,
    Motion,
    Q1Result,
    Q1System,
    Q2Result,
    Q2System,
    Status,
    checked_times,
    drive_until_steady,
    q1_dampers,
    q1_result,
    q1_timestep,
    reading_steps,
    unsteady_message,
)
from mechcheck.sim_models.pymunk.forces import force_on_b

BACKEND = "pymunk"

Array = NDArray[np.float64]

#: Half-length of the Q1 slide line, m: a groove only holds its anchor between
#: its end points, and a long one never ends within reach.
GROOVE_HALF_LENGTH = 1.0e3

#: Gauss–Seidel iterations per step. Warm starting carries the impulses from
#: step to step, so this shortens the settling; it does not change the result.
Q1_ITERATIONS = 100
#: ``Constraint.error_bias`` of the pin and the groove (fraction of a joint
#: error left after one second): corrects ~13 % of any drift per 0.01 s step.
Q1_ERROR_BIAS = 1e-6
#: Both criteria must hold this many consecutive steps, so that the turning
#: point of an oscillation is not taken for rest.
PATIENCE = 3
#: Q1 step budget; the exam system settles in ~760 steps.
MAX_STEPS = 20_000

#: Q2 time step, s. The force read at step n is m·Δ²x/dt² + (k1 + k2)·x + μ·N
#: with the central second difference of the path, off ẍ by dt²/12·x⁗: ~5e-7
#: of F for the exam motion at 1e-3 s (measured 9e-7).
Q2_TIMESTEP = 1e-3
#: Q2 iterations per step: two grooves on one body converge in a few.
Q2_ITERATIONS = 30
#: Distance of the Q2 springs' walls from x = 0, m; the mass must stay between them.
WALL_DISTANCE = 1.0
#: First lead-in before the first Q2 reading, s, and the most it may grow to.
#: Friction at step n uses N of step n − 1, and before the first step there is
#: none; a reading is accepted once N no longer changes
#: (:data:`NORMAL_CHANGE_RTOL`), otherwise the lead-in doubles.
LEAD_IN = 0.05
MAX_LEAD_IN = 0.8
#: N is steady when it changes by less than this fraction between two steps.
NORMAL_CHANGE_RTOL = 1e-9


# ------------------------------------------------------------------------- Q1


@dataclass(frozen=True)
class Q1Settings:
    """Start pose, solver and stopping rule of a Q1 settling run (see the module constants).

    ``start_x`` (m) and ``start_phi`` (rad) are where the run starts, at rest.
    """

    start_x: float = 0.0
    start_phi: float = 0.0
    damping_ratio: float = DAMPING_RATIO
    iterations: int = Q1_ITERATIONS
    error_bias: float = Q1_ERROR_BIAS
    velocity_tol: float = VELOCITY_TOL
    force_change_rtol: float = FORCE_CHANGE_RTOL
    patience: int = PATIENCE
    max_steps: int = MAX_STEPS


@dataclass
class Q1Model:
    """A built Q1 space and handles on its bodies and constraints."""

    system: Q1System
    dt: float
    space: pymunk.Space
    slider: pymunk.Body
    bar: pymunk.Body
    groove: pymunk.GrooveJoint
    pin: pymunk.PivotJoint
    spring: pymunk.DampedSpring

    def end_b(self) -> pymunk.Vec2d:
        """B in the bar's frame (centre of mass at the origin, A at +l/2 along y)."""
        return pymunk.Vec2d(0.0, -0.5 * self.system.length)

    def apply_force(self) -> None:
        """F along +x at B's current position (pymunk clears forces after every step)."""
        self.bar.apply_force_at_world_point((self.system.force, 0.0), self.bar.local_to_world(self.end_b()))

    def forces(self) -> Array:
        """(spring force on the slider, pin force on the bar x, y, normal force on the slider), N."""
        delta = self.slider.position  # the spring runs from the origin to the slider
        direction_x = delta.x / abs(delta) if abs(delta) > 0.0 else 0.0
        pin_x, pin_y = force_on_b(self.pin, self.dt)
        _, normal = force_on_b(self.groove, self.dt)
        # A spring's impulse is signed, along the unit vector from its a to its b anchor.
        return np.array([self.spring.impulse / self.dt * direction_x, pin_x, pin_y, normal])

    def point_speed(self) -> float:
        """Largest point speed of the two bodies, m/s."""
        return max(abs(self.slider.velocity),
                   abs(self.bar.velocity) + abs(self.bar.angular_velocity) * self.system.length)

    def pin_violation(self) -> float:
        """Distance between the pin's two anchors, m."""
        return float(abs(self.slider.position - self.bar.local_to_world(self.pin.anchor_b)))


def q1_model(system: Q1System, settings: Q1Settings = Q1Settings()) -> Q1Model:
    """The pymunk model of exam Q1 at rest in the start pose (pure: a new Space every call)."""
    s = system
    dt = q1_timestep(s)
    c_x, c_phi = q1_dampers(s, settings.damping_ratio)
    space = pymunk.Space()
    space.gravity = (0.0, -s.gravity)
    space.iterations = settings.iterations
    ground = space.static_body
    slider = pymunk.Body(s.slider_mass, math.inf)
    slider.position = (settings.start_x, 0.0)
    bar = pymunk.Body(s.mass, s.mass * s.length**2 / 12.0)
    bar.angle = settings.start_phi
    # The centre of mass hangs l/2 from A along the bar, (sin φ, −cos φ).
    bar.position = (settings.start_x + 0.5 * s.length * math.sin(settings.start_phi),
                    -0.5 * s.length * math.cos(settings.start_phi))
    groove = pymunk.GrooveJoint(ground, slider, (-GROOVE_HALF_LENGTH, 0.0), (GROOVE_HALF_LENGTH, 0.0),
                                (0.0, 0.0))
    pin = pymunk.PivotJoint(slider, bar, (0.0, 0.0), (0.0, 0.5 * s.length))
    spring = pymunk.DampedSpring(ground, slider, (0.0, 0.0), (0.0, 0.0), 0.0, s.stiffness, c_x)
    swing_damper = pymunk.DampedRotarySpring(ground, bar, 0.0, 0.0, c_phi)
    for joint in (groove, pin):
        joint.error_bias = settings.error_bias
    space.add(slider, bar, groove, pin, spring, swing_damper)
    return Q1Model(s, dt, space, slider, bar, groove, pin, spring)


def settle_q1(system: Q1System, settings: Q1Settings = Q1Settings()) -> Q1Result:
    """Exam Q1's equilibrium as pymunk finds it by settling from ``settings``' start pose.

    Example
    -------
    >>> from mechcheck.analytic.exam import exam_q1
    >>> result = settle_q1(exam_q1())
    >>> result.status, round(math.degrees(result.values.phi), 1)
    ('ok', 34.2)
    """
    tic = time.perf_counter()
    model = q1_model(system, settings)
    previous: Array | None = None
    change = speed = math.inf
    calm = 0
    step = 0
    for step in range(1, settings.max_steps + 1):  # noqa: B007 - the step count is reported
        model.apply_force()
        model.space.step(model.dt)
        current = model.forces()
        speed = model.point_speed()
        if previous is not None:
            scale = max(float(np.abs(current).max()), 1e-300)
            change = float(np.abs(current - previous).max()) / scale
        previous = current
        quiet = speed <= settings.velocity_tol and change <= settings.force_change_rtol
        calm = calm + 1 if quiet else 0
        if calm >= settings.patience:
            break
    x, phi = float(model.slider.position.x), float(model.bar.angle)
    diagnostics = {"x": x, "phi": phi, "timestep": model.dt, "pin_violation": model.pin_violation(),
                   "slide_violation": abs(float(model.slider.position.y)),
                   "start_x": settings.start_x, "start_phi": settings.start_phi}
    forces = tuple(float(v) for v in model.forces())
    return q1_result(BACKEND, calm >= settings.patience, x, phi, (forces[0], forces[1], forces[2], forces[3]),
                     steps=step, elapsed=time.perf_counter() - tic, speed=speed, change=change,
                     max_steps=settings.max_steps, diagnostics=diagnostics)


# ------------------------------------------------------------------------- Q2


@dataclass(frozen=True)
class Q2Settings:
    """Time step, solver and lead-in of a Q2 driven run (see the module constants)."""

    timestep: float = Q2_TIMESTEP
    iterations: int = Q2_ITERATIONS
    lead_in: float = LEAD_IN
    max_lead_in: float = MAX_LEAD_IN
    normal_change_rtol: float = NORMAL_CHANGE_RTOL


@dataclass
class Q2Model:
    """A built Q2 space and handles on its bodies and constraints."""

    system: Q2System
    dt: float
    space: pymunk.Space
    mass: pymunk.Body
    driver: pymunk.Body
    surface: pymunk.GrooveJoint
    drive: pymunk.GrooveJoint


def q2_model(system: Q2System, settings: Q2Settings = Q2Settings()) -> Q2Model:
    """The pymunk model of exam Q2 (pure: a new Space every call); the mass starts at x = 0."""
    s = system
    space = pymunk.Space()
    space.gravity = (0.0, -s.gravity)
    space.iterations = settings.iterations
    ground = space.static_body
    mass = pymunk.Body(s.mass, math.inf)
    driver = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
    reach = 2.0 * WALL_DISTANCE
    surface = pymunk.GrooveJoint(ground, mass, (-reach, 0.0), (reach, 0.0), (0.0, 0.0))
    # Vertical groove on the driver: holds the mass's x only, so its impulse is the drive force.
    drive = pymunk.GrooveJoint(driver, mass, (0.0, -reach), (0.0, reach), (0.0, 0.0))
    k1 = pymunk.DampedSpring(ground, mass, (-WALL_DISTANCE, 0.0), (0.0, 0.0), WALL_DISTANCE, s.k1, 0.0)
    k2 = pymunk.DampedSpring(ground, mass, (WALL_DISTANCE, 0.0), (0.0, 0.0), WALL_DISTANCE, s.k2, 0.0)
    for joint in (surface, drive):
        joint.error_bias = 0.0  # correct any joint error in one step: the path is prescribed
    space.add(mass, driver, surface, drive, k1, k2)
    return Q2Model(s, settings.timestep, space, mass, driver, surface, drive)


@dataclass
class _Q2Run:
    times: Array
    force: Array
    friction: Array
    normal: Array
    normal_change: Array
    tracking: Array
    steps: int


def _drive_once(system: Q2System, motion: Motion, times: Array, settings: Q2Settings,
                lead: float) -> _Q2Run:
    model = q2_model(system, settings)
    dt = model.dt
    start, steps = reading_steps(times, dt, lead)
    grid = start + dt * np.arange(-1, steps[-1] + 2)  # t_{-1} … t_{last+1}
    path = motion.position(grid)
    if np.any(np.abs(path) >= 0.5 * WALL_DISTANCE):
        raise ValueError(f"the motion leaves ±{0.5 * WALL_DISTANCE} m, too close to the springs' walls")
    # Pymunk moves bodies first in a step: start one step back, so step 0 lands on x(t_0).
    model.mass.position = (path[0], 0.0)
    model.mass.velocity = ((path[1] - path[0]) / dt, 0.0)
    n_read = len(steps)
    out = {k: np.full(n_read, np.nan) for k in ("t", "F", "f", "N", "dN", "track")}
    want = {int(n): [i for i in range(n_read) if steps[i] == n] for n in np.unique(steps)}
    normal = previous_normal = math.nan
    friction = 0.0
    for n in range(int(steps[-1]) + 1):
        v = (path[n + 2] - path[n + 1]) / dt
        # After this step's position update the driver sits on x(t_n), moving at v.
        model.driver.velocity = (v, 0.0)
        model.driver.position = (path[n + 1] - v * dt, 0.0)
        vx = model.mass.velocity.x
        friction = -system.mu * abs(normal) * math.copysign(1.0, vx) if math.isfinite(normal) else 0.0
        model.mass.force = (friction, 0.0)
        model.space.step(dt)
        previous_normal, normal = normal, force_on_b(model.surface, dt)[1]
        if n in want:
            drive_x, _ = force_on_b(model.drive, dt)
            for i in want[n]:
                out["t"][i] = start + n * dt
                out["F"][i] = drive_x
                out["f"][i] = friction
                # The friction applied in this step came from the previous step's N.
                out["N"][i] = previous_normal
                out["dN"][i] = abs(normal - previous_normal) / abs(normal)
                out["track"][i] = abs(model.mass.position.x - path[n + 1])
    return _Q2Run(out["t"], out["F"], out["f"], out["N"], out["dN"], out["track"], int(steps[-1]) + 1)


def drive_q2(system: Q2System, motion: Motion, times: ArrayLike,
             settings: Q2Settings = Q2Settings()) -> Q2Result:
    """The force pymunk needs to drive exam Q2's mass along ``motion``, read at ``times``.

    The run starts ``lead_in`` before the first reading on the prescribed
    path; if the normal force is not yet steady at any reading (the friction
    of that step was computed from a different N), the lead-in doubles, up to
    ``max_lead_in``; readings still unsteady then are NaN and the result is
    ``not_settled``.
    """
    tic = time.perf_counter()
    t = checked_times(times)
    run, lead, total_steps, steady = drive_until_steady(
        lambda lead: _drive_once(system, motion, t, settings, lead), settings.lead_in,
        settings.max_lead_in, settings.normal_change_rtol)
    status: Status = "ok" if bool(np.all(steady)) else "not_settled"
    message = unsteady_message(steady, lead)
    diagnostics = {"timestep": settings.timestep, "iterations": float(settings.iterations),
                   "lead_in": lead, "max_normal_change": float(np.nanmax(run.normal_change)),
                   "max_tracking_error": float(np.nanmax(run.tracking))}
    return Q2Result(BACKEND, run.times, np.where(steady, run.force, np.nan), run.friction, run.normal,
                    status, total_steps, time.perf_counter() - tic, message=message,
                    diagnostics=diagnostics)
