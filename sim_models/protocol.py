"""The shape of a simulator package: what a folder of ``sim_models/`` declares in its
``__init__`` (as ``SIMULATOR``), so that the harness and the studies iterate over whatever
simulators are installed and name none.

A simulator is its backends (each a :class:`~mechcheck.analytic.contract.Backend`: a
single-case solve and a sweep, on linkages) and its own constraint-stiffness experiment
for the rigid-joints study. Functions are named as ``"module:function"`` and imported only
when called, so that declaring a simulator imports neither it nor numpy.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from mechcheck.analytic.contract import Backend, resolve

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.axes import Axes

    from mechcheck.analytic.case import Case

#: How far a simulator's forces are from the analytic ones: (case, values) -> the largest
#: relative error over forces and torques (the comparison's measure, given by the harness).
ErrorOf = Callable[["Case", Mapping[str, float]], float]


@dataclass(frozen=True)
class StiffnessStudy:
    """One simulator's part of the rigid-joints study.

    ``rows``: one per setting and reading, with the keys ``simulator``, ``setting``,
    ``parameter``, ``value``, ``reading`` and ``error``; ``draw`` puts them on one panel of
    the study's figure; ``conclusion`` is one sentence from them."""

    rows: list[dict[str, object]]
    draw: Callable[[Axes, pd.DataFrame], None]
    conclusion: Callable[[pd.DataFrame], str]


@dataclass(frozen=True)
class Simulator:
    """A simulator package: its name, its backends, and its stiffness experiment
    (``"module:function"``: ``(static case, driven case, quick, error_of) ->``
    :class:`StiffnessStudy`)."""

    name: str
    backends: tuple[Backend, ...]
    stiffness: str
    #: The importable package it needs.
    requires: str

    @property
    def available(self) -> bool:
        return all(b.missing_requirement() is None for b in self.backends)

    def stiffness_study(self, case: Case, driven: Case, quick: bool,
                        error_of: ErrorOf) -> StiffnessStudy:
        study: Any = resolve(self.stiffness)(case, driven, quick, error_of)
        return study


def held_and_exact(name: str, module: str, held: str, exact: str, stiffness: str) -> Simulator:
    """The usual simulator package: the backend ``name`` (held until settled, or driven:
    tolerance family ``settled``; it also runs trajectory cases) and ``name_solve`` (forces
    at the analytic pose: ``exact_solve``), their functions ``settle``, ``solve_at_pose``,
    ``sweep`` and ``simulate`` in
    ``module``, described by ``held`` and ``exact``; both need the package ``name``."""
    return Simulator(name, (
        Backend(name, f"{module}:settle", "settled", held, sweep=f"{module}:sweep", requires=name,
                simulate=f"{module}:simulate"),
        Backend(f"{name}_solve", f"{module}:solve_at_pose", "exact_solve", exact,
                sweep=f"{module}:sweep", requires=name),
    ), stiffness, requires=name)
