"""The building blocks every joint kind writes its equations with: planar vectors, where a
link's coordinates sit, a point carried by a link, and the rows and columns of the two
systems the engine assembles (the constraint Jacobian and the member-equilibrium matrix).

Each moving link k has coordinates (t_x, t_y, φ): its rigid displacement from the drawn
pose, so a point P0 it carries is at R(φ)·P0 + t. Nothing here knows which kinds of joint
exist (:mod:`.joint_kinds` does); the engine's modules and the kinds both build on it.
"""

from __future__ import annotations

import functools
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np
from numpy.typing import NDArray

from mechcheck.analytic.linalg import FEW_POSES, Batched, Dropped
from mechcheck.analytic.values import GROUND

if TYPE_CHECKING:
    from mechcheck.analytic.joint_kinds.base import JointKind
    from mechcheck.analytic.linkage import Joint, Linkage

Array = NDArray[np.float64]


#: perp(v) = v reversed times this: (−v_y, v_x) in one operation (negation and ×−1 are
#: the same in IEEE arithmetic, signed zeros included).
_PERP = np.array([-1.0, 1.0])


def perp(v: Array) -> Array:
    """v turned +90°."""
    return np.asarray(v[..., ::-1] * _PERP, dtype=np.float64)


def rotate(angle: Array, v: Array) -> Array:
    """R(angle)·v for arrays of angles (N,) and a vector (2,) or vectors (N, 2)."""
    c, s = np.cos(angle), np.sin(angle)
    if np.ndim(v) == 1:     # one vector: its components as numbers (cheaper than 0-d views)
        x, y = float(v[0]), float(v[1])
        return _pair(c * x - s * y, s * x + c * y)
    return _pair(c * v[..., 0] - s * v[..., 1], s * v[..., 0] + c * v[..., 1])


Turn = tuple[Array, Array]


def turn_of(angle: Array) -> Turn:
    """The rotations by ``angle`` (N,) as the images of the x and y axes, (cos, sin) and
    (−sin, cos), each (N, 2): what :func:`turned` applies."""
    c, s = np.cos(angle), np.sin(angle)
    return _pair(c, s), _pair(-s, c)


def turned(turn: Turn, v: Array) -> Array:
    """:func:`rotate` by rotations given as :func:`turn_of`: x·R(e_x) + y·R(e_y), the same
    products and sums as :func:`rotate` (a + (−b) is a − b in IEEE arithmetic), in three
    operations for a link turned many times."""
    ex, ey = turn
    if np.ndim(v) == 1:
        return np.asarray(ex * float(v[0]) + ey * float(v[1]), dtype=np.float64)
    return np.asarray(ex * v[..., 0:1] + ey * v[..., 1:2], dtype=np.float64)


def _pair(x: Array, y: Array) -> Array:
    """(x, y) stacked on a last axis: what ``np.stack`` gives, at a third of its fixed cost,
    which one pose pays a few hundred times."""
    out = np.empty((*np.shape(x), 2))
    out[..., 0] = x
    out[..., 1] = y
    return out


def unit_axes(n: int) -> Array:
    """e_x and e_y at n poses, (2, n, 2), read-only: kept for a few poses (every pin's
    reaction is written along them), made anew for many."""
    return _kept_axes(n) if n <= FEW_POSES else _axes(n)


def _axes(n: int) -> Array:
    out = np.zeros((2, n, 2))
    out[0, :, 0] = 1.0
    out[1, :, 1] = 1.0
    return out


@functools.lru_cache(maxsize=FEW_POSES)
def _kept_axes(n: int) -> Array:
    out = _axes(n)
    out.flags.writeable = False
    return out


def dot(a: Array, b: Array) -> Array:
    return np.einsum("...i,...i->...", a, b)


def cross(r: Array, f: Array) -> Array:
    return r[..., 0] * f[..., 1] - r[..., 1] * f[..., 0]


def link_column(linkage: Linkage, link: str) -> int:
    """Column of the link's t_x in q (t_y and φ follow); −1 for the ground."""
    return -1 if link == GROUND else 3 * linkage.link_number[link]


@dataclass(frozen=True)
class CarriedPoints:
    """Every drawn point each moving link carries, numbered: where a few poses compute all
    of them at once (:func:`carried_rotations`), a few operations in all rather than a few
    per point (one pose pays each operation's fixed cost)."""

    #: Each (link, drawn point)'s place.
    index: dict[tuple[str, tuple[float, ...]], int]
    #: The column of each one's link's t_x in q (t_y and φ follow).
    columns: NDArray[np.intp]
    x: Array
    y: Array


def carried_points(linkage: Linkage) -> CarriedPoints:
    """The linkage's :class:`CarriedPoints`, kept (:func:`kept`)."""
    return kept(linkage, "carried points", lambda: _carried_points(linkage))


def _carried_points(linkage: Linkage) -> CarriedPoints:
    index: dict[tuple[str, tuple[float, ...]], int] = {}
    for link in linkage.links:
        if link.name != GROUND:
            for name in link.points:
                index.setdefault((link.name, linkage.points[name]), len(index))
    # The points the known forces act at: loads, centres of mass, linear springs' ends (a
    # torsion spring has none). The linkage may not have checked them yet: only those on
    # its moving links.
    acting = [(load.link, load.at) for load in linkage.loads]
    acting += [(mass.link, mass.com) for mass in linkage.masses]
    acting += [end for spring in linkage.springs for end in getattr(spring, "ends", ())]
    for link_name, p0 in acting:
        if link_name in linkage.link_number:
            index.setdefault((link_name, tuple(p0)), len(index))
    drawn = np.array([p for _, p in index], dtype=float).reshape(-1, 2)
    columns = np.array([link_column(linkage, link) for link, _ in index], dtype=np.intp)
    return CarriedPoints(index, columns, drawn[:, 0].copy(), drawn[:, 1].copy())


def carried_rotations(points: CarriedPoints, q: Array) -> Array:
    """R(φ)·P0 of every carried point at coordinates q (N, 3n): (N, points, 2), each the
    same products and sum as :func:`turned` of its link's :func:`turn_of`."""
    phi = q[:, points.columns + 2]
    c, s = np.cos(phi), np.sin(phi)
    return _pair(c * points.x + (-s) * points.y, s * points.x + c * points.y)


def carried_translations(points: CarriedPoints, q: Array) -> Array:
    """t of every carried point's link (N, points, 2)."""
    return q[:, points.columns[:, None] + _XY]


_XY = np.array([0, 1], dtype=np.intp)


@dataclass(frozen=True)
class Layout:
    """Where each moving link's three coordinates sit in q, and where each joint's and each
    driver's constraint rows start."""

    linkage: Linkage

    def index(self, link: str) -> int:
        """Column of the link's t_x (t_y and φ follow); −1 for the ground."""
        return link_column(self.linkage, link)

    @property
    def size(self) -> int:
        return 3 * len(self.linkage.moving_links)

    @cached_property
    def joint_rows(self) -> int:
        """Rows of all the joints' constraints (each kind brings its own number)."""
        return sum(j.kind.rows for j in self.linkage.joints)

    @property
    def rows(self) -> int:
        return self.joint_rows + len(self.linkage.drivers)


@dataclass
class AtCoordinates:
    """The links at coordinates q (N, 3n), each link's rotation computed once."""

    layout: Layout
    q: Array
    #: Each link's rotation (:func:`turn_of`), by its column, computed once (every joint on
    #: the link turns its points by it).
    turns: dict[int, Turn] = field(default_factory=dict, kw_only=True)

    @property
    def linkage(self) -> Linkage:
        return self.layout.linkage

    def turn(self, k: int) -> Turn:
        """The rotation (:func:`turn_of`) of the link whose t_x is column ``k`` of q."""
        found = self.turns.get(k)
        if found is None:
            found = self.turns[k] = turn_of(self.q[:, k + 2])
        return found


@dataclass
class Constraints(AtCoordinates):
    """Φ (N, m) and J = ∂Φ/∂q (entries) being written, row by row, at coordinates q (N, 3n)."""

    phi: Array
    jac: Batched

    def angle(self, link: str) -> Array:
        k = self.layout.index(link)
        return self.q[:, k + 2] if k >= 0 else np.zeros(self.q.shape[0])

    def point(self, link: str, p0: Array | tuple[float, float]) -> tuple[Array, Array]:
        """(position (N, 2), ∂position/∂φ (N, 2)) of a drawn point on ``link`` (read-only);
        a point the link carries (``p0`` a tuple) taken from all of them, computed at once
        for a few poses."""
        k = self.layout.index(link)
        n = self.q.shape[0]
        if k < 0:
            return np.broadcast_to(p0, (n, 2)).copy(), np.zeros((n, 2))
        if n <= FEW_POSES and isinstance(p0, tuple):
            positions, across, index = self._carried
            i = index.get((link, p0))
            if i is not None:
                return positions[:, i], across[:, i]
        r = turned(self.turn(k), np.asarray(p0, dtype=float))
        return self.q[:, k:k + 2] + r, perp(r)

    @cached_property
    def _carried(self) -> tuple[Array, Array, dict[tuple[str, tuple[float, ...]], int]]:
        """Every carried point's position and ∂/∂φ (N, points, 2), and their places."""
        points = carried_points(self.linkage)
        r = carried_rotations(points, self.q)
        return carried_translations(points, self.q) + r, perp(r), points.index

    def put(self, row: int, link: str, d_t: Array | None, d_phi: Array | float) -> None:
        """Add ∂(row)/∂(t_x, t_y, φ) of ``link`` (nothing for the ground); ``d_t`` None: 0."""
        k = self.layout.index(link)
        if k >= 0:
            if d_t is not None:
                self.jac.add(row, k, d_t[:, 0])
                self.jac.add(row, k + 1, d_t[:, 1])
            self.jac.add(row, k + 2, d_phi)

    def coincide(self, row: int, joint: Joint) -> None:
        """Two rows p_i(P0) − p_j(P0) = 0: the joint's links hold its point together."""
        i, j = joint.links
        self._coincide((row, i, j, self.linkage.points[joint.at]))

    def _coincide(self, pin: Pin) -> None:
        """:meth:`coincide` of one :data:`Pin`."""
        row, i, j, p0 = pin
        pi, dpi = self.point(i, p0)
        pj, dpj = self.point(j, p0)
        self.phi[:, row:row + 2] = pi - pj
        ki, kj = self.layout.index(i), self.layout.index(j)
        for c in range(2):
            if ki >= 0:
                self.jac.add(row + c, ki + c, 1.0)
                self.jac.add(row + c, ki + 2, dpi[:, c])
            if kj >= 0:
                self.jac.add(row + c, kj + c, -1.0)
                self.jac.add(row + c, kj + 2, -dpj[:, c])

    def coincide_all(self, pins: Sequence[Pin]) -> None:
        """:meth:`coincide` of several pins (the row plan's coincidences,
        :meth:`.motion_rows.RowPlan.pins`): at a few poses every point from the carried ones,
        their rows and entries written at once (the same numbers, the entries in the same
        order)."""
        n = self.q.shape[0]
        if not pins:
            return
        if not 0 < n <= FEW_POSES:   # no pose (an empty sweep part) or many: pin by pin
            for pin in pins:
                self._coincide(pin)
            return
        plan = _pins_plan(self.linkage, tuple(pins))
        positions, across, _ = self._carried
        sides = []
        for side, (places, grounded, drawn) in enumerate(plan.sides):   # links[0], links[1]
            p = np.empty((n, len(pins), 2))
            p[:, places] = positions[:, plan.carried[side, places]]
            p[:, grounded] = drawn  # the ground's point, as drawn
            sides.append(p)
        gap = sides[0] - sides[1]
        self.phi[:, plan.x_rows] = gap[..., 0]
        self.phi[:, plan.x_rows + 1] = gap[..., 1]
        if isinstance(self.jac, Dropped):     # Φ alone is asked for
            return
        # Every entry's values picked from: 1, −1, then ∂p/∂φ of every carried point (x, y)
        # and its negative.
        turned_by = across.reshape(n, -1).T
        sources = np.concatenate([self.jac_constant(1.0), self.jac_constant(-1.0), turned_by,
                                  -turned_by])
        entry_rows, entry_cols, entry_sources = plan.entries
        self.jac.add_entries(entry_rows, entry_cols, sources[entry_sources])

    def jac_constant(self, value: float) -> Array:
        """A row (1, N) of ``value``."""
        return np.full((1, self.q.shape[0]), value)

    def angle_lock(self, row: int, joint: Joint) -> None:
        """Row φ_j − φ_i."""
        i, j = joint.links
        for link, sign in ((j, 1.0), (i, -1.0)):
            k = self.layout.index(link)
            if k >= 0:
                self.phi[:, row] += sign * self.q[:, k + 2]
            self.put(row, link, None, sign)

    def along(self, row: int, joint: Joint, w0: Array) -> None:
        """Row w_i·(p_j(A0) − p_i(A0)), with w (drawn w0) fixed in the joint's links[0]."""
        i, j = joint.links
        a0 = self.linkage.points[joint.at]
        ki = self.layout.index(i)
        w = turned(self.turn(ki), w0) if ki >= 0 else rotate(self.angle(i), w0)
        pj, dpj = self.point(j, a0)
        pi, dpi = self.point(i, a0)
        d = pj - pi
        self.phi[:, row] += dot(w, d)
        if isinstance(self.jac, Dropped):     # Φ alone is asked for
            return
        self.put(row, j, w, dot(w, dpj))
        self.put(row, i, -w, dot(perp(w), d) - dot(w, dpi))


#: Two rows holding a point together: the first row, links[0], links[1] and the point as
#: drawn (what a kind declares with ``RowPlan.coincide``).
Pin = tuple[int, str, str, tuple[float, float]]


@dataclass(frozen=True)
class _PinsPlan:
    """Where :meth:`Constraints.coincide_all` reads and writes, for one set of pins."""

    #: Per side (links[0], links[1]): the pins whose link moves, the others (the ground),
    #: and the ground's drawn points (k, 2).
    sides: tuple[tuple[NDArray[np.intp], NDArray[np.intp], Array], ...]
    #: (2, pins): each pin's point's place among the carried points, on each side
    #: (0 on the ground).
    carried: NDArray[np.intp]
    x_rows: NDArray[np.intp]
    linkage: Linkage
    pins: tuple[Pin, ...]

    @cached_property
    def entries(self) -> tuple[list[int], list[int], NDArray[np.intp]]:
        """J's entries: rows, columns, and where each value comes from (derived when a
        Jacobian is first asked for: the drawing's closure needs only Φ)."""
        return _pins_entries(self.linkage, self.pins, self.carried)


def _pins_plan(linkage: Linkage, pins: tuple[Pin, ...]) -> _PinsPlan:
    """The :class:`_PinsPlan` of these pins, kept with the linkage."""
    rows = tuple(pin[0] for pin in pins)
    return kept(linkage, f"pins plan {rows}", lambda: _make_pins_plan(linkage, pins))


def _make_pins_plan(linkage: Linkage, pins: tuple[Pin, ...]) -> _PinsPlan:
    index = carried_points(linkage).index
    sides = []
    carried = np.zeros((2, len(pins)), dtype=np.intp)
    for side in (0, 1):
        places, grounded, drawn = [], [], []
        for j, pin in enumerate(pins):
            link, p0 = (pin[1], pin[2])[side], pin[3]
            if link == GROUND:
                grounded.append(j)
                drawn.append(p0)
            else:
                places.append(j)
                carried[side, j] = index[link, p0]
        sides.append((np.array(places, dtype=np.intp), np.array(grounded, dtype=np.intp),
                      np.array(drawn, dtype=float).reshape(-1, 2)))
    x_rows = np.array([pin[0] for pin in pins], dtype=np.intp)
    return _PinsPlan((sides[0], sides[1]), carried, x_rows, linkage, pins)


def _pins_entries(linkage: Linkage, pins: tuple[Pin, ...],
                  carried: NDArray[np.intp]) -> tuple[list[int], list[int], NDArray[np.intp]]:
    """:attr:`_PinsPlan.entries`."""
    count = len(carried_points(linkage).index)
    entry_rows: list[int] = []
    entry_cols: list[int] = []
    sources: list[int] = []
    for j, (row, first, second, _) in enumerate(pins):
        ki, kj = link_column(linkage, first), link_column(linkage, second)
        for c in range(2):
            # As coincide(): +1 and ∂p_i/∂φ_i, then −1 and −∂p_j/∂φ_j (the sources' rows:
            # 0 is 1, 1 is −1, 2 + 2·place + c is ∂p/∂φ, and the negatives follow).
            for k, side, sign in ((ki, 0, 0), (kj, 1, 1)):
                if k >= 0:
                    entry_rows += [row + c, row + c]
                    entry_cols += [k + c, k + 2]
                    sources += [sign, 2 + 2 * count * sign + 2 * int(carried[side, j]) + c]
    return entry_rows, entry_cols, np.array(sources, dtype=np.intp)


@dataclass
class Motion(AtCoordinates):
    """The links' motion at coordinates q and rates q̇ (N, 3n), for the J̇·q̇ terms."""

    qdot: Array

    def spin(self, link: str) -> Array:
        k = self.layout.index(link)
        return self.qdot[:, k + 2] if k >= 0 else np.zeros(self.q.shape[0])

    def rotated(self, link: str, p0: Array) -> Array:
        """R(φ)·P0 of a drawn point on ``link``."""
        k = self.layout.index(link)
        return turned(self.turn(k), p0) if k >= 0 else np.zeros((self.q.shape[0], 2))

    def position(self, link: str, p0: Array) -> Array:
        k = self.layout.index(link)
        n = self.q.shape[0]
        return self.q[:, k:k + 2] + self.rotated(link, p0) if k >= 0 \
            else np.broadcast_to(p0, (n, 2)).copy()

    def velocity(self, link: str, p0: Array) -> Array:
        k = self.layout.index(link)
        return self.qdot[:, k:k + 2] + self.spin(link)[:, None] * perp(self.rotated(link, p0)) \
            if k >= 0 else np.zeros((self.q.shape[0], 2))

    def along(self, joint: Joint, w0: Array) -> Array:
        """J̇·q̇ of the row w_i·(p_j(A0) − p_i(A0)) (:meth:`Constraints.along`)."""
        i, j = joint.links
        a0 = np.array(self.linkage.points[joint.at])
        n = self.q.shape[0]
        ki = self.layout.index(i)
        w = turned(self.turn(ki), w0) if ki >= 0 else np.broadcast_to(w0, (n, 2))
        d = self.position(j, a0) - self.position(i, a0)
        dd = self.velocity(j, a0) - self.velocity(i, a0)
        wi = self.spin(i)
        ddd = (-(self.spin(j) ** 2)[:, None] * self.rotated(j, a0)
               + (wi**2)[:, None] * self.rotated(i, a0))
        return -(wi**2) * dot(w, d) + 2 * wi * dot(perp(w), dd) + dot(w, ddd)


@dataclass(frozen=True)
class ForceLayout:
    """Rows of the links' equilibrium (ΣFx, ΣFy, ΣM each) and columns of the unknowns: each
    joint's reactions (as many as its kind has constraint rows), then each driver's effort."""

    linkage: Linkage

    def row(self, link: str) -> int:
        """First of the link's three rows; −1 for the ground (no equations)."""
        return -1 if link == GROUND else 3 * self.linkage.link_number[link]

    @cached_property
    def _first_columns(self) -> dict[str, int]:
        out, column = {}, 0
        for joint in self.linkage.joints:
            out[joint.name] = column
            column += joint.kind.rows
        return out

    def joint_columns(self, joint: Joint) -> tuple[int, ...]:
        return self._columns_of[joint.name]

    @cached_property
    def _columns_of(self) -> dict[str, tuple[int, ...]]:
        first = self._first_columns
        return {j.name: tuple(range(first[j.name], first[j.name] + j.kind.rows))
                for j in self.linkage.joints}

    def driver_column(self, index: int) -> int:
        return self.joint_unknowns + index

    @cached_property
    def joint_unknowns(self) -> int:
        return sum(j.kind.rows for j in self.linkage.joints)

    @property
    def rows(self) -> int:
        return 3 * len(self.linkage.moving_links)

    @property
    def columns(self) -> int:
        return self.joint_unknowns + len(self.linkage.drivers)

    @cached_property
    def row_scales(self) -> Array:
        """(rows,): what makes each equilibrium row a force (1, and 1/L for a moment row, L
        the linkage's size), read-only."""
        rows = np.ones(self.rows)
        rows[2::3] = 1.0 / self.linkage.scale
        rows.flags.writeable = False
        return rows

    @cached_property
    def unknown_lengths(self) -> Array:
        """(columns,): the length that makes each unknown a force (1 for a force, the
        linkage's size for a couple; the kinds' ``reaction_lengths`` and ``length``)."""
        linkage = self.linkage
        lengths = [x for joint in linkage.joints for x in joint.kind.reaction_lengths(linkage.scale)]
        lengths += [linkage.joint(d.joint).kind.length(linkage.scale) for d in linkage.drivers]
        cols = np.array(lengths, dtype=float)   # the joints' columns, in order, then the drivers'
        cols.flags.writeable = False
        return cols

    def force_pair(self, k: Batched, links: tuple[str, str], cols: tuple[int, ...],
                   directions: Array, point: Array) -> None:
        """Each column of ``cols`` times its direction (``directions`` (len(cols), N, 2))
        acting on links[1] at ``point``, and reversed on links[0] (a joint's reaction): three
        entries per column and link, the force and its moment about the origin."""
        self.force_pairs(k, (links,), (cols,), directions, point[None])

    def force_pairs(self, k: Batched, links: Sequence[tuple[str, str]],
                    cols: Sequence[tuple[int, ...]], directions: Array, points: Array) -> None:
        """:meth:`force_pair` of several joints whose columns share their directions, at
        their ``points`` (joints, N, 2): every column's entries for both links computed at
        once (negation is exact), then added joint by joint."""
        n = points.shape[1]
        entries = np.empty((points.shape[0], 2, directions.shape[0], 3, n))
        entries[:, 0, :, :2] = directions.transpose(0, 2, 1)
        entries[:, 0, :, 2] = cross(points[:, None], directions)
        np.negative(entries[:, 0], out=entries[:, 1])
        rows, columns, kept_entries = self._pair_places(tuple(links), tuple(cols))
        k.add_entries(rows, columns, entries.reshape(-1, n)[kept_entries])

    def _pair_places(self, links: tuple[tuple[str, str], ...], cols: tuple[tuple[int, ...], ...]
                     ) -> tuple[list[int], list[int], NDArray[np.intp]]:
        """Where :meth:`force_pairs` puts its entries, joint by joint, links[1] then links[0],
        column by column (a link's three rows each): rows, columns, and which of the
        computed entries go there (none for the ground). Kept for the joints."""
        key = (links, cols)
        found = self._places.get(key)
        if found is None:
            rows: list[int] = []
            columns: list[int] = []
            chosen: list[int] = []
            entry = 0
            for pair, joint_columns in zip(links, cols, strict=True):
                for link in (pair[1], pair[0]):
                    r = self.row(link)
                    for col in joint_columns:
                        if r >= 0:
                            rows += [r, r + 1, r + 2]
                            columns += [col, col, col]
                            chosen += [entry, entry + 1, entry + 2]
                        entry += 3
            found = self._places[key] = (rows, columns, np.array(chosen, dtype=np.intp))
        return found

    @cached_property
    def _places(self) -> dict[tuple[object, ...], tuple[list[int], list[int], NDArray[np.intp]]]:
        return {}

    def couple_on(self, k: Batched, link: str, col: int, sign: float) -> None:
        r = self.row(link)
        if r >= 0:
            k.add(r + 2, col, sign)

    def add_force(self, b: Array, link: str, force: Array, point: Array) -> None:
        """A known force (N, 2) at ``point`` into the known vector b (N, 3n)."""
        r = self.row(link)
        if r < 0:
            return
        b[:, r] += force[:, 0]
        b[:, r + 1] += force[:, 1]
        b[:, r + 2] += cross(point, force)

    def add_couple(self, b: Array, link: str, torque: Array) -> None:
        r = self.row(link)
        if r >= 0:
            b[:, r + 2] += torque


#: What :func:`kept` keeps: by the identity of a linkage and a name, the linkage itself
#: (so that its identity is not reused while kept) and the value, the most recent last.
_KEPT: dict[tuple[int, str], tuple[Linkage, Any]] = {}
KEPT_VALUES = 64
_KEPT_LOCK = threading.Lock()
T = TypeVar("T")


def kept(linkage: Linkage, what: str, make: Callable[[], T]) -> T:
    """``make()``, a value that depends on the linkage alone, kept for the last few
    linkages: a case solved again does not derive it again. ``what`` names the value."""
    key = (id(linkage), what)
    found = _KEPT.get(key)
    if found is not None and found[0] is linkage:
        value: T = found[1]
        return value
    value = make()
    with _KEPT_LOCK:  # solves may run in several threads
        _KEPT[key] = (linkage, value)
        while len(_KEPT) > KEPT_VALUES:
            del _KEPT[next(iter(_KEPT))]
    return value


def joints_by_kind(linkage: Linkage) -> tuple[tuple[JointKind, tuple[Joint, ...]], ...]:
    """The linkage's joints grouped by kind, each group in the file's order and the kinds in
    the order they first appear; kept (:func:`kept`)."""
    def group() -> tuple[tuple[JointKind, tuple[Joint, ...]], ...]:
        groups: dict[str, tuple[JointKind, list[Joint]]] = {}
        for joint in linkage.joints:
            groups.setdefault(joint.kind.name, (joint.kind, []))[1].append(joint)
        return tuple((kind, tuple(joints)) for kind, joints in groups.values())
    return kept(linkage, "joints by kind", group)


def joint_rows(linkage: Linkage) -> dict[str, int]:
    """Each joint's first constraint row (each kind brings its :attr:`~.JointKind.rows`);
    kept (:func:`kept`)."""
    def starts() -> dict[str, int]:
        out, row = {}, 0
        for joint in linkage.joints:
            out[joint.name] = row
            row += joint.kind.rows
        return out
    return kept(linkage, "joint rows", starts)


def force_layout(linkage: Linkage) -> ForceLayout:
    """The linkage's :class:`ForceLayout`, kept (:func:`kept`): its columns and scales are
    derived once, not on every solve of a case (they cost as much as a pose's statics)."""
    return kept(linkage, "force layout", lambda: ForceLayout(linkage))
