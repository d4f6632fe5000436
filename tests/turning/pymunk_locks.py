"""A linkage's driver turned by a servo in pymunk, to measure where it locks
(:mod:`.locks`): the linkage builder's model with that driver's gear
lock removed, a bounded ``SimpleMotor`` in its place and every other joint damped, as the
four-bar's turning model (:mod:`.pymunk_turning`) does for the crank.

Chipmunk has no linear motor. A prismatic driver's hold (a pivot) becomes its groove and
a ``PinJoint`` along the axis whose target lies far beyond the travel in the driving
sense, with full error correction capped by ``max_bias`` at the servo speed: Chipmunk then
solves for the pin's relative speed = that cap, its impulse bounded by ``max_force``
(cpPinJoint's applyImpulse), which is what ``SimpleMotor`` does for a rate."""

from __future__ import annotations

import math

import pymunk

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage_kinematics import solve_pose
from mechcheck.sim_models.pymunk.forces import torque_on_b
from mechcheck.sim_models.pymunk.linkage_model import (
    GROOVE_REACH,
    LinkageModel,
    along,
    build_linkage_model,
)
from mechcheck.sim_models.pymunk.settings import SolverSettings

from .locks import DriverLocks, drive_both_ways, driver_length
from .protocol import (
    JOINT_DAMPING,
    SERVO_SPEED,
    TIMESTEP,
    TORQUE_LIMIT,
    Sample,
)

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
    return LINK_MASS * case.linkage.scale**2


def dampers(model: LinkageModel, driven: str) -> list[pymunk.Constraint]:
    """Viscous damping of every joint but ``driven``: springs of zero stiffness, which
    Chipmunk integrates by exact exponential decay, stable at any gain. A prismatic joint's
    damper lies along its axis, anchored far back on its first link."""
    linkage = model.linkage
    unit = inertia_unit(model.case)
    far = GROOVE_REACH * linkage.scale
    out: list[pymunk.Constraint] = []
    for joint in linkage.joints:
        if joint.name == driven:
            continue
        a, b = (model.body(link) for link in joint.links)
        if joint.kind.rotates:
            out.append(pymunk.DampedRotarySpring(a, b, 0.0, 0.0, JOINT_DAMPING * unit))
        else:
            at = linkage.points[joint.at]
            out.append(pymunk.DampedSpring(a, b, along(joint, at, -far), at, far, 0.0,
                                           JOINT_DAMPING * LINK_MASS))
    return out


class LinkageServo:
    """The servo-driven pymunk model of a linkage's driver (a
    :class:`.protocol.Turner`; its "θ12" is the driver's angle from the
    drawn pose, unwrapped, or a prismatic driver's travel / L, its torque the motor's, or
    the pin's force × L)."""

    def __init__(self, case: Case, joint: str) -> None:
        self.case = case
        self.built = case  # the linkage the model is built from
        self.joint = case.linkage.joint(joint)
        self.length = driver_length(case, joint)
        self.timestep = TIMESTEP
        self.torque_limit = TORQUE_LIMIT * inertia_unit(case) * SERVO_SPEED**2
        self.drawn = solve_pose(case.linkage).q[0]
        self.model: LinkageModel | None = None
        self.motor: pymunk.Constraint | None = None

    def reset(self, sense: int) -> None:
        """A fresh model at rest in the drawn pose (a new Space has no warm-start
        impulses), the driver's gear (or a prismatic driver's hold) replaced by the
        motor."""
        model = build_linkage_model(self.built, TURN_SETTINGS, self.drawn)
        if self.joint.kind.rotates:
            model.space.remove(model.drives[self.joint.name])
            a, b = (model.body(link) for link in self.joint.links)
            # SimpleMotor drives ω_b − ω_a to −rate.
            motor: pymunk.Constraint = pymunk.SimpleMotor(a, b, -sense * SERVO_SPEED)
            motor.error_bias = TURN_SETTINGS.error_bias
            model.space.add(motor, *dampers(model, self.joint.name))
        else:
            motor = linear_servo(model, self.joint.name, sense)
        motor.max_force = self.torque_limit / self.length
        self.model, self.motor = model, motor

    def step(self) -> Sample:
        model, motor = self.model, self.motor
        assert model is not None and motor is not None, "reset() first"
        model.space.step(self.timestep)
        # The loop gap is not sampled here (it costs more than the step); the lock is read
        # from the driver's coordinate and the motor's torque alone.
        if self.joint.kind.rotates:
            a, b = (model.body(link) for link in self.joint.links)
            return Sample(float(b.angle - a.angle), math.nan, math.nan,
                          torque_on_b(motor, self.timestep), math.nan)
        # PinJoint.impulse is |jnAcc|: the stall test reads the size of the force only.
        return Sample(travel(model, self.joint.name) / self.length, math.nan, math.nan,
                      motor.impulse / self.timestep * self.length, math.nan)


def linear_servo(model: LinkageModel, joint: str, sense: int) -> pymunk.PinJoint:
    """Replace prismatic ``joint``'s hold by its groove and a pin along the axis, from
    GROOVE_REACH·L behind ``at`` on the first link to ``at`` on the second, aimed
    GROOVE_REACH·L / 2 beyond the drawn pose in ``sense`` and closing at most at the servo
    speed; the other joints damped. Returns the pin (its ``max_force`` is set by the
    caller)."""
    linkage = model.linkage
    j = linkage.joint(joint)
    a, b = (model.body(link) for link in j.links)
    at, reach = linkage.points[j.at], GROOVE_REACH * linkage.scale
    behind = along(j, at, -reach)
    model.space.remove(model.held[joint])
    groove = pymunk.GrooveJoint(a, b, behind, along(j, at, reach), at)
    pin = pymunk.PinJoint(a, b, behind, at)
    pin.distance = reach + sense * reach / 2.0
    pin.error_bias = 0.0  # correct all the error in a step, but no faster than max_bias
    pin.max_bias = SERVO_SPEED * linkage.scale
    model.space.add(groove, pin, *dampers(model, joint))
    return pin


def travel(model: LinkageModel, joint: str) -> float:
    """A prismatic joint's displacement from the drawn pose, m: ``at`` on the second link
    measured along the axis in the first link's frame (both built drawn at the pose)."""
    j = model.linkage.joint(joint)
    a, b = (model.body(link) for link in j.links)
    at = model.linkage.points[j.at]
    assert j.axis is not None
    moved = a.world_to_local(b.local_to_world(at)) - at
    return float(moved.dot(j.axis))


def loop_gap(model: LinkageModel) -> float:
    """Largest distance between the two anchors of any pin, or of a groove's pin from its
    line, m (the joints' violation)."""
    worst = 0.0
    for pin in model.pins.values():
        worst = max(worst, abs(pin.a.local_to_world(pin.anchor_a)
                               - pin.b.local_to_world(pin.anchor_b)))
    for groove in model.grooves.values():
        a, b = groove.a.local_to_world(groove.groove_a), groove.a.local_to_world(groove.groove_b)
        p = groove.b.local_to_world(groove.anchor_b)
        worst = max(worst, abs((p - a).dot((b - a).perpendicular_normal())))
    return worst


def driver_locks(case: Case, joint: str) -> DriverLocks:
    """Where ``joint``'s driver locks in pymunk, each way from the drawn pose."""
    return drive_both_ways("pymunk", case, joint, LinkageServo)
