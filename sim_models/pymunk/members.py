"""Elastic members (``axial_stiffness``, E·A) of a redundant linkage in pymunk: each stretches
by pymunk's own physics, and its stretch decides the reactions the rigid joints leave free.

A member is a rigid body whose one end joint is not a pivot but a slide along the member's
own axis, held by a spring: a :class:`pymunk.GrooveJoint` on the member, along its axis,
carries the joint's point on the other body (the force across the axis), and a
:class:`pymunk.DampedSpring` from the member's far end to that point, rest length L and
stiffness E·A/L, carries the force along it. The member stays straight and stretches by
δ = N·L/(E·A), as in the analytic engine; its ``N_<link>`` is the spring's own force
(−impulse/dt, tension +), and the joint's reaction the groove's impulse plus the spring's.
The joint turns freely in the groove, so it is still a revolute joint.

Chipmunk applies a spring's force explicitly, so a stiff member needs a short step:
:data:`STEP_FRACTION` × sqrt(m/k) for the fictitious mass m and the stiffest member's k.
The spring's damper (critical for the fictitious mass) damps the members' modes; at rest it
applies nothing, so it cannot bias a settled force.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import pymunk

from mechcheck.analytic.joint_kinds import REVOLUTE
from mechcheck.analytic.linkage import Joint, Link, Linkage
from mechcheck.sim_models.pymunk._fast import Cell, impulse_cells, read
from mechcheck.sim_models.pymunk.joint_kinds import GROOVE_REACH
from mechcheck.sim_models.pymunk.settings import SolverSettings

if TYPE_CHECKING:
    from mechcheck.sim_models.pymunk.linkage_model import LinkageModel

Vec = tuple[float, float]
#: The step as a fraction of sqrt(m/k): the explicit spring force is stable below 2 (one
#: mass on one spring), and the bodies share members. A shorter step is noisier: position
#: rounding ε·L becomes a pivot force of about m·ε·L/dt² = k·ε·L/fraction². Measured on four
#: bars (E·A up to 5e10 N): at 0.1 the readings jittered 2e-6 of the load a step and the run
#: did not come to rest in 50 000 steps; at 0.3 it settled in 216, 3e-8 of the load off.
STEP_FRACTION = 0.3


@dataclass(frozen=True)
class SlidingEnd:
    """The end of an elastic ``member`` that slides: the ``joint`` there (the member's only
    one at that end), its point ``end`` and the member's other point ``far``."""

    member: Link
    joint: Joint
    end: str
    far: str


def modelled(linkage: Linkage) -> bool:
    """The linkage's forces follow its members' stretch (redundant, with elastic members)."""
    return linkage.redundant and bool(linkage.elastic_links)


def sliding_ends(linkage: Linkage) -> dict[str, SlidingEnd] | str:
    """Per joint name, the member end that slides there; or why some member has no end to
    slide (each needs an end with a single undriven revolute joint, not another member's),
    or carries a load or a mass of its own."""
    own = [m.name for m in linkage.elastic_links if _loaded_between_ends(linkage, m)]
    if own:
        # The spring carries the tension at the sliding end; a member with loads of its own
        # (its weight) is stretched by its mean tension, which differs from that by half
        # their axial part: the stretches, and so the shares of a redundant load, would not
        # be the analytic model's.
        return (f"the elastic member {own[0]} carries a mass or a load between its ends: the "
                "pymunk model stretches a member by the tension at one end, the analytic one by "
                "its mean; apply the loads at the nodes, or check it with the analytic backend")
    driven = {d.joint for d in linkage.drivers}
    out: dict[str, SlidingEnd] = {}
    for member in linkage.elastic_links:
        end = free_end(linkage, member, driven | set(out))
        if end is None:
            return (f"the elastic member {member.name} has no end with a single undriven "
                    "revolute joint that no other member slides in, which the pymunk model "
                    "needs to stretch it")
        out[end.joint.name] = end
    return out


def _loaded_between_ends(linkage: Linkage, member: Link) -> bool:
    """The member carries a mass, or a load away from its two end points."""
    ends = [linkage.points[p] for p in member.points]
    at_an_end = [any(math.dist(load.at, end) <= 1e-12 * linkage.scale for end in ends)
                 for load in linkage.loads if load.link == member.name]
    return any(m.link == member.name for m in linkage.masses) or not all(at_an_end)


def free_end(linkage: Linkage, member: Link, taken: set[str]) -> SlidingEnd | None:
    """The member's first end (in its points' order) that can slide, or None."""
    for end, far in ((member.points[0], member.points[1]), (member.points[1], member.points[0])):
        joints = [j for j in linkage.joints if member.name in j.links and j.at == end]
        if len(joints) == 1 and joints[0].kind is REVOLUTE and joints[0].name not in taken:
            return SlidingEnd(member, joints[0], end, far)
    return None


def stiffness(linkage: Linkage, member: Link) -> float:
    """E·A/L at the drawn pose (N/m)."""
    (ax, ay), (bx, by) = (linkage.points[p] for p in member.points)
    assert member.axial_stiffness is not None
    return member.axial_stiffness / math.hypot(bx - ax, by - ay)


def member_settings(linkage: Linkage, settings: SolverSettings) -> SolverSettings:
    """``settings`` with the step the stiffest member needs (:data:`STEP_FRACTION`); the
    joints' error correction per step that of ``settings``' own step (``error_bias`` is per
    second: at the short step it would correct a drift only 1e-4 a step); and the residual
    speed at rest × sqrt(m/k)/(their step): a member's damper, 2·sqrt(k·m), then pushes at
    most 2·m·v/dt at that speed (dt, v: ``settings``' step and rest speed), what a rigid run's
    residual speed leaves in its readings. Measured on three bars, E·A 1e10–3e10 N: at rest
    by ``settings``' own speed, the readings were still 8e-6 of the load off."""
    k = max(stiffness(linkage, m) for m in linkage.elastic_links)
    root = math.sqrt(settings.fictitious_mass / k)
    dt = STEP_FRACTION * root
    return settings.with_(dt=dt, error_bias=settings.error_bias ** (settings.dt / dt),
                          settle_speed=settings.settle_speed * root / settings.dt)


@dataclass(frozen=True)
class MemberEnd:
    """A built sliding end: the ``groove`` and ``spring`` (body a the member, body b the
    other link), and whether the other link is the joint's links[1] (``on_b``)."""

    joint: str
    member: str
    groove: pymunk.GrooveJoint
    spring: pymunk.DampedSpring
    on_b: bool

    @property
    def cells(self) -> tuple[Cell, ...]:
        """The groove's accumulated impulse (x, y) on the other link."""
        return tuple(impulse_cells(self.groove))

    def reactions(self, dt: float) -> dict[str, float]:
        """F_<joint> (by links[0] on links[1]) of the last step: the groove's impulse plus
        the spring's along its line, / ``dt``."""
        gx, gy = read(self.cells)
        a = self.spring.a.local_to_world(self.spring.anchor_a)
        b = self.spring.b.local_to_world(self.spring.anchor_b)
        n = (b - a).normalized()
        push = self.spring.impulse          # on the other link, along n
        sign = 1.0 if self.on_b else -1.0
        return {f"F_{self.joint}_x": sign * (gx + push * n.x) / dt,
                f"F_{self.joint}_y": sign * (gy + push * n.y) / dt}


def build_end(model: LinkageModel, end: SlidingEnd) -> MemberEnd:
    """The groove along the member's axis and the spring (rest length L, E·A/L, damped
    critically for the fictitious mass) of one sliding end."""
    linkage, member = model.linkage, end.member
    j = end.joint
    other = j.links[1] if j.links[0] == member.name else j.links[0]
    a, b = model.body(member.name), model.body(other)
    (fx, fy), (ex, ey) = linkage.points[end.far], linkage.points[end.end]
    length = math.hypot(ex - fx, ey - fy)
    ux, uy = (ex - fx) / length, (ey - fy) / length
    reach = GROOVE_REACH * linkage.scale
    groove = pymunk.GrooveJoint(a, b, (fx + 0.5 * length * ux, fy + 0.5 * length * uy),
                                (fx + reach * ux, fy + reach * uy), (ex, ey))
    k = stiffness(linkage, member)
    damper = 2.0 * math.sqrt(k * model.settings.fictitious_mass)
    spring = pymunk.DampedSpring(a, b, (fx, fy), (ex, ey), length, k, damper)
    return MemberEnd(j.name, member.name, groove, spring, other == j.links[1])
