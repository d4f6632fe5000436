"""Closed-form positions of a linkage that decomposes into Assur groups, vectorised over poses.

A linkage decomposes when, starting from the ground, its links can be placed one group at a
time, each group attached only to bodies already placed:

- a **crank**: a link turned by a driven revolute joint about a placed body;
- an **RRR dyad**: two links a, b joined by a revolute joint M, a pinned at P1 to a placed
  body and b at P2 to another. M is where the circles of radii |M−P1| and |M−P2| meet,
  on the side of P1→P2 it was drawn on (the dyad's branch);
- an **RRP dyad**: the same, but b joined to its placed body by a prismatic joint (a
  slider-crank's rod and slider): b turns with that body and carries M along a line fixed
  in it. M is where the circle of radius |M−P1| about P1 meets that line, on the side of
  the foot of P1 it was drawn on (the branch). The mirror order (the slide first) is the
  same dyad, its links named the other way round.

The order of the groups and each dyad's branch are fixed once from the drawn pose
(:func:`assur_plan`). This is the same pose as the continuation Newton method of
:mod:`.linkage_kinematics` reaches (LINKAGES.md "Which assembly"): along the driver's path a
dyad can change branch only where its two circles touch (discriminant zero), and there the
linkage locks. So a pose is reachable exactly when it lies in the interval of driver values
about 0 where every dyad's discriminant stays positive; that interval is found once per call
on a grid of the driver's travel (the continuation's step) and refined by bisection. Link
angles come from atan2 and are carried continuously (whole turns included) from the grid.

Linkages that do not decompose this way (triads, dyads with a prismatic middle joint or two
slides, a driven slide, several drivers, free coordinates, redundant joints) have no plan
and keep the Newton path.
"""

from __future__ import annotations

import heapq
import math
import threading
from collections.abc import Iterator
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from mechcheck.analytic.joint_kinds import PRISMATIC, REVOLUTE
from mechcheck.analytic.resultant import Resultant, resultants
from mechcheck.analytic.values import GROUND, Vec2

if TYPE_CHECKING:
    from mechcheck.analytic.linkage import Joint, Linkage

Array = NDArray[np.float64]
#: A body's placement at N poses: cos φ, sin φ, t_x, t_y (floats for the ground).
Frame = tuple[Array | float, Array | float, Array | float, Array | float]
GROUND_FRAME: Frame = (1.0, 0.0, 0.0, 0.0)
#: The grid on which the path is followed: 2° of the driver, the continuation's largest step
#: (:data:`.linkage_kinematics.STEP_ROTATION`), so both look for locks as finely.
GRID_STEP = math.radians(2.0)
#: Refinement of a lock: the bracket shrinks by this many samples per round, for this many
#: rounds (33⁸ ≈ 1.4e12: a 2° bracket to 1e-14 rad, below the continuation's 2⁻⁴⁰).
LOCK_SAMPLES = 33
LOCK_ROUNDS = 9
#: Paths a plan keeps (:func:`path`), and the lock their memo is changed under.
KEPT_PATHS = 8
PATHS_LOCK = threading.Lock()
#: A link whose angle stays within ±this on the grid of the travel never crosses atan2's
#: cut at ±π between grid nodes: its raw angle is already the continuous one.
NO_WRAP = math.pi / 2


@dataclass(frozen=True)
class Crank:
    """``link`` turned by the driven revolute ``joint`` about the placed ``body``."""

    link: str
    joint: Joint
    body: str
    point: Vec2
    #: +1 when ``link`` is joint.links[1] (q = φ_link − φ_body), −1 when links[0].
    sense: float


@dataclass(frozen=True)
class Dyad:
    """Links a, b; joints (a–body1 at P1, a–b at M, b–body2 at P2); drawn points; branch."""

    links: tuple[str, str]
    joints: tuple[Joint, Joint, Joint]
    bodies: tuple[str, str]
    p1: Vec2
    m: Vec2
    p2: Vec2
    branch: float

    @property
    def lengths(self) -> tuple[float, float]:
        return (math.dist(self.m, self.p1), math.dist(self.m, self.p2))


@dataclass(frozen=True)
class SlideDyad:
    """RRP: link a pinned at P1 to body1 and at M to link b, b on a slide (joints[2]) along
    ``axis`` (drawn) fixed in body2; branch: the sign of (M − P1)·axis as drawn."""

    links: tuple[str, str]
    joints: tuple[Joint, Joint, Joint]
    bodies: tuple[str, str]
    p1: Vec2
    m: Vec2
    axis: Vec2
    branch: float

    @property
    def length(self) -> float:
        return math.dist(self.m, self.p1)


Group = Crank | Dyad | SlideDyad


@dataclass(frozen=True)
class AssurPlan:
    """The groups of a linkage in the order they are placed."""

    linkage: Linkage
    groups: tuple[Group, ...]

    @cached_property
    def paths(self) -> dict[tuple[int, int], Path]:
        """The paths traced so far, by their span of nodes (:func:`path`), oldest first."""
        return {}

    @cached_property
    def placing(self) -> dict[str, Group]:
        """The group that places each moving link."""
        return {link: g for g in self.groups
                for link in ([g.link] if isinstance(g, Crank) else g.links)}

    @property
    def carriers(self) -> dict[str, str]:
        """The link each point's position is reported on (:attr:`Linkage.carriers`)."""
        return self.linkage.carriers

    @cached_property
    def joints_on(self) -> dict[str, list[Joint]]:
        """Each moving link's joints."""
        return {link: [j for j in self.linkage.joints if link in j.links]
                for link in self.linkage.moving_links}

    @cached_property
    def couples(self) -> dict[str, int]:
        """How many drivers' couples act on each moving link."""
        return {link: sum(1 for d in self.linkage.drivers
                          if link in self.linkage.joint(d.joint).links)
                for link in self.linkage.moving_links}

    @cached_property
    def slides_on(self) -> dict[str, int]:
        """How many slides (prismatic joints) each moving link has, where it has any."""
        out: dict[str, int] = {}
        for joint in self.linkage.joints:
            if joint.kind is PRISMATIC:
                for link in joint.links:
                    if link != GROUND:
                        out[link] = out.get(link, 0) + 1
        return out

    @property
    def step(self) -> float:
        """The grid of the driver's travel (:data:`GRID_STEP`)."""
        return GRID_STEP

    @cached_property
    def quantity_names(self) -> tuple[str, ...]:
        """The quantities of :func:`.linkage_forces.solve_linkage`, in its order (kept: a
        case solved again does not spell them again)."""
        linkage = self.linkage
        names = [f"{axis}_{p}" for p in linkage.points for axis in "xy"]
        names += [f"phi_{link}" for link in linkage.moving_links]
        names += [f"q_{j.name}" for j in linkage.joints]
        names += [name for j in linkage.joints for name in j.kind.quantities(j)]
        names += [f"Q_{d.joint}" for d in linkage.drivers]
        return tuple(names + [f"S_{s.name}" for s in linkage.springs])

    @cached_property
    def constants(self) -> dict[str, Resultant]:
        """Every constant force on each moving link (loads, weights) folded into one."""
        linkage = self.linkage
        g = linkage.gravity
        loads = [(ld.link, ld.at, ld.force, ld.torque) for ld in linkage.loads]
        loads += [(m.link, m.com, (m.mass * g[0], m.mass * g[1]), 0.0) for m in linkage.masses]
        folded = resultants(loads)
        return {link: folded.get(link, Resultant()) for link in linkage.moving_links}


def assur_plan(linkage: Linkage) -> AssurPlan | None:
    """The linkage's decomposition into a crank and RRR and RRP dyads, or None if it has none
    (see module).

    Groups are taken greedily: a crank where the driven joint reaches an unplaced link, else
    the dyad whose (revolute) middle joint comes first in the file, an RRR or an RRP dyad by
    the kinds of the joints anchoring its links. Only joints next to what was just
    placed can start a new dyad, so each is looked at again only then (a heap of candidates
    in file order): the plan of a chain of n loops costs O(n log n), not O(n²)."""
    # The kinds are single instances (``JointKind.__reduce__``): compared by identity, not
    # through their __eq__, which also takes a kind's name.
    if (len(linkage.drivers) != 1 or linkage.dof != 1 or linkage.redundant
            or linkage.joint(linkage.drivers[0].joint).kind is not REVOLUTE
            or any(j.kind is not REVOLUTE and j.kind is not PRISMATIC for j in linkage.joints)):
        return None
    search = _Search(linkage)
    groups: list[Group] = []
    while len(search.placed) < len(linkage.links):
        group = search.next_group()
        if group is None:
            return None
        groups.append(group)
        search.take(group)
    if len(search.used) != len(linkage.joints):
        return None
    return AssurPlan(linkage, tuple(groups))


class _Search:
    """What :func:`assur_plan` has placed, and the joints that may start a dyad now."""

    def __init__(self, linkage: Linkage) -> None:
        self.linkage = linkage
        self.driven = {d.joint for d in linkage.drivers}
        self.placed = {GROUND}
        self.used: set[str] = set()
        self.at_link: dict[str, list[int]] = {link.name: [] for link in linkage.links}
        for k, joint in enumerate(linkage.joints):
            for link in joint.links:
                self.at_link[link].append(k)
        self.candidates = list(range(len(linkage.joints)))   # a heap: file order

    def next_group(self) -> Group | None:
        for name in self.driven:
            joint = self.linkage.joint(name)
            if name not in self.used and (joint.links[0] in self.placed) != (joint.links[1] in self.placed):
                inner = 0 if joint.links[0] in self.placed else 1
                return Crank(joint.links[1 - inner], joint, joint.links[inner],
                             self.linkage.points[joint.at], 1.0 if inner == 0 else -1.0)
        while self.candidates:
            middle = self.linkage.joints[heapq.heappop(self.candidates)]
            dyad = self._dyad_at(middle)
            if dyad is not None:
                return dyad
        return None

    def _dyad_at(self, middle: Joint) -> Dyad | SlideDyad | None:
        a, b = middle.links
        if middle.name in self.used or middle.name in self.driven or a in self.placed \
                or b in self.placed or middle.kind is not REVOLUTE:
            return None
        first, last = self._anchor(a), self._anchor(b)
        if first is None or last is None:
            return None
        if first.kind is REVOLUTE and last.kind is REVOLUTE:
            return _dyad(self.linkage, (a, b), (first, middle, last), self.placed)
        if first.kind is REVOLUTE and last.kind is PRISMATIC:
            return _slide_dyad(self.linkage, (a, b), (first, middle, last))
        if first.kind is PRISMATIC and last.kind is REVOLUTE:   # the mirror order
            return _slide_dyad(self.linkage, (b, a), (last, middle, first))
        return None     # two slides (a P-R-P dyad): not in closed form here

    def _anchor(self, link: str) -> Joint | None:
        """The undriven free joint pinning ``link`` to a placed body, if exactly one."""
        joints = self.linkage.joints
        pins = [joints[k] for k in self.at_link[link] if joints[k].name not in self.used
                and joints[k].name not in self.driven
                and joints[k].links[joints[k].links.index(link) - 1] in self.placed]
        return pins[0] if len(pins) == 1 else None

    def take(self, group: Group) -> None:
        """Place the group's links and look again at the joints near them."""
        links = [group.link] if isinstance(group, Crank) else list(group.links)
        self.placed.update(links)
        self.used.update([group.joint.name] if isinstance(group, Crank)
                         else (j.name for j in group.joints))
        # A dyad's middle joint joins two unplaced links, and it may start one once a link
        # next to either is placed: the joints of the new links' unplaced neighbours.
        near = set()
        for link in links:
            for k in self.at_link[link]:
                for other in self.linkage.joints[k].links:
                    if other not in self.placed:
                        near.update(self.at_link[other])
        for k in sorted(near):
            heapq.heappush(self.candidates, k)


def _dyad(linkage: Linkage, links: tuple[str, str], joints: tuple[Joint, Joint, Joint],
          placed: set[str]) -> Dyad | None:
    p1, m, p2 = (linkage.points[j.at] for j in joints)
    bodies = (_other(joints[0], links[0]), _other(joints[2], links[1]))
    d = (p2[0] - p1[0], p2[1] - p1[1])
    side = d[0] * (m[1] - p1[1]) - d[1] * (m[0] - p1[0])
    scale = linkage.scale
    # Drawn at a toggle (no side), or with a zero-length link: no branch to keep.
    if abs(side) <= 1e-12 * scale * scale or min(math.dist(m, p1), math.dist(m, p2)) == 0.0:
        return None
    return Dyad(links, joints, bodies, p1, m, p2, math.copysign(1.0, side))


def _slide_dyad(linkage: Linkage, links: tuple[str, str],
                joints: tuple[Joint, Joint, Joint]) -> SlideDyad | None:
    p1, m = linkage.points[joints[0].at], linkage.points[joints[1].at]
    axis = joints[2].axis
    assert axis is not None     # every prismatic joint has one (Prismatic.checked)
    bodies = (_other(joints[0], links[0]), _other(joints[2], links[1]))
    along = (m[0] - p1[0]) * axis[0] + (m[1] - p1[1]) * axis[1]
    # Drawn with the rod square to the slide (its toggle: no side), or of zero length.
    if abs(along) <= 1e-12 * linkage.scale or math.dist(m, p1) == 0.0:
        return None
    return SlideDyad(links, joints, bodies, p1, m, axis, math.copysign(1.0, along))


def _other(joint: Joint, link: str) -> str:
    return joint.links[1] if joint.links[0] == link else joint.links[0]


# -- placing the groups -------------------------------------------------------------------

def on_body(frame: Frame, p: Vec2) -> tuple[Array | float, Array | float]:
    """Where the point drawn at ``p`` on a body with this frame is now."""
    c, s, tx, ty = frame
    return c * p[0] - s * p[1] + tx, s * p[0] + c * p[1] + ty


@dataclass
class Placement:
    """Every body's frame and raw angle at N poses, each dyad's points (P1, M, P2), and
    whether every dyad closed (discriminant ≥ 0)."""

    frames: dict[str, Frame]
    angles: dict[str, Array]
    points: dict[int, tuple[Array | float, ...]]
    closed: NDArray[np.bool_]


def place(plan: AssurPlan, value: Array | np.float64) -> Placement:
    """Place every group at driver values ``value`` (N,) or one value (a number: a tenth of
    the cost per operation); angles raw (atan2) for dyad links,
    exact for cranks (relative to their body's raw angle)."""
    frames: dict[str, Frame] = {GROUND: GROUND_FRAME}
    angles: dict[str, Array] = {GROUND: np.zeros(())}   # adds to one pose or to many
    points: dict[int, tuple[Array | float, ...]] = {}
    closed = np.ones(value.shape, dtype=bool)
    with np.errstate(invalid="ignore", divide="ignore"):
        for index, group in enumerate(plan.groups):
            if isinstance(group, Crank):
                phi = angles[group.body] + group.sense * value
                c, s = np.cos(phi), np.sin(phi)
                px, py = on_body(frames[group.body], group.point)
                p0 = group.point
                frames[group.link] = (c, s, px - (c * p0[0] - s * p0[1]),
                                      py - (s * p0[0] + c * p0[1]))
                angles[group.link] = phi
                continue
            if isinstance(group, SlideDyad):
                closed &= _place_slide(group, index, frames, angles, points)
                continue
            x1, y1 = on_body(frames[group.bodies[0]], group.p1)
            x2, y2 = on_body(frames[group.bodies[1]], group.p2)
            l1, l2 = group.lengths
            dx, dy = x2 - x1, y2 - y1
            dd = dx * dx + dy * dy
            k = 0.5 * (l1 * l1 - l2 * l2 + dd)
            disc = l1 * l1 * dd - k * k
            closed &= disc >= 0.0
            root = group.branch * np.sqrt(disc)
            mx = x1 + (k * dx - root * dy) / dd
            my = y1 + (k * dy + root * dx) / dd
            points[index] = (x1, y1, mx, my, x2, y2)
            for link, (px, py), length in ((group.links[0], (x1, y1), l1),
                                           (group.links[1], (x2, y2), l2)):
                frames[link], angles[link] = _turned(group.m, (px, py), (mx, my), length, group.p1
                                                     if link == group.links[0] else group.p2)
    return Placement(frames, angles, points, closed)


def _place_slide(group: SlideDyad, index: int, frames: dict[str, Frame],
                 angles: dict[str, Array], points: dict[int, tuple[Array | float, ...]]
                 ) -> NDArray[np.bool_]:
    """Place an RRP dyad (frames, angles, points P1, M, axis u now); whether it closed.

    b turns with body2, so M moves from where body2 would carry it (M2) along u: M = M2 + s·u
    with |M − P1| = r, s = −d·u ± √(r² − (d × u)²), d = M2 − P1 (the root with s = 0 as
    drawn is the branch's)."""
    a, b = group.links
    body = frames[group.bodies[1]]
    x1, y1 = on_body(frames[group.bodies[0]], group.p1)
    c2, s2, t2x, t2y = body
    ux = c2 * group.axis[0] - s2 * group.axis[1]
    uy = s2 * group.axis[0] + c2 * group.axis[1]
    x2, y2 = on_body(body, group.m)
    dx, dy = x2 - x1, y2 - y1
    across = dx * uy - dy * ux
    r = group.length
    disc = r * r - across * across
    s = group.branch * np.sqrt(disc) - (dx * ux + dy * uy)
    mx, my = x2 + s * ux, y2 + s * uy
    points[index] = (x1, y1, mx, my, ux, uy)
    frames[a], angles[a] = _turned(group.m, (x1, y1), (mx, my), r, group.p1)
    frames[b] = (c2, s2, t2x + s * ux, t2y + s * uy)
    angles[b] = angles[group.bodies[1]]
    return np.asarray(disc >= 0.0)


def _turned(m0: Vec2, pivot: tuple[Array | float, Array | float], m: tuple[Array, Array],
            length: float, pivot0: Vec2) -> tuple[Frame, Array]:
    """The frame of a link whose drawn segment pivot0→m0 now runs pivot→m."""
    ux, uy = m0[0] - pivot0[0], m0[1] - pivot0[1]
    vx, vy = m[0] - pivot[0], m[1] - pivot[1]
    inv = 1.0 / (length * length)
    c = (ux * vx + uy * vy) * inv
    s = (ux * vy - uy * vx) * inv
    return (c, s, m[0] - (c * m0[0] - s * m0[1]), m[1] - (s * m0[0] + c * m0[1])), \
        np.arctan2(s, c)


# -- the path from the drawn pose ---------------------------------------------------------

@dataclass(frozen=True)
class Path:
    """The reachable driver interval [lo, hi] about 0 and every dyad link's continuous angle
    at the grid nodes k·step, k = first … (NaN beyond the interval)."""

    lo: float
    hi: float
    step: float
    first: int
    node_angles: dict[str, Array]

    def lift(self, link: str, value: Array, raw: Array) -> Array:
        """The continuous angle of ``link`` at ``value`` from its raw atan2 angle."""
        span = self.spans[link]
        if span is None:
            return raw
        nodes = self.node_angles[link]
        index = np.clip(np.rint(value / self.step).astype(np.int64) - self.first, *span)
        ref = nodes[index]
        return raw + math.tau * np.rint((ref - raw) / math.tau)

    @cached_property
    def spans(self) -> dict[str, tuple[int, int] | None]:
        """Each link's first and last reachable node, or None where its raw angle is
        already the continuous one (:data:`NO_WRAP`); found once per path, not per chunk."""
        out: dict[str, tuple[int, int] | None] = {}
        for link, nodes in self.node_angles.items():
            if nodes.size == 1:     # the drawn pose's node alone: the same test, in floats
                angle = float(nodes[0])
                out[link] = (0, 0) if math.isfinite(angle) and not abs(angle) < NO_WRAP else None
                continue
            reachable = np.flatnonzero(np.isfinite(nodes))
            wraps = not np.all(np.abs(nodes[reachable]) < NO_WRAP)
            out[link] = (int(reachable[0]), int(reachable[-1])) if wraps else None
        return out


def path(plan: AssurPlan, values: Array) -> Path:
    """The path of the drivers from the drawn pose over the travel of ``values`` (N,).

    It depends on the plan and the span of nodes only, so the plan keeps the last few it
    traced (:attr:`AssurPlan.paths`): a linkage swept again over the same span (a kept
    preset's next sweep, its stretches' simulators) does not place its nodes and search
    its locks again (measured: a fifth of ``mujoco_solve``'s seed E1 sweep)."""
    h = plan.step
    first = math.floor(min(float(values.min(initial=0.0)), 0.0) / h)
    last = math.ceil(max(float(values.max(initial=0.0)), 0.0) / h)
    traced = plan.paths.get((first, last))
    if traced is None:
        traced = _trace(plan, first, last)
        with PATHS_LOCK:  # a plan may be swept from several threads
            plan.paths[(first, last)] = traced
            while len(plan.paths) > KEPT_PATHS:
                del plan.paths[next(iter(plan.paths))]
    return traced


def _trace(plan: AssurPlan, first: int, last: int) -> Path:
    """:func:`path` over the nodes ``first`` … ``last`` (× the plan's step)."""
    if first == last:   # the drawn pose's node alone (a case solved at its drawn pose)
        drawn = _drawn_path(plan)
        if drawn is not None:
            return drawn
    h = plan.step
    nodes = np.arange(first, last + 1, dtype=np.float64) * h
    placed = place(plan, nodes)
    zero = -first
    lo, hi = -math.inf, math.inf
    ok = placed.closed.copy()
    up = np.flatnonzero(~ok[zero:])
    if up.size:
        hi = _lock(plan, float(nodes[zero + up[0] - 1]), float(nodes[zero + up[0]]))
        ok[zero + up[0]:] = False
    down = np.flatnonzero(~ok[:zero + 1][::-1])
    if down.size:
        lo = _lock(plan, float(nodes[zero - down[0] + 1]), float(nodes[zero - down[0]]))
        ok[:zero - down[0] + 1] = False
    angles = {}
    for link in _dyad_links(plan):
        raw = np.where(ok, placed.angles[link], np.nan)
        angles[link] = _unwrap_from(raw, zero)
    return Path(lo, hi, h, first, angles)


def _drawn_path(plan: AssurPlan) -> Path | None:
    """:func:`_trace` of the one node 0, the drawn pose, placed as a number (a tenth of an
    array's cost per operation): no lock either way, and the dyads' angles there, ~0, which
    nothing needs to carry (:attr:`Path.spans`); None if the drawing does not close."""
    placed = place(plan, np.float64(0.0))
    if not bool(placed.closed):
        return None
    angles = {link: np.array([placed.angles[link]], dtype=np.float64) for link in _dyad_links(plan)}
    return Path(-math.inf, math.inf, plan.step, 0, angles)


def _dyad_links(plan: AssurPlan) -> Iterator[str]:
    """The links whose angles are atan2's (an RRP dyad's slider turns with its body)."""
    for group in plan.groups:
        if isinstance(group, Dyad):
            yield from group.links
        elif isinstance(group, SlideDyad):
            yield group.links[0]


def _unwrap_from(raw: Array, zero: int) -> Array:
    """Carry an angle continuously outward from node ``zero`` (where it is ~0), each way up
    to the first node that does not close: each node turned by the whole turns that bring
    it nearest the one before (node steps turn a link far less than half a turn, so the
    turns add up from the raw angles' differences)."""
    out = raw.copy()
    if out.size == 1:   # one node: nothing to carry
        return out
    for side in (out[zero:], out[zero::-1]):  # views: written through
        finite = np.isfinite(side)
        n = side.size if finite.all() else int(np.argmin(finite))
        if n > 1:
            side[1:n] += math.tau * np.cumsum(np.rint((side[:n - 1] - side[1:n]) / math.tau))
    return out


def _lock(plan: AssurPlan, good: float, bad: float) -> float:
    """The last driver value that closes, between ``good`` and ``bad``."""
    for _ in range(LOCK_ROUNDS):
        samples = np.linspace(good, bad, LOCK_SAMPLES, dtype=np.float64)
        closed = place(plan, samples).closed
        first_bad = int(np.argmin(closed[1:])) + 1 if not closed[1:].all() else LOCK_SAMPLES - 1
        good, bad = float(samples[first_bad - 1]), float(samples[first_bad])
        if good == bad or abs(bad - good) <= 4e-16 * max(abs(good), abs(bad)):
            break
    return good


# -- positions ----------------------------------------------------------------------------

def assur_positions(plan: AssurPlan, values: Array) -> tuple[Array, Array]:
    """q (N, 3n) and the locked fraction (N,), as :func:`.linkage_kinematics.positions`."""
    value = values[:, 0]
    route = path(plan, value)
    placed = place(plan, value)
    q, locked = coordinates(plan, route, value, placed)
    return q, locked


def reachable(route: Path, value: Array, placed: Placement) -> tuple[NDArray[np.bool_], Array]:
    """Which poses the path reaches, and the fraction of the travel where the others lock."""
    inside = (value >= route.lo) & (value <= route.hi) & placed.closed
    if route.lo == -math.inf and route.hi == math.inf:  # no lock either way: none locks
        return inside, np.full(np.shape(value), np.nan)
    with np.errstate(invalid="ignore", divide="ignore"):
        locked = np.where(value > route.hi, route.hi / value,
                          np.where(value < route.lo, route.lo / value, np.nan))
    return inside, np.where(inside, np.nan, locked)


def coordinates(plan: AssurPlan, route: Path, value: Array,
                placed: Placement) -> tuple[Array, Array]:
    """q (N, 3n) with continuous angles, NaN rows where the path does not reach."""
    linkage = plan.linkage
    inside, locked = reachable(route, value, placed)
    q = np.empty((value.shape[0], 3 * len(linkage.moving_links)))
    for k, link in enumerate(linkage.moving_links):
        _, _, tx, ty = placed.frames[link]
        q[:, 3 * k] = tx
        q[:, 3 * k + 1] = ty
        q[:, 3 * k + 2] = continuous_angle(plan, route, link, value, placed)
    q[~inside] = np.nan
    return q, locked


def continuous_angle(plan: AssurPlan, route: Path, link: str, value: Array,
                     placed: Placement) -> Array:
    raw = placed.angles[link]
    if link in route.node_angles:
        return route.lift(link, value, raw)
    group = plan.placing[link]
    if isinstance(group, SlideDyad):     # the slider: its body's angle
        body = group.bodies[1]
        if body == GROUND:
            return np.zeros(value.shape)
        return continuous_angle(plan, route, body, value, placed)
    assert isinstance(group, Crank)
    if group.body == GROUND:
        return raw
    return raw - placed.angles[group.body] + continuous_angle(plan, route, group.body, value,
                                                               placed)
