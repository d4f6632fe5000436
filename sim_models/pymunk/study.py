"""Solver-setting study: how the pymunk force error depends on iterations, dt and error bias.

Each row varies one setting from the backend's default and reports the
relative force error against the analytic backend (the independent
reference; the study only *measures* it, nothing is tuned toward it), the
steps taken and the wall time.

Error measure (also used by the tests): for each quantity,
|sim − ref| / max(|ref|, scale), scale being the largest |ref| among that
case's quantities of the same kind (forces, or torques); the row reports the
largest over all quantities.

The driven rows vary the *starting* settings: the driven backend raises the
iterations (with the lead-in) until its readings are smooth and checks every
reading against one at dt/2, reporting the finer one (see
:mod:`sim_models.pymunk.dynamics`), so ``iterations`` and ``dt`` there are the
first rung and the coarse step, and the error is that of the accepted reading.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass

from analytic.case import Case, Motion
from analytic.forces import solve
from analytic.solution import Solution, quantity_kind
from sim_models.pymunk.dynamics import DRIVEN, drive
from sim_models.pymunk.seeds import e1
from sim_models.pymunk.settings import SETTLE, SolverSettings
from sim_models.pymunk.settle import settle


def relative_errors(sim: Mapping[str, float], ref: Mapping[str, float]) -> dict[str, float]:
    """Per-quantity relative error of forces and torques, with the per-kind scale."""
    scale: dict[str, float] = {}
    for q, v in ref.items():
        kind = quantity_kind(q)
        scale[kind] = max(scale.get(kind, 0.0), abs(v))
    return {q: abs(sim[q] - ref[q]) / max(abs(ref[q]), scale[quantity_kind(q)], 1e-300)
            for q in sim if q in ref and quantity_kind(q) != "pose"}


def max_relative_error(sim: Solution, ref: Solution) -> float:
    """The largest per-quantity relative error (inf if the run produced no forces)."""
    errors = relative_errors(sim.values, ref.values)
    return max(errors.values()) if errors else float("inf")


@dataclass(frozen=True)
class Row:
    """One study row."""

    run: str
    setting: str
    value: float
    status: str
    steps: int
    error: float
    wall_ms: float


def dynamic_e1() -> Case:
    """E1 with masses, turning at −10 rad/s and 50 rad/s² (a driven run)."""
    from analytic.case import Mass

    return e1().with_(masses=(Mass(2, 1.0, (0.04, 0.0), 1e-3), Mass(3, 2.0, (0.05, 0.01), 2e-3),
                              Mass(4, 1.5, (0.06, 0.0), 2e-3)),
                      motion=Motion(omega=-10.0, alpha=50.0))


#: (run name, case, backend function, default settings, {setting: values}).
STUDY: list[tuple[str, Callable[[], Case], Callable[[Case, SolverSettings], Solution],
                  SolverSettings, dict[str, tuple[float, ...]]]] = [
    ("settle E1", e1, settle, SETTLE, {
        "iterations": (5, 10, 30, 100, 300),
        "dt": (1e-3, 1e-2, 1e-1, 1.0),
        "error_bias": (0.9**60, 1e-3, 1e-6, 1e-12, 0.0),
    }),
    ("driven E1 ω=−10, α=50", dynamic_e1, drive, DRIVEN, {
        "iterations": (10, 30, 100),
        "dt": (1e-3, 3e-4, 1e-4, 3e-5),
        "error_bias": (0.9**60, 1e-300, 0.0),
    }),
]


def settings_study() -> list[Row]:
    """Run every study row; returns the table."""
    rows = []
    for run, make_case, backend, default, grid in STUDY:
        case = make_case()
        ref = solve(case)
        for setting, values in grid.items():
            for value in values:
                changed = default.with_(**{setting: value})
                if setting == "iterations":
                    changed = changed.with_(iterations=int(value))
                start = time.perf_counter()
                sol = backend(case, changed)
                wall = (time.perf_counter() - start) * 1e3
                rows.append(Row(run, setting, value, sol.status,
                                int(sol.diagnostics.get("steps", 0)),
                                max_relative_error(sol, ref) if sol.status == "ok" else float("nan"),
                                wall))
    return rows


def markdown(rows: list[Row]) -> str:
    """The study as a Markdown table."""
    lines = ["| run | setting | value | status | steps | max rel. error | wall ms |",
             "|---|---|---|---|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r.run} | {r.setting} | {r.value:.3g} | {r.status} | {r.steps} | "
                     f"{r.error:.1e} | {r.wall_ms:.1f} |")
    return "\n".join(lines)
