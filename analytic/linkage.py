"""Any planar linkage of revolute and prismatic joints, written as drawn (LINKAGES.md).

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
>>> rocker = Linkage(
...     points={"O": (0.0, 0.0), "A": (1.0, 0.0)},
...     links=(Link("ground", ("O",)), Link("arm", ("O", "A"))),
...     joints=(Joint("O", "revolute", ("ground", "arm"), "O"),),
...     drivers=(Driver("O", 0.5),),
... )
>>> rocker.moving_links, rocker.gruebler, rocker.dof
(('arm',), 1, 1)
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Literal

import numpy as np

from mechcheck.analytic.linkage_kinematics import joint_jacobian_at_drawn_pose
from mechcheck.analytic.values import GROUND, CaseError, FrozenMap, Vec2, finite

if TYPE_CHECKING:
    from mechcheck.analytic.linkage_assur import AssurPlan

IDENTIFIER = re.compile(r"[A-Za-z][A-Za-z0-9_]*")
JointKind = Literal["revolute", "prismatic"]


def _identifier(name: object, key: str) -> str:
    if not isinstance(name, str) or not IDENTIFIER.fullmatch(name):
        raise CaseError(f"must be an identifier (a letter, then letters, digits or _), got {name!r}",
                        key=key)
    return name


def _point(value: Vec2, key: str) -> Vec2:
    if len(value) != 2:
        raise CaseError(f"must be a pair [x, y], got {value!r}", key=key)
    return (finite(value[0], f"{key}[0]"), finite(value[1], f"{key}[1]"))


@dataclass(frozen=True)
class Link:
    """A rigid link and the points it carries."""

    name: str
    points: tuple[str, ...]


@dataclass(frozen=True)
class Joint:
    """A revolute or prismatic joint between ``links[0]`` and ``links[1]`` at point ``at``.

    Prismatic: ``axis`` is the sliding direction at the drawn pose, fixed in ``links[0]``
    (a unit vector after construction); ``at`` is carried by ``links[1]``.
    """

    name: str
    kind: JointKind
    links: tuple[str, str]
    at: str
    axis: Vec2 | None = None


@dataclass(frozen=True)
class Driver:
    """A prescribed joint coordinate, measured from the drawn pose: rad (revolute) or m
    (prismatic), with its rates; ``sense`` (+1 increasing, −1 decreasing, 0 from the
    velocity) is the quasi-static motion Coulomb friction opposes at rest."""

    joint: str
    value: float
    velocity: float = 0.0
    acceleration: float = 0.0
    sense: int = 0


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

    def __post_init__(self) -> None:
        object.__setattr__(self, "points", FrozenMap(
            {_identifier(n, f"points.{n}"): _point(p, f"points.{n}") for n, p in self.points.items()}))
        object.__setattr__(self, "links", tuple(self.links))
        self._check_links()
        object.__setattr__(self, "joints", tuple(self._checked_joint(j, i)
                                                 for i, j in enumerate(self.joints)))
        self._check_points_joined()
        self._check_connected()
        self._check_drivers()
        self._check_loads()
        self._check_springs()
        self._check_friction()

    # -- construction checks ------------------------------------------------------------
    def _check_links(self) -> None:
        names = [link.name for link in self.links]
        for i, link in enumerate(self.links):
            _identifier(link.name, f"links[{i}].name")
            if names.count(link.name) > 1:
                raise CaseError(f"duplicate link name {link.name!r}", key=f"links[{i}].name")
            if not link.points:
                raise CaseError("a link must carry at least one point", key=f"links[{i}].points")
            for point in link.points:
                if point not in self.points:
                    raise CaseError(f"unknown point {point!r}", key=f"links[{i}].points")
        if GROUND not in names:
            raise CaseError("the fixed link 'ground' must be listed", key="links")
        carried = {p for link in self.links for p in link.points}
        for name in self.points:
            if name not in carried:
                raise CaseError("no link carries this point", key=f"points.{name}")

    def _checked_joint(self, joint: Joint, i: int) -> Joint:
        key = f"joints[{i}]"
        _identifier(joint.name, f"{key}.name")
        if [j.name for j in self.joints].count(joint.name) > 1:
            raise CaseError(f"duplicate joint name {joint.name!r}", key=f"{key}.name")
        if joint.kind not in ("revolute", "prismatic"):
            raise CaseError(f"must be 'revolute' or 'prismatic', got {joint.kind!r}", key=f"{key}.kind")
        links = {link.name: link for link in self.links}
        if len(joint.links) != 2 or joint.links[0] == joint.links[1]:
            raise CaseError("must name two different links", key=f"{key}.links")
        for name in joint.links:
            if name not in links:
                raise CaseError(f"unknown link {name!r}", key=f"{key}.links")
        if joint.at not in self.points:
            raise CaseError(f"unknown point {joint.at!r}", key=f"{key}.at")
        first, second = (links[name] for name in joint.links)
        if joint.kind == "revolute":
            if joint.at not in first.points or joint.at not in second.points:
                raise CaseError(f"both links must carry point {joint.at!r} (a revolute joint "
                                "pins them there)", key=f"{key}.at")
            return joint
        if joint.at not in second.points:
            raise CaseError(f"links[1] ({second.name!r}) must carry point {joint.at!r}",
                            key=f"{key}.at")
        if joint.axis is None:
            raise CaseError("a prismatic joint needs its sliding direction", key=f"{key}.axis")
        ax, ay = _point(joint.axis, f"{key}.axis")
        length = math.hypot(ax, ay)
        if length == 0.0:
            raise CaseError("must not be zero", key=f"{key}.axis")
        return Joint(joint.name, joint.kind, joint.links, joint.at, (ax / length, ay / length))

    def _check_points_joined(self) -> None:
        """Every pair of links carrying one point is joined there, directly or through
        revolute joints at that point (LINKAGES.md: only joints join links)."""
        for name in self.points:
            carriers = [link.name for link in self.links if name in link.points]
            if len(carriers) < 2:
                continue
            pins = [j.links for j in self.joints if j.kind == "revolute" and j.at == name]
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
            for name in ("value", "velocity", "acceleration"):
                finite(getattr(d, name), f"{key}.{name}")
            if d.sense not in (-1, 0, 1):
                raise CaseError("must be 'increasing' or 'decreasing'", key=f"{key}.sense")
            if d.sense and d.velocity and (d.velocity > 0) != (d.sense > 0):
                raise CaseError(f"says {'increasing' if d.sense > 0 else 'decreasing'} but the "
                                f"velocity {d.velocity:g} moves the other way", key=f"{key}.sense")
        if len(self.drivers) > self.dof:
            raise CaseError(f"{len(self.drivers)} drivers for {self.dof} degree(s) of freedom",
                            key="drivers")
        free = self.dof - len(self.drivers)
        if free and self.is_moving:
            raise CaseError(f"{free} free coordinate(s) with motion: a free coordinate's "
                            "equilibrium pose is found only in a static case", key="drivers")
        if free and self.has_coulomb_friction:
            raise CaseError(f"{free} free coordinate(s) with Coulomb friction: the equilibrium "
                            "pose would not be unique", key="friction")
        if self.has_coulomb_friction:
            for i, d in enumerate(self.drivers):
                if d.velocity == 0.0 and d.sense == 0:
                    raise CaseError("with Coulomb friction, a driver at rest needs sense = "
                                    "'increasing' or 'decreasing': friction opposes a motion",
                                    key=f"drivers[{i}].sense")

    def _check_loads(self) -> None:
        names = {link.name for link in self.links}
        owners = [("loads", i, ld.link) for i, ld in enumerate(self.loads)]
        owners += [("masses", i, m.link) for i, m in enumerate(self.masses)]
        for kind, i, link in owners:
            if link not in names:
                raise CaseError(f"unknown link {link!r}", key=f"{kind}[{i}].link")
        for i, m in enumerate(self.masses):
            if not m.mass > 0.0:
                raise CaseError(f"must be > 0, got {m.mass:g}", key=f"masses[{i}].mass")
            if m.inertia < 0.0:
                raise CaseError(f"must be >= 0, got {m.inertia:g}", key=f"masses[{i}].inertia")

    def _check_springs(self) -> None:
        names = {link.name for link in self.links}
        joints = {j.name: j for j in self.joints}
        seen: set[str] = set()
        for i, s in enumerate(self.springs):
            key = f"springs[{i}]"
            _identifier(s.name, f"{key}.name")
            if s.name in seen:
                raise CaseError(f"duplicate spring name {s.name!r}", key=f"{key}.name")
            seen.add(s.name)
            if isinstance(s, LinearSpring):
                for k, (link, _) in enumerate(s.ends):
                    if link not in names:
                        raise CaseError(f"unknown link {link!r}", key=f"{key}.ends[{k}]")
                if s.ends[0][0] == s.ends[1][0]:
                    raise CaseError("both ends are on one link: a spring between two points of "
                                    "one rigid link does nothing", key=f"{key}.ends")
                if s.free_length < 0.0:
                    raise CaseError(f"must be >= 0, got {s.free_length:g}", key=f"{key}.free_length")
            elif s.joint not in joints or joints[s.joint].kind != "revolute":
                raise CaseError(f"must name a revolute joint, got {s.joint!r}", key=f"{key}.joint")

    def _check_friction(self) -> None:
        f = self.friction
        if f is None:
            return
        joints = {j.name: j for j in self.joints}
        for table in ("pin_radius", "joint_mu", "viscous"):
            for name in getattr(f, table):
                if name not in joints:
                    raise CaseError(f"unknown joint {name!r}", key=f"friction.{table}.{name}")
                if table == "pin_radius" and joints[name].kind != "revolute":
                    raise CaseError("a pin radius belongs to a revolute joint",
                                    key=f"friction.{table}.{name}")

    # -- derived facts ------------------------------------------------------------------
    @property
    def moving_links(self) -> tuple[str, ...]:
        return tuple(link.name for link in self.links if link.name != GROUND)

    @property
    def gruebler(self) -> int:
        """Gruebler–Kutzbach: 3(n − 1) − 2j for n links (ground included) and j joints."""
        return 3 * (len(self.links) - 1) - 2 * len(self.joints)

    @cached_property
    def joint_rank(self) -> int:
        """Rank of the joints' constraint Jacobian at the drawn pose."""
        jac = joint_jacobian_at_drawn_pose(self)
        if jac.size == 0:
            return 0
        s = np.linalg.svd(jac, compute_uv=False)
        return int((s > 1e-9 * max(1.0, float(s[0]))).sum())

    @cached_property
    def assur_plan(self) -> AssurPlan | None:
        """The closed-form decomposition into a crank and RRR dyads, if it has one."""
        from mechcheck.analytic.linkage_assur import assur_plan
        return assur_plan(self)

    @property
    def dof(self) -> int:
        """Degrees of freedom by the rank of the constraint Jacobian at the drawn pose."""
        return 3 * len(self.moving_links) - self.joint_rank

    @property
    def redundant(self) -> bool:
        """The joints' constraints are dependent at the drawn pose (over-constrained, or a
        singular drawing): the reactions are then not unique."""
        return self.joint_rank < 2 * len(self.joints)

    @property
    def is_moving(self) -> bool:
        return any(d.velocity or d.acceleration for d in self.drivers)

    @property
    def has_coulomb_friction(self) -> bool:
        f = self.friction
        if f is None:
            return False
        pins = any(f.coefficient(n) * r > 0.0 for n, r in f.pin_radius.items())
        slides = any(j.kind == "prismatic" and f.coefficient(j.name) > 0.0 for j in self.joints)
        return pins or slides

    @property
    def scale(self) -> float:
        """A characteristic length: the largest distance between two points (m)."""
        xy = np.array(list(self.points.values()))
        return float(max(np.ptp(xy[:, 0]), np.ptp(xy[:, 1]), 1e-9))

    def joint(self, name: str) -> Joint:
        return next(j for j in self.joints if j.name == name)


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
