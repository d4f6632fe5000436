"""MuJoCo's warnings, routed into Python.

Without a handler MuJoCo prints its warnings and appends them to
``MUJOCO_LOG.TXT`` in whatever directory the user runs from. The handler
installed on import (this module is imported with the package) keeps them in
memory instead, and :func:`noting_warnings` moves the ones raised while a
Solution was computed into that Solution's ``warnings`` diagnostic.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import TypeVar

import mujoco

from mechcheck.analytic.solution import Solution

T = TypeVar("T")

#: Messages raised since the last :func:`noting_warnings` collected them.
_RAISED: list[str] = []


def _keep(message: str) -> None:
    _RAISED.append(message.strip())


def install() -> None:
    """Route MuJoCo's warnings here (idempotent; called on import)."""
    mujoco.set_mju_user_warning(_keep)


def raised_during(compute: Callable[[], T]) -> tuple[T, list[str]]:
    """``compute()`` and the MuJoCo warnings it raised (each once), taken off the list."""
    start = len(_RAISED)
    try:
        value = compute()
    finally:
        raised = list(dict.fromkeys(_RAISED[start:]))
        del _RAISED[start:]
    return value, raised


def noting_warnings(compute: Callable[[], Solution]) -> Solution:
    """``compute()``, with any MuJoCo warning raised meanwhile in its ``warnings`` diagnostic."""
    solution, raised = raised_during(compute)
    if not raised:
        return solution
    return dataclasses.replace(
        solution, diagnostics={**solution.diagnostics, "warnings": " | ".join(raised)})


install()
