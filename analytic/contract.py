"""The one contract every backend meets, declared where the backend lives.

A backend is a value: its name, its single-case solve, its sweep, the tolerance family it
is judged by and the distribution it needs. The analytic backends declare theirs in
:mod:`mechcheck.analytic.backends`; each simulator package (a folder of ``sim_models/``)
declares its own as ``BACKENDS`` in its ``__init__``; :mod:`mechcheck.backends` finds them
all. Functions are named as ``"module:function"`` and imported only when called, so that
listing the backends (``mechcheck backends``, ``--help``) imports no simulator and no numpy.

What the functions take and return:

- ``solve``: ``(Case) -> Solution``, one linkage case at its own pose;
- ``simulate``: ``(Case) -> tuple[Trajectory, ...]``, a trajectory case's runs, one per
  setting of the backend's ladder (the reference: one);
- ``sweep``: over a linkage's first driver's values (rad or m from the drawn pose),
  vectorised: ``(Case, values) -> LinkageResults``; a simulator's:
  ``(Case, values, backend name) -> list[Solution]``, one per pose.

A backend sees only linkages: :meth:`Backend.solver` and :meth:`Backend.sweeper` run a
four-bar or slider-crank as its linkage and read it under the preset's names
(:mod:`mechcheck.analytic.presets`), the same way for every backend.

The harness calls a backend only at poses that pass the pose gate (:func:`mechcheck.run.gated`,
:func:`mechcheck.sweep.gated_poses`): where the reference's pose analysis says ``singular``,
``indeterminate`` or ``no_solution``, no other backend is called and each reports that
verdict.
"""

from __future__ import annotations

import functools
import importlib
import importlib.util
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

if TYPE_CHECKING:
    import numpy as np

    from mechcheck.analytic.case import Case
    from mechcheck.analytic.solution import Solution
    from mechcheck.analytic.trajectory import Trajectory

#: How a backend's numbers are judged (the tolerance policy's rows,
#: :mod:`mechcheck.tolerance`): ``reference`` (the analytic backend, which the others are
#: compared with), ``analytic`` (the same equations by other algebra), ``exact_solve``
#: (a simulator's constraint forces at the exact analytic pose) and ``settled`` (a
#: simulation held until it settles, or driven).
Family = Literal["reference", "analytic", "exact_solve", "settled"]


class BackendUnavailable(LookupError):
    """An unknown backend, one whose module is not there, or a sweep it does not have."""


def resolve(target: str) -> Callable[..., Any]:
    """The function a ``"module:function"`` reference names, imported now."""
    module, function = target.split(":")
    try:
        found: Callable[..., Any] = getattr(importlib.import_module(module), function)
    except (ImportError, AttributeError) as error:
        raise BackendUnavailable(f"{target!r} is not available: {error}") from None
    return found


@dataclass(frozen=True)
class Backend:
    """One backend, as its package declares it."""

    name: str
    #: ``"module:function"``: ``(Case) -> Solution``, of a linkage case.
    solve: str
    family: Family
    #: One line for ``mechcheck backends``.
    summary: str = ""
    #: ``"module:function"`` of its sweep of a linkage's first driver (None: it has none).
    sweep: str | None = None
    #: True: the sweeps are vectorised solvers returning arrays; False: a simulator's,
    #: returning one Solution per pose.
    vectorised: bool = False
    #: The importable package it needs (None: nothing beyond mechcheck's own).
    requires: str | None = None
    #: ``"module:function"`` of its run of a trajectory case (None: it has none):
    #: ``(Case) -> tuple[Trajectory, ...]``, one per setting of its ladder
    #: (:mod:`mechcheck.analytic.trajectory`).
    simulate: str | None = None

    def missing_requirement(self) -> str | None:
        """The package this backend needs and this installation lacks, if any (looked up
        without importing it)."""
        if self.requires and importlib.util.find_spec(self.requires) is None:
            return self.requires
        return None

    def solver(self) -> Callable[[Case], Solution]:
        """Its single-case solve, imported now; a preset runs as its linkage."""
        return functools.partial(solve_any, self._load(self.solve, ""), self.name)

    def sweeper(self) -> Callable[..., Any] | None:
        """Its sweep (None if it has none), imported now: over a linkage's first driver, or
        a preset's θ12 (rad) run as its linkage's driver (:mod:`.presets`); vectorised:
        ``(Case, grid)``, a simulator's ``(Case, grid, backend)``."""
        if self.sweep is None:
            return None
        sweep = self._load(self.sweep, " sweep")
        solve = self._load(self.solve, "")
        return functools.partial(vector_sweep_any if self.vectorised else sweep_any, sweep, solve,
                                 self.name)

    def simulator(self) -> Callable[[Case], tuple[Trajectory, ...]] | None:
        """Its run of a trajectory case (None if it has none), imported now."""
        if self.simulate is None:
            return None
        found: Callable[[Case], tuple[Trajectory, ...]] = self._load(self.simulate, " simulate")
        return found

    def _load(self, target: str, what: str) -> Callable[..., Any]:
        missing = self.missing_requirement()
        if missing:
            raise BackendUnavailable(f"backend {self.name!r} is not available: {missing} is "
                                     "not installed")
        try:
            return resolve(target)
        except BackendUnavailable as error:
            raise BackendUnavailable(f"backend {self.name!r}{what}: {error}") from None


def solve_any(solve: Callable[[Case], Solution], name: str, case: Case) -> Solution:
    """A backend's ``solve`` (of linkages) on any case: a preset as its linkage."""
    if case.is_preset:
        from mechcheck.analytic.presets import solve_preset

        return solve_preset(case, solve, name)
    return solve(case)


def vector_sweep_any(sweep: Callable[..., Any], solve: Callable[[Case], Solution], name: str,
                     case: Case, grid: np.ndarray) -> Any:
    """A vectorised backend's ``sweep`` (of linkages) on any case: a preset's θ12 grid run
    as its linkage's (:func:`~mechcheck.analytic.presets.preset_results`)."""
    if case.is_preset:
        from mechcheck.analytic.presets import preset_results

        return preset_results(case, grid, name, sweep, solve)
    return sweep(case, grid)


def sweep_any(sweep: Callable[..., list[Solution]], solve: Callable[[Case], Solution], name: str,
              case: Case, grid: np.ndarray, backend: str) -> list[Solution]:
    """A simulator's ``sweep`` (of linkages) on any case: a preset's θ12 grid run as its
    linkage's (:func:`~mechcheck.analytic.presets.sweep_preset`)."""
    if case.is_preset:
        from mechcheck.analytic.case import preset_of
        from mechcheck.analytic.presets import sweep_preset

        # A simulator drives a moving or Coulomb-friction preset pose by pose (each is a run
        # of its own from the pose); held statics run as the linkage's sweep.
        return sweep_preset(case, grid, backend, sweep, solve,
                            one_by_one=preset_of(case).is_moving or case.has_coulomb_friction)
    return sweep(case, grid, backend)
