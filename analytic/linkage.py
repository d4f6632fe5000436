"""Any planar linkage of revolute, prismatic, pin-in-slot and gear joints, written as drawn
(LINKAGES.md).

A :class:`Linkage` is one immutable value: named points at their global positions in the
**drawn pose**, links that carry them, joints between links, the drivers that move it,
and what loads it (forces, masses, gravity, springs, friction). It checks itself when
built: every rule of LINKAGES.md that a file can break raises :class:`CaseError` naming
the key. Everything inside is SI and radians; the case file's degrees and millimetres
are converted at the border (:mod:`mechcheck.casefile`).

A link's pose is its rigid displacement from the drawn pose: a point P0 it carries is at
R(φ)·P0 + t. The ground (``"ground"``) never moves.

Examples
--------
>>> from mechcheck.analytic.joint_kinds import REVOLUTE
>>> rocker = Linkage(
...     points={"O": (0.0, 0.0), "A": (1.0, 0.0)},
...     links=(Link("ground", ("O",)), Link("arm", ("O", "A"))),
...     joints=(Joint("O", REVOLUTE, ("ground", "arm"), "O"),),
...     drivers=(Driver("O", 0.5),),
... )
>>> rocker.moving_links, rocker.gruebler, rocker.dof
(('arm',), 1, 1)
"""

from __future__ import annotations

import itertools
import re
from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from mechcheck.analytic import linalg
from mechcheck.analytic.joint_kinds import KINDS, GearMesh, JointKind
from mechcheck.analytic.linalg import Batched
from mechcheck.analytic.linkage_kinematics import (
    constraint_system,
    joint_system_at,
    solve_in_lengths,
    unit_scales,
)
from mechcheck.analytic.values import (
    GROUND,
    MAX_TIME,
    MIN_LINK_LENGTH,
    CaseError,
    FrozenMap,
    Vec2,
    bounded_angle,
    driver_displacement,
    driver_rotation,
    finite,
    length_text,
    nonnegative,
    pair,
    positive,
    too_close,
)

if TYPE_CHECKING:
    from mechcheck.analytic.linkage_assur import AssurPlan

IDENTIFIER = re.compile(r"[A-Za-z][A-Za-z0-9_]*")


def _identifier(name: object, key: str) -> str:
    if not isinstance(name, str) or not IDENTIFIER.fullmatch(name):
        raise CaseError(f"must be an identifier (a letter, then letters, digits or _), got {name!r}",
                        key=key)
    return name


def _point(value: Vec2, key: str) -> Vec2:
    return pair(value, key)


def _force(value: Vec2, key: str) -> Vec2:
    """A force's components, named as a case file writes them (``force.x``, ``force.y``)."""
    if isinstance(value, str) or not hasattr(value, "__len__") or len(value) != 2:
        raise CaseError(f"must be a pair (x, y), got {value!r}", key=key)
    return (finite(value[0], f"{key}.x"), finite(value[1], f"{key}.y"))


@dataclass(frozen=True)
class Link:
    """A link and the points it carries: rigid, or, given ``axial_stiffness`` (E·A, N), a
    two-point member that stays straight and stretches by N·L/(E·A) under its axial force
    (:mod:`.linkage_elastic`)."""

    name: str
    points: tuple[str, ...]
    axial_stiffness: float | None = None


@dataclass(frozen=True)
class Joint:
    """A joint of some kind (:mod:`.joint_kinds`) between ``links[0]`` and ``links[1]`` at
    point ``at``; a kind given by its name (as a case file writes it) is held as its value.

    Prismatic and pin-in-slot: ``axis`` is the sliding direction at the drawn pose, fixed
    in ``links[0]`` (a unit vector after construction); ``at`` is carried by ``links[1]``.
    Gear: ``mesh`` holds the pair's centres, pitch radii and pressure angle; ``at`` is the
    first gear's centre.
    """

    name: str
    kind: JointKind
    links: tuple[str, str]
    at: str
    axis: Vec2 | None = None
    mesh: GearMesh | None = None

    def __post_init__(self) -> None:
        if isinstance(self.kind, str) and self.kind in KINDS:
            object.__setattr__(self, "kind", KINDS[self.kind])


@dataclass(frozen=True)
class Effort:
    """A driver's effort over time, N·m on a joint that turns or N on one that slides,
    positive driving its coordinate up: linear between its (time, value) rows, held at
    the first and last value outside them. One row is a constant effort."""

    times: tuple[float, ...]
    values: tuple[float, ...]

    def at(self, t: float | np.ndarray) -> np.ndarray:
        return np.asarray(np.interp(t, self.times, self.values))


@dataclass(frozen=True)
class Driver:
    """A prescribed joint coordinate, measured from the drawn pose: rad (revolute) or m
    (prismatic), with its rates; ``sense`` (+1 increasing, −1 decreasing, 0 from the
    velocity) is the quasi-static motion Coulomb friction opposes at rest.

    In a linkage that moves freely (``Linkage.free_motion``) a driver with an ``effort``
    prescribes that effort instead of a motion: ``value`` and ``velocity`` are then its
    coordinate and rate at time 0, and a driver without one moves as
    value + velocity·t + acceleration·t²/2."""

    joint: str
    value: float
    velocity: float = 0.0
    acceleration: float = 0.0
    sense: int = 0
    effort: Effort | None = None


@dataclass(frozen=True)
class PointLoad:
    """A force fixed in direction (N) at a point fixed to ``link`` (given at the drawn pose),
    and a couple (N·m, CCW +)."""

    link: str
    at: Vec2
    force: Vec2 = (0.0, 0.0)
    torque: float = 0.0


@dataclass(frozen=True)
class LinkMass:
    """Mass (kg), centre of mass at the drawn pose (m), inertia about it (kg·m²)."""

    link: str
    mass: float
    com: Vec2
    inertia: float = 0.0


@dataclass(frozen=True)
class LinearSpring:
    """A spring between a point of one link and a point of another (drawn pose, m).
    Its tension is k(L − L0) + c·L̇, positive pulling the ends together."""

    name: str
    ends: tuple[tuple[str, Vec2], tuple[str, Vec2]]
    stiffness: float
    free_length: float
    damping: float = 0.0


@dataclass(frozen=True)
class TorsionSpring:
    """A spring at a revolute joint: S = k(q − q0) + c·q̇, −S on links[1], +S on links[0]."""

    name: str
    joint: str
    stiffness: float
    free_rotation: float = 0.0
    damping: float = 0.0


@dataclass(frozen=True)
class JointFriction:
    """Coulomb friction (friction circle μ·r at pins with a radius, μ·|N| on every
    prismatic joint, ``joint_mu`` overriding μ) and viscous terms per joint."""

    mu: float = 0.0
    pin_radius: Mapping[str, float] = field(default_factory=dict)
    joint_mu: Mapping[str, float] = field(default_factory=dict)
    viscous: Mapping[str, float] = field(default_factory=dict)

    def coefficient(self, joint: str) -> float:
        return self.joint_mu.get(joint, self.mu)


@dataclass(frozen=True)
class Linkage:
    """The mechanism as drawn, its drivers and its loads. Checks itself (LINKAGES.md)."""

    points: Mapping[str, Vec2]
    links: tuple[Link, ...]
    joints: tuple[Joint, ...]
    drivers: tuple[Driver, ...] = ()
    loads: tuple[PointLoad, ...] = ()
    masses: tuple[LinkMass, ...] = ()
    springs: tuple[LinearSpring | TorsionSpring, ...] = ()
    gravity: Vec2 = (0.0, 0.0)
    friction: JointFriction | None = None
    #: Where the reference point (the ground's first point) is in the file's frame, m: every
    #: position inside is held relative to it (:meth:`_centre_points`), and positions reported
    #: back add it (:meth:`drawn`).
    offset: Vec2 = (0.0, 0.0)
    #: Moves freely over time (``mechcheck simulate``): drivers may prescribe efforts, free
    #: coordinates may move and carry Coulomb friction (their motion comes from the
    #: equations of motion, not from an equilibrium search).
    free_motion: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "points", FrozenMap(
            {_identifier(n, f"points.{n}"): _point(p, f"points.{n}") for n, p in self.points.items()}))
        object.__setattr__(self, "links", tuple(self.links))
        self._check_links()
        shift = self._centre_points()
        object.__setattr__(self, "joints", tuple(self._checked_joint(j, i)
                                                 for i, j in enumerate(self.joints)))
        self._check_points_joined()
        self._check_connected()
        self._check_drivers()
        self._check_loads()
        self._check_springs()
        self._check_friction()
        self._centre_loads(shift)

    # -- construction checks ------------------------------------------------------------
    def _check_links(self) -> None:
        names = [link.name for link in self.links]
        counts = Counter(names)   # counted once: a link list of thousands stays linear
        for i, link in enumerate(self.links):
            _identifier(link.name, f"links[{i}].name")
            if counts[link.name] > 1:
                raise CaseError(f"duplicate link name {link.name!r}", key=f"links[{i}].name")
            if not link.points:
                raise CaseError("a link must carry at least one point", key=f"links[{i}].points")
            for point in link.points:
                if point not in self.points:
                    raise CaseError(f"unknown point {point!r}", key=f"links[{i}].points")
            if link.axial_stiffness is not None:
                self._check_member(link, f"links[{i}]")
        if GROUND not in names:
            raise CaseError("the fixed link 'ground' must be listed", key="links")
        carried = {p for link in self.links for p in link.points}
        for name in self.points:
            if name not in carried:
                raise CaseError("no link carries this point", key=f"points.{name}")
        self._check_spacing()

    def _check_member(self, link: Link, key: str) -> None:
        """An elastic member: a moving link between two points, its E·A > 0."""
        positive(float(link.axial_stiffness or 0.0), f"{key}.axial_stiffness")
        if link.name == GROUND or len(set(link.points)) != 2:
            raise CaseError("only a moving link between two points stretches: give it two "
                            "points, or leave it rigid", key=f"{key}.axial_stiffness")

    def _check_spacing(self) -> None:
        """Points of one link are at one place or a link length apart, and the drawing is
        that large: closer points are no drawing of a machine, and the simulators' bodies
        built on them degenerate."""
        for link in self.links:
            close = too_close([(p, self.points[p]) for p in dict.fromkeys(link.points)])
            if close is not None:
                first, second, distance = close
                raise CaseError(f"is {length_text(distance)} from {first!r}, which link "
                                f"{link.name!r} also carries: two points of one link are at one "
                                f"place or at least {length_text(MIN_LINK_LENGTH)} (a micrometre) "
                                "apart", key=f"points.{second}")
        xs, ys = [p[0] for p in self.points.values()], [p[1] for p in self.points.values()]
        if max(max(xs) - min(xs), max(ys) - min(ys)) < MIN_LINK_LENGTH:
            raise CaseError(f"the drawing is less than {length_text(MIN_LINK_LENGTH)} (a micrometre) "
                            "across: no linkage is that small", key="points")

    def _checked_joint(self, joint: Joint, i: int) -> Joint:
        key = f"joints[{i}]"
        _identifier(joint.name, f"{key}.name")
        if self._joint_name_counts[joint.name] > 1:
            raise CaseError(f"duplicate joint name {joint.name!r}", key=f"{key}.name")
        if not isinstance(joint.kind, JointKind):
            names = " or ".join(repr(name) for name in KINDS)
            raise CaseError(f"must be {names}, got {joint.kind!r}", key=f"{key}.kind")
        links = self._links_by_name
        if len(joint.links) != 2 or joint.links[0] == joint.links[1]:
            raise CaseError("must name two different links", key=f"{key}.links")
        for name in joint.links:
            if name not in links:
                raise CaseError(f"unknown link {name!r}", key=f"{key}.links")
        if joint.at not in self.points:
            raise CaseError(f"unknown point {joint.at!r}", key=f"{key}.at")
        checked = joint.kind.checked(joint, links, key)
        checked.kind.check_drawing(checked, self.points, key)
        return checked

    def _check_points_joined(self) -> None:
        """Every pair of links carrying one point is joined there, directly or through
        revolute joints at that point (LINKAGES.md: only joints join links)."""
        carried_by: dict[str, list[str]] = {}
        for link in self.links:
            for point in dict.fromkeys(link.points):
                carried_by.setdefault(point, []).append(link.name)
        pinned_at: dict[str, list[tuple[str, str]]] = {}
        for j in self.joints:
            if j.kind.pins:
                pinned_at.setdefault(j.at, []).append(j.links)
        for name in self.points:
            carriers = carried_by.get(name, [])
            if len(carriers) < 2:
                continue
            pins = pinned_at.get(name, [])
            if _components(carriers, pins) > 1:
                raise CaseError(f"links {', '.join(map(repr, carriers))} all carry {name!r} but "
                                "are not all joined there by revolute joints", key=f"points.{name}")

    def _check_connected(self) -> None:
        names = [link.name for link in self.links]
        if _components(names, [j.links for j in self.joints]) > 1:
            raise CaseError("the linkage is not connected: some links are joined to no others",
                            key="joints")

    def _check_drivers(self) -> None:
        joints = {j.name: j for j in self.joints}
        seen: set[str] = set()
        for i, d in enumerate(self.drivers):
            key = f"drivers[{i}]"
            if d.joint not in joints:
                raise CaseError(f"unknown joint {d.joint!r}", key=f"{key}.joint")
            if d.joint in seen:
                raise CaseError(f"joint {d.joint!r} is driven twice", key=f"{key}.joint")
            seen.add(d.joint)
            self._check_driver(d, joints[d.joint], key)
        self._check_driver_count()

    def _check_driver(self, d: Driver, joint: Joint, key: str) -> None:
        # The file's key: a joint that turns is driven by a rotation, one that slides by a
        # displacement; both bounded, as the pose is reached by continuation.
        kind = joint.kind
        if not kind.drivable:
            raise CaseError(f"joint {joint.name!r} is a {kind.name}, which cannot be driven: "
                            "drive one of its links at another joint", key=f"{key}.joint")
        if kind.rotates:
            driver_rotation(d.value, f"{key}.{kind.driver_key}")
        else:
            driver_displacement(d.value, self.scale, f"{key}.{kind.driver_key}")
        for name in ("velocity", "acceleration"):
            finite(getattr(d, name), f"{key}.{name}")
        if isinstance(d.sense, bool) or d.sense not in (-1, 0, 1):
            raise CaseError("must be 'increasing' or 'decreasing'", key=f"{key}.sense")
        if d.sense and d.velocity and (d.velocity > 0) != (d.sense > 0):
            raise CaseError(f"says {'increasing' if d.sense > 0 else 'decreasing'} but the "
                            f"velocity {d.velocity:g} moves the other way", key=f"{key}.sense")
        if d.effort is not None:
            self._check_effort(d, f"{key}.{'torque' if kind.rotates else 'force'}")
        if self.has_coulomb_friction and d.velocity == 0.0 and d.sense == 0 \
                and not self.free_motion:
            raise CaseError("with Coulomb friction, a driver at rest needs sense = "
                            "'increasing' or 'decreasing': friction opposes a motion",
                            key=f"{key}.sense")

    def _check_effort(self, d: Driver, key: str) -> None:
        """An effort's rows (``key``: the driver's ``torque`` or ``force``)."""
        effort = d.effort
        assert effort is not None
        if not self.free_motion:
            raise CaseError("an effort moves a linkage over time: give the case a "
                            "[case.simulate] table", key=key)
        if d.acceleration:
            raise CaseError("a driver with an effort has no prescribed acceleration: it "
                            "follows from the effort", key=key.rsplit(".", 1)[0] + ".acceleration")
        if not effort.times or len(effort.times) != len(effort.values):
            raise CaseError("must be a number or rows of [time, value]", key=key)
        for t, value in zip(effort.times, effort.values, strict=True):
            finite(value, key)
            if not 0.0 <= finite(t, key) <= MAX_TIME:
                raise CaseError(f"times must be within 0 … {MAX_TIME:g} s, got {t:g}", key=key)
        if any(b <= a for a, b in itertools.pairwise(effort.times)):
            raise CaseError("times must increase row by row", key=key)

    def _check_driver_count(self) -> None:
        if len(self.drivers) > self.dof:
            raise CaseError(f"{len(self.drivers)} drivers for {self.dof} degree(s) of freedom",
                            key="drivers")
        free = self.dof - len(self.drivers)
        if self.free_motion:
            return      # free coordinates move by the equations of motion
        if free and self.is_moving:
            raise CaseError(f"{free} free coordinate(s) with motion: a free coordinate's "
                            "equilibrium pose is found only in a static case", key="drivers")
        if free and self.has_coulomb_friction:
            raise CaseError(f"{free} free coordinate(s) with Coulomb friction: the equilibrium "
                            "pose would not be unique", key="friction")

    def _check_loads(self) -> None:
        names = {link.name for link in self.links}
        owners = [("loads", i, ld.link) for i, ld in enumerate(self.loads)]
        owners += [("masses", i, m.link) for i, m in enumerate(self.masses)]
        for kind, i, link in owners:
            if link not in names:
                raise CaseError(f"unknown link {link!r}", key=f"{kind}[{i}].link")
        _point(self.gravity, "gravity")
        for i, ld in enumerate(self.loads):
            _point(ld.at, f"loads[{i}].at")
            _force(ld.force, f"loads[{i}].force")
            finite(ld.torque, f"loads[{i}].torque")
        for i, m in enumerate(self.masses):
            positive(m.mass, f"masses[{i}].mass")
            _point(m.com, f"masses[{i}].com")
            nonnegative(m.inertia, f"masses[{i}].inertia")

    def _check_springs(self) -> None:
        joints = {j.name: j for j in self.joints}
        seen: set[str] = set()
        for i, s in enumerate(self.springs):
            key = f"springs[{i}]"
            _identifier(s.name, f"{key}.name")
            if s.name in seen:
                raise CaseError(f"duplicate spring name {s.name!r}", key=f"{key}.name")
            seen.add(s.name)
            if isinstance(s, LinearSpring):
                self._check_linear_spring(s, key)
            elif isinstance(s, TorsionSpring):
                if s.joint not in joints or not joints[s.joint].kind.pins:
                    raise CaseError(f"must name a revolute joint, got {s.joint!r}", key=f"{key}.joint")
                nonnegative(s.stiffness, f"{key}.stiffness")
                bounded_angle(s.free_rotation, f"{key}.free_rotation")
                nonnegative(s.damping, f"{key}.damping")
            else:
                raise CaseError(f"must be a LinearSpring or a TorsionSpring, got {s!r}", key=key)

    def _check_linear_spring(self, s: LinearSpring, key: str) -> None:
        names = {link.name for link in self.links}
        if len(s.ends) != 2:
            raise CaseError("must be two ends [link, point]", key=f"{key}.ends")
        for k, end in enumerate(s.ends):
            if not isinstance(end, (tuple, list)) or len(end) != 2:
                raise CaseError(f"must be [link, [x, y]], got {end!r}", key=f"{key}.ends[{k}]")
            link, at = end
            if not isinstance(link, str) or link not in names:
                raise CaseError(f"unknown link {link!r}", key=f"{key}.ends[{k}]")
            if isinstance(at, str) or not hasattr(at, "__len__") or len(at) != 2:
                raise CaseError(f"must be [link, [x, y]], got {end!r}", key=f"{key}.ends[{k}]")
            # One key for the end, whichever coordinate is bad: the file writes it
            # [link, [x, y]], so an index past ends[k] would point into the link's name.
            for v in at:
                finite(v, f"{key}.ends[{k}]")
        if s.ends[0][0] == s.ends[1][0]:
            raise CaseError("both ends are on one link: a spring between two points of "
                            "one rigid link does nothing", key=f"{key}.ends")
        nonnegative(s.stiffness, f"{key}.stiffness")
        if finite(s.free_length, f"{key}.free_length") < 0.0:
            raise CaseError(f"must be >= 0, got {length_text(s.free_length)}", key=f"{key}.free_length")
        nonnegative(s.damping, f"{key}.damping")

    def _check_friction(self) -> None:
        f = self.friction
        if f is None:
            return
        joints = {j.name: j for j in self.joints}
        nonnegative(f.mu, "friction.mu")
        for table in ("pin_radius", "joint_mu", "viscous"):
            for name, value in getattr(f, table).items():
                if name not in joints:
                    raise CaseError(f"unknown joint {name!r}", key=f"friction.{table}.{name}")
                if table == "pin_radius" and not joints[name].kind.pins:
                    raise CaseError("a pin radius belongs to a revolute joint",
                                    key=f"friction.{table}.{name}")
                if not joints[name].kind.frictional:
                    raise CaseError(f"a {joints[name].kind.name} joint has no friction model",
                                    key=f"friction.{table}.{name}")
                nonnegative(value, f"friction.{table}.{name}")

    # -- where the drawing sits -----------------------------------------------------------
    def _centre_points(self) -> Vec2:
        """Hold the points relative to the reference point (the ground's first point), and
        return the shift: every tolerance of the engine is then independent of where the
        drawing sits (a four-bar drawn 5 km from the origin kept 1e-12 m of its closure)."""
        ground = next(link for link in self.links if link.name == GROUND)
        rx, ry = self.points[ground.points[0]]
        if rx == 0.0 and ry == 0.0:
            return (0.0, 0.0)
        object.__setattr__(self, "points", FrozenMap(
            {n: (x - rx, y - ry) for n, (x, y) in self.points.items()}))
        object.__setattr__(self, "offset", (self.offset[0] + rx, self.offset[1] + ry))
        return (rx, ry)

    def _centre_loads(self, shift: Vec2) -> None:
        """Move the drawn positions of loads, centres of mass and spring ends by the points'
        shift (:meth:`_centre_points`)."""
        if shift == (0.0, 0.0):
            return

        def moved(p: Vec2) -> Vec2:
            return (p[0] - shift[0], p[1] - shift[1])

        object.__setattr__(self, "loads", tuple(replace(ld, at=moved(ld.at)) for ld in self.loads))
        object.__setattr__(self, "masses", tuple(replace(m, com=moved(m.com)) for m in self.masses))
        object.__setattr__(self, "springs", tuple(
            replace(s, ends=((s.ends[0][0], moved(s.ends[0][1])), (s.ends[1][0], moved(s.ends[1][1]))))
            if isinstance(s, LinearSpring) else s for s in self.springs))

    def drawn(self, p: Vec2) -> Vec2:
        """A position held relative to the reference point, in the file's frame (m)."""
        return (p[0] + self.offset[0], p[1] + self.offset[1])

    # -- derived facts ------------------------------------------------------------------
    @cached_property
    def moving_links(self) -> tuple[str, ...]:
        return tuple(link.name for link in self.links if link.name != GROUND)

    @cached_property
    def link_number(self) -> dict[str, int]:
        """Each moving link's place in :attr:`moving_links`."""
        return {name: k for k, name in enumerate(self.moving_links)}

    @cached_property
    def carriers(self) -> dict[str, str]:
        """The link each point's position is reported on: the first that carries it."""
        out: dict[str, str] = {}
        for link in self.links:
            for point in link.points:
                out.setdefault(point, link.name)
        return out

    @cached_property
    def _joint_name_counts(self) -> Counter[str]:
        return Counter(j.name for j in self.joints)

    @cached_property
    def _links_by_name(self) -> dict[str, Link]:
        return {link.name: link for link in self.links}

    @cached_property
    def _joints_by_name(self) -> dict[str, Joint]:
        return {j.name: j for j in self.joints}

    @property
    def elastic_links(self) -> tuple[Link, ...]:
        """The members that stretch (:attr:`Link.axial_stiffness`)."""
        return tuple(link for link in self.links if link.axial_stiffness is not None)

    @property
    def constraint_rows(self) -> int:
        """What the joints remove: Σ(3 − Sᵢ), each kind's rows."""
        return sum(j.kind.rows for j in self.joints)

    @property
    def gruebler(self) -> int:
        """Gruebler–Kutzbach: 3(n − 1) − Σ(3 − Sᵢ) for n links (ground included), each
        joint leaving its Sᵢ freedoms."""
        return 3 * (len(self.links) - 1) - self.constraint_rows

    @property
    def drawn_rank(self) -> int:
        """Rank of the joints' constraint Jacobian at the drawn pose (in length units:
        :func:`.linkage_kinematics.unit_scales`, so that it does not depend on the drawing's
        place, orientation or size)."""
        return self._drawn[0]

    @property
    def drawn_residual(self) -> np.ndarray:
        """Φ of the joints' constraints at the drawn pose (1, rows), read-only: found with
        :attr:`drawn_rank`, so that a solve's test that the drawing closes costs nothing."""
        return self._drawn[1]

    @cached_property
    def _drawn(self) -> tuple[int, np.ndarray]:
        phi, jac = constraint_system(self, np.zeros((1, 3 * len(self.moving_links))),
                                     np.zeros((1, 0)), drivers=False)
        phi.flags.writeable = False
        return self._rank_of(jac), phi

    @cached_property
    def joint_rank(self) -> int:
        """Rank of the joints' constraint Jacobian: at the drawn pose, or, where the drawing
        sits on a change point (a four-bar drawn flat), a little way along the linkage's own
        motions, where the constraints are independent again. Constraints dependent at every
        pose (a second pin at one point, a triangle of slides) stay dependent there."""
        drawn = self.drawn_rank
        if drawn == self.constraint_rows:
            return drawn
        return max([drawn, *(self._rank_near_drawing(seed) for seed in range(PROBES))])

    @property
    def drawn_at_change_point(self) -> bool:
        """The drawing sits where the joints' constraints are dependent although they are
        not elsewhere: which branch the linkage takes from there is not drawn."""
        return self.drawn_rank < self.joint_rank

    def _rank_at(self, q: np.ndarray) -> int:
        return self._rank_of(joint_system_at(self, q))

    def _rank_of(self, jac: Batched) -> int:
        rows, cols = unit_scales(self, drivers=False)
        scaled = jac.scaled(np.broadcast_to(rows, (1, rows.size)), cols)
        return linalg.rank(scaled.dense()[0] if scaled.small else scaled.at(0))

    def _rank_near_drawing(self, seed: int) -> int:
        """The rank a step of 10⁻³ of the linkage's size away from the drawn pose, along a
        random motion the constraints allow to first order, brought back onto them."""
        size = 3 * len(self.moving_links)
        rows, cols = unit_scales(self, drivers=False)
        jac = joint_system_at(self, np.zeros(size))
        direction = np.random.default_rng(seed).standard_normal(size) / cols   # in lengths
        along = direction - solve_in_lengths(self, jac, jac_times(jac, direction), drivers=False)[0]
        norm = float(np.linalg.norm(along / cols))
        if not norm > 0.0:
            return self.drawn_rank
        q = along * (1e-3 * self.scale / norm)
        for _ in range(50):
            phi, jac = constraint_system(self, q[None, :], np.zeros((1, 0)), drivers=False)
            if np.abs(phi * rows).max(initial=0.0) <= 1e-13 * self.scale:
                return self._rank_at(q)
            # Gauss–Newton back onto the constraints, blind to the nearly dependent
            # directions (a plain step there is as large as 1/σ_min).
            scaled = jac.scaled(rows[None, :], cols)
            q = q - linalg.solve_truncated(scaled, phi * rows, 1e-6)[0] * cols
        return self.drawn_rank   # not back on the constraints: no evidence either way

    @cached_property
    def assur_plan(self) -> AssurPlan | None:
        """The closed-form decomposition into a crank and RRR and RRP dyads, if it has one."""
        from mechcheck.analytic.linkage_assur import assur_plan
        return assur_plan(self)

    @property
    def dof(self) -> int:
        """Degrees of freedom by the rank of the constraint Jacobian (:attr:`joint_rank`)."""
        return 3 * len(self.moving_links) - self.joint_rank

    @property
    def redundant(self) -> bool:
        """The joints' constraints are dependent (over-constrained): the reactions are then
        not unique."""
        return self.joint_rank < self.constraint_rows

    @property
    def is_moving(self) -> bool:
        return any(d.velocity or d.acceleration for d in self.drivers)

    @property
    def efforts(self) -> tuple[Driver, ...]:
        """The drivers that prescribe an effort rather than a motion."""
        return tuple(d for d in self.drivers if d.effort is not None)

    @property
    def has_coulomb_friction(self) -> bool:
        f = self.friction
        if f is None:
            return False
        return any(j.kind.coulomb_coefficient(f, j) > 0.0 for j in self.joints)

    @cached_property
    def scale(self) -> float:
        """A characteristic length: twice the largest distance of a point from the points'
        centroid (m), between the drawing's diameter and twice it; unchanged when the whole
        drawing is moved or turned, and scaled with it."""
        xy = np.array(list(self.points.values()))
        xy = xy - xy[0]     # the same digits wherever the drawing sits
        return float(max(2.0 * np.sqrt(((xy - xy.mean(axis=0)) ** 2).sum(axis=1)).max(), 1e-300))

    def joint(self, name: str) -> Joint:
        return self._joints_by_name[name]


#: Random motions tried from a drawing whose constraints are dependent (:attr:`Linkage.joint_rank`).
PROBES = 3


def jac_times(jac: Batched, x: np.ndarray) -> np.ndarray:
    """J·x at one pose."""
    return np.asarray(jac.at(0) @ x if not jac.small else jac.dense()[0] @ x)[None, :]


def _components(nodes: list[str], edges: list[tuple[str, str]]) -> int:
    """Connected components of a graph (union–find), counting only the given nodes."""
    parent = {n: n for n in nodes}

    def root(n: str) -> str:
        while parent[n] != n:
            parent[n] = parent[parent[n]]
            n = parent[n]
        return n

    for a, b in edges:
        if a in parent and b in parent:
            parent[root(a)] = root(b)
    return len({root(n) for n in nodes})
