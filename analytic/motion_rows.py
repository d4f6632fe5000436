"""A linkage's constraint rows evaluated over all its joints at once, at one pose: what the
trajectory reference (:mod:`.linkage_dynamics`) asks at every right-hand side.

:func:`.linkage_kinematics.constraint_system` writes the rows joint by joint, vectorised
over many poses; a trajectory asks one pose at a time, thousands of times, so here the
loop over joints becomes index arrays. Each kind says which rows it writes in the
primitives :class:`~.rigid.Constraints` offers (:meth:`.JointKind.plan`,
:meth:`.JointKind.plan_drive`): two points held together (``coincide``), two links' angles
locked (``angle_lock``), a point's offset along a direction fixed in a link (``along``).
A :class:`RowPlan` collects them once per linkage; :class:`Rows` holds them as arrays and
evaluates Φ, J = ∂Φ/∂q and J̇·q̇ of every row of a primitive with a few numpy operations.
A kind with no such form (a gear mesh) leaves its rows to its own ``constrain`` and
``accelerate``, one joint at a time. The same declarations (:func:`row_plan`) tell the
statics which rows are pins (:meth:`RowPlan.pins`), written at once for many poses.

Each moving link k has coordinates (t_x, t_y, φ) at columns 3k … 3k + 2; the ground is
link n (the count of moving links) here, its columns cut off the Jacobian.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from mechcheck.analytic.linalg import Batched
from mechcheck.analytic.rigid import Array, Constraints, Layout, Motion, Pin, kept
from mechcheck.analytic.values import GROUND

if TYPE_CHECKING:
    from mechcheck.analytic.linkage import Joint, Linkage

Index = NDArray[np.intp]


@dataclass
class RowPlan:
    """The rows being declared, by the kinds (:meth:`.JointKind.plan`): each primitive's
    row and the points and links it reads, as lists."""

    linkage: Linkage
    point_links: list[int] = field(default_factory=list)
    point_drawn: list[tuple[float, float]] = field(default_factory=list)
    coincident: list[tuple[int, int, int]] = field(default_factory=list)
    locked: list[tuple[int, int, int]] = field(default_factory=list)
    aligned: list[tuple[int, int, int, int, float, float]] = field(default_factory=list)
    general: list[tuple[Joint, int, bool]] = field(default_factory=list)

    def link(self, name: str) -> int:
        """The link's number (the ground: the count of moving links)."""
        return len(self.linkage.moving_links) if name == GROUND else self.linkage.link_number[name]

    def point(self, link: str, drawn: tuple[float, float]) -> int:
        self.point_links.append(self.link(link))
        self.point_drawn.append((float(drawn[0]), float(drawn[1])))
        return len(self.point_links) - 1

    def coincide(self, row: int, joint: Joint) -> None:
        """Rows ``row``, ``row + 1``: p_i(P0) − p_j(P0) (:meth:`.Constraints.coincide`)."""
        i, j = joint.links
        p0 = self.linkage.points[joint.at]
        self.coincident.append((row, self.point(i, p0), self.point(j, p0)))

    def angle_lock(self, row: int, joint: Joint) -> None:
        """Row φ_j − φ_i (:meth:`.Constraints.angle_lock`)."""
        i, j = joint.links
        self.locked.append((row, self.link(i), self.link(j)))

    def along(self, row: int, joint: Joint, w0: Array) -> None:
        """Row w_i·(p_j(A0) − p_i(A0)), w drawn as w0 and fixed in links[0]
        (:meth:`.Constraints.along`)."""
        i, j = joint.links
        a0 = self.linkage.points[joint.at]
        self.aligned.append((row, self.point(i, a0), self.point(j, a0), self.link(i),
                             float(w0[0]), float(w0[1])))

    def pins(self, starts: tuple[int, ...]) -> tuple[Pin, ...]:
        """The coincidences (:data:`.rigid.Pin`) that start at these rows, in their order:
        the rows :meth:`.Constraints.coincide_all` writes at once."""
        found = {row: (a, b) for row, a, b in self.coincident}
        return tuple(self._pin(row, *found[row]) for row in starts if row in found)

    def _pin(self, row: int, a: int, b: int) -> Pin:
        names = (*self.linkage.moving_links, GROUND)
        return row, names[self.point_links[a]], names[self.point_links[b]], self.point_drawn[a]

    def by_the_joint(self, joint: Joint, row: int, *, drive: bool = False) -> None:
        """The joint's rows from its kind's own ``constrain`` (``drive``: ``drive``) and
        ``accelerate``, one joint at a time."""
        self.general.append((joint, row, drive))


@dataclass(frozen=True)
class RowState:
    """The rows at one pose: the links' turns and the plan's points, Φ without the
    drivers' targets, and J's entries (in :attr:`Rows.entry_rows`, :attr:`Rows.entry_cols`)."""

    q: Array
    cos: Array
    sin: Array
    rx: Array
    ry: Array
    px: Array
    py: Array
    phi: Array
    entries: Array


@dataclass(frozen=True)
class Rows:
    """Every row of a plan as index arrays (see the module's docstring)."""

    count: int
    size: int
    links: int
    point_links: Index
    drawn_x: Array
    drawn_y: Array
    co_row: Index
    co_a: Index
    co_b: Index
    lock_row: Index
    lock_a: Index
    lock_b: Index
    al_row: Index
    al_i: Index
    al_j: Index
    al_link: Index
    al_wx: Array
    al_wy: Array
    #: J's entries: constant ones first (their values), then those that vary, in the order
    #: :meth:`at` computes them; ``keep``: the varying ones that are not the ground's.
    entry_rows: Index
    entry_cols: Index
    constants: Array
    keep: Index
    general: tuple[tuple[Joint, int, bool], ...]
    linkage: Linkage

    def at(self, q: Array, *, jacobian: bool = True) -> RowState:
        """The rows at coordinates q (3n,); ``jacobian`` False: Φ alone (no entries)."""
        qe = np.concatenate([q, _GROUND_COORDINATES])
        angles = qe[2::3]
        cos, sin = np.cos(angles), np.sin(angles)
        pl = self.point_links
        cl, sl = cos[pl], sin[pl]
        rx = cl * self.drawn_x - sl * self.drawn_y
        ry = sl * self.drawn_x + cl * self.drawn_y
        px = qe[3 * pl] + rx
        py = qe[3 * pl + 1] + ry
        phi = np.zeros(self.count)
        parts = [self.constants]
        if self.co_row.size:
            a, b = self.co_a, self.co_b
            phi[self.co_row] = px[a] - px[b]
            phi[self.co_row + 1] = py[a] - py[b]
            if jacobian:
                parts += [-ry[a], rx[a], ry[b], -rx[b]]
        if self.lock_row.size:
            phi[self.lock_row] = angles[self.lock_b] - angles[self.lock_a]
        if self.al_row.size:
            wx, wy = self._axes(cos, sin)
            i, j = self.al_i, self.al_j
            dx, dy = px[j] - px[i], py[j] - py[i]
            phi[self.al_row] = wx * dx + wy * dy
            if jacobian:
                parts += [wx, wy, wy * rx[j] - wx * ry[j], -wx, -wy,
                          (wx * dy - wy * dx) - (wy * rx[i] - wx * ry[i])]
        entries = np.concatenate(parts)[self.keep] if jacobian else self.constants
        state = RowState(q, cos, sin, rx, ry, px, py, phi, entries)
        if self.general:
            self._by_the_joints(state)
        return state

    def _axes(self, cos: Array, sin: Array) -> tuple[Array, Array]:
        """Each ``along`` row's direction w = R(φ_i)·w0 now."""
        c, s = cos[self.al_link], sin[self.al_link]
        return c * self.al_wx - s * self.al_wy, s * self.al_wx + c * self.al_wy

    def dense(self, state: RowState) -> Array:
        """J (rows × 3n) at ``state``."""
        out = np.zeros((self.count, self.size))
        out[self.entry_rows, self.entry_cols] = state.entries[:self.entry_rows.size]
        if self.general:
            out += state.entries[self.entry_rows.size:].reshape(self.count, self.size)
        return out

    def quadratic(self, state: RowState, qdot: Array) -> Array:
        """J̇·q̇ (rows,) at ``state`` and rates q̇ (3n,): the part of Φ̈ without q̈."""
        qde = np.concatenate([qdot, _GROUND_COORDINATES])
        omega = qde[2::3]
        out = np.zeros(self.count)
        pl = self.point_links
        spin = omega[pl]
        square = spin * spin
        rx, ry = state.rx, state.ry
        if self.co_row.size:
            a, b = self.co_a, self.co_b
            out[self.co_row] = square[b] * rx[b] - square[a] * rx[a]
            out[self.co_row + 1] = square[b] * ry[b] - square[a] * ry[a]
        if self.al_row.size:
            wx, wy = self._axes(state.cos, state.sin)
            i, j = self.al_i, self.al_j
            vx = qde[3 * pl] - spin * ry
            vy = qde[3 * pl + 1] + spin * rx
            dx, dy = state.px[j] - state.px[i], state.py[j] - state.py[i]
            ddx, ddy = vx[j] - vx[i], vy[j] - vy[i]
            wi = spin[i]
            out[self.al_row] = (-(wi * wi) * (wx * dx + wy * dy) + 2.0 * wi * (wx * ddy - wy * ddx)
                                + wx * (square[i] * rx[i] - square[j] * rx[j])
                                + wy * (square[i] * ry[i] - square[j] * ry[j]))
        if self.general:
            motion = Motion(Layout(self.linkage), state.q[None, :], qdot[None, :])
            general = np.zeros((1, self.count))
            for joint, row, drive in self.general:
                if drive:
                    terms = joint.kind.drive_acceleration(motion, joint)
                    if terms is not None:
                        general[:, row] = terms
                else:
                    joint.kind.accelerate(motion, joint, general, row)
            out += general[0]
        return out

    def _by_the_joints(self, state: RowState) -> None:
        """The rows of kinds without a plan, written by the kinds themselves into Φ and
        appended to the entries as a dense block."""
        c = Constraints(Layout(self.linkage), state.q[None, :], np.zeros((1, self.count)),
                        Batched(self.count, self.size, 1))
        for joint, row, drive in self.general:
            (joint.kind.drive if drive else joint.kind.constrain)(c, joint, row)
        state.phi[:] += c.phi[0]
        block = c.jac.dense()[0].ravel()
        object.__setattr__(state, "entries", np.concatenate([state.entries, block]))


_GROUND_COORDINATES = np.zeros(3)


def joint_rows(linkage: Linkage) -> Rows:
    """Every joint's rows, then one row per driver on its joint (the order of
    :func:`.linkage_kinematics.constraint_system`), kept with the linkage."""
    return kept(linkage, "motion rows", lambda: _rows_of(*row_plan(linkage)))


def row_plan(linkage: Linkage) -> tuple[RowPlan, int]:
    """The kinds' declarations of :func:`joint_rows` and their count of rows, kept with the
    linkage: the statics read its pins (:meth:`RowPlan.pins`)."""
    def make() -> tuple[RowPlan, int]:
        plan = RowPlan(linkage)
        row = 0
        for joint in linkage.joints:
            joint.kind.plan(plan, joint, row)
            row += joint.kind.rows
        for driver in linkage.drivers:
            joint = linkage.joint(driver.joint)
            joint.kind.plan_drive(plan, joint, row)
            row += 1
        return plan, row
    return kept(linkage, "row plan", make)


def coordinate_rows(linkage: Linkage, joints: tuple[str, ...]) -> Rows:
    """One row per named joint: its coordinate (its driver row, without a target)."""
    plan = RowPlan(linkage)
    for row, name in enumerate(joints):
        joint = linkage.joint(name)
        joint.kind.plan_drive(plan, joint, row)
    return _rows_of(plan, len(joints))


def _rows_of(plan: RowPlan, count: int) -> Rows:
    n = len(plan.linkage.moving_links)
    ints = lambda values: np.array(values, dtype=np.intp).reshape(-1)  # noqa: E731
    co = np.array(plan.coincident, dtype=np.intp).reshape(-1, 3)
    lock = np.array(plan.locked, dtype=np.intp).reshape(-1, 3)
    al = np.array(plan.aligned, dtype=np.float64).reshape(-1, 6)
    al_i, al_j, al_link = (al[:, k].astype(np.intp) for k in (1, 2, 3))
    pl = ints(plan.point_links)
    # constant entries: a coincidence's ±1 on t, a lock's ±1 on φ
    rows, cols, values = [], [], []
    for row, a, b in co:
        for k in range(2):
            rows += [row + k, row + k]
            cols += [3 * pl[a] + k, 3 * pl[b] + k]
            values += [1.0, -1.0]
    for row, a, b in lock:
        rows += [row, row]
        cols += [3 * b + 2, 3 * a + 2]
        values += [1.0, -1.0]
    # varying entries, in the order Rows.at computes them
    co_r = co[:, 0]
    for r, c in ((co_r, 3 * pl[co[:, 1]] + 2), (co_r + 1, 3 * pl[co[:, 1]] + 2),
                 (co_r, 3 * pl[co[:, 2]] + 2), (co_r + 1, 3 * pl[co[:, 2]] + 2)):
        rows += list(r)
        cols += list(c)
    al_r = al[:, 0].astype(np.intp)
    lj, li = pl[al_j], pl[al_i]
    for c in (3 * lj, 3 * lj + 1, 3 * lj + 2, 3 * li, 3 * li + 1, 3 * li + 2):
        rows += list(al_r)
        cols += list(c)
    rows_a, cols_a = ints(rows), ints(cols)
    keep = np.flatnonzero(cols_a < 3 * n)
    constants = np.array(values)
    return Rows(count, 3 * n, n, pl, np.array([p[0] for p in plan.point_drawn]),
                np.array([p[1] for p in plan.point_drawn]),
                co[:, 0], co[:, 1], co[:, 2], lock[:, 0], lock[:, 1], lock[:, 2],
                al_r, al_i, al_j, al_link, al[:, 4].copy(), al[:, 5].copy(),
                rows_a[keep], cols_a[keep], constants, keep, tuple(plan.general), plan.linkage)
