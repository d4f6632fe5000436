"""The known forces on a linkage's links at a pose: loads, weights, D'Alembert inertia,
springs and viscous friction, reduced to each link's (Fx, Fy, M about the origin) — the
right-hand side b of the member-equilibrium equations (:mod:`.linkage_forces`) and the
forces whose equilibrium the free coordinates seek (:mod:`.linkage_equilibrium`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mechcheck.analytic.linkage import LinearSpring, Linkage, TorsionSpring
from mechcheck.analytic.linkage_kinematics import LinkagePose
from mechcheck.analytic.rigid import Array, ForceLayout, force_layout


def known_vector(pose: LinkagePose) -> Array:
    """b (N, 3n): every force that does not depend on the unknowns, on each link."""
    linkage = pose.linkage
    layout = force_layout(linkage)
    n = pose.q.shape[0]
    b = np.zeros((n, layout.rows))
    for load in linkage.loads:
        at = pose.point(load.link, load.at)[0]
        layout.add_force(b, load.link, np.full((n, 2), load.force), at)
        layout.add_couple(b, load.link, np.full(n, load.torque))
    g = np.array(linkage.gravity)
    for m in linkage.masses:
        com, _, acc = pose.point(m.link, m.com)
        layout.add_force(b, m.link, m.mass * (g[None, :] - acc), com)
        if not pose.at_rest:    # at rest −I·α is −0, which adds nothing to any number
            layout.add_couple(b, m.link, -m.inertia * pose.angle(m.link)[2])
    for spring in linkage.springs:
        _add_spring(b, layout, pose, spring)
    _add_viscous(b, layout, pose)
    return b


#: A linear spring whose ends are closer than this fraction of the linkage's size has ends
#: that meet, to rounding: its line of action, and the rate of its length, are undefined.
MEETING = 1e-12


def spring_axis(linkage: Linkage, d: Array) -> tuple[Array, Array, NDArray[np.bool_]]:
    """(length, unit vector along ``d`` (N, 2) from a linear spring's first end to its second,
    where the ends meet). Where they meet the unit vector is 0: a spring without tension
    there adds nothing, and one with tension is withheld (:func:`undirected_springs`)."""
    length = np.hypot(d[:, 0], d[:, 1])
    meets = length <= MEETING * linkage.scale
    with np.errstate(divide="ignore", invalid="ignore"):
        unit = np.where(meets[:, None], 0.0, d / length[:, None])
    return length, unit, meets


def spring_force(pose: LinkagePose, spring: LinearSpring | TorsionSpring) -> Array:
    """S (N,): tension k(L − L0) + c·L̇ of a linear spring, k(q − q0) + c·q̇ of a torsional one.

    Where a linear spring's ends meet, L̇ is undefined unless they move together: there a
    damped spring's tension is NaN."""
    if isinstance(spring, TorsionSpring):
        q, qdot, _ = pose.joint_coordinate(pose.linkage.joint(spring.joint))
        return spring.stiffness * (q - spring.free_rotation) + spring.damping * qdot
    (la, pa), (lb, pb) = spring.ends
    a, va, _ = pose.point(la, pa)
    bb, vb, _ = pose.point(lb, pb)
    length, unit, meets = spring_axis(pose.linkage, bb - a)
    tension = spring.stiffness * (length - spring.free_length)
    if spring.damping:
        moving = np.any(vb != va, axis=1)
        rate = np.where(meets & moving, np.nan, np.einsum("ni,ni->n", unit, vb - va))
        tension = tension + spring.damping * rate
    return tension


def undirected_springs(pose: LinkagePose) -> NDArray[np.str_]:
    """Per pose, the linear springs (comma-separated; empty: none) whose ends meet while they
    carry a tension: a force without a line of action, so the reactions are not unique."""
    linear = [s for s in pose.linkage.springs if isinstance(s, LinearSpring)]
    out = np.full(pose.q.shape[0], "", dtype=object if linear else "<U1")
    for spring in linear:
        (la, pa), (lb, pb) = spring.ends
        meets = spring_axis(pose.linkage, pose.point(lb, pb)[0] - pose.point(la, pa)[0])[2]
        loaded = meets & ~(spring_force(pose, spring) == 0.0)
        out[loaded] = np.where(out[loaded] == "", spring.name, out[loaded] + ", " + spring.name)
    return out.astype(str)


def _add_spring(b: Array, layout: ForceLayout, pose: LinkagePose,
                spring: LinearSpring | TorsionSpring) -> None:
    s = spring_force(pose, spring)
    if isinstance(spring, TorsionSpring):
        i, j = pose.linkage.joint(spring.joint).links
        layout.add_couple(b, j, -s)
        layout.add_couple(b, i, s)
        return
    (la, pa), (lb, pb) = spring.ends
    a = pose.point(la, pa)[0]
    bb = pose.point(lb, pb)[0]
    e = spring_axis(pose.linkage, bb - a)[1]
    layout.add_force(b, la, s[:, None] * e, a)    # tension pulls a toward b
    layout.add_force(b, lb, -s[:, None] * e, bb)


def _add_viscous(b: Array, layout: ForceLayout, pose: LinkagePose) -> None:
    """−c·q̇ on links[1] (and the reverse on links[0]) at every joint with a viscous term,
    as each joint's kind applies it (a couple at a pin, a force along a slide)."""
    f = pose.linkage.friction
    if f is None:
        return
    for name, c in f.viscous.items():
        joint = pose.linkage.joint(name)
        joint.kind.viscous(b, layout, pose, joint, c)
