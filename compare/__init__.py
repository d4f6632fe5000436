"""mechcheck: the force analysis of planar mechanisms, checked against MuJoCo and pymunk.

The public Python API is these few names (README, "Python API"):

- :func:`load_cases`: the validated Cases of case files (none: the built-in suite);
- :func:`solve`: one Case through one backend, a :class:`Solution`;
- :func:`check`: Cases through backends, compared with ``analytic`` under the
  tolerance policy: a :class:`RunResult` with ``exit_status`` and ``comparison``;
- :func:`available_backends`: the backends this installation can run;
- :func:`mechcheck.testing.assert_solution_close`, for a project's own tests.

Everything else (``mechcheck.analytic``, ``mechcheck.sim_models``, the tables,
reports and CLI) is importable but may change between versions.

Examples
--------
>>> import mechcheck
>>> e1 = next(c for c in mechcheck.load_cases() if c.name == "seed-E1-as-stated")
>>> round(mechcheck.solve(e1).values["T12"], 5)
2.90133
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from mechcheck.analytic.solution import Solution
from mechcheck.analytic.values import CaseError
from mechcheck.verdicts import DEFAULT_FAIL_ON

if TYPE_CHECKING:
    from mechcheck.analytic.case import Case
    from mechcheck.run import RunResult

__all__ = ["Case", "CaseError", "RunResult", "Solution", "available_backends", "check", "load_cases", "solve"]


def load_cases(*paths: str | Path) -> list[Case]:
    """The Cases of case files (TOML), validated, in file order; no path: the built-in suite.

    A file that cannot be used raises :class:`CaseError`, whose message names the
    file, the case and the key (the same line ``mechcheck run`` prints).
    """
    from mechcheck.casefile import builtin_case_files, load_cases as load

    return load(*(paths or builtin_case_files()))


def solve(case: Case, backend: str = "analytic") -> Solution:
    """``case`` through one backend (see :func:`available_backends`); SI values, angles in
    radians. Behind the pose gate, as in ``mechcheck run``: where the analytic pose analysis
    finds no unique forces, the backend is not called and reports that verdict."""
    from mechcheck.run import solve_gated

    return solve_gated(backend, case)


def check(cases: Sequence[Case], backends: Sequence[str] | None = None, *,
          fail_on: Sequence[str] = DEFAULT_FAIL_ON) -> RunResult:
    """Every Case through every backend, compared with ``analytic`` as ``mechcheck run`` does.

    ``backends`` defaults to every available one. The result's ``exit_status`` is
    0 when everything agrees and 1 otherwise; ``comparison`` is the comparison
    table as a DataFrame, in table units (degrees), one row per quantity.
    """
    from mechcheck import backends as registry
    from mechcheck.run import run

    names = registry.available() if backends is None else list(backends)
    return run(cases, names, fail_on=fail_on)


def available_backends() -> list[str]:
    """The backends whose simulator is installed here (``analytic`` first)."""
    from mechcheck import backends as registry

    return registry.available()


def __getattr__(name: str) -> object:
    # Case (numpy) and RunResult (pandas) are imported only when asked for, so that
    # `import mechcheck`, `mechcheck --help` and the pytest plugin stay light.
    if name == "Case":
        from mechcheck.analytic.case import Case

        return Case
    if name == "RunResult":
        from mechcheck.run import RunResult

        return RunResult
    raise AttributeError(f"module 'mechcheck' has no attribute {name!r}")
