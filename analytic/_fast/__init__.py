"""The fence: what the engine opens numpy up for, for one pose's speed, and the one seam
the engine's modules call it through (this module).

A case solved on its own is one pose: its matrices are a few dozen numbers, and each numpy
call costs more in its Python wrapper (argument checks, error-state contexts) than in its
arithmetic. Here LAPACK is called through numpy's own generalised ufuncs
(:mod:`numpy.linalg._umath_linalg`, the routines :func:`numpy.linalg.solve` and
:func:`numpy.linalg.inv` call), so the numbers are those of the public functions, to the
bit (``tests/test_analytic_fast.py``).

Every function here gives its result, or None where the public function would do
something else (raise on a singular matrix, meet a number that is not finite), and the
caller then runs its own code.
"""

from __future__ import annotations

from mechcheck.analytic._fast.lapack import inverse, solve_square

__all__ = ["inverse", "solve_square"]
