"""Run backends over cases and reach a verdict.

Exit statuses (CONVENTIONS.md): 0 every comparison within tolerance, 1 any
not (or a backend verdict listed in ``fail_on``), 2 unusable input.
"""

from __future__ import annotations

import dataclasses
import math
import time
import traceback
from collections.abc import Sequence
from dataclasses import dataclass, field

import pandas as pd

from mechcheck import backends as registry
from mechcheck.analytic.case import Case
from mechcheck.analytic.solution import Solution
from mechcheck.tables import COMPARISON_COLUMNS, comparison_detail
from mechcheck.verdicts import DEFAULT_FAIL_ON, Progress, without_numbers


@dataclass(frozen=True)
class RunResult:
    """The outcome of :func:`run`: every Solution, the comparison and the exit status."""

    cases: list[Case]
    solutions: list[Solution]
    detail: pd.DataFrame = field(repr=False)
    wall_time_s: float
    fail_on: tuple[str, ...] = DEFAULT_FAIL_ON

    @property
    def comparison(self) -> pd.DataFrame:
        """The comparison table exactly as ``comparison.csv`` holds it (table units)."""
        return self.detail[COMPARISON_COLUMNS]

    @property
    def failed_comparisons(self) -> pd.DataFrame:
        return self.detail[~self.detail["passed"].astype(bool)]

    @property
    def failing_verdicts(self) -> list[Solution]:
        return [s for s in self.solutions if s.status in self.fail_on]

    @property
    def exit_status(self) -> int:
        return 1 if len(self.failed_comparisons) or self.failing_verdicts else 0

    @property
    def nothing_compared(self) -> str | None:
        """Why no number was compared with the reference, or None when something was."""
        if len(self.detail):
            return None
        if not {s.backend for s in self.solutions} - {registry.REFERENCE}:
            return f"only the reference backend ({registry.REFERENCE}) ran"
        return "no backend gave a number the reference gave too (see the verdicts)"

    @property
    def summary(self) -> str:
        """The run in one line, as the command line prints it: what was compared, and every
        backend verdict that gave no number (a PASS with none compared says why)."""
        word = "PASS" if self.exit_status == 0 else "FAIL"
        n = f"{len(self.cases)} case{'s' if len(self.cases) != 1 else ''}"
        verdicts = f"{len(self.failing_verdicts)} failing verdicts"
        absent = without_numbers((s.status, s.case) for s in self.solutions)
        if absent:
            verdicts += f"; no numbers: {absent}"
        if self.nothing_compared:
            return f"{n}, nothing compared: {self.nothing_compared}; {verdicts} ({word})"
        return (f"{n}, {len(self.detail)} comparisons, {len(self.failed_comparisons)} outside "
                f"tolerance, {verdicts} ({word})")


#: The reference's verdicts that are properties of the pose: there no backend has forces to
#: give (SIMULATORS.md: a simulator there returns finite but meaningless numbers).
POSE_VERDICTS = ("singular", "indeterminate", "no_solution")


def gated(reference: Solution, name: str) -> Solution | None:
    """The pose gate, run once per case before any other backend: where the reference's pose
    analysis found no unique forces, backend ``name`` is not called and reports the same
    verdict; else None."""
    if reference.status not in POSE_VERDICTS:
        return None
    diagnostics = {k: v for k, v in reference.diagnostics.items() if k == "condition_number"}
    return Solution(reference.case, name, {}, status=reference.status,
                    message=gated_message(reference.message, reference.backend),
                    diagnostics=diagnostics, units=reference.units)


def gated_message(message: str, reference: str) -> str:
    """The message of a backend not run at a pose the reference gave a pose verdict."""
    return f"{message}; not run (the pose verdict of {reference})"


def solve_gated(name: str, case: Case, reference: Solution | None = None) -> Solution:
    """Backend ``name`` on ``case`` behind the pose gate (:func:`gated`); the reference is
    computed here unless given."""
    if reference is None:
        reference = call_backend(registry.load(registry.REFERENCE), registry.REFERENCE, case)
    if name == registry.REFERENCE:
        return reference
    return gated(reference, name) or call_backend(registry.load(name), name, case)


def call_backend(backend: registry.SolveFunction, name: str, case: Case) -> Solution:
    """Run one backend; a crash becomes an ``error`` verdict, not a lost run, and a number
    that is not finite never passes (:func:`finite_only`)."""
    try:
        return finite_only(backend(case))
    except Exception as error:
        return Solution(case.name, name, {}, status="error", message=crash_message(error))


def crash_message(error: BaseException) -> str:
    """A backend's crash in one line: the exception's last line."""
    return traceback.format_exception_only(error)[-1].strip()


def finite_only(solution: Solution) -> Solution:
    """A Solution whose every value is finite.

    A backend that has a verdict simply has no number for what is not finite (the
    contract writes no row rather than a NaN). A backend that claims ``ok`` with a
    NaN or an infinity has failed: its verdict becomes ``error``, naming the quantities.
    """
    bad = [q for q, v in solution.values.items() if not math.isfinite(v)]
    if not bad:
        return solution
    finite = {q: v for q, v in solution.values.items() if math.isfinite(v)}
    if solution.status != "ok":
        return dataclasses.replace(solution, values=finite)
    return dataclasses.replace(solution, values={}, status="error",
                               message=non_finite_message(solution.backend, bad))


def non_finite_message(backend: str, quantities: Sequence[str]) -> str:
    """The ``error`` verdict's message of a backend that gave a number that is not finite."""
    return (f"{backend} produced non-finite {', '.join(quantities)} (NaN or infinity): the "
            "numbers overflowed or the method broke down; no number is reported")


def run(cases: Sequence[Case], backend_names: Sequence[str], *,
        progress: Progress | None = None, fail_on: Sequence[str] = DEFAULT_FAIL_ON) -> RunResult:
    """Every backend on every case; the reference backend always runs."""
    names = list(dict.fromkeys([registry.REFERENCE, *backend_names]))
    functions = {n: registry.load(n) for n in names}
    start = time.perf_counter()
    solutions: list[Solution] = []
    total, done = len(cases) * len(names), 0
    for case in cases:
        reference = call_backend(functions[registry.REFERENCE], registry.REFERENCE, case)
        for name in names:
            solution = reference if name == registry.REFERENCE else (
                gated(reference, name) or call_backend(functions[name], name, case))
            solutions.append(solution)
            done += 1
            if progress:
                progress(done, total, f"{case.name} · {name}")
    detail = comparison_detail(cases, solutions)
    return RunResult(list(cases), solutions, detail, time.perf_counter() - start, tuple(fail_on))
