"""Seed 001's mechanism theory measured in pymunk: turn the crank and see.

The same two experiments as :mod:`mechcheck.sim_models.mujoco.turning`, judged by the
same run protocol, result types and extreme finder (:mod:`mechcheck.sim_models.turning`):

- :func:`turn_crank` drives the crank with a :class:`pymunk.SimpleMotor` of
  bounded torque (``max_force``) — pymunk's velocity servo — in place of the
  model's crank lock, with viscous damping on the passive joints (a
  :class:`pymunk.DampedRotarySpring` of zero stiffness at A and B0, a
  :class:`pymunk.DampedSpring` of zero stiffness along the slide);
- :func:`amplification` holds the crank with the model's own lock (a
  :class:`pymunk.GearJoint` to the ground) against a pure torque on the rocker
  (or a force along the slide) and steps until settled; the lock's signed
  accumulated impulse / dt (:mod:`mechcheck.sim_models.pymunk.forces`) is T12.

Everything is read from pymunk's bodies and constraints; the analytic pose
only seeds the first configuration (:func:`~mechcheck.sim_models.pymunk.model.build_model`).
"""

from __future__ import annotations

import math
import time

import numpy as np
import pymunk
from numpy.typing import ArrayLike

from mechcheck.analytic.case import Case, SliderCrankGeometry
from mechcheck.sim_models.pymunk.forces import torque_on_b
from mechcheck.sim_models.pymunk.model import Model, build_model, slide_axes
from mechcheck.sim_models.pymunk.readout import loop_violation
from mechcheck.sim_models.pymunk.settings import SolverSettings
from mechcheck.sim_models.turning import (
    JOINT_DAMPING,
    SERVO_SPEED,
    TIMESTEP,
    TORQUE_LIMIT,
    Amplification,
    Sample,
    TurnResult,
    amplification_result,
    branch_sign,
    seed_pose,
    turn_result,
)

SIMULATOR = "pymunk"

#: Link mass of the turning and holding models, kg (uniform bars, as the
#: static backend's fictitious masses).
LINK_MASS = 1000.0

#: Settings of a turning run. Same step as MuJoCo's (one sample per 0.057° of
#: crank); damping = 1: no global drag, the dissipation is the passive joints'
#: damping alone, as in MuJoCo. error_bias = 1e-100 corrects ~20 % of a joint
#: error per step. Full correction (error_bias = 0) keeps the loop tightest
#: while turning (double-crank: 1e-6 m open) but, at a toggle, where the
#: servo's bounded torque becomes loop forces of T/(a short lever arm),
#: kicks the links so hard that some linkages never come to rest (measured on
#: random non-Grashof four-bars, links 0.05–0.5 m: 2 of 55 rang in a limit
#: cycle, one with the crank 0.45° past its limit and the loop 0.14 mm
#: open). A gentle correction (1e-6, ~1.4 % per step) jams all of them but
#: leaves the turning double-crank's loop 6.6e-5 m open; 1e-100 jammed 60 of
#: 60 with it 4.8e-6 m open and the dead positions 2e-4° off. 100
#: iterations: with 50, one of 30 still rang.
TURN_SETTINGS = SolverSettings(dt=TIMESTEP, iterations=100, error_bias=1e-100, damping=1.0,
                               fictitious_mass=LINK_MASS)


def inertia_unit(case: Case) -> float:
    """m·L², kg·m²: the unit of the servo torque bound and joint damping (as in MuJoCo)."""
    return LINK_MASS * case.geometry.scale**2


def joint_dampers(model: Model) -> list[pymunk.Constraint]:
    """Viscous damping of the passive joints: coupler on crank at A, and rocker
    on ground at B0 (or slider along the slide).

    Springs of zero stiffness: pure dampers, integrated by Chipmunk's exact
    exponential decay, so they are stable at any gain.
    """
    case = model.case
    unit = inertia_unit(case)
    b = model.bodies
    static = model.space.static_body
    dampers: list[pymunk.Constraint] = [
        pymunk.DampedRotarySpring(b[2], b[3], 0.0, 0.0, JOINT_DAMPING * unit)]
    if isinstance(case.geometry, SliderCrankGeometry):
        # Anchored far back on the slide axis, the spring's line is the axis itself.
        (ux, uy), (nx, ny) = slide_axes(case)
        e = case.geometry.offset
        far = 100.0 * case.geometry.scale
        anchor = (e * nx - far * ux, e * ny - far * uy)
        dampers.append(pymunk.DampedSpring(static, b[4], anchor, (0.0, 0.0), far, 0.0,
                                           JOINT_DAMPING * LINK_MASS))
    else:
        dampers.append(pymunk.DampedRotarySpring(static, b[4], 0.0, 0.0, JOINT_DAMPING * unit))
    return dampers


class PymunkTurner:
    """The servo-driven pymunk model of a Case (a :class:`~mechcheck.sim_models.turning.Turner`)."""

    def __init__(self, case: Case) -> None:
        self.case = case
        self.timestep = TIMESTEP
        self.torque_limit = TORQUE_LIMIT * inertia_unit(case) * SERVO_SPEED**2
        self.model: Model | None = None
        self.motor: pymunk.SimpleMotor | None = None

    def reset(self, sense: int) -> None:
        """A fresh model (pymunk keeps warm-start impulses; a new Space has none)."""
        model = build_model(self.case, TURN_SETTINGS)
        model.space.remove(model.drive)  # the crank lock gives way to the servo
        # SimpleMotor drives w_b − w_a to −rate: rate = −ω turns the crank CCW.
        motor = pymunk.SimpleMotor(model.space.static_body, model.bodies[2], -sense * SERVO_SPEED)
        motor.max_force = self.torque_limit
        motor.error_bias = TURN_SETTINGS.error_bias
        model.space.add(motor, *joint_dampers(model))
        self.model, self.motor = model, motor

    def step(self) -> Sample:
        model, motor = self.model, self.motor
        assert model is not None and motor is not None, "reset() first"
        model.space.step(self.timestep)
        b = model.bodies
        if isinstance(self.case.geometry, SliderCrankGeometry):
            (ux, uy), _ = slide_axes(self.case)
            output = b[4].position.x * ux + b[4].position.y * uy
        else:
            output = b[4].angle
        return Sample(float(b[2].angle), float(b[3].angle), float(output),
                      torque_on_b(motor, self.timestep), loop_violation(model))


def turn_crank(case: Case, turns: float = 1.0, sense: int = 1) -> TurnResult:
    """Drive the crank of ``case`` in pymunk through ``turns`` turns (``sense`` +1 CCW).

    Starts at rest on the case's pose at ``case.theta12``; if the crank jams
    against a toggle it is also driven the other way from the same start, so
    ``reach`` is the whole reachable range of θ12.
    """
    start = time.perf_counter()
    return turn_result(SIMULATOR, PymunkTurner(case), turns, sense, start)


# -- amplification -----------------------------------------------------------------------------

#: Settings of a holding run. The static backend's long step (0.1 s) is
#: unstable next to a toggle: there the locked linkage is a near-flat
#: triangle A-B-B0 that warm-started Gauss–Seidel holds only loosely, the
#: rocker rings with growing amplitude and snaps through to the mirror
#: branch (measured on the non-Grashof example: from 0.1° of crank off the
#: toggle at dt = 0.1 s; 0.03° with 3000 iterations; 0.01 s still failed at
#: 0.003°). At dt = 1e-3 s with Chipmunk's default error_bias (0.9⁶⁰, ~1 %
#: of the error corrected per step), 300 iterations and strong damping
#: (1e-9 of the velocity kept per second, 2 % removed per step) every pose
#: down to 0.001° settled on its branch (measured).
HOLD_SETTINGS = SolverSettings(dt=1.0e-3, iterations=300, error_bias=0.9**60, damping=1.0e-9,
                               fictitious_mass=LINK_MASS)

#: Settled when, for HOLD_PATIENCE consecutive steps, T12 changes by at most
#: HOLD_FORCE_RTOL of itself and no point of any link moves faster than
#: HOLD_SPEED times the longest link per second.
HOLD_FORCE_RTOL = 1.0e-9
HOLD_SPEED = 1.0e-9
HOLD_PATIENCE = 3
HOLD_MAX_STEPS = 20000


def apply_output_load(model: Model, load: float) -> None:
    """The output load for the next step: a couple on the rocker, or a force on the slider at B along u."""
    body = model.bodies[4]
    if model.groove is None:
        body.torque += load
    else:
        (ux, uy), _ = slide_axes(model.case)
        body.apply_force_at_local_point((load * ux, load * uy), (0.0, 0.0))


def hold_at(case: Case, theta12: float, load: float
            ) -> tuple[tuple[float, float, float], float, bool, int]:
    """Hold the crank at ``theta12`` against ``load`` until settled.

    Returns (pose θ12, θ13, output; T12; settled; steps).
    """
    model = build_model(case.with_(theta12=theta12, loads=(), masses=(), friction=None),
                        HOLD_SETTINGS)
    dt = HOLD_SETTINGS.dt
    scale = case.geometry.scale
    previous = math.nan
    calm = 0
    torque = math.nan
    settled = False
    steps = 0
    for steps in range(1, HOLD_MAX_STEPS + 1):  # noqa: B007 - the step count is reported
        apply_output_load(model, load)
        model.space.step(dt)
        torque = torque_on_b(model.drive, dt)
        speed = max(abs(b.velocity) + abs(b.angular_velocity) * scale for b in model.bodies.values())
        calm = calm + 1 if (abs(torque - previous) <= HOLD_FORCE_RTOL * abs(torque)
                            and speed <= HOLD_SPEED * scale) else 0
        previous = torque
        if calm >= HOLD_PATIENCE:
            settled = True
            break
    b = model.bodies
    if model.groove is None:
        output = b[4].angle
    else:
        (ux, uy), _ = slide_axes(case)
        output = b[4].position.x * ux + b[4].position.y * uy
    return (float(b[2].angle), float(b[3].angle), float(output)), torque, settled, steps


def amplification(case: Case, theta12_values: ArrayLike, output_load: float = 1.0) -> Amplification:
    """T12 needed to hold ``output_load`` at each θ12, measured in pymunk.

    ``output_load`` is a pure torque on the rocker (N·m, CCW +) for a
    four-bar, a force on the slider along the slide direction u (N) for a
    slider-crank; it is the only load (the case's own loads, masses and
    friction are not applied). Each θ12 gets a fresh model locked there,
    seeded on the analytic pose at rest, stepped until settled.
    """
    start = time.perf_counter()
    thetas = np.atleast_1d(np.asarray(theta12_values, dtype=float))
    seed_branch = branch_sign(case, *np.array([seed_pose(case, t)[1:] for t in thetas]).T)
    rows = [hold_at(case, float(t), output_load) for t in thetas]
    return amplification_result(SIMULATOR, case, output_load, rows, seed_branch, start)
