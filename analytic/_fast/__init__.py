"""The fence: what the analytic engine opens numpy up for or does compiled, for speed, and
the one seam the engine's modules call it through (this package's names below).

- :mod:`.lapack`: one pose's small dense solves. A case solved on its own is one pose: its
  matrices are a few dozen numbers, and each numpy call costs more in its Python wrapper
  than in its arithmetic. LAPACK is called through numpy's own generalised ufuncs (the
  routines :func:`numpy.linalg.solve` and :func:`numpy.linalg.inv` call), so the numbers are
  those of the public functions, to the bit (``tests/test_analytic_fast.py``).
- :mod:`.compiled`: :func:`kernel`, which imports a numba kernel module where numba is
  installed (the ``fast`` extra) and not switched off (``MECHCHECK_PURE_PYTHON=1``);
- :mod:`.plans`: what the trajectory kernel is handed (named arrays);
- :mod:`.motion_kernel`: the trajectory reference's right-hand side, compiled;
- :mod:`.motion`: its seam, imported by the trajectory reference itself (it builds its plan
  from the engine's rows and terms, which use this package's LAPACK).

Every function here gives its result, or None where it cannot take a case or a state (a
singular matrix, a number that is not finite, a state the kernel does not handle), and the
caller then runs its own numpy code. A compiled path gives the numbers its numpy twin gives,
to rounding (the sums of matrix products may add in another order;
``tests/test_motion_compiled.py``).
"""

from mechcheck.analytic._fast.compiled import kernel
from mechcheck.analytic._fast.lapack import inverse, solve_square

__all__ = ["inverse", "kernel", "solve_square"]
