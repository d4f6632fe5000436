"""What the trajectory kernel (:mod:`.motion_kernel`) is handed: a linkage's rows, masses,
loads and springs as named arrays (NamedTuples, which numba takes as they are), built once
per linkage from the numpy path's own values (:class:`.motion_rows.Rows`,
:class:`.motion_terms.Terms`), so that both read the same numbers."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from mechcheck.analytic.motion_rows import Rows
from mechcheck.analytic.motion_terms import Terms

Array = np.ndarray


class RowsPlan(NamedTuple):
    """One :class:`.Rows`: its ``row_count`` rows over ``size`` columns, the points its
    primitives read (their link, drawn x and y), and each primitive's rows:
    ``coincide`` (row, point a, point b), ``lock`` (row, link a, link b), ``along`` (row,
    point i, point j, the link its direction is fixed in) with that direction as drawn
    (``along_w``)."""

    row_count: int
    size: int
    point_links: Array
    drawn_x: Array
    drawn_y: Array
    coincide: Array
    lock: Array
    along: Array
    along_w: Array


class TermsPlan(NamedTuple):
    """One :class:`.Terms`: each moving link's mass, centre (as drawn, in the link) and
    inertia about it; gravity; the point loads (link, point, force, couple, and where their
    components add up); the linear springs (a ends then b ends: link and point; stiffness,
    free length, damping; where they add up) and the length under which a spring's ends
    meet; the torsion springs', dampers' and viscous joints' coordinates (``coordinates``)
    with (k, k·q0, c) of each."""

    mass: Array
    com_x: Array
    com_y: Array
    inertia: Array
    gravity: Array
    load_links: Array
    load_x: Array
    load_y: Array
    load_force: Array
    load_torque: Array
    load_index: Array
    spring_ends: Array
    spring_drawn: Array
    spring_stiffness: Array
    spring_length: Array
    spring_damping: Array
    spring_index: Array
    meeting: float
    coordinates: RowsPlan
    coordinate_terms: Array


class Settings(NamedTuple):
    """The tracker's settings the kernel follows (:mod:`.linkage_dynamics`: the closure
    tolerance in m, RCOND, JUMP, CHORD_ITERATIONS, NEWTON_ITERATIONS), handed over rather
    than compiled in, so that a cached kernel never keeps an old value."""

    tolerance: float
    rcond: float
    jump: float
    chord_iterations: int
    newton_iterations: int
    #: Below this bound on the scaled Jacobian's smallest singular value (1/‖J⁻¹‖_F) the
    #: numpy path takes the state: it interpolates the rates along the branch there
    #: (:mod:`.motion_bridge`); 0 where it never does.
    sigma_floor: float


class MotionPlan(NamedTuple):
    """A trajectory's equations of motion: the constraint rows (the driver rows of the
    independent coordinates last), their scales (rows' and columns', to lengths), the
    coordinates that move by the equations of motion, the masses and forces; and the
    tracker's :class:`Settings`."""

    rows: RowsPlan
    row_scales: Array
    col_scales: Array
    moving: Array
    terms: TermsPlan
    settings: Settings


def rows_plan(rows: Rows) -> RowsPlan:
    """The kernel's copy of ``rows`` (every row written in the primitives, none by a kind
    one joint at a time: the caller checks ``rows.general``)."""
    ints = lambda *columns: np.ascontiguousarray(np.column_stack(columns), dtype=np.int64)  # noqa: E731
    return RowsPlan(rows.count, rows.size, rows.point_links.astype(np.int64), rows.drawn_x,
                    rows.drawn_y, ints(rows.co_row, rows.co_a, rows.co_b),
                    ints(rows.lock_row, rows.lock_a, rows.lock_b),
                    ints(rows.al_row, rows.al_i, rows.al_j, rows.al_link),
                    np.ascontiguousarray(np.column_stack([rows.al_wx, rows.al_wy]), dtype=np.float64))


def terms_plan(terms: Terms) -> TermsPlan:
    """The kernel's copy of ``terms``."""
    coordinates = terms.coordinates
    if coordinates is None:
        none = np.zeros(0, dtype=np.int64)
        plan = RowsPlan(0, 3 * terms.links, none, np.zeros(0), np.zeros(0),
                        np.zeros((0, 3), dtype=np.int64), np.zeros((0, 3), dtype=np.int64),
                        np.zeros((0, 4), dtype=np.int64), np.zeros((0, 2)))
    else:
        plan = rows_plan(coordinates)
    table = np.column_stack([terms.coordinate_stiffness, terms.coordinate_free,
                             terms.coordinate_damping]).reshape(-1, 3)
    ints = lambda values: np.asarray(values, dtype=np.int64)  # noqa: E731
    return TermsPlan(terms.mass, terms.com_x, terms.com_y, terms.inertia, terms.gravity,
                     ints(terms.load_links), terms.load_x.astype(np.float64),
                     terms.load_y.astype(np.float64), terms.load_force, terms.load_torque,
                     ints(terms.load_index), ints(terms.spring_ends), terms.spring_drawn,
                     terms.spring_stiffness.astype(np.float64),
                     terms.spring_length.astype(np.float64),
                     terms.spring_damping.astype(np.float64), ints(terms.spring_index),
                     float(terms.meeting), plan, np.ascontiguousarray(table, dtype=np.float64))
