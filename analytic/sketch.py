"""A linkage written as a sketch with dimensions, assembled into its drawn pose.

A sketch gives every point roughly, as drawn by hand, and the dimensions that make it
exact: the distance between two points of one link (``length``), or the direction of the
line from one to the other (``angle``, CCW from +x: how a driven crank's angle is given).
The ground is exact as sketched, and so is the line of a slide on the ground (through its
point as sketched, along its axis); every other point moves to meet the dimensions.

Before solving, the dimensions must fix the sketch and nothing twice: each moving link is
made rigid by its own dimensions (2k − 3 independent distances for its k points, an angle
counting as one), and all of them together fix every moving point. Both are counted as
ranks at a generic (random) placing of the points, so that neither depends on how the sketch
happens to be drawn. The assembly is the solution nearest the sketch: damped least squares
(Levenberg–Marquardt) from the sketched points, then Newton's method to the last digits.
It must then meet every dimension to :data:`MET_RTOL` of itself, leave every point within
:data:`NEAR_SKETCH` of the sketch's size of where it was drawn, and fix the points firmly
(:data:`FIRMNESS`).

Examples
--------
A crank O→A, 1 long at 90°, assembles A from a sketch that put it at (0.1, 0.9):

>>> from mechcheck.analytic.joint_kinds import REVOLUTE
>>> from mechcheck.analytic.linkage import Joint, Link, Linkage
>>> shape = Linkage(points={"O": (0.0, 0.0), "A": (0.1, 0.9)},
...                 links=(Link("ground", ("O",)), Link("crank", ("O", "A"))),
...                 joints=(Joint("O", REVOLUTE, ("ground", "crank"), "O"),))
>>> a = assembled(shape, (Dimension(("O", "A"), length=1.0),
...                       Dimension(("O", "A"), angle=math.pi / 2)))["A"]
>>> round(a[0], 12) + 0.0, round(a[1], 12)
(0.0, 1.0)
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np

from mechcheck.analytic import linalg
from mechcheck.analytic.linalg import Batched
from mechcheck.analytic.values import (
    GROUND,
    MIN_LINK_LENGTH,
    CaseError,
    Vec2,
    bounded_angle,
    finite,
    length_text,
)

if TYPE_CHECKING:
    from mechcheck.analytic.linkage import Joint, Link, Linkage

#: A dimension is met when it is within this fraction of itself (an angle: within this
#: many radians; a slide's line: within this fraction of the sketch's size).
MET_RTOL = 1e-12
#: The farthest a point may move from where it is sketched, as a fraction of the sketch's
#: size (``Linkage.scale``, about its diameter): a hand sketch is within tens of percent, and
#: a point that moves further has been carried to an assembly the sketch does not show.
NEAR_SKETCH = 0.25
#: The smallest singular value of the assembly's equations, relative to the largest, that
#: fixes the points firmly: below it (three points of one link on one line, a linkage folded
#: at a toggle) a residual of 1e-16 leaves the points uncertain by more than 1e-10 of the size.
FIRMNESS = 1e-6
#: The most moving points a sketch assembles: its ranks are dense decompositions, cubic in
#: the count, and no hand sketch has more.
MAX_SKETCH_POINTS = 400
#: Newton steps that polish the least-squares solution to the last digits.
POLISH_STEPS = 8


@dataclass(frozen=True)
class Dimension:
    """The distance (m) between two points of one link, or the direction (rad, CCW from
    +x) of the line from ``points[0]`` to ``points[1]``: one of ``length`` and ``angle``."""

    points: tuple[str, str]
    length: float | None = None
    angle: float | None = None

    def __post_init__(self) -> None:
        if (self.length is None) == (self.angle is None):
            raise CaseError("give a length or an angle (one of them)")
        if self.length is not None:
            if finite(self.length, "length") < MIN_LINK_LENGTH:
                raise CaseError(f"must be at least {length_text(MIN_LINK_LENGTH)} (a micrometre), "
                                f"got {length_text(self.length)}", key="length")
        else:
            bounded_angle(float(self.angle or 0.0), "angle")


@dataclass(frozen=True)
class _Equation:
    """One equation the assembled points meet, in units of the sketch's size:
    |p1 − p0| = length, or n·(p1 − p0) = 0 for a direction, or n·(p0 − origin) = 0 for a
    slide's line."""

    key: str
    points: tuple[str, ...]
    length: float | None = None
    normal: Vec2 = (0.0, 0.0)
    origin: Vec2 | None = None
    #: A direction's angle (rad), as the file gives it: for messages.
    angle: float = 0.0

    def value(self, at: Mapping[str, np.ndarray]) -> float:
        """The residual, with the points at ``at``."""
        if self.origin is not None:
            return float(np.dot(self.normal, at[self.points[0]] - np.array(self.origin)))
        d = at[self.points[1]] - at[self.points[0]]
        if self.length is not None:
            return float(np.hypot(d[0], d[1]) - self.length)
        return float(np.dot(self.normal, d))

    def gradients(self, at: Mapping[str, np.ndarray]) -> list[tuple[str, np.ndarray]]:
        """∂(residual)/∂(each point's x, y)."""
        n = np.array(self.normal)
        if self.origin is not None:
            return [(self.points[0], n)]
        if self.length is not None:
            d = at[self.points[1]] - at[self.points[0]]
            n = d / max(float(np.hypot(d[0], d[1])), 1e-300)
        return [(self.points[0], -n), (self.points[1], n)]

    def error(self, at: Mapping[str, np.ndarray]) -> float:
        """How far it is from met, relative (:data:`MET_RTOL`): a length to itself, a line
        to the size, a direction by its angle (so that the opposite direction is far)."""
        if self.origin is not None:
            return abs(self.value(at))
        if self.length is not None:
            return abs(self.value(at)) / self.length
        d = at[self.points[1]] - at[self.points[0]]
        along = np.array([self.normal[1], -self.normal[0]])
        return abs(math.atan2(float(np.dot(self.normal, d)), float(np.dot(along, d))))

    def unmet(self, at: Mapping[str, np.ndarray], size: float) -> str:
        """What it comes to instead, for a message (lengths in metres: × ``size``)."""
        first = self.points[0]
        if self.origin is not None:
            return f"{first} is {length_text(abs(self.value(at)) * size)} off its slide's line"
        second = self.points[1]
        d = at[second] - at[first]
        if self.length is not None:
            return (f"{first}–{second} comes to {length_text(float(np.hypot(d[0], d[1])) * size)}, "
                    f"not {length_text(self.length * size)}")
        return (f"{first}→{second} points at {math.degrees(math.atan2(d[1], d[0])):.6g}°, "
                f"not {math.degrees(self.angle):.6g}°")


def assembled(shape: Linkage, dimensions: Sequence[Dimension]) -> dict[str, Vec2]:
    """The sketch's points moved to meet its dimensions, on the assembly nearest the sketch,
    in the file's frame (m); a :class:`CaseError` naming the key where it cannot be.

    ``shape`` is the linkage as sketched (its points, links and joints; loads, drivers
    and the rest play no part).
    """
    refuse_unsketchable(shape.joints)
    refuse_too_large(shape.points, shape.links, len(dimensions))
    size = shape.scale
    sketch = _Sketch(shape, tuple(_equation(shape, d, i, size) for i, d in enumerate(dimensions)))
    sketch.check_links_rigid()
    sketch.check_determined()
    at = sketch.solve()
    sketch.check_assembled(at)
    return {name: shape.drawn((float(p[0]) * size, float(p[1]) * size)) for name, p in at.items()}


def refuse_unsketchable(joints: Sequence[Joint]) -> None:
    """A CaseError for a joint a sketch cannot hold: a gear mesh, or a slide whose guide
    moves (its line would move with an orientation the sketch does not fix)."""
    for i, joint in enumerate(joints):
        if not joint.kind.sketchable:
            raise CaseError(f"a {joint.kind} joint cannot be sketched (its centre distance "
                            "comes from its pitch radii): write this linkage's points exactly, "
                            "without [[case.dimensions]]", key=f"joints[{i}].kind")
        if joint.kind.slides and joint.links[0] != GROUND:
            raise CaseError(f"in a sketch, a {joint.kind} joint's guide (links[0]) is the "
                            "ground, whose line is kept as sketched: write this linkage's points "
                            "exactly, without [[case.dimensions]]", key=f"joints[{i}].links")


def _moving_points(points: Iterable[str], links: Sequence[Link]) -> list[str]:
    """The points the ground does not carry: the sketch's unknowns."""
    ground = {p for link in links if link.name == GROUND for p in link.points}
    return [name for name in points if name not in ground]


def refuse_too_large(points: Iterable[str], links: Sequence[Link], dimensions: int) -> None:
    """A sketch beyond :data:`MAX_SKETCH_POINTS` moving points, or with more dimensions than
    two for each of that many (more than can be independent), is refused before any work
    that grows with its size."""
    count = len(_moving_points(points, links))
    if count > MAX_SKETCH_POINTS or dimensions > 2 * MAX_SKETCH_POINTS:
        raise CaseError(f"a sketch assembles at most {MAX_SKETCH_POINTS} moving points with "
                        f"{2 * MAX_SKETCH_POINTS} dimensions, this one has {count} and "
                        f"{dimensions}: write a larger linkage's points exactly",
                        key="dimensions")


def _equation(shape: Linkage, d: Dimension, i: int, size: float) -> _Equation:
    """A dimension as an equation, once its points are known to lie on one moving link."""
    key = f"dimensions[{i}]"
    first, second = d.points
    for name in d.points:
        if name not in shape.points:
            raise CaseError(f"unknown point {name!r}", key=f"{key}.points")
    if first == second:
        raise CaseError("must name two different points", key=f"{key}.points")
    common = [link.name for link in shape.links if first in link.points and second in link.points]
    if not common:
        raise CaseError(f"{first!r} and {second!r} are on different links: a dimension is "
                        "between two points of one link", key=f"{key}.points")
    if common == [GROUND]:
        raise CaseError(f"{first!r} and {second!r} are both on the ground, which is exact "
                        "as sketched: write their coordinates exactly", key=f"{key}.points")
    if d.length is not None:
        return _Equation(key, d.points, length=d.length / size)
    assert d.angle is not None
    return _Equation(key, d.points, normal=(-math.sin(d.angle), math.cos(d.angle)), angle=d.angle)


class _Sketch:
    """The sketch's unknowns (every point off the ground) and its equations, in units of
    its size, so that every rank and residual is the same wherever and however large it is."""

    def __init__(self, shape: Linkage, dimensions: tuple[_Equation, ...]) -> None:
        self.shape = shape
        self.size = shape.scale
        self.free = _moving_points(shape.points, shape.links)
        self.dimensions = dimensions
        self.equations = self._slide_lines() + dimensions

    def _slide_lines(self) -> tuple[_Equation, ...]:
        """A slide on the ground keeps its point on the line drawn through it."""
        out = []
        for i, joint in enumerate(self.shape.joints):
            if joint.kind.slides and joint.at in self.free:
                assert joint.axis is not None   # a checked slide has its unit axis
                origin = self.shape.points[joint.at]
                out.append(_Equation(f"joints[{i}]", (joint.at,), normal=(-joint.axis[1], joint.axis[0]),
                                     origin=(origin[0] / self.size, origin[1] / self.size)))
        return tuple(out)

    # -- the points as one vector, in sizes ---------------------------------------------
    @cached_property
    def index(self) -> dict[str, int]:
        return {name: k for k, name in enumerate(self.free)}

    def points(self, x: np.ndarray) -> dict[str, np.ndarray]:
        """Every point, in sizes: the ground's as sketched, the others from x."""
        out = {name: np.array(p) / self.size for name, p in self.shape.points.items()}
        for name, k in self.index.items():
            out[name] = x[2 * k:2 * k + 2]
        return out

    def sketched(self) -> np.ndarray:
        return np.array([c for name in self.free for c in self.shape.points[name]]) / self.size

    def residuals(self, x: np.ndarray) -> np.ndarray:
        at = self.points(x)
        return np.array([e.value(at) for e in self.equations])

    def jacobian(self, x: np.ndarray) -> Batched:
        return _jacobian(self.equations, self.points(x), self.index)

    def dense_jacobian(self, x: np.ndarray) -> np.ndarray:
        return self.jacobian(x).dense()[0]

    # -- what the dimensions fix --------------------------------------------------------
    def check_links_rigid(self) -> None:
        """Each moving link rigid by its own dimensions, none of them repeating the others."""
        by_link: dict[str, list[_Equation]] = {}
        for e in self.dimensions:
            by_link.setdefault(self._link_of(e), []).append(e)
        for i, link in enumerate(self.shape.links):
            names = list(dict.fromkeys(link.points))
            if link.name == GROUND or len(names) < 2:
                continue
            own = by_link.get(link.name, [])
            jac = _jacobian(own, _generic(names), {name: k for k, name in enumerate(names)})
            dependent = first_dependent(jac)
            if dependent is not None:
                raise CaseError(f"repeats what the other dimensions of link {link.name!r} "
                                "already fix: remove it", key=own[dependent].key)
            angle = any(e.length is None for e in own)
            needed = 2 * len(names) - 3 + angle
            if len(own) < needed:
                raise CaseError(
                    f"link {link.name!r} is not rigid: its {len(names)} points need {needed} "
                    f"independent dimensions (2k − 3{', and 1 for its angle' if angle else ''}), "
                    f"it has {len(own)}: give {needed - len(own)} more", key=f"links[{i}]")

    def _link_of(self, e: _Equation) -> str:
        """The first moving link that carries both of a dimension's points."""
        return next(name for name, points in self.carried.items()
                    if name != GROUND and set(e.points) <= points)

    @cached_property
    def carried(self) -> dict[str, set[str]]:
        """Each link's points, as a set."""
        return {link.name: set(link.points) for link in self.shape.links}

    def check_determined(self) -> None:
        """The equations fix every moving point, none of them twice."""
        jac = _jacobian(self.equations, self.points(self.sketched()) | _generic(self.free),
                        self.index)
        dependent = first_dependent(jac)
        if dependent is not None:
            raise CaseError("one dimension too many: with the ground and the dimensions before "
                            "it, every point it touches is already fixed; remove it",
                            key=self.equations[dependent].key)
        missing = jac.cols - jac.rows
        if missing:
            raise CaseError(f"the dimensions leave the sketch {missing} degree(s) of freedom: "
                            "give the direction of each driven link with an angle, e.g. "
                            "{ points = [\"O\", \"A\"], angle = 60.0 }", key="dimensions")

    # -- the assembly -------------------------------------------------------------------
    def solve(self) -> dict[str, np.ndarray]:
        """The points (sizes) nearest the sketch that meet the equations: least squares
        from the sketch, polished by Newton."""
        from scipy.optimize import least_squares

        if not self.free:
            return self.points(self.sketched())
        x = least_squares(self.residuals, self.sketched(), jac=self.dense_jacobian, method="lm",
                          xtol=1e-15, ftol=1e-15, gtol=1e-15).x
        r = self.residuals(x)
        for _ in range(POLISH_STEPS):
            if not np.abs(r).max() > 1e-16:
                break
            # A step kept only where it helps: a sketch that cannot assemble keeps the
            # least-squares compromise, which the refusal quotes.
            trial = x - linalg.solve(self.jacobian(x), r[None, :])[0]
            r_trial = self.residuals(trial)
            if not np.abs(r_trial).max() < np.abs(r).max():
                break
            x, r = trial, r_trial
        return self.points(x)

    def check_assembled(self, at: dict[str, np.ndarray]) -> None:
        """Every dimension met, every point near its sketch, the points fixed firmly."""
        errors = [e.error(at) for e in self.equations]
        worst = int(np.argmax(errors)) if errors else 0
        if errors and not errors[worst] <= MET_RTOL:
            e = self.equations[worst]
            raise CaseError(f"the sketch does not assemble: no pose meets every dimension, and "
                            f"this one is furthest from met ({e.unmet(at, self.size)})", key=e.key)
        for name in self.free:
            moved = float(np.hypot(*(at[name] * self.size - np.array(self.shape.points[name]))))
            if moved > NEAR_SKETCH * self.size:
                raise CaseError(f"moved {length_text(moved)} from where it is sketched to meet "
                                f"the dimensions, more than {NEAR_SKETCH:g} × the sketch's size "
                                f"({length_text(self.size)}): draw it nearer its place",
                                key=f"points.{name}")
        jac = self.jacobian(np.concatenate([at[n] for n in self.free]))
        if jac.cols and not linalg.condition(jac)[0] * FIRMNESS < 1.0:
            raise CaseError("the dimensions meet where they do not fix the points firmly "
                            "(three points of one link on one line, or links folded onto one "
                            "line at a toggle): write this pose's points exactly",
                            key="dimensions")


def _generic(names: Sequence[str]) -> dict[str, np.ndarray]:
    """A random placing of the points ``names`` (in sizes, around the sketch's): the
    dimensions' ranks there are their ranks anywhere but at special placings."""
    rng = np.random.default_rng(0)
    return {name: rng.uniform(-1.0, 1.0, 2) for name in names}


def _jacobian(equations: Sequence[_Equation], at: Mapping[str, np.ndarray],
              index: Mapping[str, int]) -> Batched:
    """∂(equations)/∂(the points ``index`` numbers), with the points at ``at``, as entries
    (a few per equation: a large sketch is solved sparse, :mod:`.linalg`)."""
    jac = Batched(len(equations), 2 * len(index), 1)
    for r, e in enumerate(equations):
        for name, g in e.gradients(at):
            k = index.get(name)
            if k is not None:
                jac.add(r, 2 * k, float(g[0]))
                jac.add(r, 2 * k + 1, float(g[1]))
    return jac


def first_dependent(jac: Batched) -> int | None:
    """The first row that depends on the rows before it, or None (a bisection on the rank
    of the leading rows, which are independent up to that row and not beyond)."""
    rows = jac.dense()[0] if jac.small else jac.at(0).tocsr()
    if not jac.rows or linalg.rank(rows) == jac.rows:
        return None
    independent, dependent = 0, jac.rows   # leading rows: independent, not independent
    while dependent - independent > 1:
        mid = (independent + dependent) // 2
        if linalg.rank(rows[:mid]) == mid:
            independent = mid
        else:
            dependent = mid
    return dependent - 1
