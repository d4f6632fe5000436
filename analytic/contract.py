"""The one contract every backend meets, declared where the backend lives.

A backend is a value: its name, its single-case solve, its sweep, the tolerance family it
is judged by and the distribution it needs. The analytic backends declare theirs in
:mod:`mechcheck.analytic.backends`; each simulator package (a folder of ``sim_models/``)
declares its own as ``BACKENDS`` in its ``__init__``; :mod:`mechcheck.backends` finds them
all. Functions are named as ``"module:function"`` and imported only when called, so that
listing the backends (``mechcheck backends``, ``--help``) imports no simulator and no numpy.

What the functions take and return:

- ``solve``: ``(Case) -> Solution``, one case at its own pose;
- ``sweep``, vectorised: ``(Case, θ12 in rad) -> PoseResults``; a simulator's:
  ``(Case, θ12 in rad, backend name) -> list[Solution]``, one per pose;
- ``linkage_sweep``: the same for a linkage, over its first driver's values (rad or m from
  the drawn pose); vectorised: ``-> LinkageResults``.

The harness calls a backend only at poses that pass the pose gate (:func:`mechcheck.run.gated`,
:func:`mechcheck.sweep.gated_poses`): where the reference's pose analysis says ``singular``,
``indeterminate`` or ``no_solution``, no other backend is called and each reports that
verdict.
"""

from __future__ import annotations

import importlib
import importlib.util
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

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
    #: ``"module:function"``: ``(Case) -> Solution``.
    solve: str
    family: Family
    #: One line for ``mechcheck backends``.
    summary: str = ""
    #: ``"module:function"`` of its sweep over θ12 (None: it has none).
    sweep: str | None = None
    #: ``"module:function"`` of its sweep of a linkage's first driver (None: it has none).
    linkage_sweep: str | None = None
    #: True: the sweeps are vectorised solvers returning arrays; False: a simulator's,
    #: returning one Solution per pose.
    vectorised: bool = False
    #: The importable package it needs (None: nothing beyond mechcheck's own).
    requires: str | None = None

    def missing_requirement(self) -> str | None:
        """The package this backend needs and this installation lacks, if any (looked up
        without importing it)."""
        if self.requires and importlib.util.find_spec(self.requires) is None:
            return self.requires
        return None

    def solver(self) -> Callable[..., Any]:
        """Its single-case solve, imported now."""
        return self._load(self.solve, "")

    def sweeper(self, linkage: bool) -> Callable[..., Any] | None:
        """Its sweep of a four-bar or slider-crank (of a linkage), or None if it has none."""
        target = self.linkage_sweep if linkage else self.sweep
        return None if target is None else self._load(target, " sweep")

    def _load(self, target: str, what: str) -> Callable[..., Any]:
        missing = self.missing_requirement()
        if missing:
            raise BackendUnavailable(f"backend {self.name!r} is not available: {missing} is "
                                     "not installed")
        try:
            return resolve(target)
        except BackendUnavailable as error:
            raise BackendUnavailable(f"backend {self.name!r}{what}: {error}") from None
