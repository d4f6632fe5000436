"""A simulator's backend functions as the harness calls them: the registry's contract runs a
four-bar or slider-crank as its linkage (:mod:`mechcheck.analytic.contract`), so a test
can give either kind of case to either function."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from mechcheck.analytic.case import Case
from mechcheck.analytic.contract import solve_any, sweep_any
from mechcheck.analytic.solution import Solution


def solver(solve: Callable[..., Solution], name: str) -> Callable[..., Solution]:
    """``solve(case, *settings)`` of backend ``name``, on any case."""
    def call(case: Case, *args: Any, **kwargs: Any) -> Solution:
        return solve_any(lambda c: solve(c, *args, **kwargs), name, case)
    return call


def sweeper(sweep: Callable[..., list[Solution]], solves: dict[str, Callable[..., Solution]],
            default: str) -> Callable[..., list[Solution]]:
    """``sweep(case, grid, backend)`` of a simulator, on any case (``solves``: each backend's
    single-pose solve, for the poses a preset runs one by one)."""
    def call(case: Case, grid: ArrayLike, backend: str = default) -> list[Solution]:
        return sweep_any(sweep, solves[backend], backend, case, np.asarray(grid, dtype=float),
                         backend)
    return call
