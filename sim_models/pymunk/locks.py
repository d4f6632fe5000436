"""A linkage's driver turned by a servo in pymunk, to measure where it locks
(:mod:`mechcheck.sim_models.locks`): the linkage builder's model with that driver's gear
lock removed, a bounded ``SimpleMotor`` in its place and every other joint damped, as the
four-bar's turning model (:mod:`.turning`) does for the crank."""

from __future__ import annotations

import math

import pymunk

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage_kinematics import solve_pose
from mechcheck.sim_models.locks import DriverLocks, drive_both_ways
from mechcheck.sim_models.pymunk.forces import torque_on_b
from mechcheck.sim_models.pymunk.linkage_model import (
    GROOVE_REACH,
    LinkageModel,
    along,
    build_linkage_model,
)
from mechcheck.sim_models.pymunk.settings import SolverSettings
from mechcheck.sim_models.turning import (
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
        if joint.kind == "revolute":
            out.append(pymunk.DampedRotarySpring(a, b, 0.0, 0.0, JOINT_DAMPING * unit))
        else:
            at = linkage.points[joint.at]
            out.append(pymunk.DampedSpring(a, b, along(joint, at, -far), at, far, 0.0,
                                           JOINT_DAMPING * LINK_MASS))
    return out


class LinkageServo:
    """The servo-driven pymunk model of a linkage's driver (a
    :class:`~mechcheck.sim_models.turning.Turner`; its "θ12" is the driver's angle from the
    drawn pose, unwrapped)."""

    def __init__(self, case: Case, joint: str) -> None:
        self.case = case
        self.built = case  # the linkage the model is built from
        self.joint = case.linkage.joint(joint)
        self.timestep = TIMESTEP
        self.torque_limit = TORQUE_LIMIT * inertia_unit(case) * SERVO_SPEED**2
        self.drawn = solve_pose(case.linkage).q[0]
        self.model: LinkageModel | None = None
        self.motor: pymunk.SimpleMotor | None = None

    def reset(self, sense: int) -> None:
        """A fresh model at rest in the drawn pose (a new Space has no warm-start
        impulses), the driver's gear replaced by the motor."""
        model = build_linkage_model(self.built, TURN_SETTINGS, self.drawn)
        model.space.remove(model.drives[self.joint.name])
        a, b = (model.body(link) for link in self.joint.links)
        # SimpleMotor drives ω_b − ω_a to −rate.
        motor = pymunk.SimpleMotor(a, b, -sense * SERVO_SPEED)
        motor.max_force = self.torque_limit
        motor.error_bias = TURN_SETTINGS.error_bias
        model.space.add(motor, *dampers(model, self.joint.name))
        self.model, self.motor = model, motor

    def step(self) -> Sample:
        model, motor = self.model, self.motor
        assert model is not None and motor is not None, "reset() first"
        model.space.step(self.timestep)
        a, b = (model.body(link) for link in self.joint.links)
        # The loop gap is not sampled here (it costs more than the step); the lock is read
        # from the driver's angle and the motor's torque alone.
        return Sample(float(b.angle - a.angle), math.nan, math.nan,
                      torque_on_b(motor, self.timestep), math.nan)


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
