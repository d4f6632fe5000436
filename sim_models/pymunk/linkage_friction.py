"""Joint friction of a linkage emulated from pymunk's reactions and velocities (as the
four-bar's, :mod:`.friction`).

Pymunk has no friction that scales with a reaction, and a loop-closing pin is a plain
constraint. So each friction term of LINKAGES.md is an explicit load applied inside the
velocity integration, one value per joint acting on ``links[1]`` and its opposite on
``links[0]``:

- a revolute joint: the couple −μ·r·|F|·sign(q̇) − c·q̇ (friction circle and viscous);
- a sliding joint (prismatic, pin in a slot): the force −μ·|N|·sign(q̇) − c·q̇ along
  the axis through ``at``, N the reaction's normal component. This force is part of the
  joint's reported reaction (:func:`with_sliding`), as in MuJoCo's linkage model.

What each kind's rate, Coulomb term and load are: :mod:`.joint_kinds`.

q̇ is the joint's relative rate measured on the bodies. The loads belong to the step
they act in; how they are made consistent with that step's own reactions (a prediction,
then a fixed-point pass) is :func:`.linkage_dynamics.step_with_friction`'s.
"""

from __future__ import annotations

import math

import pymunk

from mechcheck.analytic.linkage import Joint
from mechcheck.sim_models.pymunk.joint_kinds import builder
from mechcheck.sim_models.pymunk.linkage_model import LinkageModel
from mechcheck.sim_models.pymunk.readout import Values


class Diverged(RuntimeError):
    """The simulation produced a non-finite number: the run is lost, no reading."""


def sign(x: float) -> float:
    """Sign with sign(0) = 0."""
    return math.copysign(1.0, x) if x else 0.0


#: Per joint, the friction acting on links[1]: a couple (N·m, revolute) or a force along
#: the axis (N, a sliding joint); links[0] takes the opposite.
JointLoads = dict[str, float]


def joint_rate(model: LinkageModel, joint: Joint) -> float:
    """q̇ of a joint from the bodies' velocities: ω_b − ω_a, or the speed of ``at`` on
    links[1] relative to links[0] along the axis (:mod:`.joint_kinds`)."""
    return builder(joint).rate(model, joint)


def joint_rates(model: LinkageModel) -> dict[str, float]:
    """``qdot_<joint>`` of every joint."""
    return {f"qdot_{joint.name}": joint_rate(model, joint) for joint in model.linkage.joints}


def friction_loads(model: LinkageModel, state: Values, viscous: bool = True) -> JointLoads:
    """The friction of every joint at ``state`` (reactions ``F_<joint>_x/y`` and rates
    ``qdot_<joint>``; a sliding joint's axis at the model's pose); ``viscous=False``
    leaves out the viscous terms (a quasi-static run, whose analytic motion has no speed)."""
    linkage = model.linkage
    f = linkage.friction
    if f is None:
        return {}
    out: JointLoads = {}
    for joint in linkage.joints:
        name = joint.name
        rate = state[f"qdot_{name}"]
        coulomb = builder(joint).coulomb(model, joint, f, state[f"F_{name}_x"], state[f"F_{name}_y"])
        damping = f.viscous.get(name, 0.0) if viscous else 0.0
        value = -coulomb * sign(rate) - damping * rate
        if value:
            out[name] = value
    return out


def apply_joint_friction(model: LinkageModel, link: str, body: pymunk.Body,
                         loads: JointLoads) -> None:
    """Add the friction on ``link`` (its body) from ``loads``, at the current pose."""
    linkage = model.linkage
    # The joints in the loads' order (friction_loads builds them in the linkage's), walked
    # rather than looked up by name: this runs for every body at every step.
    for joint in linkage.joints:
        value = loads.get(joint.name)
        if value is None or link not in joint.links:
            continue
        share = 1.0 if joint.links[1] == link else -1.0
        builder(joint).apply_friction(model, joint, body, share * value)


def with_sliding(model: LinkageModel, values: Values, loads: JointLoads) -> Values:
    """The reactions with each sliding joint's friction force added to its F (the force
    by links[0] on links[1] includes it)."""
    out = dict(values)
    for joint in model.linkage.joints:
        value = loads.get(joint.name)
        force = builder(joint).sliding(model, joint, value) if value is not None else None
        if force is not None:
            out[f"F_{joint.name}_x"] += force[0]
            out[f"F_{joint.name}_y"] += force[1]
    return out
