"""Run trajectory cases (``mechcheck simulate``) and reach a verdict.

Every backend with a trajectory run (:meth:`~mechcheck.analytic.contract.Backend.simulator`)
runs each case: the analytic reference once, a simulator once per rung of its ladder of
settings. Every run's numbers are read the same way (:meth:`Trajectory.quantities`), and a
rung's error is the worst, over the output times and the position quantities, of its
difference from the reference: x_ and y_ of points and q_ of sliding joints over the case's
scale, phi_ and q_ of turning joints in rad. A simulator's verdict is that of its finest
rung (the last), within the policy's trajectory tolerance (:mod:`mechcheck.tolerance`); the
reference's own check is its energy balance. The outcome is a :class:`SimulateResult`, a
:class:`~mechcheck.run.RunResult` whose comparison rows are the finest rungs' worst errors
per quantity, so that the summary, the exit status, JUnit and the report's first screen are
``run``'s.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from mechcheck import backends as registry
from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage import Linkage
from mechcheck.analytic.linkage_backends import quantity_units
from mechcheck.analytic.solution import Solution, kind_of_unit, table_values, unit_factor, wraps
from mechcheck.analytic.trajectory import Trajectory
from mechcheck.analytic.values import GROUND
from mechcheck.run import RunResult, crash_message, non_finite_message
from mechcheck.tables import COMPARISON_COLUMNS, ordered
from mechcheck.tolerance import ENERGY, TRAJECTORY, of_tolerance, tolerance_for
from mechcheck.verdicts import DEFAULT_FAIL_ON, Progress

#: The comparison rows' columns: ``run``'s, the time of the worst error, and the provenance
#: the report shows.
DETAIL_COLUMNS = [*COMPARISON_COLUMNS, "time", "atol", "case_kind", "reason", "overridden",
                  "of_tolerance"]
#: ``comparison.csv`` of a simulate run: ``run``'s columns and the time (s) of the worst error.
TRAJECTORY_COMPARISON_COLUMNS = [*COMPARISON_COLUMNS, "time"]
#: One row per run (rung) of a backend on a case: accuracy against cost.
RUNG_COLUMNS = ["case", "backend", "rung", "settings", "default", "status", "error", "quantity",
                "time", "wall_time", "steps", "message"]

#: The file of a simulate run that ``run`` does not write: one row per run (its long table of
#: every run's quantities at every output time is ``cli.TRAJECTORIES``).
RUNS_FILE = "runs.csv"

#: The quantity of the reference's energy check in the comparison table.
ENERGY_RESIDUAL = "energy_residual"


@dataclass(frozen=True)
class SimulateResult(RunResult):
    """The outcome of :func:`simulate`: ``run``'s result, whose ``solutions`` are each
    backend's verdict on each case (no values: the numbers are the trajectories) and whose
    ``detail`` holds the finest rungs' worst errors per quantity and the reference's energy
    check; with every run (``trajectories``, by case and backend) and the rungs' table."""

    trajectories: Mapping[str, Mapping[str, tuple[Trajectory, ...]]] = field(
        default_factory=dict, repr=False)
    rungs: pd.DataFrame = field(default_factory=lambda: pd.DataFrame(columns=RUNG_COLUMNS),
                                repr=False)

    @property
    def comparison(self) -> pd.DataFrame:
        """The comparison table exactly as ``comparison.csv`` holds it (table units)."""
        return self.detail[TRAJECTORY_COMPARISON_COLUMNS]

    def table(self) -> pd.DataFrame:
        """Every run's quantities at every output time, long: case, backend, rung, time,
        quantity, value (table units: m, degrees; joint coordinates keep their turns)."""
        cases = {c.name: c for c in self.cases}
        parts = [trajectory_rows(cases[name], backend, rung, run)
                 for name, by_backend in self.trajectories.items()
                 for backend, runs in by_backend.items() for rung, run in enumerate(runs)]
        if not parts:
            return pd.DataFrame({"case": [], "backend": [], "rung": [], "time": [],
                                 "quantity": [], "value": []})
        table = pd.concat(parts, ignore_index=True)   # categories differing by case: objects
        for column in ("case", "backend", "quantity"):
            table[column] = table[column].astype("category")
        return table


def trajectory_rows(case: Case, backend: str, rung: int, run: Trajectory) -> pd.DataFrame:
    """One run's quantities, one row per (time, quantity), in table units."""
    quantities = run.quantities(case.linkage)
    units = quantity_units(case.linkage)
    names = ordered(quantities)
    times = np.asarray(run.times, dtype=float)
    values = np.concatenate([table_values(q, quantities[q], units[q]) for q in names]) \
        if names else np.zeros(0)
    # The names as codes into their categories: a long table holds millions of rows.
    codes = np.repeat(np.arange(len(names), dtype=np.int32), len(times))
    return pd.DataFrame({"case": case.name, "backend": backend, "rung": rung,
                         "time": np.tile(times, len(names)),
                         "quantity": pd.Categorical.from_codes(codes, categories=pd.Index(names)),
                         "value": values})


@dataclass(frozen=True)
class RunError:
    """A run's worst difference from the reference: per quantity, its largest error over the
    output times (positions over the case's scale, angles in rad) and where it was."""

    errors: dict[str, float]      # quantity → worst error
    at: dict[str, int]            # quantity → index of the output time of its worst error

    @property
    def worst(self) -> str | None:
        """The quantity of the largest error (a NaN first: it never passes)."""
        return max(self.errors, key=lambda q: (math.isnan(self.errors[q]), self.errors[q]),
                   default=None)

    @property
    def value(self) -> float:
        worst = self.worst
        return math.nan if worst is None else self.errors[worst]


def compared(linkage: Linkage, quantities: Iterable[str]) -> list[str]:
    """The quantities a run is judged by, in table order: all but the positions of points on
    the ground, which no backend moves."""
    fixed = {f"{axis}_{point}" for point, link in linkage.carriers.items() if link == GROUND
             for axis in "xy"}
    return ordered(set(quantities) - fixed)


def run_error(case: Case, reference: Trajectory, run: Trajectory) -> RunError:
    """``run``'s error against ``reference``: per quantity, the worst over the output times."""
    ref, own = reference.quantities(case.linkage), run.quantities(case.linkage)
    units = quantity_units(case.linkage)
    errors: dict[str, float] = {}
    at: dict[str, int] = {}
    for q in compared(case.linkage, set(ref) & set(own)):
        diff = np.asarray(own[q], dtype=float) - np.asarray(ref[q], dtype=float)
        if wraps(q, units[q]):   # a link's direction: modulo a turn
            diff = np.remainder(diff + math.pi, math.tau) - math.pi
        error = np.abs(diff) / (case.scale if units[q] == "m" else 1.0)
        if not len(error):
            continue
        # A NaN is the worst an error can be: it never passes.
        index = int(np.argmax(np.where(np.isnan(error), np.inf, error)))
        errors[q], at[q] = float(error[index]), index
    return RunError(errors, at)


def comparison_rows(case: Case, reference: Trajectory, run: Trajectory,
                    backend: str) -> list[dict[str, object]]:
    """A simulator's finest run against the reference: one row per quantity, at the time of
    its worst error, in table units, with the policy's trajectory tolerance."""
    found = run_error(case, reference, run)
    ref, own = reference.quantities(case.linkage), run.quantities(case.linkage)
    units = quantity_units(case.linkage)
    rows: list[dict[str, object]] = []
    for q, rel_err in found.errors.items():
        i, unit = found.at[q], units[q]
        tol = tolerance_for(case, backend, q, TRAJECTORY, kind_of_unit(unit))
        abs_err = rel_err * (case.scale if unit == "m" else 1.0)
        value, reference_value = (float(table_values(q, v[q][i], unit)) for v in (own, ref))
        rows.append({
            "case": case.name, "quantity": q, "backend": backend, "value": value,
            "reference": reference_value, "abs_err": abs_err * unit_factor(unit),
            "rel_err": rel_err, "tolerance": tol.rtol,
            "passed": bool(rel_err <= tol.rtol or abs_err <= tol.atol),
            "time": float(run.times[i]), "atol": tol.atol, "case_kind": TRAJECTORY,
            "reason": tol.reason, "overridden": tol.overridden,
            "of_tolerance": of_tolerance(rel_err, abs_err, tol.rtol, tol.atol),
        })
    return rows


def energy_row(case: Case, reference: Trajectory) -> dict[str, object] | None:
    """The reference's own check: the largest residual of its energy balance over the
    largest energy term met, within the policy's energy tolerance; None when it reports no
    energy balance."""
    energy = reference.energy
    if energy is None:
        return None
    residual = np.abs(energy.residual)
    worst = float(np.max(np.where(np.isnan(residual), np.inf, residual))) if residual.size else 0.0
    scale = energy.scale
    rel_err = worst / scale if scale > 0 else (0.0 if worst == 0 else math.inf)
    tol = tolerance_for(case, registry.REFERENCE, ENERGY_RESIDUAL, TRAJECTORY, ENERGY)
    index = int(np.argmax(np.where(np.isnan(residual), np.inf, residual))) if residual.size else 0
    return {"case": case.name, "quantity": ENERGY_RESIDUAL, "backend": registry.REFERENCE,
            "value": worst, "reference": 0.0, "abs_err": worst, "rel_err": rel_err,
            "tolerance": tol.rtol, "passed": bool(rel_err <= tol.rtol or worst <= tol.atol),
            "time": float(reference.times[index]) if len(reference.times) else math.nan,
            "atol": tol.atol, "case_kind": TRAJECTORY, "reason": tol.reason,
            "overridden": tol.overridden,
            "of_tolerance": of_tolerance(rel_err, worst, tol.rtol, tol.atol)}


def no_trajectory_message(name: str) -> str:
    """Why a backend without a trajectory run is not run on a trajectory case."""
    simulators = [n for n, b in registry.REGISTRY.items()
                  if b.simulate is not None and n != registry.REFERENCE]
    return (f"{name} solves one pose and has no run over time (the backends that simulate: "
            f"{', '.join(simulators) or 'none installed'})")


def run_backend(name: str, case: Case) -> tuple[Trajectory, ...] | Solution:
    """Backend ``name``'s runs of ``case``, or the verdict that it gave none: not applicable
    (no trajectory run), or an error (it is missing, crashed or returned nothing)."""
    backend = registry.get(name)
    if backend.simulate is None:
        return Solution(case.name, name, {}, status="not_applicable",
                        message=no_trajectory_message(name))
    try:
        simulator = backend.simulator()
        assert simulator is not None
        runs = tuple(simulator(case))
    except Exception as error:
        return Solution(case.name, name, {}, status="error", message=crash_message(error))
    if not runs:
        return Solution(case.name, name, {}, status="error",
                        message=f"{name} returned no run of the trajectory")
    return runs


def verdict(case: Case, name: str, runs: tuple[Trajectory, ...]) -> Solution:
    """A backend's verdict on a trajectory case, from its finest run (the last): its own
    status; ``error`` where it claims ``ok`` with a number that is not finite, or at times
    other than the case's; its diagnostics, wall time and steps."""
    finest = runs[-1]
    diagnostics: dict[str, float | str] = {**finest.diagnostics, "wall_time_s": finest.wall_time,
                                           "steps": float(finest.steps), "rungs": float(len(runs))}
    if finest.status != "ok":
        return Solution(case.name, name, {}, status=finest.status,
                        message=finest.message or f"{name} gave no trajectory",
                        diagnostics=diagnostics)
    expected = np.asarray(case.simulation.outputs if case.simulation else (), dtype=float)
    times = np.asarray(finest.times, dtype=float)
    if times.shape != expected.shape or not np.allclose(times, expected, rtol=0.0,
                                                        atol=1e-12 * max(1.0, expected[-1])):
        return Solution(case.name, name, {}, status="error", diagnostics=diagnostics,
                        message=f"{name} reported {len(times)} times, not the case's "
                                f"{len(expected)} output times")
    coordinates = np.asarray(finest.coordinates, dtype=float)
    if coordinates.size == 0 or not np.isfinite(coordinates).all():
        return Solution(case.name, name, {}, status="error", diagnostics=diagnostics,
                        message=non_finite_message(name, ["coordinates"]))
    return Solution(case.name, name, {}, diagnostics=diagnostics)


def settings_text(settings: Mapping[str, object]) -> str:
    """A run's settings in one cell: ``dt=0.001, integrator=RK4``."""
    return ", ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}"
                     for k, v in settings.items())


def rung_rows(case: Case, name: str, runs: tuple[Trajectory, ...],
              reference: Trajectory | None) -> list[dict[str, object]]:
    """Each run of a backend on a case: its settings, error against the reference (NaN
    where either gave no number), wall time and steps."""
    rows: list[dict[str, object]] = []
    for index, run in enumerate(runs):
        error = RunError({}, {})
        comparable = reference is not None and run is not reference and run.status == "ok" \
            and np.shape(run.coordinates) == np.shape(reference.coordinates)
        if comparable and reference is not None:
            error = run_error(case, reference, run)
        worst = error.worst
        rows.append({"case": case.name, "backend": name, "rung": index,
                     "settings": settings_text(run.settings), "default": bool(run.default),
                     "status": run.status, "error": error.value, "quantity": worst or "",
                     "time": float(run.times[error.at[worst]]) if worst else math.nan,
                     "wall_time": float(run.wall_time), "steps": int(run.steps),
                     "message": run.message})
    return rows


def simulate(cases: Sequence[Case], backend_names: Sequence[str], *,
             progress: Progress | None = None,
             fail_on: Sequence[str] = DEFAULT_FAIL_ON) -> SimulateResult:
    """Every backend on every trajectory case; the reference backend always runs."""
    names = list(dict.fromkeys([registry.REFERENCE, *backend_names]))
    start = time.perf_counter()
    solutions: list[Solution] = []
    found: dict[str, dict[str, tuple[Trajectory, ...]]] = {}
    detail: list[dict[str, object]] = []
    rungs: list[dict[str, object]] = []
    total, done = len(cases) * len(names), 0
    for case in cases:
        reference: Trajectory | None = None
        for name in names:
            outcome = run_backend(name, case)
            if isinstance(outcome, Solution):
                solutions.append(outcome)
            else:
                found.setdefault(case.name, {})[name] = outcome
                solution = verdict(case, name, outcome)
                solutions.append(solution)
                if name == registry.REFERENCE and solution.status == "ok":
                    reference = outcome[-1]
                    energy = energy_row(case, reference)
                    detail += [energy] if energy else []
                elif reference is not None and solution.status == "ok":
                    detail += comparison_rows(case, reference, outcome[-1], name)
                rungs += rung_rows(case, name, outcome, reference)
            done += 1
            if progress:
                progress(done, total, f"{case.name} · {name}")
    return SimulateResult(list(cases), solutions, pd.DataFrame(detail, columns=DETAIL_COLUMNS),
                          time.perf_counter() - start, tuple(fail_on), found,
                          pd.DataFrame(rungs, columns=RUNG_COLUMNS))
