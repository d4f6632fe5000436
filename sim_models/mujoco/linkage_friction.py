"""Coulomb friction of a linkage emulated from MuJoCo's current reactions.

MuJoCo's ``frictionloss`` is a constant limit, not μ·|F|, and a loop-closing pin has no
joint at all (it is a ``connect``). So each Coulomb term of LINKAGES.md is applied as a
load through ``xfrc_applied``, its magnitude from the reactions MuJoCo reports
(:meth:`.linkage_rig.LinkageRig.read`) and its sense from the joint's relative motion:

- a revolute joint with a pin radius r: the couple −μ·r·|F|·sign(q̇) on links[1] and its
  opposite on links[0] (the friction circle);
- a prismatic joint or a pin in a slot: the force −μ·|N|·sign(q̇) along its axis through ``at`` on links[1],
  its opposite on links[0] at the same point; N is the reaction's normal component. This
  force is part of the joint's reported reaction (:attr:`LinkageRig.sliding`).

Viscous friction is MuJoCo's own joint damping (:mod:`.linkage_model`), or on a loop-closing joint
a couple from MuJoCo's joint rates (:meth:`.linkage_rig.LinkageRig.wrenches`).
"""

from __future__ import annotations

import math

import numpy as np

from mechcheck.analytic.values import GROUND
from mechcheck.sim_models.mujoco.joint_kinds import builder_of
from mechcheck.sim_models.mujoco.linkage_rig import Array, LinkageRig
from mechcheck.sim_models.mujoco.rig import cross_z


def magnitude(values: dict[str, float], name: str) -> float:
    """|F| of the reaction ``name`` (``F_<joint>``) in a reading."""
    return math.hypot(values[f"{name}_x"], values[f"{name}_y"])


def friction_loads(rig: LinkageRig, values: dict[str, float],
                   senses: dict[str, float]) -> tuple[Array, dict[str, float]]:
    """(xfrc per body, force along each sliding joint's axis) of every Coulomb term at
    the reactions ``values``, opposing the joints' senses of motion ``senses`` (q̇ or its
    sign)."""
    linkage = rig.linkage
    f = linkage.friction
    xfrc = np.zeros((rig.model.nbody, 6))
    sliding: dict[str, float] = {}
    if f is None:
        return xfrc, sliding
    d = rig.data
    for joint in linkage.joints:
        sign = float(np.sign(senses[joint.name]))
        i, j = joint.links
        if not builder_of(joint).sliding_friction:
            moment = -f.coefficient(joint.name) * f.pin_radius.get(joint.name, 0.0) \
                * magnitude(values, f"F_{joint.name}") * sign
            for link, share in ((j, 1.0), (i, -1.0)):
                if link != GROUND:
                    xfrc[rig.body[link], 5] += share * moment
            continue
        u = rig.axis_of(joint)
        normal = -values[f"F_{joint.name}_x"] * u[1] + values[f"F_{joint.name}_y"] * u[0]
        along = -f.coefficient(joint.name) * abs(normal) * sign
        sliding[joint.name] = along
        point = rig.point_on(j, linkage.points[joint.at])
        for link, share in ((j, 1.0), (i, -1.0)):
            if link != GROUND:
                b = rig.body[link]
                force = share * along * u
                xfrc[b, 0:2] += force
                xfrc[b, 5] += float(cross_z(point - d.xipos[b, :2], force))
    return xfrc, sliding


def apply_friction(rig: LinkageRig, values: dict[str, float], senses: dict[str, float]) -> None:
    """Set the rig's friction loads from ``values`` (see :func:`friction_loads`)."""
    rig.extra, rig.sliding = friction_loads(rig, values, senses)


def clear_friction(rig: LinkageRig) -> None:
    rig.extra = np.zeros_like(rig.extra)
    rig.sliding = {}


def friction_change(new: dict[str, float], old: dict[str, float]) -> float:
    """Largest change of a force between two readings, relative to the largest force."""
    forces = [q for q in new if q[0] in "FQMS" and not math.isnan(new[q])]
    size = max((abs(new[q]) for q in forces), default=0.0)
    return max((abs(new[q] - old[q]) for q in forces), default=0.0) / max(size, 1e-300)
