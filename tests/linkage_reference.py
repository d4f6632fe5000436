"""An independent reference solver for ``mechanism = "linkage"`` cases (LINKAGES.md).

This module is test code. It reads one ``[[case]]`` table as the plain dict that
:mod:`tomllib` gives and shares nothing with the production engine: it is the
oracle that engine is tested against.

Method (maximal coordinates, Nikravesh, *Computer-Aided Analysis of Mechanical
Systems*, ch. 3, 11):

* Every moving link i carries q_i = (x_i, y_i, φ_i): the position of a reference
  point of the link (the centroid of its drawn points) and the rotation φ_i of the
  link from the drawn pose. A point drawn at P⁰ on link i is at
  p = r_i + A(φ_i)(P⁰ − c_i). The drawn pose is q = (c_i, 0) for every link, and it
  satisfies every joint constraint by construction.
* Joints are constraints Φ(q) = 0, each written "links[0] minus links[1]", so that
  with the constraint forces Q_c = −Φ_qᵀλ each multiplier *is* the contract's
  reaction, the force BY links[0] ON links[1]:
  revolute Φ = p_a − p_b (λ = F); prismatic Φ = (n_a·(p_a − p_b), φ_a − φ_b)
  (λ = (N, M): a force N·n_a at ``at`` and a couple M on links[1]); pin in a slot
  (seed 001's Cs: ``at`` of links[1] slides along the slot fixed in links[0] and turns
  in it) Φ = n_a·(p_a − p_b), one row (λ = N: a force N·n_a at ``at``, no couple).
  A driver is Φ = s·value − q_joint (λ = Q, the effort on links[1]).
* Positions: pseudo-arclength continuation of Φ(q, s) = 0 from the drawn pose (s = 0)
  to s = 1, all drivers moving together. A turning point in s is a lock
  (``no_solution`` at the driver values there); a sign change of the bordered
  Jacobian's determinant is a bifurcation (``singular``).
* Velocities Φ_q q̇ = −Φ_t; accelerations Φ_q q̈ = γ with γ written out per joint.
* Forces: Φ_qᵀλ = Q(q, q̇) + Q_coulomb(λ) − E(q, q̇, q̈), square when DOF equals the
  number of drivers. E is Newton–Euler of each link about its reference point.
  Coulomb friction makes Q depend on |λ|: Newton on λ from the frictionless
  answer (∂|F|/∂F = F/|F|).
* Free coordinates (DOF > drivers, static): Newton on the equilibrium equations
  Φ(q) = 0, Q(q) − Φ_qᵀλ = 0 in (q, λ) from the drawn pose (drivers at 0), then the
  drivers stepped to their values; stability from the sign of the stiffness reduced
  to the null space of Φ_q. Newton finds the nearest equilibrium, stable or not.

How this module reads the places where LINKAGES.md leaves a choice:

* ``phi_`` and revolute ``q_`` are radians wrapped to [−π, π); the unwrapped values
  are in ``LinkageResult.q``. ``x_``/``y_`` are given for every point, ground points
  included (a point's position on the first link that carries it).
* A prismatic reaction ``F_`` is the whole force of links[0] on links[1] through the
  joint except the driver's effort: the normal force plus the joint's Coulomb and
  viscous friction along the axis. The driver's −Q acts on links[0] at the same point.
* The revolute friction moment is μ·r·|F| with |F| the joint's own reaction; ``joint_mu``
  overrides ``mu`` for revolute and prismatic joints alike; a missing ``mu`` is 0.
  "Coulomb friction" (for the refusals) means some joint with μ·r > 0 or μ > 0.
* Coulomb senses: drivers with a velocity use it; a resting driver moves at ±1 rad/s
  or m/s in its ``sense``. A joint with Coulomb friction whose relative speed is zero
  (below 1e-9 of the largest) makes the forces ``indeterminate``.
* A load, mass or spring end named by a point that its link does not carry is that
  point's drawn position, fixed to the link. Loads and masses on the ground do nothing.
* Redundant constraints: the pose is still solved (with a full-rank subset of rows)
  and reported, without forces. A final condition number above 1e8 is ``singular``;
  Coulomb equations without a solution are ``no_solution`` ("friction self-locks").
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

Vector = NDArray[np.float64]
Matrix = NDArray[np.float64]

GROUND = -1  # link index of the fixed link

#: Newton has converged when a step is below this (dimensionless); then it takes one more.
NEWTON_TOL = 1e-13
NEWTON_MAX_ITERATIONS = 60
#: Condition number (dimensionless Jacobian) above which a pose is `singular` (CONVENTIONS).
SINGULAR_CONDITION = 1e8
#: Singular values below this fraction of the largest count as zero for the rank.
RANK_RTOL = 1e-9
#: A relative speed this small against the largest speed is an exact zero: a Coulomb
#: term whose sense is then undefined reverses at this pose.
ZERO_SPEED_RTOL = 1e-9
#: Continuation: first and largest step along the path (dimensionless arclength:
#: radians, lengths over the drawing size), smallest step before giving up.
FIRST_STEP, LARGEST_STEP, SMALLEST_STEP = 0.02, 0.05, 1e-11
#: Tangents of consecutive accepted points differ by less than this angle (rad).
LARGEST_TURN = 0.2
#: A path longer than this many accepted steps (≈ 2500 rad of travel) is not followed.
MAX_PATH_STEPS = 50_000

IDENTIFIER = re.compile(r"[A-Za-z][A-Za-z0-9_]*\Z")
CASE_KEYS = {"name", "mechanism", "description", "seed", "tolerance", "length_unit", "gravity",
             "points", "links", "joints", "drivers", "loads", "masses", "springs", "friction"}


class LinkageInputError(ValueError):
    """The case is unusable or refused by the contract (the CLI's exit 2)."""


# -- plane geometry ---------------------------------------------------------------------
def rot(phi: float) -> Matrix:
    """The rotation matrix A(φ)."""
    c, s = math.cos(phi), math.sin(phi)
    return np.array([[c, -s], [s, c]])


def perp(v: Vector) -> Vector:
    """v turned +90° (k × v)."""
    return np.array([-v[1], v[0]])


def cross2(r: Vector, f: Vector) -> float:
    """z-component of r × f."""
    return float(r[0] * f[1] - r[1] * f[0])


def wrap(angle: float) -> float:
    """angle wrapped to [−π, π)."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def sign(x: float) -> float:
    x = float(x)
    return float((x > 0.0) - (x < 0.0))


# -- the parsed linkage -----------------------------------------------------------------
@dataclass(frozen=True)
class Attachment:
    """A point fixed to a link: its link index and its vector from the link's reference
    point at the drawn pose (for the ground: its global position)."""

    link: int
    local: Vector


@dataclass(frozen=True)
class Joint:
    """A revolute, prismatic or pin-in-slot joint between links a = links[0] and b = links[1].

    ``on_a`` and ``on_b`` are the joint point ``at`` fixed to each link (on a it is the
    point of a that coincides with ``at`` at the drawn pose). ``axis`` is the unit
    sliding direction at the drawn pose (prismatic and pin in a slot only).
    """

    @property
    def rows(self) -> int:
        """Constraint rows: 2 (revolute, prismatic), 1 (pin in a slot: it turns freely)."""
        return 1 if self.kind == "pin_in_slot" else 2

    @property
    def slides(self) -> bool:
        """Whether the joint's coordinate is a travel along an axis fixed in links[0]."""
        return self.kind != "revolute"

    name: str
    kind: str
    a: int
    b: int
    at: str
    on_a: Attachment
    on_b: Attachment
    axis: Vector


@dataclass(frozen=True)
class Driver:
    """A prescribed joint coordinate: value (rad or m), its rates (SI) and the Coulomb sense."""

    joint: int
    value: float
    velocity: float
    acceleration: float
    sense: float  # +1 increasing, −1 decreasing, 0 not given


@dataclass(frozen=True)
class Load:
    """A force fixed in direction, applied at a point of a link, and a couple."""

    at: Attachment
    force: Vector
    torque: float


@dataclass(frozen=True)
class Mass:
    """Mass, centre of mass and inertia about it, of one link."""

    com: Attachment
    mass: float
    inertia: float


@dataclass(frozen=True)
class LinearSpring:
    """Tension k(L − L0) + c·L̇ between two points of different links."""

    name: str
    ends: tuple[Attachment, Attachment]
    stiffness: float
    free_length: float
    damping: float


@dataclass(frozen=True)
class TorsionalSpring:
    """Moment k(q − q0) + c·q̇ at a revolute joint: −S on links[1], +S on links[0]."""

    name: str
    joint: int
    stiffness: float
    free_rotation: float
    damping: float


@dataclass(frozen=True)
class JointFriction:
    """Friction of one joint: Coulomb coefficient times arm (revolute: μ·r, prismatic: μ)
    and viscous coefficient."""

    coulomb: float
    viscous: float


@dataclass(frozen=True)
class Linkage:
    """One linkage case in SI, ready for the solver."""

    name: str
    points: dict[str, Vector]
    carriers: dict[str, list[int]]  # point name -> links (GROUND or moving index) carrying it
    link_names: list[str]  # moving links, in file order
    centres: list[Vector]  # reference point of each moving link at the drawn pose
    joints: list[Joint]
    drivers: list[Driver]
    loads: list[Load]
    masses: list[Mass]
    springs: list[LinearSpring]
    torsion: list[TorsionalSpring]
    friction: list[JointFriction]  # one per joint
    gravity: Vector
    size: float  # largest distance between two drawn points: the length scale
    length_unit: float  # metres per file length unit

    @property
    def n(self) -> int:
        """Number of coordinates, 3 per moving link."""
        return 3 * len(self.link_names)

    @property
    def has_coulomb(self) -> bool:
        return any(f.coulomb > 0.0 for f in self.friction)

    def column_scale(self) -> Vector:
        """Size of each coordinate: lengths by the drawing size, angles by one radian."""
        return np.tile([self.size, self.size, 1.0], len(self.link_names))


# -- reading a case ---------------------------------------------------------------------
def _fail(case: dict[str, Any], key: str, why: str) -> LinkageInputError:
    return LinkageInputError(f"case {case.get('name', '?')!r}: {key}: {why}")


def _number(case: dict[str, Any], key: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise _fail(case, key, f"expected a finite number, got {value!r}")
    return float(value)


def _pair(case: dict[str, Any], key: str, value: Any) -> Vector:
    if not isinstance(value, list) or len(value) != 2:
        raise _fail(case, key, f"expected [x, y], got {value!r}")
    return np.array([_number(case, key, v) for v in value])


def _check_keys(case: dict[str, Any], key: str, table: dict[str, Any], allowed: set[str]) -> None:
    unknown = set(table) - allowed
    if unknown:
        raise _fail(case, key, f"unknown key(s) {sorted(unknown)}")


def parse_case(case: dict[str, Any]) -> Linkage:
    """The Linkage of one ``[[case]]`` table: mm → m, degrees → radians, names → indices."""
    _check_keys(case, "case", case, CASE_KEYS)
    if case.get("mechanism") != "linkage":
        raise _fail(case, "mechanism", "expected \"linkage\"")
    unit = {"m": 1.0, "mm": 1e-3}.get(case.get("length_unit", "m"))
    if unit is None:
        raise _fail(case, "length_unit", "expected \"m\" or \"mm\"")

    points = {name: unit * _pair(case, f"points.{name}", xy)
              for name, xy in case.get("points", {}).items()}
    for name in points:
        if not IDENTIFIER.match(name):
            raise _fail(case, f"points.{name}", "not an identifier")

    link_index, carriers, names, centres = _read_links(case, points)
    joints = [_read_joint(case, k, jt, points, link_index, carriers, centres)
              for k, jt in enumerate(case.get("joints", []))]
    _check_shared_points(case, carriers, joints, link_index)
    _check_connected(case, joints, len(names))
    joint_index = {j.name: k for k, j in enumerate(joints)}
    if len(joint_index) != len(joints):
        raise _fail(case, "joints", "joint names must be unique")

    def attach(key: str, link_name: Any, at: Any) -> Attachment:
        if link_name not in link_index:
            raise _fail(case, key, f"unknown link {link_name!r}")
        link = link_index[link_name]
        if isinstance(at, str):
            if at not in points:
                raise _fail(case, key, f"unknown point {at!r}")
            where = points[at]
        else:
            where = unit * _pair(case, key, at)
        return Attachment(link, where if link == GROUND else where - centres[link])

    drivers = _read_drivers(case, joints, joint_index, unit)
    loads = [_read_load(case, k, ld, attach) for k, ld in enumerate(case.get("loads", []))]
    masses = [_read_mass(case, k, m, attach) for k, m in enumerate(case.get("masses", []))]
    springs, torsion = _read_springs(case, joints, joint_index, attach, unit)
    friction = _read_friction(case, joints, joint_index, unit)
    gravity = _pair(case, "gravity", case["gravity"]) if "gravity" in case else np.zeros(2)

    if drivers and friction and any(f.coulomb > 0.0 for f in friction):
        for d in drivers:
            if d.velocity == 0.0 and d.sense == 0.0:
                raise _fail(case, f"drivers.{joints[d.joint].name}.sense",
                            "Coulomb friction with a resting driver needs sense")
    all_xy = np.array(list(points.values()))
    size = float(max((np.linalg.norm(p - r) for p in all_xy for r in all_xy), default=0.0))
    return Linkage(str(case.get("name", "")), points, carriers, names, centres, joints, drivers,
                   loads, masses, springs, torsion, friction, gravity, size if size > 0 else 1.0,
                   unit)


def _read_links(case: dict[str, Any], points: dict[str, Vector]
                ) -> tuple[dict[str, int], dict[str, list[int]], list[str], list[Vector]]:
    """Link indices (ground −1, moving links 0, 1, … in file order), the links carrying
    each point, and each moving link's reference point (centroid of its points)."""
    link_index: dict[str, int] = {}
    carriers: dict[str, list[int]] = {p: [] for p in points}
    names: list[str] = []
    centres: list[Vector] = []
    for k, lk in enumerate(case.get("links", [])):
        _check_keys(case, f"links[{k}]", lk, {"name", "points"})
        name = lk.get("name")
        if not isinstance(name, str) or not IDENTIFIER.match(name) or name in link_index:
            raise _fail(case, f"links[{k}].name", f"bad or repeated link name {name!r}")
        carried = lk.get("points", [])
        if not carried:
            raise _fail(case, f"links.{name}.points", "a link carries no point")
        for p in carried:
            if p not in points:
                raise _fail(case, f"links.{name}.points", f"unknown point {p!r}")
        index = GROUND if name == "ground" else len(names)
        link_index[name] = index
        for p in carried:
            carriers[p].append(index)
        if index != GROUND:
            names.append(name)
            centres.append(np.mean([points[p] for p in carried], axis=0))
    if "ground" not in link_index:
        raise _fail(case, "links", "the link \"ground\" is missing")
    for p, links in carriers.items():
        if not links:
            raise _fail(case, f"points.{p}", "no link carries this point")
    return link_index, carriers, names, centres


def _read_joint(case: dict[str, Any], k: int, jt: dict[str, Any], points: dict[str, Vector],
                link_index: dict[str, int], carriers: dict[str, list[int]],
                centres: list[Vector]) -> Joint:
    """One joint, with its point fixed to both links (prismatic: the coincident point on a)."""
    _check_keys(case, f"joints[{k}]", jt, {"name", "kind", "links", "at", "axis"})
    name = jt.get("name")
    if not isinstance(name, str) or not IDENTIFIER.match(name):
        raise _fail(case, f"joints[{k}].name", f"bad joint name {name!r}")
    key = f"joints.{name}"
    pair = jt.get("links")
    if not isinstance(pair, list) or len(pair) != 2 or any(x not in link_index for x in pair):
        raise _fail(case, f"{key}.links", f"expected two known links, got {pair!r}")
    a, b = link_index[pair[0]], link_index[pair[1]]
    if a == b:
        raise _fail(case, f"{key}.links", "a joint joins two different links")
    at = jt.get("at")
    if at not in points:
        raise _fail(case, f"{key}.at", f"unknown point {at!r}")
    kind = jt.get("kind")
    axis = np.zeros(2)
    if kind == "revolute":
        if a not in carriers[at] or b not in carriers[at]:
            raise _fail(case, f"{key}.at", "both links of a revolute joint must carry its point")
        if "axis" in jt:
            raise _fail(case, f"{key}.axis", "a revolute joint has no axis")
    elif kind in ("prismatic", "pin_in_slot"):
        if b not in carriers[at]:
            raise _fail(case, f"{key}.at", f"links[1] of a {kind} joint must carry its point")
        axis = _pair(case, f"{key}.axis", jt.get("axis"))
        if np.linalg.norm(axis) == 0.0:
            raise _fail(case, f"{key}.axis", "zero axis")
        axis = axis / np.linalg.norm(axis)
    else:
        raise _fail(case, f"{key}.kind", f"expected revolute, prismatic or pin_in_slot, got {kind!r}")

    def fixed_to(link: int) -> Attachment:
        return Attachment(link, points[at] if link == GROUND else points[at] - centres[link])

    return Joint(name, kind, a, b, at, fixed_to(a), fixed_to(b), axis)


def _check_shared_points(case: dict[str, Any], carriers: dict[str, list[int]],
                         joints: list[Joint], link_index: dict[str, int]) -> None:
    """Links carrying one point must be connected through revolute joints at that point."""
    names = {v: k for k, v in link_index.items()}
    for p, links in carriers.items():
        if len(links) < 2:
            continue
        reached = {links[0]}
        grew = True
        while grew:
            grew = False
            for j in joints:
                if j.kind == "revolute" and j.at == p and ((j.a in reached) != (j.b in reached)):
                    reached |= {j.a, j.b}
                    grew = True
        missing = [names[x] for x in links if x not in reached]
        if missing:
            raise _fail(case, f"points.{p}", f"links {missing} carry it but are not joined there")


def _check_connected(case: dict[str, Any], joints: list[Joint], moving: int) -> None:
    reached = {GROUND}
    grew = True
    while grew:
        grew = False
        for j in joints:
            if (j.a in reached) != (j.b in reached):
                reached |= {j.a, j.b}
                grew = True
    if len(reached) != moving + 1:
        raise _fail(case, "joints", "the linkage is disconnected")


def _read_drivers(case: dict[str, Any], joints: list[Joint], joint_index: dict[str, int],
                  unit: float) -> list[Driver]:
    drivers: list[Driver] = []
    for k, d in enumerate(case.get("drivers", [])):
        _check_keys(case, f"drivers[{k}]", d, {"joint", "rotation", "displacement", "velocity",
                                               "acceleration", "sense"})
        name = d.get("joint")
        if name not in joint_index:
            raise _fail(case, f"drivers[{k}].joint", f"unknown joint {name!r}")
        joint = joint_index[name]
        if any(x.joint == joint for x in drivers):
            raise _fail(case, f"drivers.{name}", "a joint is driven at most once")
        key = "rotation" if joints[joint].kind == "revolute" else "displacement"
        if key not in d:
            raise _fail(case, f"drivers.{name}.{key}", "missing")
        value = _number(case, f"drivers.{name}.{key}", d[key])
        value = math.radians(value) if key == "rotation" else unit * value
        velocity = _number(case, f"drivers.{name}.velocity", d.get("velocity", 0.0))
        acceleration = _number(case, f"drivers.{name}.acceleration", d.get("acceleration", 0.0))
        sense_word = d.get("sense")
        sense = {None: 0.0, "increasing": 1.0, "decreasing": -1.0}.get(sense_word)
        if sense is None:
            raise _fail(case, f"drivers.{name}.sense", "expected increasing or decreasing")
        if sense and velocity and sense != sign(velocity):
            raise _fail(case, f"drivers.{name}.sense", "disagrees with the velocity")
        drivers.append(Driver(joint, value, velocity, acceleration, sense))
    return drivers


def _force(case: dict[str, Any], key: str, f: Any) -> Vector:
    if not isinstance(f, dict):
        raise _fail(case, key, "expected { magnitude, angle } or { x, y }")
    if set(f) == {"magnitude", "angle"}:
        a = math.radians(_number(case, key, f["angle"]))
        return _number(case, key, f["magnitude"]) * np.array([math.cos(a), math.sin(a)])
    if set(f) == {"x", "y"}:
        return np.array([_number(case, key, f["x"]), _number(case, key, f["y"])])
    raise _fail(case, key, "expected { magnitude, angle } or { x, y }")


def _read_load(case: dict[str, Any], k: int, ld: dict[str, Any], attach: Any) -> Load:
    key = f"loads[{k}]"
    _check_keys(case, key, ld, {"link", "at", "force", "torque"})
    if "force" not in ld and "torque" not in ld:
        raise _fail(case, key, "a load has a force, a torque or both")
    if "force" in ld and "at" not in ld:
        raise _fail(case, f"{key}.at", "a force needs its point")
    at = attach(key, ld.get("link"), ld.get("at", [0.0, 0.0]))
    force = _force(case, f"{key}.force", ld["force"]) if "force" in ld else np.zeros(2)
    return Load(at, force, _number(case, f"{key}.torque", ld.get("torque", 0.0)))


def _read_mass(case: dict[str, Any], k: int, m: dict[str, Any], attach: Any) -> Mass:
    key = f"masses[{k}]"
    _check_keys(case, key, m, {"link", "mass", "com", "inertia"})
    mass = _number(case, f"{key}.mass", m.get("mass"))
    inertia = _number(case, f"{key}.inertia", m.get("inertia", 0.0))
    if mass < 0.0 or inertia < 0.0:
        raise _fail(case, key, "mass and inertia must not be negative")
    return Mass(attach(f"{key}.com", m.get("link"), m.get("com")), mass, inertia)


def _read_springs(case: dict[str, Any], joints: list[Joint], joint_index: dict[str, int],
                  attach: Any, unit: float) -> tuple[list[LinearSpring], list[TorsionalSpring]]:
    linear: list[LinearSpring] = []
    torsion: list[TorsionalSpring] = []
    seen: set[str] = set()
    for k, sp in enumerate(case.get("springs", [])):
        name = sp.get("name")
        if not isinstance(name, str) or not IDENTIFIER.match(name) or name in seen:
            raise _fail(case, f"springs[{k}].name", f"bad or repeated spring name {name!r}")
        seen.add(name)
        key = f"springs.{name}"
        stiffness = _number(case, f"{key}.stiffness", sp.get("stiffness"))
        damping = _number(case, f"{key}.damping", sp.get("damping", 0.0))
        if "ends" in sp:
            _check_keys(case, key, sp, {"name", "ends", "stiffness", "free_length", "damping"})
            ends = sp["ends"]
            if not isinstance(ends, list) or len(ends) != 2:
                raise _fail(case, f"{key}.ends", "expected two [link, point] ends")
            e0, e1 = (attach(f"{key}.ends", e[0], e[1]) for e in ends)
            if e0.link == e1.link:
                raise _fail(case, f"{key}.ends", "a spring between two points of one link")
            free = unit * _number(case, f"{key}.free_length", sp.get("free_length"))
            linear.append(LinearSpring(name, (e0, e1), stiffness, free, damping))
        else:
            _check_keys(case, key, sp, {"name", "joint", "stiffness", "free_rotation", "damping"})
            joint = joint_index.get(sp.get("joint"), -1)
            if joint < 0 or joints[joint].kind != "revolute":
                raise _fail(case, f"{key}.joint", "a torsional spring needs a revolute joint")
            q0 = math.radians(_number(case, f"{key}.free_rotation", sp.get("free_rotation", 0.0)))
            torsion.append(TorsionalSpring(name, joint, stiffness, q0, damping))
    return linear, torsion


def _read_friction(case: dict[str, Any], joints: list[Joint], joint_index: dict[str, int],
                   unit: float) -> list[JointFriction]:
    """Per joint: μ·r (revolute with a pin radius), μ (every prismatic joint), viscous c."""
    f = case.get("friction")
    if f is None:
        return [JointFriction(0.0, 0.0) for _ in joints]
    _check_keys(case, "friction", f, {"mu", "pin_radius", "joint_mu", "viscous"})
    for table in ("pin_radius", "joint_mu", "viscous"):
        for name in f.get(table, {}):
            if name not in joint_index:
                raise _fail(case, f"friction.{table}.{name}", "unknown joint")
    for name in f.get("pin_radius", {}):
        if joints[joint_index[name]].kind != "revolute":
            raise _fail(case, f"friction.pin_radius.{name}", "a pin radius needs a revolute joint")
    mu = _number(case, "friction.mu", f.get("mu", 0.0))
    out = []
    for j in joints:
        mu_j = _number(case, f"friction.joint_mu.{j.name}", f.get("joint_mu", {}).get(j.name, mu))
        visc = _number(case, f"friction.viscous.{j.name}", f.get("viscous", {}).get(j.name, 0.0))
        if j.kind == "revolute":
            radius = unit * _number(case, f"friction.pin_radius.{j.name}",
                                    f.get("pin_radius", {}).get(j.name, 0.0))
            out.append(JointFriction(mu_j * radius, visc))
        else:
            out.append(JointFriction(mu_j, visc))
    return out


# -- points and joint coordinates -------------------------------------------------------
def link_position(q: Vector, link: int) -> tuple[Vector, float]:
    """Reference point r and rotation φ of a link (the ground: origin, 0)."""
    if link == GROUND:
        return np.zeros(2), 0.0
    return q[3 * link:3 * link + 2], float(q[3 * link + 2])


def link_rate(qd: Vector, link: int) -> tuple[Vector, float]:
    """ṙ and φ̇ of a link (the ground: 0, 0)."""
    return link_position(qd, link)


def point(q: Vector, at: Attachment) -> Vector:
    """Global position of a point fixed to a link."""
    r, phi = link_position(q, at.link)
    return np.asarray(r + rot(phi) @ at.local)


def point_velocity(q: Vector, qd: Vector, at: Attachment) -> Vector:
    """ṗ = ṙ + φ̇ k × A s."""
    _, phi = link_position(q, at.link)
    rd, w = link_rate(qd, at.link)
    return np.asarray(rd + w * perp(rot(phi) @ at.local))


def point_jacobian(lk: Linkage, q: Vector, at: Attachment) -> Matrix:
    """∂p/∂q (2 × n): [I, k × A s] in the columns of the point's link."""
    out = np.zeros((2, lk.n))
    if at.link != GROUND:
        c = 3 * at.link
        out[:, c:c + 2] = np.eye(2)
        out[:, c + 2] = perp(rot(float(q[c + 2])) @ at.local)
    return out


def point_quadratic(q: Vector, qd: Vector, at: Attachment) -> Vector:
    """The velocity-squared part of p̈: −φ̇² A s (centripetal)."""
    _, phi = link_position(q, at.link)
    _, w = link_rate(qd, at.link)
    return np.asarray(-(w**2) * (rot(phi) @ at.local))


def slide_frame(q: Vector, joint: Joint) -> tuple[Vector, Vector, Vector]:
    """Axis u and normal n of a prismatic joint (carried by links[0]) and d = p_b − p_a."""
    _, phi_a = link_position(q, joint.a)
    u = rot(phi_a) @ joint.axis
    return u, perp(u), point(q, joint.on_b) - point(q, joint.on_a)


def joint_coordinate(q: Vector, joint: Joint) -> float:
    """Revolute: φ_b − φ_a (unwrapped). Prismatic: u·(p_b − p_a), `at` along the axis."""
    if joint.kind == "revolute":
        return link_position(q, joint.b)[1] - link_position(q, joint.a)[1]
    u, _, d = slide_frame(q, joint)
    return float(u @ d)


def joint_coordinate_row(lk: Linkage, q: Vector, joint: Joint) -> Vector:
    """∂q_joint/∂q. Prismatic: u·(P_b − P_a) + (n·d) e_φa, since ∂u/∂φ_a = n."""
    row = np.zeros(lk.n)
    if joint.kind == "revolute":
        if joint.b != GROUND:
            row[3 * joint.b + 2] += 1.0
        if joint.a != GROUND:
            row[3 * joint.a + 2] -= 1.0
        return row
    u, n, d = slide_frame(q, joint)
    row += u @ (point_jacobian(lk, q, joint.on_b) - point_jacobian(lk, q, joint.on_a))
    if joint.a != GROUND:
        row[3 * joint.a + 2] += n @ d
    return row


def joint_rate(lk: Linkage, q: Vector, qd: Vector, joint: Joint) -> float:
    """q̇ of a joint: relative angular velocity, or the sliding speed along the axis."""
    return float(joint_coordinate_row(lk, q, joint) @ qd)


# -- constraints Φ(q, s), Φ_q and γ ---------------------------------------------------
def joint_offsets(lk: Linkage) -> list[int]:
    """The first constraint row of each joint (joints have 1 or 2 rows)."""
    starts, row = [], 0
    for j in lk.joints:
        starts.append(row)
        row += j.rows
    return starts


def joint_row_count(lk: Linkage) -> int:
    """Rows of all joints: the drivers' rows follow them."""
    return sum(j.rows for j in lk.joints)


def constraint_count(lk: Linkage) -> int:
    return joint_row_count(lk) + len(lk.drivers)


def constraints(lk: Linkage, q: Vector, s: float) -> Vector:
    """Φ: per joint its rows "links[0] minus links[1]", then per driver s·value − q_joint."""
    out = np.zeros(constraint_count(lk))
    for r, j in zip(joint_offsets(lk), lk.joints, strict=True):
        if j.kind == "revolute":
            out[r:r + 2] = point(q, j.on_a) - point(q, j.on_b)
            continue
        _, n, d = slide_frame(q, j)
        out[r] = -(n @ d)
        if j.kind == "prismatic":  # a pin in a slot turns freely: no second row
            out[r + 1] = link_position(q, j.a)[1] - link_position(q, j.b)[1]
    base = joint_row_count(lk)
    for k, drv in enumerate(lk.drivers):
        out[base + k] = s * drv.value - joint_coordinate(q, lk.joints[drv.joint])
    return out


def jacobian(lk: Linkage, q: Vector) -> Matrix:
    """Φ_q. Prismatic normal row: −n·(P_b − P_a) + (u·d) e_φa, since ∂n/∂φ_a = −u."""
    jac = np.zeros((constraint_count(lk), lk.n))
    for r, j in zip(joint_offsets(lk), lk.joints, strict=True):
        pa, pb = point_jacobian(lk, q, j.on_a), point_jacobian(lk, q, j.on_b)
        if j.kind == "revolute":
            jac[r:r + 2] = pa - pb
            continue
        u, n, d = slide_frame(q, j)
        jac[r] = -(n @ (pb - pa))
        if j.a != GROUND:
            jac[r, 3 * j.a + 2] += u @ d
        if j.kind == "pin_in_slot":
            continue
        if j.a != GROUND:
            jac[r + 1, 3 * j.a + 2] = 1.0
        if j.b != GROUND:
            jac[r + 1, 3 * j.b + 2] = -1.0
    base = joint_row_count(lk)
    for k, drv in enumerate(lk.drivers):
        jac[base + k] = -joint_coordinate_row(lk, q, lk.joints[drv.joint])
    return jac


def driver_column(lk: Linkage) -> Vector:
    """Φ_s: only driver rows depend on the path parameter s."""
    out = np.zeros(constraint_count(lk))
    out[joint_row_count(lk):] = [d.value for d in lk.drivers]
    return out


def gamma(lk: Linkage, q: Vector, qd: Vector) -> Vector:
    """γ of Φ_q q̈ = γ: minus the velocity-squared part of Φ̈, and −θ̈ for drivers.

    Prismatic, with d = p_b − p_a and ḋ its rate (u̇ = φ̇_a n, ṅ = −φ̇_a u):
    normal row γ = −φ̇_a²(n·d) − 2φ̇_a(u·ḋ) + n·(d̈ quadratic);
    driver row γ = −θ̈ − φ̇_a²(u·d) + 2φ̇_a(n·ḋ) + u·(d̈ quadratic).
    """
    out = np.zeros(constraint_count(lk))
    for r, j in zip(joint_offsets(lk), lk.joints, strict=True):
        quad_d = point_quadratic(q, qd, j.on_b) - point_quadratic(q, qd, j.on_a)
        if j.kind == "revolute":
            out[r:r + 2] = quad_d  # Φ = p_a − p_b: γ = −(quad_a − quad_b)
            continue
        u, n, d = slide_frame(q, j)
        d_dot = point_velocity(q, qd, j.on_b) - point_velocity(q, qd, j.on_a)
        w_a = link_rate(qd, j.a)[1]
        out[r] = -(w_a**2) * (n @ d) - 2.0 * w_a * (u @ d_dot) + n @ quad_d
    base = joint_row_count(lk)
    for k, drv in enumerate(lk.drivers):
        j = lk.joints[drv.joint]
        out[base + k] = -drv.acceleration
        if j.slides:
            quad_d = point_quadratic(q, qd, j.on_b) - point_quadratic(q, qd, j.on_a)
            u, n, d = slide_frame(q, j)
            d_dot = point_velocity(q, qd, j.on_b) - point_velocity(q, qd, j.on_a)
            w_a = link_rate(qd, j.a)[1]
            out[base + k] += -(w_a**2) * (u @ d) + 2.0 * w_a * (n @ d_dot) + u @ quad_d
    return out


def row_scale(lk: Linkage) -> Vector:
    """Divides rows of lengths by the drawing size so that Φ is dimensionless."""
    rows = np.ones(constraint_count(lk))
    for r, j in zip(joint_offsets(lk), lk.joints, strict=True):
        rows[r] = 1.0 / lk.size
        if j.kind == "revolute":
            rows[r + 1] = 1.0 / lk.size
    base = joint_row_count(lk)
    for k, drv in enumerate(lk.drivers):
        if lk.joints[drv.joint].slides:
            rows[base + k] = 1.0 / lk.size
    return rows


def scaled_jacobian(lk: Linkage, q: Vector, rows: Vector) -> Matrix:
    """Φ_q in dimensionless rows and columns (rows selects the rows kept)."""
    jac = jacobian(lk, q) * row_scale(lk)[:, None] * lk.column_scale()[None, :]
    return np.asarray(jac[rows.astype(bool)])


def condition(matrix: Matrix) -> float:
    sv = np.linalg.svd(matrix, compute_uv=False)
    return math.inf if sv.size == 0 or sv[-1] == 0.0 else float(sv[0] / sv[-1])


# -- mobility ---------------------------------------------------------------------------
@dataclass
class Mobility:
    """Degrees of freedom at the drawn pose and the independent joint rows."""

    gruebler: int
    dof: int
    rank: int
    redundant_joints: list[str]
    keep: Vector  # 1 for each constraint row used by the solver, 0 for a redundant one


def mobility(lk: Linkage) -> Mobility:
    """Gruebler 3(n − 1) − Σ(3 − Sᵢ) (a row per constraint: 2 for R and P, 1 for a pin in a
    slot); DOF 3(n − 1) − rank J of the joint rows at the drawn pose.

    The joints of a redundancy are those with weight in a left null vector of J. The
    solver drops dependent rows, chosen greedily in file order, to keep a full-rank set.
    """
    q0 = drawn_pose(lk)
    nj = joint_row_count(lk)
    full = jacobian(lk, q0) * row_scale(lk)[:, None] * lk.column_scale()[None, :]
    joint_rows = full[:nj]
    u, sv, _ = np.linalg.svd(joint_rows) if nj else (np.zeros((0, 0)), np.zeros(0), None)
    tol = RANK_RTOL * (sv[0] if sv.size else 1.0)
    rank = int(np.sum(sv > tol))
    redundant: list[str] = []
    for vec in u[:, rank:].T if nj else []:
        for r, j in zip(joint_offsets(lk), lk.joints, strict=True):
            if np.max(np.abs(vec[r:r + j.rows])) > 1e-6 and j.name not in redundant:
                redundant.append(j.name)
    keep = np.ones(constraint_count(lk))
    chosen: list[Vector] = []
    for r in range(nj):
        trial = np.array([*chosen, joint_rows[r]])
        if np.linalg.matrix_rank(trial, tol=tol) == len(trial):
            chosen.append(joint_rows[r])
        else:
            keep[r] = 0.0
    return Mobility(lk.n - nj, lk.n - rank, rank, redundant, keep)


def drawn_pose(lk: Linkage) -> Vector:
    """q at the drawn pose: every link at its reference point, unrotated."""
    q = np.zeros(lk.n)
    for i, c in enumerate(lk.centres):
        q[3 * i:3 * i + 2] = c
    return q


# -- positions: continuation from the drawn pose ---------------------------------------
@dataclass
class Path:
    """The end of the walk along s: the pose at s = 1, or where and why it stopped."""

    status: str  # ok | no_solution | singular
    q: Vector
    s: float
    steps: int
    message: str = ""


def _path_system(lk: Linkage, rows: Vector, w: Vector, span: float
                 ) -> tuple[Vector, Matrix, Vector]:
    """F(w) and [F_q, F_s] in scaled variables w = (q / column scale, s·span)."""
    cols = lk.column_scale()
    q = w[:-1] * cols
    s = w[-1] / span
    keep = rows.astype(bool)
    rs = row_scale(lk)[keep]
    f = constraints(lk, q, s)[keep] * rs
    jq = jacobian(lk, q)[keep] * rs[:, None] * cols[None, :]
    js = (driver_column(lk)[keep] * rs / span)[:, None]
    return f, np.hstack([jq, js]), q


def _tangent(jac: Matrix, previous: Vector) -> Vector:
    """Unit tangent of the path: the null vector of [F_q, F_s], turned like ``previous``."""
    t = np.linalg.solve(np.vstack([jac, previous]), np.r_[np.zeros(jac.shape[0]), 1.0])
    return np.asarray(t / np.linalg.norm(t))


def _correct(lk: Linkage, rows: Vector, w_pred: Vector, t: Vector, span: float
             ) -> tuple[Vector, int]:
    """Newton back onto the path within the hyperplane through w_pred normal to t.

    Returns the point and the iterations it took, or −1 if Newton did not converge.
    """
    w = w_pred.copy()
    for it in range(1, 16):
        f, jac, _ = _path_system(lk, rows, w, span)
        try:
            step = np.linalg.solve(np.vstack([jac, t]), np.r_[f, t @ (w - w_pred)])
        except np.linalg.LinAlgError:
            return w, -1
        w = w - step
        if np.max(np.abs(step)) < NEWTON_TOL * 1e3:  # then one more, to the rounding floor
            f, jac, _ = _path_system(lk, rows, w, span)
            w = w - np.linalg.solve(np.vstack([jac, t]), np.r_[f, t @ (w - w_pred)])
            return w, it
    return w, -1


def _bordered_sign(lk: Linkage, rows: Vector, w: Vector, t: Vector, span: float) -> float:
    """Sign of det [F_w; tᵀ]: it flips where the path crosses another branch."""
    _, jac, _ = _path_system(lk, rows, w, span)
    return float(np.linalg.slogdet(np.vstack([jac, t]))[0])


def _bisect_along(lk: Linkage, rows: Vector, w: Vector, t: Vector, h: float, span: float,
                  before: Any) -> Vector:
    """The last point between w and w + h·t (corrected onto the path) for which
    ``before(point, tangent)`` still holds, by bisection on the arclength to 1e-9."""
    lo, hi = 0.0, h
    best = w
    while hi - lo > 1e-9:
        mid = 0.5 * (lo + hi)
        wm, iterations = _correct(lk, rows, w + mid * t, t, span)
        if iterations < 0:
            hi = mid
            continue
        _, jac, _ = _path_system(lk, rows, wm, span)
        if before(wm, _tangent(jac, t)):
            lo, best = mid, wm
        else:
            hi = mid
    return best


def _locate_fold(lk: Linkage, rows: Vector, w: Vector, t: Vector, h: float, span: float
                 ) -> Vector:
    """The turning point of s between w and w + h·t, where the tangent's s-component
    changes sign. Near a fold s is quadratic in arclength, so an arclength error δ
    gives s to about δ²."""
    return _bisect_along(lk, rows, w, t, h, span, lambda wm, tm: tm[-1] > 0.0)


def _locate_branch_point(lk: Linkage, rows: Vector, w: Vector, t: Vector, h: float,
                         span: float, orientation: float) -> Vector:
    """The singular pose between w and w + h·t where the bordered determinant changes sign."""
    return _bisect_along(lk, rows, w, t, h, span,
                         lambda wm, tm: _bordered_sign(lk, rows, wm, tm, span) == orientation)


def trace_drivers(lk: Linkage, rows: Vector) -> Path:
    """The pose reached continuously from the drawn pose as all drivers go from 0 to
    their values together (s from 0 to 1), by pseudo-arclength continuation.

    The arclength is measured in radians and in lengths over the drawing size; s is
    scaled by the largest driver travel so that one unit of w_s is one such unit.
    """
    q0 = drawn_pose(lk)
    travel = [abs(d.value) / (lk.size if lk.joints[d.joint].slides else 1.0)
              for d in lk.drivers]
    span = max(travel, default=0.0)
    if span == 0.0:
        return Path("ok", q0, 1.0, 0)
    w = np.r_[q0 / lk.column_scale(), 0.0]
    _, jac, _ = _path_system(lk, rows, w, span)
    t = np.linalg.svd(jac)[2][-1]  # the null vector of [F_q, F_s], by SVD: robust at s = 0
    t = t if t[-1] >= 0.0 else -t
    if t[-1] <= RANK_RTOL:
        return Path("singular", q0, 0.0, 0, "the drawn pose is a dead point of the drivers")
    orientation = _bordered_sign(lk, rows, w, t, span)
    h = FIRST_STEP
    steps = 0
    while True:
        w_new, iterations = _correct(lk, rows, w + h * t, t, span)
        ok = 0 <= iterations <= 6  # more means the step was too long for the curvature
        t_new = t
        if ok:
            _, jac, _ = _path_system(lk, rows, w_new, span)
            t_new = _tangent(jac, t)
            ok = bool(t @ t_new > math.cos(LARGEST_TURN) and np.linalg.norm(w_new - w) < 2 * h)
        if not ok:
            h *= 0.5
            if h < SMALLEST_STEP:
                return Path("singular", w[:-1] * lk.column_scale(), w[-1] / span, steps,
                            "the path from the drawn pose cannot be followed")
            continue
        steps += 1
        if steps > MAX_PATH_STEPS:
            return Path("singular", w_new[:-1] * lk.column_scale(), w_new[-1] / span, steps,
                        "the path from the drawn pose does not reach the drivers' values")
        if t_new[-1] <= 0.0:  # s turns back: the linkage locks here, unless s = 1 comes first
            fold = _locate_fold(lk, rows, w, t, h, span)
            s_lock = fold[-1] / span
            if s_lock < 1.0:
                return Path("no_solution", fold[:-1] * lk.column_scale(), s_lock, steps,
                            lock_message(lk, s_lock))
            return Path("ok", _finish_at_end(lk, rows, w, fold, span), 1.0, steps)
        if _bordered_sign(lk, rows, w_new, t_new, span) != orientation:
            branch = _locate_branch_point(lk, rows, w, t, h, span, orientation)
            s_branch = branch[-1] / span
            if s_branch >= 1.0:
                return Path("ok", _finish_at_end(lk, rows, w, branch, span), 1.0, steps)
            return Path("singular", branch[:-1] * lk.column_scale(), s_branch, steps,
                        "passes a singular pose at " + driver_values_text(lk, s_branch))
        if w_new[-1] >= span:
            q = _finish_at_end(lk, rows, w, w_new, span)
            return Path("ok", q, 1.0, steps)
        w, t = w_new, t_new
        h = min(LARGEST_STEP, 1.5 * h)


def _finish_at_end(lk: Linkage, rows: Vector, w: Vector, w_new: Vector, span: float) -> Vector:
    """Newton on Φ(q, 1) = 0 from the point interpolated between the last two at s = 1."""
    frac = (span - w[-1]) / (w_new[-1] - w[-1])
    x = w + frac * (w_new - w)
    x[-1] = span
    e_s = np.r_[np.zeros(lk.n), 1.0]
    for _ in range(NEWTON_MAX_ITERATIONS):
        f, jac, _ = _path_system(lk, rows, x, span)
        step = np.linalg.solve(np.vstack([jac, e_s]), np.r_[f, 0.0])
        x = x - step
        if np.max(np.abs(step)) < NEWTON_TOL:
            break
    f, jac, _ = _path_system(lk, rows, x, span)
    x = x - np.linalg.solve(np.vstack([jac, e_s]), np.r_[f, 0.0])
    return np.asarray(x[:-1] * lk.column_scale())


def driver_values_text(lk: Linkage, s: float) -> str:
    """"rotation 97.26° of O2", in the file's units, for every driver at path parameter s."""
    parts = []
    for d in lk.drivers:
        j = lk.joints[d.joint]
        if j.kind == "revolute":
            parts.append(f"rotation {math.degrees(s * d.value):.6g}° of {j.name}")
        else:
            unit = "mm" if lk.length_unit == 1e-3 else "m"
            parts.append(f"displacement {s * d.value / lk.length_unit:.6g} {unit} of {j.name}")
    return ", ".join(parts)


def lock_message(lk: Linkage, s: float) -> str:
    """"locks at rotation 97.26° of O2" (LINKAGES.md's example of the verdict's message)."""
    return "locks at " + driver_values_text(lk, s)


# -- kinematics -------------------------------------------------------------------------
def velocities(lk: Linkage, q: Vector, rows: Vector, rates: Vector) -> Vector:
    """q̇ from Φ_q q̇ = −Φ_t; only the drivers depend on time, Φ_t = θ̇."""
    keep = rows.astype(bool)
    rhs = np.zeros(constraint_count(lk))
    rhs[joint_row_count(lk):] = -rates
    return np.asarray(np.linalg.solve(jacobian(lk, q)[keep], rhs[keep]))


def accelerations(lk: Linkage, q: Vector, qd: Vector, rows: Vector) -> Vector:
    """q̈ from Φ_q q̈ = γ."""
    keep = rows.astype(bool)
    return np.asarray(np.linalg.solve(jacobian(lk, q)[keep], gamma(lk, q, qd)[keep]))


# -- generalized forces -----------------------------------------------------------------
def add_force(out: Vector, q: Vector, link: int, where: Vector, force: Vector) -> None:
    """Adds a force acting at the global point ``where`` on ``link``: (F, (p − r) × F)."""
    if link == GROUND:
        return
    r, _ = link_position(q, link)
    out[3 * link:3 * link + 2] += force
    out[3 * link + 2] += cross2(where - r, force)


def add_couple(out: Vector, link: int, moment: float) -> None:
    if link != GROUND:
        out[3 * link + 2] += moment


def spring_values(lk: Linkage, q: Vector, qd: Vector) -> dict[str, float]:
    """S of every spring: k(L − L0) + c·L̇ (linear), k(q − q0) + c·q̇ (torsional)."""
    out = {}
    for sp in lk.springs:
        p0, p1 = point(q, sp.ends[0]), point(q, sp.ends[1])
        length = float(np.linalg.norm(p1 - p0))
        e = (p1 - p0) / length
        rate = float(e @ (point_velocity(q, qd, sp.ends[1]) - point_velocity(q, qd, sp.ends[0])))
        out[sp.name] = sp.stiffness * (length - sp.free_length) + sp.damping * rate
    for ts in lk.torsion:
        j = lk.joints[ts.joint]
        out[ts.name] = (ts.stiffness * (joint_coordinate(q, j) - ts.free_rotation)
                        + ts.damping * joint_rate(lk, q, qd, j))
    return out


def applied_forces(lk: Linkage, q: Vector, qd: Vector) -> Vector:
    """Q of loads, weights, springs and viscous joint friction at (q, q̇)."""
    out = np.zeros(lk.n)
    for ld in lk.loads:
        add_force(out, q, ld.at.link, point(q, ld.at), ld.force)
        add_couple(out, ld.at.link, ld.torque)
    for m in lk.masses:
        add_force(out, q, m.com.link, point(q, m.com), m.mass * lk.gravity)
    tension = spring_values(lk, q, qd)
    for sp in lk.springs:
        p0, p1 = point(q, sp.ends[0]), point(q, sp.ends[1])
        e = (p1 - p0) / np.linalg.norm(p1 - p0)
        add_force(out, q, sp.ends[0].link, p0, tension[sp.name] * e)  # tension pulls the
        add_force(out, q, sp.ends[1].link, p1, -tension[sp.name] * e)  # ends together
    for ts in lk.torsion:
        j = lk.joints[ts.joint]
        add_couple(out, j.b, -tension[ts.name])
        add_couple(out, j.a, tension[ts.name])
    for j, fr in zip(lk.joints, lk.friction, strict=True):
        if fr.viscous:
            add_joint_action(out, q, j, -fr.viscous * joint_rate(lk, q, qd, j))
    return out


def add_joint_action(out: Vector, q: Vector, joint: Joint, amount: float) -> None:
    """Adds an action along a joint's freedom: on links[1] a couple (revolute) or a force
    along the axis through `at` (prismatic), and the opposite on links[0]."""
    if joint.kind == "revolute":
        add_couple(out, joint.b, amount)
        add_couple(out, joint.a, -amount)
        return
    u, _, _ = slide_frame(q, joint)
    where = point(q, joint.on_b)
    add_force(out, q, joint.b, where, amount * u)
    add_force(out, q, joint.a, where, -amount * u)


def inertia_forces(lk: Linkage, q: Vector, qd: Vector, qdd: Vector) -> Vector:
    """E: m·a_G and I_G·φ̈ + (r_G − r) × m·a_G per link (Newton–Euler about r)."""
    out = np.zeros(lk.n)
    for m in lk.masses:
        if m.com.link == GROUND:
            continue
        c = 3 * m.com.link
        rc = rot(float(q[c + 2])) @ m.com.local
        a_g = qdd[c:c + 2] + perp(rc) * qdd[c + 2] - rc * qd[c + 2] ** 2
        out[c:c + 2] += m.mass * a_g
        out[c + 2] += m.inertia * qdd[c + 2] + cross2(rc, m.mass * a_g)
    return out


def coulomb_forces(lk: Linkage, q: Vector, lam: Vector, senses: Vector) -> tuple[Vector, Matrix]:
    """Q of Coulomb friction for multipliers λ, and ∂Q/∂λ.

    Revolute: the couple −μr|F|·sense on links[1] (friction circle). Prismatic: the force
    −μ|N|·sense along the axis through `at` on links[1]. links[0] gets the opposite.
    """
    out = np.zeros(lk.n)
    d_out = np.zeros((lk.n, lam.size))
    offsets = joint_offsets(lk)
    for k, (j, fr) in enumerate(zip(lk.joints, lk.friction, strict=True)):
        if fr.coulomb == 0.0 or senses[k] == 0.0:
            continue
        unit = np.zeros(lk.n)
        add_joint_action(unit, q, j, -fr.coulomb * senses[k])
        r = offsets[k]
        if j.kind == "revolute":
            f = lam[r:r + 2]
            mag = float(np.hypot(*f))
            out += unit * mag
            if mag > 0.0:
                d_out[:, r:r + 2] += np.outer(unit, f / mag)
        else:
            out += unit * abs(float(lam[r]))
            d_out[:, r] += unit * sign(float(lam[r]))
    return out, d_out


def coulomb_senses(lk: Linkage, q: Vector, rows: Vector) -> tuple[Vector, float]:
    """sign of each joint's relative motion, from the drivers' velocities (a resting
    driver moves at ±1 unit/s in its `sense`), and the smallest |speed| of a joint with
    Coulomb friction over the largest joint speed (0: a Coulomb term reverses here)."""
    rates = np.array([d.velocity if d.velocity else d.sense for d in lk.drivers])
    qd = velocities(lk, q, rows, rates)
    speeds = np.array([joint_rate(lk, q, qd, j) * (1.0 if j.kind == "revolute" else 1 / lk.size)
                       for j in lk.joints])
    scale = float(np.max(np.abs(speeds), initial=0.0))
    senses = np.zeros(len(lk.joints))
    smallest = math.inf
    for k, fr in enumerate(lk.friction):
        if fr.coulomb > 0.0:
            smallest = min(smallest, abs(speeds[k]) / scale if scale else 0.0)
            senses[k] = 0.0 if abs(speeds[k]) <= ZERO_SPEED_RTOL * scale else sign(speeds[k])
    return senses, smallest


def multipliers(lk: Linkage, q: Vector, qd: Vector, qdd: Vector, rows: Vector
                ) -> tuple[Vector, int]:
    """λ of Φ_qᵀλ = Q + Q_coulomb(λ) − E, with Newton on the Coulomb terms.

    Raises ArithmeticError when the friction equations do not converge (self-locking).
    """
    keep = rows.astype(bool)
    jt = jacobian(lk, q)[keep].T
    known = applied_forces(lk, q, qd) - inertia_forces(lk, q, qd, qdd)
    lam_kept = np.linalg.solve(jt, known)
    lam = np.zeros(constraint_count(lk))
    lam[keep] = lam_kept
    if not lk.has_coulomb:
        return lam, 0
    senses, _ = coulomb_senses(lk, q, rows)
    for it in range(1, NEWTON_MAX_ITERATIONS + 1):
        qc, dqc = coulomb_forces(lk, q, lam, senses)
        residual = jt @ lam[keep] - known - qc
        step = np.linalg.solve(jt - dqc[:, keep], residual)
        lam[keep] -= step
        if np.max(np.abs(step)) <= 1e-12 * max(float(np.max(np.abs(lam))), 1e-300):
            qc, dqc = coulomb_forces(lk, q, lam, senses)
            lam[keep] -= np.linalg.solve(jt - dqc[:, keep], jt @ lam[keep] - known - qc)
            return lam, it + 1
    raise ArithmeticError("the Coulomb friction equations did not converge")


# -- free coordinates: static equilibrium ----------------------------------------------
def _static_residual(lk: Linkage, rows: Vector, q: Vector, lam: Vector, s: float) -> Vector:
    """[Φ(q, s); Q(q) − Φ_qᵀλ] on the kept rows: constraints and equilibrium."""
    keep = rows.astype(bool)
    zero = np.zeros(lk.n)
    return np.asarray(np.r_[constraints(lk, q, s)[keep] * row_scale(lk)[keep],
                            applied_forces(lk, q, zero) - jacobian(lk, q)[keep].T @ lam])


def _force_stiffness(lk: Linkage, rows: Vector, q: Vector, lam: Vector) -> Matrix:
    """∂(Q − Φ_qᵀλ)/∂q by central differences (h² ≈ 1e-12 relative)."""
    keep = rows.astype(bool)
    zero = np.zeros(lk.n)
    cols = lk.column_scale()
    out = np.zeros((lk.n, lk.n))
    for c in range(lk.n):
        h = 1e-6 * cols[c]
        dq = np.zeros(lk.n)
        dq[c] = h
        plus = applied_forces(lk, q + dq, zero) - jacobian(lk, q + dq)[keep].T @ lam
        minus = applied_forces(lk, q - dq, zero) - jacobian(lk, q - dq)[keep].T @ lam
        out[:, c] = (plus - minus) / (2.0 * h)
    return out


def _equilibrium_newton(lk: Linkage, rows: Vector, q: Vector, lam: Vector, s: float
                        ) -> tuple[Vector, Vector, bool]:
    """Newton on the static residual in (q, λ); steps are capped at 0.25 rad or 0.25 of
    the drawing size so that it does not leap across the configuration space."""
    keep = rows.astype(bool)
    cols = lk.column_scale()
    m = int(keep.sum())
    for _ in range(NEWTON_MAX_ITERATIONS):
        res = _static_residual(lk, rows, q, lam, s)
        jac = np.zeros((m + lk.n, lk.n + m))
        jac[:m, :lk.n] = jacobian(lk, q)[keep] * row_scale(lk)[keep][:, None]
        jac[m:, :lk.n] = _force_stiffness(lk, rows, q, lam)
        jac[m:, lk.n:] = -jacobian(lk, q)[keep].T
        try:
            step = np.linalg.solve(jac, res)
        except np.linalg.LinAlgError:
            return q, lam, False
        size = float(np.max(np.abs(step[:lk.n] / cols)))
        if size > 0.25:
            step *= 0.25 / size
        q, lam = q - step[:lk.n], lam - step[lk.n:]
        lam_size = max(float(np.max(np.abs(lam), initial=0.0)), 1e-12)
        if size < 1e-12 and float(np.max(np.abs(step[lk.n:]), initial=0.0)) < 1e-10 * lam_size:
            return q, lam, True
    return q, lam, False


def free_equilibrium(lk: Linkage, rows: Vector) -> tuple[str, Vector, Vector, str, int]:
    """Static equilibrium with free coordinates, from the drawn pose, then the drivers
    moved to their values in steps (each step's equilibrium from the previous one).

    Returns (status, q, λ over all rows, message, steps).
    """
    keep = rows.astype(bool)
    q = drawn_pose(lk)
    lam, *_ = np.linalg.lstsq(jacobian(lk, q)[keep].T, applied_forces(lk, q, np.zeros(lk.n)),
                              rcond=None)
    travel = [abs(d.value) / (lk.size if lk.joints[d.joint].slides else 1.0)
              for d in lk.drivers]
    n_steps = max(1, math.ceil(max(travel, default=0.0) / 0.05))
    s, ds, steps = 0.0, 1.0 / n_steps, 0
    q, lam, ok = _equilibrium_newton(lk, rows, q, lam, 0.0)
    if not ok:
        return "singular", q, _full(lk, rows, lam), "no equilibrium found from the drawn pose", 0
    while s < 1.0:
        target = min(1.0, s + ds)
        q_new, lam_new, ok = _equilibrium_newton(lk, rows, q, lam, target)
        if not ok:
            ds *= 0.5
            if ds < 1e-9:
                return "no_solution", q, _full(lk, rows, lam), lock_message(lk, s), steps
            continue
        q, lam, s = q_new, lam_new, target
        steps += 1
    return "ok", q, _full(lk, rows, lam), "", steps


def _full(lk: Linkage, rows: Vector, lam_kept: Vector) -> Vector:
    lam = np.zeros(constraint_count(lk))
    lam[rows.astype(bool)] = lam_kept
    return lam


def reduced_stiffness(lk: Linkage, q: Vector, lam: Vector, rows: Vector) -> Matrix:
    """K_r = −Nᵀ ∂(Q − Φ_qᵀλ)/∂q N on the null space N of Φ_q (scaled coordinates):
    the Hessian of the potential energy along the free directions."""
    keep = rows.astype(bool)
    cols = lk.column_scale()
    jac = scaled_jacobian(lk, q, rows)
    _, sv, vt = np.linalg.svd(jac)
    rank = int(np.sum(sv > RANK_RTOL * (sv[0] if sv.size else 1.0)))
    basis = vt[rank:].T
    stiff = -_force_stiffness(lk, rows, q, lam[keep]) * cols[None, :] * cols[:, None]
    k_r = basis.T @ stiff @ basis
    return np.asarray(0.5 * (k_r + k_r.T))


# -- outputs ----------------------------------------------------------------------------
def position_values(lk: Linkage, q: Vector) -> dict[str, float]:
    """x_/y_ of every point, phi_ of every moving link and q_ of every joint (rad, m)."""
    out: dict[str, float] = {}
    for name, links in lk.carriers.items():
        link = links[0]
        local = lk.points[name] if link == GROUND else lk.points[name] - lk.centres[link]
        xy = point(q, Attachment(link, local))
        out[f"x_{name}"], out[f"y_{name}"] = float(xy[0]), float(xy[1])
    for i, name in enumerate(lk.link_names):
        out[f"phi_{name}"] = wrap(float(q[3 * i + 2]))
    for j in lk.joints:
        value = joint_coordinate(q, j)
        out[f"q_{j.name}"] = wrap(value) if j.kind == "revolute" else value
    return out


def force_values(lk: Linkage, q: Vector, qd: Vector, lam: Vector) -> dict[str, float]:
    """F_, M_ of every joint, Q_ of every driver and S_ of every spring.

    A prismatic reaction is N·n plus its friction along u (Coulomb and viscous) through
    `at`; its moment about `at` is M. The driver effort is not part of the reaction.
    """
    out: dict[str, float] = {}
    senses = np.zeros(len(lk.joints))
    if lk.has_coulomb:
        senses, _ = coulomb_senses(lk, q, np.ones(constraint_count(lk)))
    offsets = joint_offsets(lk)
    for k, (j, fr) in enumerate(zip(lk.joints, lk.friction, strict=True)):
        r = offsets[k]
        if j.kind == "revolute":
            out[f"F_{j.name}_x"], out[f"F_{j.name}_y"] = lam[r:r + 2]
            continue
        u, n, _ = slide_frame(q, j)
        along = (-fr.coulomb * senses[k] * abs(float(lam[r]))
                 - fr.viscous * joint_rate(lk, q, qd, j))
        out[f"F_{j.name}_x"], out[f"F_{j.name}_y"] = lam[r] * n + along * u
        if j.kind == "prismatic":  # a pin in a slot carries no couple
            out[f"M_{j.name}"] = float(lam[r + 1])
    base = joint_row_count(lk)
    for k, d in enumerate(lk.drivers):
        out[f"Q_{lk.joints[d.joint].name}"] = float(lam[base + k])
    for name, value in spring_values(lk, q, qd).items():
        out[f"S_{name}"] = value
    return {key: float(v) for key, v in out.items()}


@dataclass
class LinkageResult:
    """The reference's answer for one case.

    ``values`` holds the quantities of LINKAGES.md "What comes out" in SI with angles in
    radians (``phi_``, revolute ``q_`` wrapped to [−π, π)); ``q``, ``qd``, ``qdd`` are the
    maximal coordinates (unwrapped) and their rates.
    """

    status: str  # ok | no_solution | singular | indeterminate
    message: str
    values: dict[str, float]
    diagnostics: dict[str, Any]
    linkage: Linkage
    q: Vector | None = None
    qd: Vector | None = None
    qdd: Vector | None = None
    extra: dict[str, Any] = field(default_factory=dict)


def solve(case: dict[str, Any]) -> LinkageResult:
    """Pose, kinematics and every force of one linkage case (see the module docstring)."""
    lk = parse_case(case)
    mob = mobility(lk)
    diag: dict[str, Any] = {"dof": mob.dof, "gruebler": mob.gruebler,
                            "redundant_joints": mob.redundant_joints}
    n_drivers = len(lk.drivers)
    if mob.dof < n_drivers:
        raise _fail(case, "drivers", f"{n_drivers} drivers for {mob.dof} degrees of freedom")
    moving = any(d.velocity or d.acceleration for d in lk.drivers)
    if mob.dof > n_drivers:
        if moving:
            raise _fail(case, "drivers", "free coordinates with motion")
        if lk.has_coulomb:
            raise _fail(case, "friction", "free coordinates with Coulomb friction")
        return _solve_free(lk, mob, diag)
    return _solve_driven(lk, mob, diag)


def _solve_driven(lk: Linkage, mob: Mobility, diag: dict[str, Any]) -> LinkageResult:
    """DOF = drivers: continuation to the pose, then kinematics and multipliers."""
    rows = mob.keep
    try:
        path = trace_drivers(lk, rows)
    except np.linalg.LinAlgError:  # an exactly singular Jacobian met on the way
        path = Path("singular", drawn_pose(lk), 0.0, 0, "a singular pose on the path")
    diag["steps"] = path.steps
    if path.status != "ok":
        diag["s"] = float(path.s)
        where = "lock" if path.status == "no_solution" else "singular_at"
        diag[where] = {lk.joints[d.joint].name: float(path.s * d.value) for d in lk.drivers}
        return LinkageResult(path.status, path.message, position_values(lk, path.q), diag, lk,
                             path.q)
    q = path.q
    cond = condition(scaled_jacobian(lk, q, rows))
    diag["condition"] = cond
    values = position_values(lk, q)
    if cond > SINGULAR_CONDITION:
        return LinkageResult("singular", f"condition number {cond:.3g}", values, diag, lk, q)
    qd = velocities(lk, q, rows, np.array([d.velocity for d in lk.drivers]))
    qdd = accelerations(lk, q, qd, rows)
    if mob.redundant_joints:
        return LinkageResult("indeterminate",
                             f"redundant constraints at joints {mob.redundant_joints}",
                             values, diag, lk, q, qd, qdd)
    if lk.has_coulomb:
        _, smallest = coulomb_senses(lk, q, rows)
        diag["min_sense_speed"] = float(smallest)
        if smallest <= ZERO_SPEED_RTOL:
            return LinkageResult("indeterminate", "a Coulomb friction term reverses at this pose",
                                 values, diag, lk, q, qd, qdd)
    try:
        lam, iterations = multipliers(lk, q, qd, qdd, rows)
    except (ArithmeticError, np.linalg.LinAlgError):
        return LinkageResult("no_solution", "friction self-locks", values, diag, lk, q, qd, qdd)
    diag["friction_iterations"] = iterations
    values.update(force_values(lk, q, qd, lam))
    return LinkageResult("ok", "", values, diag, lk, q, qd, qdd, {"lambda": lam})


def _solve_free(lk: Linkage, mob: Mobility, diag: dict[str, Any]) -> LinkageResult:
    """DOF > drivers, static: the equilibrium pose of the free coordinates and its stability."""
    rows = mob.keep
    status, q, lam, message, steps = free_equilibrium(lk, rows)
    diag["steps"] = steps
    values = position_values(lk, q)
    zero = np.zeros(lk.n)
    if status != "ok":
        return LinkageResult(status, message, values, diag, lk, q)
    diag["condition"] = condition(scaled_jacobian(lk, q, rows))
    k_r = reduced_stiffness(lk, q, lam, rows)
    eig = np.linalg.eigvalsh(k_r)
    diag["stable"] = bool(eig.size and eig[0] > RANK_RTOL * max(abs(eig[-1]), 1e-300))
    # In an orthonormal basis of the free directions in scaled coordinates: only their
    # signs are meaningful (the sizes depend on the basis).
    diag["reduced_stiffness_eigenvalues"] = [float(e) for e in eig]
    if mob.redundant_joints:
        return LinkageResult("indeterminate",
                             f"redundant constraints at joints {mob.redundant_joints}",
                             values, diag, lk, q, zero, zero)
    values.update(force_values(lk, q, zero, lam))
    return LinkageResult("ok", "", values, diag, lk, q, zero, zero, {"lambda": lam})


def solve_file(path: str) -> dict[str, LinkageResult]:
    """Every case of a TOML file, by name."""
    import tomllib

    with open(path, "rb") as fh:
        cases = tomllib.load(fh)["case"]
    return {c["name"]: solve(c) for c in cases}
