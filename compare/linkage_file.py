"""``mechanism = "linkage"`` case tables (LINKAGES.md) → a validated
:class:`~mechcheck.analytic.linkage.Linkage`.

pydantic checks the structure (unknown and missing keys, types); the Linkage value checks
the rules of LINKAGES.md and the bounds of every number itself (with lengths quoted in
the file's unit). A sketch's points (``[[case.dimensions]]``) are first moved to meet its
dimensions (:mod:`mechcheck.analytic.sketch`). Lengths and points are converted from
``length_unit`` to metres and angles from degrees to radians here, at the border;
velocities and accelerations are already SI (rad/s, m/s).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Annotated, Any, Literal

from pydantic import Field

from mechcheck.analytic.case import MAX_OUTPUTS, CaseError, Simulation, Vec2
from mechcheck.analytic.joint_kinds import GEAR, GearMesh, JointKind, kind_named
from mechcheck.analytic.linkage import (
    Driver,
    Effort,
    Joint,
    JointFriction,
    LinearSpring,
    Link,
    Linkage,
    LinkMass,
    PointLoad,
    TorsionSpring,
)
from mechcheck.analytic.sketch import Dimension, assembled, refuse_too_large, refuse_unsketchable
from mechcheck.analytic.values import LENGTH_UNITS, MAX_TIME, finite, lengths_quoted_in
from mechcheck.specs import Pair, SeedSpec, Strict, ToleranceSpec, force_vector, needs_an_effect, validated

#: A point name or [x, y], checked by :func:`linkage_from_spec` (pydantic would name the
#: key of a bad pair after its union branch, ``at.str``).
PointRef = Any


class LinkSpec(Strict):
    name: str
    points: list[str]
    #: E·A (N) of a two-point member that stretches.
    axial_stiffness: float | None = None


class JointSpec(Strict):
    name: str
    kind: Literal["revolute", "prismatic", "pin_in_slot", "gear"]
    links: Annotated[list[str], Field(min_length=2, max_length=2)]
    at: str | None = None
    axis: Pair | None = None
    #: A gear mesh's: its centres (points of links[0] and links[1]), pitch radii
    #: (length_unit), pressure angle (deg) and whether it is internal.
    centres: Annotated[list[str], Field(min_length=2, max_length=2)] | None = None
    pitch_radii: Annotated[list[float], Field(min_length=2, max_length=2)] | None = None
    pressure_angle: float | None = None
    internal: bool | None = None


#: The keys only a gear mesh has.
GEAR_KEYS = ("centres", "pitch_radii", "pressure_angle", "internal")


#: A driver's effort: a constant, or rows of [time (s), value].
EffortSpec = float | list[Annotated[list[float], Field(min_length=2, max_length=2)]]


class DriverSpec(Strict):
    joint: str
    rotation: float | None = None
    displacement: float | None = None
    velocity: float = 0.0
    acceleration: float = 0.0
    sense: Literal["increasing", "decreasing"] | None = None
    #: N·m on a joint that turns, N on one that slides (``[case.simulate]`` only).
    torque: EffortSpec | None = None
    force: EffortSpec | None = None


class SimulateSpec(Strict):
    """``[case.simulate]``: the end time (s), the output times (a count of evenly spaced
    times from 0 to end, or the times, s) and joint rates at time 0 (rad/s, m/s)."""

    end: float
    outputs: Annotated[int, Field(ge=1)] | list[float] = 101
    rates: dict[str, float] = {}


class DimensionSpec(Strict):
    """A sketch's dimension: the distance (length_unit) or direction (deg, CCW from +x) of
    points[1] from points[0], two points of one link."""

    points: Annotated[list[str], Field(min_length=2, max_length=2)]
    length: float | None = None
    angle: float | None = None


class LinkageLoadSpec(Strict):
    link: str
    at: PointRef
    force: dict[str, Any] | None = None
    torque: float = 0.0


class LinkageMassSpec(Strict):
    link: str
    mass: float
    com: PointRef
    inertia: float = 0.0


class LinearSpringSpec(Strict):
    name: str
    ends: Annotated[list[list[Any]], Field(min_length=2, max_length=2)]  # [[link, point], …]
    stiffness: float
    free_length: float
    damping: float = 0.0


class TorsionSpringSpec(Strict):
    name: str
    joint: str
    stiffness: float
    free_rotation: float = 0.0
    damping: float = 0.0


class LinkageFrictionSpec(Strict):
    mu: Annotated[float, Field(ge=0.0)] = 0.0
    pin_radius: dict[str, Annotated[float, Field(ge=0.0)]] = {}
    joint_mu: dict[str, Annotated[float, Field(ge=0.0)]] = {}
    viscous: dict[str, Annotated[float, Field(ge=0.0)]] = {}


class LinkageCaseSpec(Strict):
    """One ``mechanism = "linkage"`` table, structurally valid."""

    name: str
    mechanism: Literal["linkage"]
    length_unit: Literal["m", "mm"] = "m"
    gravity: Pair = [0.0, 0.0]
    points: dict[str, Pair]
    links: list[LinkSpec]
    joints: list[JointSpec]
    drivers: list[DriverSpec] = []
    loads: list[LinkageLoadSpec] = []
    masses: list[LinkageMassSpec] = []
    springs: list[dict[str, Any]] = []
    friction: LinkageFrictionSpec | None = None
    #: Given, the points are a sketch that these dimensions make exact (:mod:`.sketch`).
    dimensions: list[DimensionSpec] = []
    description: str = ""
    seed: SeedSpec | None = None
    tolerance: list[ToleranceSpec] = []
    simulate: SimulateSpec | None = None


def simulation_from_spec(spec: SimulateSpec) -> Simulation:
    """``[case.simulate]`` as a Simulation: a count of outputs spread evenly over 0 … end."""
    outputs = spec.outputs
    if isinstance(outputs, int):
        if outputs > MAX_OUTPUTS:
            raise CaseError(f"must name 1 … {MAX_OUTPUTS} times, got {outputs}",
                            key="simulate.outputs")
        end = finite(spec.end, "simulate.end", MAX_TIME)
        outputs = [end * k / max(outputs - 1, 1) for k in range(outputs)] if outputs > 1 \
            else [end]
    return Simulation(spec.end, tuple(outputs), dict(spec.rates))


def linkage_from_spec(spec: LinkageCaseSpec) -> Linkage:
    """The Linkage of a validated table: lengths to metres, degrees to radians."""
    scale = LENGTH_UNITS[spec.length_unit]
    points = {name: (p[0] * scale, p[1] * scale) for name, p in spec.points.items()}
    links = tuple(Link(link.name, tuple(link.points), link.axial_stiffness) for link in spec.links)
    joints = tuple(_joint(j, i, scale) for i, j in enumerate(spec.joints))
    if spec.dimensions:
        points = _assembled(spec, points, links, joints)

    def where(ref: PointRef, key: str) -> Vec2:
        if isinstance(ref, str):
            if ref not in points:
                raise CaseError(f"unknown point {ref!r}", key=key)
            return points[ref]
        if spec.dimensions:
            raise CaseError("in a sketch, name a point: coordinates would be the sketch's, not "
                            "the assembled pose's (add the point to its link, with dimensions)",
                            key=key)
        if not isinstance(ref, list) or len(ref) != 2:
            raise CaseError(f"must be a point name or [x, y], got {ref!r}", key=key)
        # Type and finiteness before scaling: true × 1e-3 would pass as a number.
        return (finite(ref[0], key, math.inf) * scale, finite(ref[1], key, math.inf) * scale)

    kinds = {j.name: j.kind for j in spec.joints}
    springs: list[LinearSpring | TorsionSpring] = []
    for i, table in enumerate(spec.springs):
        if "joint" in table:
            t = validated(TorsionSpringSpec, table, f"springs[{i}]")
            springs.append(TorsionSpring(t.name, t.joint, t.stiffness, math.radians(t.free_rotation),
                                         t.damping))
        else:
            s = validated(LinearSpringSpec, table, f"springs[{i}]")
            ends = tuple(_spring_end(end, f"springs[{i}].ends[{k}]", where)
                         for k, end in enumerate(s.ends))
            springs.append(LinearSpring(s.name, (ends[0], ends[1]), s.stiffness,
                                        s.free_length * scale, s.damping))
    for i, ld in enumerate(spec.loads):
        needs_an_effect(ld, f"loads[{i}]")
    f = spec.friction
    with lengths_quoted_in(spec.length_unit):
        return Linkage(
            points=points,
            links=links,
            joints=joints,
            drivers=tuple(_driver(d, i, kinds, scale) for i, d in enumerate(spec.drivers)),
            loads=tuple(PointLoad(ld.link, where(ld.at, f"loads[{i}].at"),
                                  force_vector(ld.force, f"loads[{i}].force"), ld.torque)
                        for i, ld in enumerate(spec.loads)),
            masses=tuple(LinkMass(m.link, m.mass, where(m.com, f"masses[{i}].com"), m.inertia)
                         for i, m in enumerate(spec.masses)),
            springs=tuple(springs),
            gravity=(spec.gravity[0], spec.gravity[1]),
            friction=None if f is None else JointFriction(
                f.mu, {k: v * scale for k, v in f.pin_radius.items()}, dict(f.joint_mu),
                dict(f.viscous)),
            free_motion=spec.simulate is not None,
        )


def _assembled(spec: LinkageCaseSpec, points: dict[str, Vec2], links: tuple[Link, ...],
               joints: tuple[Joint, ...]) -> dict[str, Vec2]:
    """A sketch's points (m) moved to meet its dimensions (:func:`.sketch.assembled`)."""
    scale = LENGTH_UNITS[spec.length_unit]
    refuse_unsketchable(joints)
    refuse_too_large(points, links, len(spec.dimensions))
    with lengths_quoted_in(spec.length_unit):
        dimensions = tuple(_dimension(d, f"dimensions[{i}]", scale)
                           for i, d in enumerate(spec.dimensions))
        return assembled(Linkage(points=points, links=links, joints=joints), dimensions)


def _dimension(d: DimensionSpec, key: str, scale: float) -> Dimension:
    """A dimension in SI: a length in metres, an angle in radians."""
    try:
        return Dimension((d.points[0], d.points[1]),
                         length=None if d.length is None else d.length * scale,
                         angle=None if d.angle is None else math.radians(d.angle))
    except CaseError as error:
        raise error.located(key_prefix=key) from None


def _joint(j: JointSpec, i: int, scale: float) -> Joint:
    """A joint table as a Joint: a gear mesh's keys into its GearMesh, the others' ``at``."""
    key = f"joints[{i}]"
    kind = kind_named(j.kind)
    axis = None if j.axis is None else (j.axis[0], j.axis[1])
    given = [k for k in GEAR_KEYS if getattr(j, k) is not None]
    if kind is not GEAR:
        if given:
            raise CaseError(f"only a gear joint has {given[0]!r}", key=f"{key}.{given[0]}")
        if j.at is None:
            raise CaseError(f"a {j.kind} joint needs the point it acts at", key=f"{key}.at")
        return Joint(j.name, kind, (j.links[0], j.links[1]), j.at, axis)
    if j.at is not None:
        raise CaseError("a gear mesh has no 'at': its centres say where its gears turn",
                        key=f"{key}.at")
    for needed in ("centres", "pitch_radii"):
        if getattr(j, needed) is None:
            raise CaseError("a gear mesh needs it", key=f"{key}.{needed}")
    assert j.centres is not None and j.pitch_radii is not None
    radii = tuple(finite(r, f"{key}.pitch_radii", math.inf) * scale for r in j.pitch_radii)
    angle = finite(20.0 if j.pressure_angle is None else j.pressure_angle,
                   f"{key}.pressure_angle", 90.0)
    mesh = GearMesh((j.centres[0], j.centres[1]), (radii[0], radii[1]), math.radians(angle),
                    bool(j.internal))
    return Joint(j.name, kind, (j.links[0], j.links[1]), j.centres[0], axis, mesh)


def _spring_end(end: list[Any], key: str, where: Any) -> tuple[str, Vec2]:
    """``[link, point name]`` or ``[link, [x, y]]``."""
    if len(end) != 2 or not isinstance(end[0], str):
        raise CaseError(f"must be [link, point name] or [link, [x, y]], got {end!r}", key=key)
    return end[0], where(end[1], key)


def _driver(d: DriverSpec, i: int, kinds: Mapping[str, str], scale: float) -> Driver:
    """A driver's value in its joint's unit: ``rotation`` (deg) for a joint that turns,
    ``displacement`` (length_unit) for one that slides."""
    key = f"drivers[{i}]"
    name = kinds.get(d.joint)
    if name is None:
        raise CaseError(f"unknown joint {d.joint!r}", key=f"{key}.joint")
    kind = kind_named(name)
    if not kind.drivable:   # the engine's refusal, said before the value's key is looked at
        return Driver(d.joint, 0.0, d.velocity, d.acceleration)
    wanted = kind.driver_key
    other = "displacement" if wanted == "rotation" else "rotation"
    if getattr(d, other) is not None:
        raise CaseError(f"a {kind} joint is driven by '{wanted}', not '{other}'",
                        key=f"{key}.{other}")
    value = getattr(d, wanted) or 0.0
    value = math.radians(value) if kind.rotates else value * scale
    sense = {"increasing": 1, "decreasing": -1, None: 0}[d.sense]
    return Driver(d.joint, value, d.velocity, d.acceleration, sense, _effort(d, kind, key))


def _effort(d: DriverSpec, kind: JointKind, key: str) -> Effort | None:
    """A driver's ``torque`` (a joint that turns) or ``force`` (one that slides) as an
    Effort; the rows' bounds are the Linkage's to check."""
    wanted, other = ("torque", "force") if kind.rotates else ("force", "torque")
    if getattr(d, other) is not None:
        raise CaseError(f"a {kind} joint is driven by a '{wanted}', not a '{other}'",
                        key=f"{key}.{other}")
    given = getattr(d, wanted)
    if given is None:
        return None
    if isinstance(given, list):
        if not given:
            raise CaseError("must be a number or rows of [time, value]", key=f"{key}.{wanted}")
        return Effort(tuple(row[0] for row in given), tuple(row[1] for row in given))
    return Effort((0.0,), (given,))
