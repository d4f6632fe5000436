"""Positions, velocities and accelerations of any :class:`~mechcheck.analytic.linkage.Linkage`,
vectorised over poses.

Each moving link k has coordinates (t_x, t_y, φ): its rigid displacement from the drawn
pose, so a point P0 it carries is at R(φ)·P0 + t (:mod:`.rigid`). Each joint's kind
(:mod:`.joint_kinds`) writes its constraint rows, and a driver's row on it: a pin's
p_i(P0) − p_j(P0) = 0 and φ_j − φ_i = q, a slide's φ_j − φ_i = 0, n_i·(p_j − p_i) = 0
and u_i·(p_j − p_i) = q.

The pose is the one reached **continuously from the drawn pose**: every driver moves from
0 to its value along s ∈ [0, 1] in small steps, each closed by Newton's method from the
last (LINKAGES.md "Which assembly"); the drawn pose picks the branch. Where Newton can no
longer close the loop, the linkage locks, and the value where it does is found by
bisection on s. Velocities and accelerations follow from J·q̇ = [0, v] and
J·q̈ = [0, a] − (J̇·q̇), with J̇·q̇ written out per constraint.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mechcheck.analytic import linalg, motion_rows
from mechcheck.analytic.linalg import Batched, Dropped
from mechcheck.analytic.rigid import (
    Array,
    Constraints,
    Layout,
    Motion,
    Pin,
    Turn,
    carried_points,
    carried_rotations,
    carried_translations,
    joint_rows,
    joints_by_kind,
    kept,
    link_column,
    perp,
    rotate,
    turn_of,
    turned,
)

if TYPE_CHECKING:
    from mechcheck.analytic.joint_kinds.base import JointFrame
    from mechcheck.analytic.linkage import Joint, Linkage

#: Largest driver step of the continuation: 2° of rotation, or 2 % of the linkage's size
#: of displacement. Small enough that Newton, started from the last pose, converges in a
#: few iterations and never jumps to another branch away from a singular pose.
STEP_ROTATION = math.radians(2.0)
STEP_DISPLACEMENT = 0.02
#: Newton's closure, relative to the linkage's size, and its iteration budget per step.
CLOSURE_RTOL = 1e-13
NEWTON_ITERATIONS = 25
#: Bisection steps on s when locating where a linkage locks: 2⁻⁴⁰ of the driver's travel.
LOCK_BISECTIONS = 40
#: A step Newton does not close is tried in halves down to 2⁻⁸ of it before it counts as a
#: lock: a gear train's last gear may turn tens of times faster than its driver.
HALVINGS = 8


@dataclass(frozen=True)
class LinkagePose:
    """Every link's displacement from the drawn pose at N poses: q, q̇, q̈ of shape (N, 3n),
    the driver values (N, d), and where the linkage locked (NaN rows; ``locked_at`` holds
    the fraction s of the drivers' travel where it locked, else NaN)."""

    linkage: Linkage
    drivers: Array
    q: Array
    qdot: Array
    qddot: Array
    locked_at: Array
    #: The points :meth:`point` keeps, by link and drawn point; the links' rotations computed
    #: so far (:meth:`turn`); the frames :meth:`frame` keeps, by joint. Each pose's own (not
    #: passed on by ``dataclasses.replace``), and plain fields: a cached property's lock
    #: costs more than a pose's point.
    points_asked: dict[tuple[str, tuple[float, ...]], tuple[Array, Array, Array]] = field(
        default_factory=dict, init=False, repr=False, compare=False)
    turns: dict[int, Turn] = field(default_factory=dict, init=False, repr=False, compare=False)
    frames_asked: dict[str, JointFrame] = field(default_factory=dict, init=False, repr=False,
                                                compare=False)

    def head(self, n: int) -> LinkagePose:
        """The first ``n`` poses."""
        return self.take(slice(None, n))

    def take(self, which: slice | NDArray[np.intp]) -> LinkagePose:
        """The poses ``which`` (a slice or indices), in that order."""
        return LinkagePose(self.linkage, self.drivers[which], self.q[which], self.qdot[which],
                           self.qddot[which], self.locked_at[which])

    def link_state(self, link: str, which: Array) -> tuple[Array, Array]:
        """(t (N, 2), φ (N,)) of ``link`` from one of q, q̇, q̈."""
        k = link_column(self.linkage, link)
        n = which.shape[0]
        if k < 0:
            return np.zeros((n, 2)), np.zeros(n)
        return which[:, k:k + 2], which[:, k + 2]

    def point(self, link: str, drawn: ArrayLike) -> tuple[Array, Array, Array]:
        """Global position, velocity and acceleration of a point fixed to ``link`` that was
        at ``drawn`` in the drawn pose (read-only). A few poses keep each point asked for:
        the statics of one pose asks for a joint's point several times (its frame, its
        coordinate, its reported force), and each computation is a dozen calls."""
        if self.q.shape[0] > linalg.FEW_POSES or not isinstance(drawn, tuple):
            return self._point(link, drawn)
        key = (link, drawn)
        found = self.points_asked.get(key)
        if found is None:
            found = self.points_asked[key] = self._carried(key) or _read_only(
                self._point(link, drawn))
        return found

    def _carried(self, key: tuple[str, tuple[float, ...]]) -> tuple[Array, Array, Array] | None:
        """A point its link carries, at a few poses at rest: every carried point is placed
        at once on the first one asked for (:func:`.rigid.carried_rotations`); None if
        ``key`` is not one, or the pose moves."""
        if not self.at_rest:
            return None
        positions, rest, index = self._all_carried
        i = index.get(key)
        return None if i is None else (positions[:, i], rest, rest)

    def drawn_positions(self) -> Array | None:
        """Every point of the drawing (``linkage.points``, in order) on the link that reports
        it (``linkage.carriers``), (N, points, 2), at a few poses at rest: :meth:`position`
        of each, gathered from the carried points at once; else None."""
        if self.q.shape[0] > linalg.FEW_POSES or not self.at_rest:
            return None
        positions = self._all_carried[0]
        moving, carried, ground, drawn = _drawn_places(self.linkage)
        out = np.empty((self.q.shape[0], len(self.linkage.points), 2))
        out[:, moving] = positions[:, carried]
        out[:, ground] = drawn + 0.0    # as position() gives the ground's: P0 with its zeros +0
        return out

    @cached_property
    def _all_carried(self) -> tuple[Array, Array, dict[tuple[str, tuple[float, ...]], int]]:
        """Every carried point's position (N, points, 2), the rates' zeros (N, 2), and the
        points' places; read-only."""
        points = carried_points(self.linkage)
        positions = carried_translations(points, self.q) + carried_rotations(points, self.q)
        rest = np.zeros((self.q.shape[0], 2))
        positions.flags.writeable = rest.flags.writeable = False
        return positions, rest, points.index

    def _point(self, link: str, drawn: ArrayLike) -> tuple[Array, Array, Array]:
        if self.at_rest:    # what the sums below give: +0 at every pose
            position = self.position(link, drawn)
            return position, np.zeros(position.shape), np.zeros(position.shape)
        p0 = np.asarray(drawn, dtype=float)
        t, phi = self.link_state(link, self.q)
        v, omega = self.link_state(link, self.qdot)
        a, alpha = self.link_state(link, self.qddot)
        k = link_column(self.linkage, link)
        r = turned(self.turn(k), p0) if k >= 0 else rotate(phi, p0)
        position = t + r
        across = perp(r)
        velocity = v + omega[:, None] * across
        acceleration = a + alpha[:, None] * across - (omega**2)[:, None] * r
        return position, velocity, acceleration

    def position(self, link: str, drawn: ArrayLike) -> Array:
        """:meth:`point`'s position alone (N, 2): the same numbers, without the rates."""
        k = link_column(self.linkage, link)
        if isinstance(drawn, tuple) and k >= 0:     # as :func:`.rigid.turned`, in fewer calls
            found = self.points_asked.get((link, drawn)) or (
                self._carried((link, drawn)) if self.q.shape[0] <= linalg.FEW_POSES else None)
            if found is not None:
                return found[0]
            ex, ey = self.turn(k)
            return np.asarray(self.q[:, k:k + 2] + (ex * float(drawn[0]) + ey * float(drawn[1])),
                              dtype=np.float64)
        if isinstance(drawn, tuple):    # the ground's: 0 + R(0)·P0 is P0 with its zeros +0
            return np.full((self.q.shape[0], 2), drawn, dtype=np.float64) + 0.0
        p0 = np.asarray(drawn, dtype=float)
        t, phi = self.link_state(link, self.q)
        return np.asarray(t + (turned(self.turn(k), p0) if k >= 0 else rotate(phi, p0)),
                          dtype=np.float64)

    def turn(self, k: int) -> Turn:
        """The rotation (:func:`.rigid.turn_of`) of the link whose t_x is column ``k`` of q,
        computed once (every point the link carries is turned by it)."""
        found = self.turns.get(k)
        if found is None:
            found = self.turns[k] = turn_of(self.q[:, k + 2])
        return found

    def turned(self, link: str, v: Array) -> Array:
        """A vector ``v`` (2,) fixed in ``link``, turned as the link is (N, 2): :func:`.rigid.
        rotate` by its angle, through its rotation computed once (:meth:`turn`)."""
        k = link_column(self.linkage, link)
        return turned(self.turn(k), v) if k >= 0 else rotate(self.link_state(link, self.q)[1], v)

    @cached_property
    def at_rest(self) -> bool:
        """Every rate exactly +0 and every pose assembled (finite): then every point's
        velocity and acceleration in :meth:`point` are +0 (+0 + (±0) is +0)."""
        return bool(self.assembled.all() and not (
            self.qdot.any() or self.qddot.any()
            or np.signbit(self.qdot).any() or np.signbit(self.qddot).any()))

    def angle(self, link: str) -> tuple[Array, Array, Array]:
        """φ, ω, α of ``link`` (rotation from the drawn pose)."""
        return (self.link_state(link, self.q)[1], self.link_state(link, self.qdot)[1],
                self.link_state(link, self.qddot)[1])

    def frame(self, joint: Joint) -> JointFrame:
        """Where ``joint`` acts (its kind's :meth:`~.JointKind.frame`), kept for a few poses as
        :meth:`point` keeps points: the matrix K and the reported forces both ask."""
        if self.q.shape[0] > linalg.FEW_POSES:
            return joint.kind.frame(self, joint)
        found = self.frames_asked.get(joint.name)
        if found is None:
            found = self.frames_asked[joint.name] = joint.kind.frame(self, joint)
        return found

    def joint_coordinate(self, joint: Joint) -> tuple[Array, Array, Array]:
        """q, q̇, q̈ of a joint: relative rotation (rad) or displacement along the axis (m)."""
        return joint.kind.coordinate(self, joint)

    @cached_property
    def assembled(self) -> NDArray[np.bool_]:
        """Which poses the linkage reaches (asked for by every verdict: computed once)."""
        return np.all(np.isfinite(self.q), axis=1)


def _drawn_places(linkage: Linkage) -> tuple[NDArray[np.intp], NDArray[np.intp],
                                               NDArray[np.intp], Array]:
    """Where :meth:`LinkagePose.drawn_positions` finds each point: the places of the points a
    moving link reports and their places among the carried points, the places of the
    ground's and their drawn coordinates; kept (:func:`.rigid.kept`)."""
    def places() -> tuple[NDArray[np.intp], NDArray[np.intp], NDArray[np.intp], Array]:
        index = carried_points(linkage).index
        moving: list[int] = []
        carried: list[int] = []
        ground: list[int] = []
        drawn: list[tuple[float, float]] = []
        for i, (name, p0) in enumerate(linkage.points.items()):
            link = linkage.carriers[name]
            if (link, p0) in index:
                moving.append(i)
                carried.append(index[link, p0])
            else:
                ground.append(i)
                drawn.append(p0)
        return (np.array(moving, dtype=np.intp), np.array(carried, dtype=np.intp),
                np.array(ground, dtype=np.intp), np.array(drawn, dtype=float).reshape(-1, 2))
    return kept(linkage, "drawn places", places)


def known_at_rest(pose: LinkagePose) -> LinkagePose:
    """``pose``, whose rates its solver made +0 wherever it assembles (NaN elsewhere), with
    :attr:`LinkagePose.at_rest` known without a pass over them."""
    pose.__dict__["at_rest"] = bool(pose.assembled.all())   # what the cached property stores
    return pose


def _read_only(arrays: tuple[Array, Array, Array]) -> tuple[Array, Array, Array]:
    """``arrays``, which are kept and handed out again, made read-only."""
    for a in arrays:
        a.flags.writeable = False
    return arrays


def known_assembled(pose: LinkagePose, assembled: NDArray[np.bool_]) -> LinkagePose:
    """``pose`` with :attr:`LinkagePose.assembled` given (a solver that wrote q chunk by
    chunk knows it without another pass over all of q)."""
    pose.__dict__["assembled"] = assembled   # what the cached property stores
    return pose


# -- constraints ------------------------------------------------------------------------

def residual_and_jacobian(linkage: Linkage, q: Array, targets: Array, *,
                          drivers: bool = True) -> tuple[Array, Array]:
    """Φ (N, m) and J = ∂Φ/∂q (N, m, 3n) for coordinates q and driver targets (N, d);
    without ``drivers``, the joints' rows only."""
    phi, jac = constraint_system(linkage, q, targets, drivers=drivers)
    return phi, jac.dense()


def constraint_system(linkage: Linkage, q: Array, targets: Array, *,
                      drivers: bool = True, jacobian: bool = True) -> tuple[Array, Batched]:
    """Φ (N, m) and J = ∂Φ/∂q as entries (:class:`~.linalg.Batched`), as
    :func:`residual_and_jacobian`: each joint's rows as its kind writes them, then each
    driver's row on its joint. Without ``jacobian``, J's entries are dropped as written
    (:class:`~.linalg.Dropped`): Φ alone, at a third of the cost."""
    layout = Layout(linkage)
    n = q.shape[0]
    rows = layout.rows if drivers else layout.joint_rows
    entries = Batched(rows, layout.size, n) if jacobian else Dropped(rows, layout.size, n)
    c = Constraints(layout, q, np.zeros((n, rows)), entries)
    _write_joints(c)
    row = layout.joint_rows
    for k, driver in enumerate(linkage.drivers if drivers else ()):
        joint = linkage.joint(driver.joint)
        joint.kind.drive(c, joint, row)
        c.phi[:, row] -= targets[:, k]
        row += 1
    return c.phi, c.jac


def _write_joints(c: Constraints) -> None:
    """Every joint's rows, kind by kind: the pins all at once, the others by their kinds'
    ``constrain``, joint by joint (:func:`_joint_writers`)."""
    for pins, others in _joint_writers(c.linkage):
        c.coincide_all(pins)
        for joint, row in others:
            joint.kind.constrain(c, joint, row)


def _joint_writers(linkage: Linkage) -> tuple[tuple[tuple[Pin, ...],
                                                     tuple[tuple[Joint, int], ...]], ...]:
    """Per kind (:func:`~.rigid.joints_by_kind`): the joints whose rows their kind's plan
    declares as one coincidence (:meth:`.motion_rows.RowPlan.pins`), and the others with their
    first rows; kept (:func:`~.rigid.kept`)."""
    def split() -> tuple[tuple[tuple[Pin, ...], tuple[tuple[Joint, int], ...]], ...]:
        starts = joint_rows(linkage)
        plan = motion_rows.row_plan(linkage)[0]
        groups = []
        for _, joints in joints_by_kind(linkage):
            # a coincidence is two rows: a kind with more writes them all itself
            pins = plan.pins(tuple(starts[j.name] for j in joints if j.kind.rows == 2))
            pinned = {pin[0] for pin in pins}
            others = tuple((j, starts[j.name]) for j in joints if starts[j.name] not in pinned)
            groups.append((pins, others))
        return tuple(groups)
    return kept(linkage, "joint writers", split)


def quadratic_terms(linkage: Linkage, q: Array, qdot: Array) -> Array:
    """J̇·q̇ (N, m): the part of Φ̈ that does not hold q̈, for J·q̈ = a − J̇·q̇."""
    layout = Layout(linkage)
    m = Motion(layout, q, qdot)
    out = np.zeros((q.shape[0], layout.rows))
    row = 0
    for joint in linkage.joints:
        joint.kind.accelerate(m, joint, out, row)
        row += joint.kind.rows
    for driver in linkage.drivers:
        joint = linkage.joint(driver.joint)
        terms = joint.kind.drive_acceleration(m, joint)
        if terms is not None:
            out[:, row] = terms
        row += 1
    return out


def joint_system_at(linkage: Linkage, q: Array) -> Batched:
    """∂(joint constraints)/∂q at coordinates q (3n,), as entries."""
    return constraint_system(linkage, q[None, :], np.zeros((1, 0)), drivers=False)[1]


# -- solving ----------------------------------------------------------------------------

def solve_batched(a: Array, b: Array) -> Array:
    """a·x = b for every pose: exact where a is square and regular, else least squares."""
    return linalg.solve(a, b)


def unit_scales(linkage: Linkage, *, drivers: bool = True) -> tuple[Array, Array]:
    """Row and column scales that make the constraint system a system in lengths: rotation
    columns become L·φ (L the linkage's size) and angle rows are multiplied by L. Solved
    in these units, least-squares and least-norm steps, residuals and ranks do not depend on
    where the drawing sits, how it is turned or how large it is. Kept with the linkage
    (:func:`.rigid.kept`; read-only): every Newton step and solve asks for them."""
    return kept(linkage, f"unit scales, drivers {drivers}", lambda: _unit_scales(linkage, drivers))


def _unit_scales(linkage: Linkage, drivers: bool) -> tuple[Array, Array]:
    size = linkage.scale
    cols = np.ones(Layout(linkage).size)
    cols[2::3] = 1.0 / size
    rows: list[float] = []
    for joint in linkage.joints:
        rows += joint.kind.row_lengths(size)
    if drivers:
        rows += [linkage.joint(d.joint).kind.length(size) for d in linkage.drivers]
    out = np.array(rows)
    out.flags.writeable = False
    cols.flags.writeable = False
    return out, cols


def solve_in_lengths(linkage: Linkage, jac: Batched, rhs: Array, *,
                     drivers: bool = True) -> Array:
    """J·x = rhs at every pose, solved in the units of :func:`unit_scales`."""
    rows, cols = unit_scales(linkage, drivers=drivers)
    scaled = jac.scaled(np.broadcast_to(rows, (jac.poses, rows.size)), cols)
    return linalg.solve(scaled, rhs * rows) * cols


def _newton(linkage: Linkage, q: Array, targets: Array) -> tuple[Array, NDArray[np.bool_]]:
    """Close the loops from q at the driver targets; returns (q, converged)."""
    q = q.copy()
    converged = np.zeros(q.shape[0], dtype=bool)
    with np.errstate(all="ignore"):
        for _ in range(NEWTON_ITERATIONS):
            phi, jac = constraint_system(linkage, q, targets)
            converged = _closed(linkage, phi)
            if converged.all():
                break
            step = solve_in_lengths(linkage, jac, phi)
            step[converged] = 0.0
            q = q - step
    return q, converged & np.all(np.isfinite(q), axis=1)


def _closed(linkage: Linkage, phi: Array) -> NDArray[np.bool_]:
    """Which poses' residuals Φ (N, m) meet Newton's closure (:data:`CLOSURE_RTOL`)."""
    rows, _ = unit_scales(linkage)
    err = np.abs(phi * rows).max(axis=1) if phi.shape[1] else np.zeros(phi.shape[0])
    return np.isfinite(err) & (err <= CLOSURE_RTOL * linkage.scale)


def _step_size(linkage: Linkage, driver: int) -> float:
    """The continuation's largest step of a driver (rad or m)."""
    kind = linkage.joint(linkage.drivers[driver].joint).kind
    return STEP_ROTATION if kind.rotates else STEP_DISPLACEMENT * linkage.scale


def _steps(linkage: Linkage, values: Array) -> int:
    """Continuation steps so that no driver moves more than one step at a time."""
    count = 1
    for k in range(len(linkage.drivers)):
        travel = float(np.abs(values[:, k]).max()) if values.size else 0.0
        count = max(count, math.ceil(travel / _step_size(linkage, k)))
    return count


def positions(linkage: Linkage, values: Array) -> tuple[Array, Array]:
    """q (N, 3n) at each row of driver values (N, d), reached from the drawn pose; rows that
    lock are NaN, with the fraction s of their travel where they locked (else NaN).

    In closed form where the linkage decomposes into a crank and RRR and RRP dyads
    (:mod:`.linkage_assur`), else by continuation (:func:`continuation_positions`).
    """
    plan = linkage.assur_plan
    if plan is not None and values.shape[0]:
        from mechcheck.analytic.linkage_assur import assur_positions
        return assur_positions(plan, values)
    return continuation_positions(linkage, values)


def continuation_positions(linkage: Linkage, values: Array) -> tuple[Array, Array]:
    """:func:`positions` by continuation: Newton's method from the drawn pose in steps of at
    most :data:`STEP_ROTATION` (or :data:`STEP_DISPLACEMENT`), bisecting where it locks.

    One driver: the path is walked once each way from the drawn pose, through anchors one
    step apart, and every pose is closed from the anchor before it, so the cost grows with
    the travel plus the number of poses, not with their product. Several drivers move
    together along s·values, all poses at once."""
    if values.shape[1] == 1 and values.shape[0]:
        return _walked_positions(linkage, values[:, 0])
    n = values.shape[0]
    q = np.zeros((n, Layout(linkage).size))
    locked = np.full(n, np.nan)
    alive = np.ones(n, dtype=bool)
    steps = _steps(linkage, values)
    previous = 0.0
    for s in np.linspace(0.0, 1.0, steps + 1)[1:]:
        trial, ok = _newton(linkage, q[alive], s * values[alive])
        if not ok.all():
            where = np.flatnonzero(alive)[~ok]
            locked[where] = _lock_fraction(linkage, q[where], values[where], previous, s)
            alive[where] = False
            q[where] = np.nan
        q[alive] = trial[ok]
        previous = s
    return q, locked


def _closed_drawing(linkage: Linkage) -> tuple[Array, NDArray[np.bool_]]:
    """The drawing closed by Newton's method (q (1, 3n), and whether it closed): the start
    of every path, kept with the linkage (:func:`.rigid.kept`), read-only."""
    def close() -> tuple[Array, NDArray[np.bool_]]:
        q, targets = np.zeros((1, Layout(linkage).size)), np.zeros((1, 1))
        # The drawing closes as drawn (each joint's points coincide there): Newton's first
        # test, on the joints' rows the linkage found with its rank at the drawing; a
        # driver's row is its joint's coordinate, zero at the drawing by definition.
        phi = np.zeros((1, Layout(linkage).rows))
        phi[:, :linkage.constraint_rows] = linkage.drawn_residual
        with np.errstate(all="ignore"):
            drawn = _closed(linkage, phi)
        q, ok = (q, drawn) if drawn.all() else _newton(linkage, q, targets)
        q.flags.writeable = False
        ok.flags.writeable = False
        return q, ok
    return kept(linkage, "closed drawing", close)


def _walked_positions(linkage: Linkage, value: Array) -> tuple[Array, Array]:
    """:func:`continuation_positions` of one driver at values (N,)."""
    n = value.shape[0]
    q = np.full((n, Layout(linkage).size), np.nan)
    locked = np.full(n, np.nan)
    size = _step_size(linkage, 0)
    start, closed = _closed_drawing(linkage)
    if not closed[0]:   # the drawing itself does not close
        locked[:] = 0.0
        return q, locked
    drawn = value == 0.0
    q[drawn] = start[0]     # the drawing, closed: no path to walk
    if drawn.all():     # a case solved at its drawn pose
        return q, locked
    for side in (1.0, -1.0):
        rows = np.flatnonzero((side * value > 0.0) & ~drawn)
        if not rows.size:
            continue
        travel = float(np.abs(value[rows]).max())
        anchors, reach = _walk(linkage, start[0], side, size, travel)
        inside = rows[np.abs(value[rows]) <= reach]
        beyond = rows[np.abs(value[rows]) > reach]
        locked[beyond] = reach / np.abs(value[beyond])
        if not inside.size:
            continue
        before = np.minimum(np.floor(np.abs(value[inside]) / size).astype(np.intp), len(anchors) - 1)
        trial, ok = _newton(linkage, anchors[before], value[inside, None])
        for i in np.flatnonzero(~ok):
            anchor = math.copysign(before[i] * size, float(value[inside[i]]))
            trial[i:i + 1], ok[i:i + 1] = _in_halves(linkage, anchors[before[i]][None, :], anchor,
                                                    value[inside[i], None][None, :])
        q[inside[ok]] = trial[ok]
        if not ok.all():    # between the last anchor and a lock: where exactly, per pose
            bad = inside[~ok]
            lo = np.where(value[bad] != 0.0, before[~ok] * size / np.abs(value[bad]), 0.0)
            locked[bad] = _lock_fraction(linkage, anchors[before[~ok]], value[bad, None],
                                         lo, np.ones(bad.size))
    return q, locked


@dataclass
class _Path:
    """One side of one driver's path from the drawn pose, as far as it has been walked in
    whole steps (:func:`_walk`): the anchors k·size, and the step where it locks (0: not
    met) with how far the path reaches."""

    anchors: list[Array]
    locked_at: int = 0
    reach: float = math.inf
    lock: threading.Lock = field(default_factory=threading.Lock)


#: The paths walked so far (:func:`_walk`), by what they depend on (:func:`_path_key`), the
#: most recently used last; at most :data:`KEPT_PATHS`.
_PATHS: dict[tuple[str, float, float], _Path] = {}
KEPT_PATHS = 16
_PATHS_LOCK = threading.Lock()


def _kept_path(linkage: Linkage, side: float, size: float, start: Array) -> _Path:
    """The path of the linkage's driver on one ``side`` in steps of ``size``, as far as it
    has been walked: kept for a mechanism, not for one Linkage value, since a case at
    another driver value (a sweep's pose, a driven run's start) is a new value of the same
    mechanism and walks the same path."""
    key = (_path_key(linkage), side, size)
    with _PATHS_LOCK:
        path = _PATHS.pop(key, None) or _Path([start])
        _PATHS[key] = path
        while len(_PATHS) > KEPT_PATHS:
            del _PATHS[next(iter(_PATHS))]
    return path


def _path_key(linkage: Linkage) -> str:
    """What a path from the drawn pose depends on, as text: the drawing, the links, the
    joints and the driven joints; not the drivers' values or rates, nor the loads."""
    return kept(linkage, "path key", lambda: repr((tuple(linkage.points.items()), linkage.links,
                                                   linkage.joints,
                                                   tuple(d.joint for d in linkage.drivers))))


def _walk(linkage: Linkage, start: Array, side: float, size: float,
          travel: float) -> tuple[Array, float]:
    """The anchors k·size (k = 0, 1, …) of one driver's path on one side of the drawn pose,
    up to ``travel`` or to where the linkage locks, and how far the path reaches.

    The whole steps (k·size ≤ ``travel``) are kept (:func:`_kept_path`): a path walked
    again, farther or not (a sweep analysed in parts, a driven run started at each of its
    poses), goes on from where the last walk stopped, through the same Newton steps from
    the same anchors, so to the same poses. A last step short of a whole one is walked anew
    each time."""
    count = math.ceil(travel / size) if travel > 0.0 else 0
    path = _kept_path(linkage, side, size, start)
    with path.lock:  # solves may run in several threads
        while (not path.locked_at and len(path.anchors) <= count
               and len(path.anchors) * size <= travel):
            k = len(path.anchors)
            found, reach = _anchor(linkage, path.anchors[-1], side, size, k, k * size)
            if found is None:
                path.locked_at, path.reach = k, reach
            else:
                path.anchors.append(found)
        whole = 1
        while whole < len(path.anchors) and whole <= count and whole * size <= travel:
            whole += 1
        anchors = path.anchors[:whole]
        if path.locked_at == whole and whole <= count and whole * size <= travel:
            return np.array(anchors), path.reach
    for k in range(whole, count + 1):
        found, reach = _anchor(linkage, anchors[-1], side, size, k, min(k * size, travel))
        if found is None:
            return np.array(anchors), reach
        anchors.append(found)
    return np.array(anchors), math.inf


def _anchor(linkage: Linkage, before: Array, side: float, size: float, k: int,
            value: float) -> tuple[Array | None, float]:
    """Step k of a path (:func:`_walk`), from the anchor ``before`` to the driver at
    side·``value``: the pose there, or None and how far the path reaches (where it locks)."""
    target = np.array([[side * value]])
    trial, ok = _newton(linkage, before[None, :], target)
    if not ok[0]:
        trial, ok = _in_halves(linkage, before[None, :], side * (k - 1) * size, target)
    if ok[0]:
        return trial[0], math.inf
    fraction = _lock_fraction(linkage, before[None, :], target,
                              np.array([(k - 1) * size / abs(target[0, 0])]), np.ones(1))
    return None, float(fraction[0]) * abs(target[0, 0])


def _in_halves(linkage: Linkage, q: Array, start: float, target: Array,
               depth: int = HALVINGS) -> tuple[Array, NDArray[np.bool_]]:
    """Newton from q (one pose, its driver at ``start``) to ``target`` (1, 1) through halves
    of the step where one step does not converge: a link that turns many times faster than
    the driver (the last gear of a train) leaves Newton's reach within a driver step that
    suits every other linkage. Not converged after ``depth`` halvings: a lock."""
    if depth == 0:
        return q, np.zeros(1, dtype=bool)
    mid = np.array([[0.5 * (start + float(target[0, 0]))]])
    halfway, ok = _newton(linkage, q, mid)
    if not ok[0]:
        halfway, ok = _in_halves(linkage, q, start, mid, depth - 1)
        if not ok[0]:
            return q, ok
    trial, ok = _newton(linkage, halfway, target)
    if ok[0]:
        return trial, ok
    return _in_halves(linkage, halfway, float(mid[0, 0]), target, depth - 1)


def _lock_fraction(linkage: Linkage, q: Array, values: Array, lo: float | Array,
                   hi: float | Array) -> Array:
    """Bisection on s between a pose that closes (lo) and one that does not (hi)."""
    lo_s = np.broadcast_to(np.asarray(lo, dtype=float), (q.shape[0],)).copy()
    hi_s = np.broadcast_to(np.asarray(hi, dtype=float), (q.shape[0],)).copy()
    good = q.copy()
    for _ in range(LOCK_BISECTIONS):
        mid = 0.5 * (lo_s + hi_s)
        trial, ok = _newton(linkage, good, mid[:, None] * values)
        lo_s = np.where(ok, mid, lo_s)
        hi_s = np.where(ok, hi_s, mid)
        good[ok] = trial[ok]
    return lo_s


def solve_pose(linkage: Linkage, values: ArrayLike | None = None,
               velocities: ArrayLike | None = None,
               accelerations: ArrayLike | None = None) -> LinkagePose:
    """The pose, velocity and acceleration of every link at each row of driver values.

    Without arguments: the linkage's own drivers (one pose). Values are per driver in
    driver units (rad or m from the drawn pose), shape (N, d) or (d,).
    """
    d = len(linkage.drivers)
    own = np.array([[drv.value for drv in linkage.drivers]]).reshape(1, d)
    vals = own if values is None else np.atleast_2d(np.asarray(values, dtype=float)).reshape(-1, d)
    n = vals.shape[0]
    rates = _driver_rates(linkage, n, velocities, accelerations)
    q, locked = positions(linkage, vals)
    if rates is None:
        return _at_rest(linkage, vals, q, locked)
    vel, acc = rates
    joints_rows = linkage.constraint_rows
    with np.errstate(all="ignore"):
        _, jac = constraint_system(linkage, np.nan_to_num(q), vals)
        rhs = np.zeros((n, Layout(linkage).rows))
        rhs[:, joints_rows:] = vel
        qdot = solve_in_lengths(linkage, jac, rhs)
        rhs = -quadratic_terms(linkage, np.nan_to_num(q), qdot)
        rhs[:, joints_rows:] += acc
        qddot = solve_in_lengths(linkage, jac, rhs)
    bad = ~np.all(np.isfinite(q), axis=1)
    qdot[bad] = np.nan
    qddot[bad] = np.nan
    return LinkagePose(linkage, vals, q, qdot, qddot, locked)


def _driver_rates(linkage: Linkage, n: int, velocities: ArrayLike | None,
                  accelerations: ArrayLike | None) -> tuple[Array, Array] | None:
    """The drivers' velocities and accelerations (n, d); None where all are zero."""
    if velocities is None and accelerations is None \
            and not any(drv.velocity or drv.acceleration for drv in linkage.drivers):
        return None     # the case's own drivers at rest: no arrays needed
    d = len(linkage.drivers)
    vel = np.broadcast_to(np.array([drv.velocity for drv in linkage.drivers]) if velocities is None
                          else np.asarray(velocities, dtype=float), (n, d))
    acc = np.broadcast_to(np.array([drv.acceleration for drv in linkage.drivers])
                          if accelerations is None else np.asarray(accelerations, dtype=float), (n, d))
    return None if not (vel.any() or acc.any()) else (vel, acc)


def _at_rest(linkage: Linkage, vals: Array, q: Array, locked: Array) -> LinkagePose:
    """The pose with every driver at rest: J·q̇ = 0 and J·q̈ = −J̇·q̇ = 0 have the solution
    zero at every pose that assembles (the two solves would give it, up to the sign of a
    zero), NaN at one that does not."""
    bad = ~np.all(np.isfinite(q), axis=1)
    qdot = np.zeros(q.shape)
    qdot[bad] = np.nan
    return known_at_rest(known_assembled(LinkagePose(linkage, vals, q, qdot, qdot.copy(), locked),
                                         ~bad))
