"""Compiled kernels (numba, the ``fast`` extra): the simulators' kernels are imported through
the analytic engine's switch, :func:`mechcheck.analytic._fast.compiled.kernel`, so one
environment variable (``MECHCHECK_PURE_PYTHON=1``) turns every compiled path off."""

from mechcheck.analytic._fast.compiled import kernel

__all__ = ["kernel"]
