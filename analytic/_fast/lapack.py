"""Dense LAPACK on a few small matrices, through numpy's generalised ufuncs: the same
routines as :func:`numpy.linalg.solve` and :func:`numpy.linalg.inv`, without their
wrappers (a third to a fifth of the time on a 9×9 matrix)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

try:  # private, and only inside the fence: a numpy without it gives None, the public path
    from numpy.linalg import _umath_linalg
except ImportError:  # pragma: no cover - numpy 2 has it
    _umath_linalg = None  # type: ignore[assignment]

Array = NDArray[np.float64]


def solve_square(a: Array, b: Array) -> Array | None:
    """x with a·x = b, a (N, n, n) and b (N, n) finite; None where a result is not finite
    (a singular matrix: :func:`numpy.linalg.solve` raises there)."""
    if _umath_linalg is None:  # pragma: no cover
        return None
    with np.errstate(all="ignore"):
        x = _umath_linalg.solve(a, b[..., None], signature="dd->d")[..., 0]
    return x if np.isfinite(x).all() else None


def inverse(a: Array) -> Array | None:
    """a⁻¹, a (N, n, n) finite; None where it is not finite (a singular matrix)."""
    if _umath_linalg is None:  # pragma: no cover
        return None
    with np.errstate(all="ignore"):
        out = _umath_linalg.inv(a, signature="d->d")
    return out if np.isfinite(out).all() else None
