"""The seam of the trajectory kernel (:mod:`.motion_kernel`): one right-hand side of the
analytic reference compiled, where numba is installed and the linkage's rows are all
written in the primitives (:mod:`.motion_rows`); else None, and the numpy path runs."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from mechcheck.analytic._fast.compiled import kernel
from mechcheck.analytic._fast.plans import MotionPlan, rows_plan, terms_plan
from mechcheck.analytic.linalg import DENSE_COLUMNS
from mechcheck.analytic.motion_rows import Rows
from mechcheck.analytic.motion_terms import Terms

Array = np.ndarray
KERNEL = "mechcheck.analytic._fast.motion_kernel"


class Settings(NamedTuple):
    """The tracker's settings the kernel follows (:mod:`.linkage_dynamics`)."""

    tolerance: float
    rcond: float
    jump: float
    chord_iterations: int
    newton_iterations: int


class Step(NamedTuple):
    """One right-hand side: the state closed at x, ẋ (positions q, the scaled Jacobian
    there and its inverse, the rates S, q̇, the bias q̈₀, cos and sin of each link's φ, the
    ground's last) and its equations of motion (every coordinate's acceleration and
    effort, the work and dissipation rates)."""

    q: Array
    jacobian: Array
    inverse: Array
    rates: Array
    qdot: Array
    bias: Array
    cos: Array
    sin: Array
    acceleration: Array
    efforts: Array
    work: float
    dissipated: float


def motion_plan(rows: Rows, terms: Terms, scales: tuple[Array, Array], moving: Array,
                settings: Settings) -> MotionPlan | None:
    """The kernel's plan of a linkage's equations of motion; None where it does not run
    them: without numba, where a kind writes its own rows (a gear mesh), or where the
    Jacobian is not square or is solved sparse (:data:`.linalg.DENSE_COLUMNS`)."""
    coordinates = terms.coordinates
    if kernel(KERNEL) is None or rows.general or rows.count != rows.size \
            or rows.size > DENSE_COLUMNS or (coordinates is not None and coordinates.general):
        return None
    floats = lambda a: np.ascontiguousarray(a, dtype=np.float64)  # noqa: E731
    return MotionPlan(rows_plan(rows), floats(scales[0]), floats(scales[1]),
                      np.ascontiguousarray(moving, dtype=np.int64), terms_plan(terms), *settings)


def step(plan: MotionPlan, near: tuple[Array, ...], x: Array, xdot: Array, known: Array,
         applied: Array) -> Step | None:
    """The right-hand side at x, ẋ from the last state ``near`` (its x, ẋ, q, S, q̈₀ and
    scaled Jacobian's inverse); None where the numpy path must take it (see
    :mod:`.motion_kernel`)."""
    compiled = kernel(KERNEL)
    assert compiled is not None    # a plan exists only where the kernel does
    try:
        *found, ok = compiled.step(plan, *near, x, xdot, known, applied)
    except np.linalg.LinAlgError:     # a singular Jacobian or mass matrix
        return None
    return Step(*found) if ok else None
