"""A linkage's driver turned by a servo in MuJoCo, to measure where it locks
(:mod:`.locks`): the linkage builder's model with that driver's joint
equality switched off, a bounded-torque velocity servo on its joint and every other tree
joint damped, as the four-bar's turning model (:mod:`.mujoco_turning`) does for the crank."""

from __future__ import annotations

import math
from collections.abc import Callable

import mujoco

from mechcheck.analytic.case import Case
from mechcheck.sim_models.mujoco.linkage_model import spanning_tree
from mechcheck.sim_models.mujoco.linkage_rig import LinkageRig
from mechcheck.sim_models.mujoco.model import SETTLE_MASS, Settings

from .locks import DriverLocks, drive_both_ways, driver_length
from .protocol import (
    CRANK_ARMATURE,
    JOINT_DAMPING,
    SERVO_GAIN,
    SERVO_SPEED,
    TIMESTEP,
    TORQUE_LIMIT,
    Sample,
)

#: Links of the settling mass, as the four-bar's turning model.
TURN_SETTINGS = Settings(timestep=TIMESTEP, masses="settle")


def inertia_unit(case: Case) -> float:
    """m·L², kg·m²: the unit of the servo gain, torque bound and joint damping."""
    return SETTLE_MASS * case.linkage.scale**2


def servo_customizer(case: Case, joint: str) -> Callable[[mujoco.MjSpec], None]:
    """The edit that turns the linkage's model into the servo model of ``joint``'s driver:
    its joint equality switched off, a velocity servo on the joint and the other tree
    joints damped (a slide by the same rate per metre of the size)."""
    linkage = case.linkage
    unit = inertia_unit(case)
    length = driver_length(case, joint)

    def customize(spec: mujoco.MjSpec) -> None:
        spec.equality(f"drive_{joint}").active = False
        for t in spanning_tree(linkage).tree:
            if t.joint.name != joint:
                scale = unit if t.joint.kind.rotates else SETTLE_MASS
                spec.joint(t.joint.name).damping = [JOINT_DAMPING * scale, 0.0, 0.0]
        add_servo(spec, joint, unit, length)

    return customize


def add_servo(spec: mujoco.MjSpec, joint: str, unit: float, length: float = 1.0) -> None:
    """A bounded-torque velocity servo on ``joint`` (gain, bound and armature in units of
    ``unit`` = m·L², :mod:`.protocol`), integrated implicitly so that
    its gain −kv·q̇ is not limited by the inertia of a short link. On a slide, ``length``
    = L (:func:`.locks.driver_length`): the same servo per unit of
    travel / L, its force × L bounded as the torque."""
    inertia = unit / length**2  # kg·m² on a hinge, kg on a slide
    spec.option.integrator = int(mujoco.mjtIntegrator.mjINT_IMPLICITFAST)
    spec.joint(joint).armature = CRANK_ARMATURE * inertia
    servo = spec.add_actuator(name="servo", trntype=mujoco.mjtTrn.mjTRN_JOINT, target=joint)
    servo.set_to_velocity(kv=SERVO_GAIN * inertia)
    servo.forcelimited = True
    bound = TORQUE_LIMIT * inertia * SERVO_SPEED**2 * length
    servo.forcerange = [-bound, bound]


class LinkageServo:
    """The servo-driven MuJoCo model of a linkage's driver (a
    :class:`.protocol.Turner`; its "θ12" is the driver's angle from the
    drawn pose, or a prismatic driver's travel / L, its torque the servo's, or its force × L;
    the other sample fields are not measured)."""

    def __init__(self, case: Case, joint: str) -> None:
        self.case = case
        self.length = driver_length(case, joint)
        self.timestep = TIMESTEP
        self.torque_limit = TORQUE_LIMIT * inertia_unit(case) * SERVO_SPEED**2
        self.rig = LinkageRig(case, TURN_SETTINGS, servo_customizer(case, joint))
        self.q = int(self.rig.model.joint(joint).qposadr[0])

    def reset(self, sense: int) -> None:
        """At rest in the drawn pose (every joint coordinate 0), servo aimed at sense·ω."""
        m, d = self.rig.model, self.rig.data
        mujoco.mj_resetData(m, d)
        d.ctrl[0] = sense * SERVO_SPEED * self.length
        mujoco.mj_forward(m, d)

    def step(self) -> Sample:
        rig = self.rig
        mujoco.mj_step(rig.model, rig.data)
        return Sample(float(rig.data.qpos[self.q]) / self.length, math.nan, math.nan,
                      float(rig.data.actuator_force[0]) * self.length, rig.loop_violation())


def driver_locks(case: Case, joint: str) -> DriverLocks:
    """Where ``joint``'s driver locks in MuJoCo, each way from the drawn pose."""
    return drive_both_ways("mujoco", case, joint, LinkageServo)
