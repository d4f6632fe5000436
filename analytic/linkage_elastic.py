"""Statically indeterminate linkages with elastic members (seed 001's S = −1 structure: "the
equations are not enough; the joints displace, and the solution starts from those
displacements, δ = F·L / (E·A)").

A two-point link may carry ``axial_stiffness`` (E·A, N): it stays straight and stretches by
δ = N·L/(E·A) under its axial force N (tension +). Where the joints' constraints are
redundant, equilibrium K x = −b leaves the reactions free along K's null space (the
structure's self-stress states). Small displacements decide them: of all reactions in
equilibrium, the actual ones make the members' stretches compatible, which is the
stationary point of the complementary energy ½ Σ ∫N_i²dx/(E·A_i) (Castigliano–Menabrea;
the displacement method's answer, written in forces). Rigid members store no energy: a
self-stress state through rigid members only is not decided, and stays ``indeterminate``.

A member's own loads (its weight, forces between its ends) make its tension vary along it:
its ``N_<link>`` is the mean of the tensions just inside its ends, and it stretches by
∫N dx/(E·A), which is that mean's N·L/(E·A) plus Σ (t − ½)·F·e·L/(E·A) over those loads
(t: where each acts, from the first point to the second; :func:`stretch_offsets`). A
weight at the middle adds nothing to it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mechcheck.analytic.linkage import Link, Linkage
from mechcheck.analytic.linkage_kinematics import LinkagePose
from mechcheck.analytic.rigid import Array, ForceLayout

#: Singular values of a matrix below this fraction of its largest count as zero.
RANK_RTOL = 1e-9


def axial_rows(pose: LinkagePose, k: Array) -> Array:
    """Per pose, the row a_i of each elastic member with N_i = a_i·x + n_i (N, members,
    unknowns; n_i from :func:`axial_offsets`): the mean of the tensions just inside its two
    ends, each the axial component of the forces on the member at that end, here the
    joints' (from K's columns)."""
    linkage = pose.linkage
    layout = ForceLayout(linkage)
    members = linkage.elastic_links
    out = np.zeros((pose.q.shape[0], len(members), layout.columns))
    for m, link in enumerate(members):
        e = _axis(pose, link)
        r = layout.row(link.name)
        for end, sign in ((link.points[1], 0.5), (link.points[0], -0.5)):
            for joint in linkage.joints:
                if link.name in joint.links and joint.at == end:
                    cols = list(layout.joint_columns(joint))
                    force = k[:, r:r + 2, cols]     # (N, 2, c): the force on the member
                    out[:, m, cols] += sign * np.einsum("ni,nic->nc", e, force)
    return out


def _axis(pose: LinkagePose, link: Link) -> Array:
    """The member's unit vector from its first point to its second, per pose."""
    a, b = (pose.linkage.points[p] for p in link.points)
    d = pose.point(link.name, b)[0] - pose.point(link.name, a)[0]
    return d / np.hypot(d[:, 0], d[:, 1])[:, None]


def axial_offsets(pose: LinkagePose) -> Array:
    """n_i of :func:`axial_rows` (N, members): the part of the mean end tension that the
    loads applied at the member's own end points give (½(L_B − L_A)·e)."""
    linkage = pose.linkage
    out = np.zeros((pose.q.shape[0], len(linkage.elastic_links)))
    for m, link in enumerate(linkage.elastic_links):
        e = _axis(pose, link)
        for end, sign in ((link.points[1], 0.5), (link.points[0], -0.5)):
            at = np.asarray(linkage.points[end])
            for load in linkage.loads:
                if load.link == link.name and np.allclose(load.at, at, rtol=0.0,
                                                          atol=1e-12 * linkage.scale):
                    out[:, m] += sign * (e @ np.asarray(load.force))
    return out


@dataclass(frozen=True)
class OwnLoad:
    """A force on an elastic member: ``t``, where it acts along the member (0 at ``start``,
    1 at the other point, drawn); ``force`` (N); ``inside``: between the member's ends for
    its ``N_<link>`` (a point load away from both end points, or any weight; a point load at
    an end point is part of the tension just inside that end)."""

    t: float
    force: tuple[float, float]
    inside: bool


def own_loads(linkage: Linkage, member: Link, start: str) -> list[OwnLoad]:
    """The member's point loads and its weight at its centre of mass, placed along it from
    its point ``start``."""
    a = np.asarray(linkage.points[start])
    b = np.asarray(linkage.points[member.points[1] if member.points[0] == start
                                  else member.points[0]])
    d = b - a
    tol = 1e-12 * linkage.scale

    def along(at: tuple[float, float]) -> float:
        return float(np.clip(np.dot(np.asarray(at) - a, d) / np.dot(d, d), 0.0, 1.0))

    def between_ends(at: tuple[float, float]) -> bool:
        return min(np.hypot(*(np.asarray(at) - a)), np.hypot(*(np.asarray(at) - b))) > tol

    out = [OwnLoad(along(load.at), load.force, between_ends(load.at))
           for load in linkage.loads if load.link == member.name]
    gx, gy = linkage.gravity
    out += [OwnLoad(along(m.com), (m.mass * gx, m.mass * gy), True)
            for m in linkage.masses if m.link == member.name]
    return out


def stretch_excess(linkage: Linkage, member: Link) -> Array:
    """Σ (t − ½)·F over the member's loads between its ends (:func:`own_loads`, t from its
    first point): along its axis from its first point to its second, what ∫N dx/L exceeds
    its ``N_<link>`` by (N, a vector)."""
    total = np.zeros(2)
    for load in own_loads(linkage, member, member.points[0]):
        if load.inside:
            total += (load.t - 0.5) * np.asarray(load.force)
    return total


def stretch_offsets(pose: LinkagePose) -> Array:
    """Per pose and member, ∫N dx/L minus its ``N_<link>`` (N, members): the
    :func:`stretch_excess` along the member's axis at the pose."""
    linkage = pose.linkage
    out = np.zeros((pose.q.shape[0], len(linkage.elastic_links)))
    for m, link in enumerate(linkage.elastic_links):
        out[:, m] = _axis(pose, link) @ stretch_excess(linkage, link)
    return out


def compliance(members: tuple[Link, ...], points: dict[str, tuple[float, float]]) -> Array:
    """L/(E·A) of each member at the drawn pose (m/N)."""
    out = []
    for link in members:
        (ax, ay), (bx, by) = (points[p] for p in link.points)
        assert link.axial_stiffness is not None
        out.append(float(np.hypot(bx - ax, by - ay)) / link.axial_stiffness)
    return np.array(out)


def compatible_forces(pose: LinkagePose, k: Array, b: Array) -> tuple[Array, NDArray[np.bool_]]:
    """The reactions x (N, unknowns) in equilibrium (K x = −b) whose members' stretches
    (∫N dx/(E·A) each) are compatible, and where that does not decide them (a self-stress
    state through rigid members only, or a pose with no matrix)."""
    n, _, cols = k.shape
    x = np.full((n, cols), np.nan)
    undecided = np.ones(n, dtype=bool)
    rows, offsets = axial_rows(pose, k), axial_offsets(pose) + stretch_offsets(pose)
    weight = np.sqrt(compliance(pose.linkage.elastic_links, dict(pose.linkage.points)))
    for p in range(n):
        if not (np.isfinite(k[p]).all() and np.isfinite(b[p]).all()):
            continue
        u, s, vt = np.linalg.svd(k[p])
        rank = int(np.sum(s > RANK_RTOL * s[0])) if s.size else 0
        particular = vt[:rank].T @ ((u[:, :rank].T @ -b[p]) / s[:rank])
        free = vt[rank:].T                       # K's null space: the self-stress states
        energy = weight[:, None] * (rows[p] @ free)
        if free.shape[1] and np.linalg.matrix_rank(energy, tol=None) < free.shape[1]:
            continue
        y = np.linalg.lstsq(energy, -weight * (rows[p] @ particular + offsets[p]), rcond=None)[0]
        x[p] = particular + free @ y
        undecided[p] = False
    return x, undecided


def axial_forces(pose: LinkagePose, k: Array, x: Array) -> dict[str, Array]:
    """``N_<link>`` of each elastic member (tension +)."""
    forces = np.einsum("nmc,nc->nm", axial_rows(pose, k), x) + axial_offsets(pose)
    return {f"N_{link.name}": forces[:, m] for m, link in enumerate(pose.linkage.elastic_links)}


def largest_strain(pose: LinkagePose, axial: dict[str, Array]) -> Array:
    """max |δ/L| = |N|/(E·A) over the members, per pose: how small the displacements are."""
    strains = [np.abs(axial[f"N_{link.name}"]) / float(link.axial_stiffness or np.inf)
               for link in pose.linkage.elastic_links]
    return np.max(strains, axis=0) if strains else np.zeros(pose.q.shape[0])

