"""The fence: what the analytic engine does compiled, for speed, and the switch every
compiled path in the package goes through.

- :mod:`.compiled`: :func:`kernel`, which imports a numba kernel module where numba is
  installed (the ``fast`` extra) and not switched off (``MECHCHECK_PURE_PYTHON=1``);
- :mod:`.plans`: what the trajectory kernel is handed (named arrays);
- :mod:`.motion_kernel`: the trajectory reference's right-hand side, compiled;
- :mod:`.motion`: its seam (this package's names below).

A compiled path gives the numbers its numpy twin gives, to rounding (the sums of matrix
products may add in another order); where it cannot take a case or a state, it says so
(None) and the numpy path runs (``tests/test_motion_compiled.py``).
"""

from mechcheck.analytic._fast.compiled import kernel
from mechcheck.analytic._fast.motion import Kernel, Settings, Step, motion_plan, step
from mechcheck.analytic._fast.plans import MotionPlan

__all__ = ["Kernel", "MotionPlan", "Settings", "Step", "kernel", "motion_plan", "step"]
