"""Joint friction emulated from pymunk's current reactions, updated every step.

- Coulomb at a pin (i, j): the SimpleMotor(rate = 0) between i and j gets
  ``max_force = μ·r·|F_ij|`` from the pivot's last impulse. While the joint
  turns, the motor saturates and applies exactly that moment against the
  relative rotation: the friction-circle moment.
- Coulomb on the slide: a force −μ_s·|N|·sign(ṡ) along u at pin B, with N the
  groove's last normal impulse / dt and ṡ the slider's own velocity.
- Viscous: −c·(ω_j − ω_i) on j (and the opposite on i), −c·ṡ·u on the slider,
  from the bodies' own velocities.

The reactions used are those of the previous step (the motor limits must be
known before the solver runs); in the slow, smooth motion this is used for,
that lag is one step of a slowly varying force.
"""

from __future__ import annotations

import math

from mechcheck.sim_models.pymunk.model import Model, pin_anchors, slide_axes


def update_pin_friction(model: Model) -> None:
    """Set every friction motor's torque limit to μ·r·|F| of its pin's last reaction."""
    f = model.case.friction
    if f is None:
        return
    dt = model.settings.dt
    for joint, motor in model.motors.items():
        motor.max_force = f.pin_moment_arm(joint) * model.pins[joint].impulse / dt


def slide_speed(model: Model) -> float:
    """ṡ: the slider's velocity along the slide axis, m/s."""
    (ux, uy), _ = slide_axes(model.case)
    v = model.bodies[4].velocity
    return v.x * ux + v.y * uy


def slide_friction_force(model: Model, sense: float) -> float:
    """Force along u on the slider from Coulomb and viscous slide friction, N.

    ``sense`` is the sign of ṡ friction opposes (from the simulated motion).
    """
    f = model.case.friction
    if f is None or model.groove is None:
        return 0.0
    normal = model.groove.impulse / model.settings.dt
    force = -f.slide_coefficient() * normal * sense
    c = f.viscous.get("slide", 0.0)
    return force - c * slide_speed(model)


def apply_viscous_pin_moments(model: Model) -> None:
    """−c·(ω_j − ω_i) on link j and +c·(ω_j − ω_i) on link i at every viscous pin."""
    f = model.case.friction
    if f is None:
        return
    for joint, (i, _, j, _) in pin_anchors(model.case).items():
        c = f.viscous.get(joint, 0.0)
        if c == 0.0:
            continue
        bi = model.bodies.get(i) if i != 1 else None
        wi = bi.angular_velocity if bi is not None else 0.0
        moment = -c * (model.bodies[j].angular_velocity - wi)
        model.bodies[j].torque += moment
        if bi is not None:
            bi.torque -= moment


def sign(x: float) -> float:
    """Sign with sign(0) = 0."""
    return math.copysign(1.0, x) if x else 0.0

