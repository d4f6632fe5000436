"""The seam of the trajectory kernel (:mod:`.motion_kernel`): one right-hand side of the
analytic reference compiled, where numba is installed and the linkage's rows are all
written in the primitives (:mod:`.motion_rows`); else None, and the numpy path runs."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np

from mechcheck.analytic._fast.compiled import kernel
from mechcheck.analytic._fast.plans import MotionPlan, Settings, rows_plan, terms_plan
from mechcheck.analytic.linalg import DENSE_COLUMNS
from mechcheck.analytic.motion_rows import Rows
from mechcheck.analytic.motion_terms import Terms

Array = np.ndarray
KERNEL = "mechcheck.analytic._fast.motion_kernel"


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


class Kernel(NamedTuple):
    """A linkage's :class:`.MotionPlan` and the kernel compiled for it
    (:func:`.motion_kernel.compiled_step`)."""

    plan: MotionPlan
    run: Callable[..., tuple[Any, ...]]


def motion_plan(rows: Rows, terms: Terms, scales: tuple[Array, Array], moving: Array,
                settings: Settings) -> Kernel | None:
    """The kernel of a linkage's equations of motion; None where it does not run them:
    without numba, where a kind writes its own rows (a gear mesh), or where the Jacobian
    is not square or is solved sparse (:data:`.linalg.DENSE_COLUMNS`)."""
    compiled = kernel(KERNEL)
    coordinates = terms.coordinates
    if compiled is None or rows.general or rows.count != rows.size \
            or rows.size > DENSE_COLUMNS or (coordinates is not None and coordinates.general):
        return None
    plan = MotionPlan(rows_plan(rows), _floats(scales[0]), _floats(scales[1]),
                      np.ascontiguousarray(moving, dtype=np.int64), terms_plan(terms), settings)
    return Kernel(plan, compiled.compiled_step(plan))


def step(kernel: Kernel, near: tuple[Array, ...], x: Array, xdot: Array, known: Array,
         applied: Array) -> Step | None:
    """The right-hand side at x, ẋ from the last state ``near`` (its x, ẋ, q, S, q̈₀ and
    scaled Jacobian's inverse); None where the numpy path must take it (see
    :mod:`.motion_kernel`)."""
    arrays = [_floats(a) for a in (*near, x, xdot, known, applied)]  # the compiled types
    try:
        *found, ok = kernel.run(kernel.plan, *arrays)
    except np.linalg.LinAlgError:     # a singular Jacobian or mass matrix
        return None
    return Step(*found) if ok else None


def _floats(a: Array) -> Array:
    """``a`` as C-ordered float64 (itself where it is: the numpy path's arrays are)."""
    return np.ascontiguousarray(a, dtype=np.float64)
