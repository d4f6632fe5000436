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

A member's own loads (its weight at its centre of mass, forces between its ends) make its
tension vary along it, and the spring carries the tension at the sliding end only. The
member's stretch is ∫N dx/(E·A): a load F at the fraction t of the way from the pinned end
to the sliding end adds t·F·e to the spring's tension over the whole length (e the axis
from the pinned end to the sliding end), so the spring's rest length is L plus that stretch
(:func:`own_load_terms`). Its ``N_<link>`` is the mean of the tensions just inside the two
ends, the analytic engine's: the spring's plus F·e for a point load at the sliding end and
½·F·e for a weight or a load between the ends.

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
from mechcheck.analytic.linkage_elastic import own_loads
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
    slide (each needs an end with a single undriven revolute joint, not another member's).
    """
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


def own_load_terms(linkage: Linkage, end: SlidingEnd) -> tuple[float, Vec]:
    """The member's own loads F (:func:`mechcheck.analytic.linkage_elastic.own_loads`), each
    at t from the pinned end to the sliding end: Σ t·F·e, the stretch they add × E·A/L (e the
    drawn axis from the pinned end to the sliding end); and Σ c·F, whose part along the
    axis the mean of the end tensions adds to the spring's (c = ½ between the ends, t for a
    point load at an end: 1 at the sliding end, 0 at the pinned one), taken along the axis
    where it is read."""
    (fx, fy), (ex, ey) = linkage.points[end.far], linkage.points[end.end]
    length = math.hypot(ex - fx, ey - fy)
    ux, uy = (ex - fx) / length, (ey - fy) / length
    stretching, mean_x, mean_y = 0.0, 0.0, 0.0
    for load in own_loads(linkage, end.member, end.far):
        (lx, ly), c = load.force, 0.5 if load.inside else load.t
        stretching += load.t * (lx * ux + ly * uy)
        mean_x, mean_y = mean_x + c * lx, mean_y + c * ly
    return stretching, (mean_x, mean_y)


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
    other link), whether the other link is the joint's links[1] (``on_b``), and what the
    member's own loads add to the spring's tension in its N, along the axis (``mean_share``,
    :func:`own_load_terms`)."""

    joint: str
    member: str
    groove: pymunk.GrooveJoint
    spring: pymunk.DampedSpring
    on_b: bool
    mean_share: Vec = (0.0, 0.0)

    @property
    def cells(self) -> tuple[Cell, ...]:
        """The groove's accumulated impulse (x, y) on the other link."""
        return tuple(impulse_cells(self.groove))

    def reactions(self, dt: float) -> dict[str, float]:
        """F_<joint> (by links[0] on links[1]) of the last step: the groove's impulse plus
        the spring's along its line, / ``dt``; and N_<member>, the spring's tension plus
        ``mean_share`` along the member's axis now (the spring's line)."""
        gx, gy = read(self.cells)
        a = self.spring.a.local_to_world(self.spring.anchor_a)
        b = self.spring.b.local_to_world(self.spring.anchor_b)
        n = (b - a).normalized()
        push = self.spring.impulse          # on the other link, along n
        sign = 1.0 if self.on_b else -1.0
        return {f"F_{self.joint}_x": sign * (gx + push * n.x) / dt,
                f"F_{self.joint}_y": sign * (gy + push * n.y) / dt,
                f"N_{self.member}": -push / dt + self.mean_share[0] * n.x
                + self.mean_share[1] * n.y}


def build_end(model: LinkageModel, end: SlidingEnd) -> MemberEnd:
    """The groove along the member's axis and the spring (E·A/L, damped critically for the
    fictitious mass; rest length L plus the stretch of the member's own loads,
    :func:`own_load_terms`) of one sliding end."""
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
    stretching, mean = own_load_terms(linkage, end)
    spring = pymunk.DampedSpring(a, b, (fx, fy), (ex, ey), length + stretching / k, k, damper)
    return MemberEnd(j.name, member.name, groove, spring, other == j.links[1], mean)
