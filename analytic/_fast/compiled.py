"""Compiled kernels (numba, the ``fast`` extra: ``pip install '.[fast]'``), where installed.

A kernel module does what a numpy or Python function next to it does, in the same
floating-point operations, so either gives the same numbers; the kernel only skips the
interpreter's per-call and per-step overhead. :func:`kernel` imports one if it can:
without numba, with numba unable to compile or cache here or switched off
(``NUMBA_DISABLE_JIT``), or with ``MECHCHECK_PURE_PYTHON=1`` in the environment, there is
none and the caller runs its own Python.
"""

from __future__ import annotations

import importlib
import os
from functools import cache
from types import ModuleType


@cache
def kernel(name: str) -> ModuleType | None:
    """The kernel module ``name`` (imported, which compiles or loads it), or None."""
    if os.environ.get("MECHCHECK_PURE_PYTHON", "") not in ("", "0"):
        return None
    try:
        module = importlib.import_module(name)
        from numba import config
    except (ImportError, RuntimeError):  # numba missing, or unable to compile or cache here
        return None
    # NUMBA_DISABLE_JIT runs the kernels as Python, where their raw memory access cannot.
    return None if getattr(config, "DISABLE_JIT", False) else module
