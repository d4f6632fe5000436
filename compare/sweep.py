"""Whole-cycle sweeps: every pose of every case through each backend, on any
``concurrent.futures`` executor, written to Parquet as it goes, resumable.

The work is split into tasks (case × backend × chunk of θ12). A task's
results are written as one Parquet part, atomically, the moment it finishes;
its file name carries a digest of the case, the backend and the θ12 values,
so a re-run skips every task whose part exists and recomputes only the rest
(and a changed case never reuses stale parts).

Vectorised backends (the analytic ones) solve a chunk in one call; simulator backends run
their own ``sweep`` (warm starts, continuation) over the chunk's poses that pass the pose
gate (:func:`gated_poses`). Which is which, and each backend's sweep functions, come from
the backend's declaration (:mod:`mechcheck.analytic.contract`).
"""

from __future__ import annotations

import functools
import hashlib
import io
import math
import time
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import Executor, Future, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pyarrow.parquet as pq

from mechcheck import backends as registry
from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage_backends import (
    DecidedPoses,
    pose_verdicts as linkage_verdicts,
    quantity_units,
)
from mechcheck.analytic.solution import QUANTITY_UNITS, Solution, kind_of_unit, table_values
from mechcheck.analytic.values import (
    LENGTH_UNITS,
    MAX_ANGLE_DEG,
    MAX_DRIVER_ROTATION_DEG,
    MAX_DRIVER_TRAVEL,
    length_text,
)
from mechcheck.backends import REFERENCE, BackendUnavailable
from mechcheck.output import OutputError, file_stem, write_all
from mechcheck.run import POSE_VERDICTS, crash_message, finite_only, gated_message, non_finite_message

#: The most poses a sweep takes per case: ten times the 10⁶-pose analytic sweep the
#: benchmarks time (about 8 s); a larger grid is far more likely a typo than a plan.
MAX_SWEEP_POSES = 10_000_000

#: Bump when the part format or a backend's meaning changes: old parts are then ignored.
PART_FORMAT = 3
#: Poses per task. Vector backends: large chunks keep numpy efficient while
#: parts stay small enough to resume from (≈ 0.2 s of work each). Simulators:
#: a chunk is one continuation run; 60 poses of 1° let two workers share a turn.
VECTOR_CHUNK = 200_000
SIMULATOR_CHUNK = 60

RESULT_COLUMNS = ["case", "backend", "theta12", "quantity", "value", "unit"]
#: ``theta12``: the sweep's axis, in the task's unit (:func:`driver_axis`); ``restart``: why a
#: simulator ran the pose again from the analytic pose ("" if it did not); ``wall_time_s``:
#: what the pose cost the backend (its share of a vectorised chunk).
STATUS_COLUMNS = ["case", "backend", "theta12", "status", "condition_number", "message",
                  "restart", "wall_time_s"]


@dataclass(frozen=True, eq=False)
class SweepTask:
    """One unit of work: a backend over a chunk of the sweep's axis of one case (θ12 of a
    preset, a linkage's first driver), in ``unit``: ``deg``, or a prismatic driver's ``mm``
    or ``m`` (:func:`driver_axis`).

    ``digest`` identifies the work (format, case, backend, values, unit): a part
    written under another digest is never mistaken for this task's.
    """

    case: Case
    backend: str
    theta12_deg: np.ndarray
    chunk: int
    digest: str
    unit: str = "deg"

    @property
    def part_name(self) -> str:
        return f"{file_stem(self.case.name)}__{self.backend}__{self.chunk:05d}__{self.digest}"


@functools.cache
def software_versions() -> tuple[str, ...]:
    """mechcheck's and the simulators' versions: parts from other versions are not reused.

    Computed once per process: each look-up scans every installed distribution.
    """
    from importlib.metadata import PackageNotFoundError, version

    out = []
    for package in ("mechcheck", "mujoco", "pymunk", "numpy"):
        try:
            out.append(f"{package}={version(package)}")
        except PackageNotFoundError:
            out.append(f"{package}=?")
    return tuple(out)


def task_digest(case: Case, backend: str, theta12_deg: np.ndarray, unit: str = "deg") -> str:
    h = hashlib.sha256(repr((PART_FORMAT, software_versions(), case, backend, unit)).encode())
    h.update(np.ascontiguousarray(theta12_deg, dtype=np.float64).tobytes())
    return h.hexdigest()[:16]


def parse_range(text: str, option: str = "--theta12") -> np.ndarray:
    """``START:STOP:STEP`` in degrees: START, START + STEP, … every value below STOP.

    STOP itself is excluded (``0:360:1`` is 360 poses, and a whole turn does not
    visit 0° twice), also where rounding puts it a hair inside; ``0:10:3`` is
    0, 3, 6, 9. A grid of more than :data:`MAX_SWEEP_POSES` poses is refused.
    """
    option = f"{option} {text!r}"
    try:
        start, stop, step = (float(p) for p in text.split(":"))
    except ValueError:
        raise ValueError(f"{option}: must be START:STOP:STEP in degrees, e.g. 0:360:1") from None
    if not all(math.isfinite(v) for v in (start, stop, step)):
        raise ValueError(f"{option}: START, STOP and STEP must be finite numbers")
    if step <= 0 or stop <= start:
        raise ValueError(f"{option}: needs STOP > START and STEP > 0")
    if max(abs(start), abs(stop)) > MAX_ANGLE_DEG:
        raise ValueError(f"{option}: angles must lie within ±{MAX_ANGLE_DEG:g}°")
    steps = (stop - start) / step
    count = math.ceil(steps - 1e-9 * max(1.0, steps))
    if count > MAX_SWEEP_POSES:
        raise ValueError(f"{option}: {count:,} poses; a sweep takes at most "
                         f"{MAX_SWEEP_POSES:,} per case (use a larger STEP)")
    return start + step * np.arange(count, dtype=float)


def plan(cases: Sequence[Case], backends: Sequence[str], theta12_deg: np.ndarray,
         driver_grid: np.ndarray | None = None,
         length_units: Mapping[str, str] | None = None) -> list[SweepTask]:
    """The tasks of a sweep; the reference backend is always included.

    A four-bar or slider-crank sweeps θ12 over ``theta12_deg``; a linkage sweeps its first
    driver over ``driver_grid`` (degrees of a revolute joint; a prismatic one's length in
    its case file's ``length_unit``, ``length_units[case name]``, mm if not given; from the
    drawn pose; default: the θ12 grid), its other drivers at their own values.
    """
    names = list(dict.fromkeys([REFERENCE, *backends]))
    for name in names:
        declared = registry.get(name)
        if declared.sweep is None:
            raise BackendUnavailable(f"backend {name!r} has no sweep")
    tasks = []
    for case in cases:
        grid = theta12_deg if case.is_preset or driver_grid is None else driver_grid
        unit = axis_unit(case, (length_units or {}).get(case.name, "mm"))
        if not case.is_preset:
            check_driver_grid(case, grid, "--theta12" if driver_grid is None else "--driver",
                              unit)
        for name in names:
            size = VECTOR_CHUNK if registry.get(name).vectorised else SIMULATOR_CHUNK
            for chunk, start in enumerate(range(0, len(grid), size)):
                part = np.array(grid[start:start + size], dtype=float)
                tasks.append(SweepTask(case, name, part, chunk,
                                       task_digest(case, name, part, unit), unit))
    return tasks


def slides(case: Case) -> bool:
    """Whether the sweep's axis is a length: a linkage's first driver is prismatic."""
    if case.is_preset:
        return False
    return not case.linkage.joint(case.linkage.drivers[0].joint).kind.rotates


def axis_unit(case: Case, length_unit: str = "mm") -> str:
    """The unit of a case's sweep axis: ``deg``, or ``length_unit`` for a sliding driver."""
    return length_unit if slides(case) else "deg"


def driver_axis(case: Case, unit: str) -> str:
    """The sweep axis by name and unit, as tables and figures label it: ``θ12, deg`` for a
    four-bar or slider-crank, ``rotation of O2, deg`` or ``displacement of cyl, mm`` for a
    linkage's first driver (from its drawn pose)."""
    if case.is_preset:
        return f"θ12, {unit}"
    joint = case.linkage.drivers[0].joint
    return f"{'displacement' if slides(case) else 'rotation'} of {joint}, {unit}"


def check_driver_grid(case: Case, grid: np.ndarray, option: str, unit: str = "mm") -> None:
    """Refuse a linkage's sweep grid beyond the bounds of its first driver's values (a case
    file's own bounds: :data:`~mechcheck.analytic.values.MAX_DRIVER_ROTATION_DEG` and
    :data:`~mechcheck.analytic.values.MAX_DRIVER_TRAVEL` times the linkage's size)."""
    if not case.linkage.drivers or not grid.size:
        return
    reach = float(np.abs(grid).max())
    driver = case.linkage.drivers[0]
    if case.linkage.joint(driver.joint).kind.rotates:
        if reach > MAX_DRIVER_ROTATION_DEG:
            raise ValueError(f"{option}: case '{case.name}': a rotation of {reach:g}° of "
                             f"{driver.joint}; a linkage's driver turns at most "
                             f"±{MAX_DRIVER_ROTATION_DEG:g}° (ten turns) from its drawn pose")
        return
    bound = MAX_DRIVER_TRAVEL * case.linkage.scale / LENGTH_UNITS[unit]
    if reach > bound * (1.0 + 1e-12):
        raise ValueError(f"{option}: case '{case.name}': a displacement of "
                         f"{length_text(reach * LENGTH_UNITS[unit], unit)} of {driver.joint} "
                         f"(in the case file's length_unit); a linkage's driver moves at most "
                         f"±{length_text(bound * LENGTH_UNITS[unit], unit)} "
                         f"({MAX_DRIVER_TRAVEL:g} × its size) from its drawn pose")


def check_theta12_grid(case: Case, theta12: np.ndarray) -> None:
    """Refuse a preset's θ12 (rad) beyond ±:data:`~mechcheck.analytic.values.MAX_ANGLE_DEG`,
    as a case file and ``--theta12`` are refused."""
    reach = math.degrees(float(np.abs(theta12).max())) if theta12.size else 0.0
    if reach > MAX_ANGLE_DEG:
        raise ValueError(f"driver_values: case '{case.name}': θ12 = {reach:g}°; angles must "
                         f"lie within ±{MAX_ANGLE_DEG:g}°")


UNITS = ["N", "N*m", "deg", "m"]


def units_of(case: Case) -> dict[str, str]:
    """The table unit of every quantity the case's backends report."""
    if case.is_preset:
        return {q: unit for q, (unit, _) in QUANTITY_UNITS.items()}
    return quantity_units(case.linkage)


def _long_frame(case: Case, backend: str, theta_deg: np.ndarray,
                values: dict[str, np.ndarray]) -> pd.DataFrame:
    """Long rows from per-quantity arrays (table units), dropping absent (NaN) values.

    Text columns are categorical: a 10⁶-pose sweep has 10⁷ rows.
    """
    units = units_of(case)
    quantities = list(values)
    thetas, vals, q_codes, u_codes = [], [], [], []
    for code, (quantity, array) in enumerate(values.items()):
        unit = units[quantity]
        ok = np.isfinite(array)
        thetas.append(theta_deg[ok])
        vals.append(table_values(quantity, array[ok], unit))
        q_codes.append(np.full(int(ok.sum()), code, dtype=np.int16))
        u_codes.append(np.full(int(ok.sum()), UNITS.index(unit), dtype=np.int8))
    if not thetas:
        return pd.DataFrame(columns=RESULT_COLUMNS)
    theta = np.concatenate(thetas)
    n = theta.shape[0]
    return pd.DataFrame({
        "case": _categorical(np.zeros(n, dtype=np.int8), [case.name]),
        "backend": _categorical(np.zeros(n, dtype=np.int8), [backend]),
        "theta12": theta,
        "quantity": _categorical(np.concatenate(q_codes), quantities),
        "value": np.concatenate(vals),
        "unit": _categorical(np.concatenate(u_codes), UNITS),
    })


def _categorical(codes: np.ndarray, categories: list[str]) -> pd.Categorical[Any]:
    return pd.Categorical.from_codes(codes, dtype=pd.CategoricalDtype(categories))


def grid_si(case: Case, grid: np.ndarray, unit: str = "mm") -> np.ndarray:
    """A sweep's grid in the engine's units: a preset's θ12 (deg) in rad; a linkage's (deg of
    a revolute first driver, ``unit`` of a prismatic one) in rad or m."""
    return grid * LENGTH_UNITS[unit] if slides(case) else np.radians(grid)


def vector_poses(case: Case, backend: str, grid: np.ndarray) -> DecidedPoses | None:
    """Vectorised backend ``backend`` over ``grid`` (SI: a linkage's first driver from the
    drawn pose, or a preset's θ12), behind the reference's pose gate; None where the backend
    has no sweep or its method refuses the case (Coulomb friction)."""
    solver = registry.get(backend).sweeper()
    if solver is None:
        return None
    try:
        results = solver(case, grid)
    except ValueError:  # the method refuses this case (Coulomb friction)
        return None
    statuses, messages = pose_verdicts(case, results)
    values = dict(results.values)
    if backend != REFERENCE:
        # Behind the pose gate, as `run` runs it: at the reference's pose verdict the
        # backend is not run, gives no number and repeats the reference's reason.
        verdicts, reasons, _ = reference_verdicts(case, grid)
        gated = np.isin(verdicts, POSE_VERDICTS)
        statuses = np.where(gated, np.array(verdicts, dtype=object), statuses)
        messages = np.where(gated, np.array([gated_message(r, REFERENCE) for r in reasons],
                                            dtype=object), messages)
        values = {q: np.where(gated, np.nan, v) for q, v in values.items()}
    statuses, messages = _non_finite_errors(backend, statuses, messages, values)
    # A pose with a verdict keeps its pose (as `run`'s Solution does), no force.
    units = units_of(case)
    values = {q: v if kind_of_unit(units[q]) == "pose" else np.where(statuses == "ok", v, np.nan)
              for q, v in values.items()}
    return DecidedPoses(values, statuses, messages, lambda: results.condition)


def _run_vector(task: SweepTask) -> tuple[pd.DataFrame, pd.DataFrame]:
    theta_deg = np.asarray(task.theta12_deg)
    start = time.perf_counter()
    poses = vector_poses(task.case, task.backend, grid_si(task.case, theta_deg, task.unit))
    if poses is None:
        return _not_applicable(task)
    status = pd.DataFrame({"case": task.case.name, "backend": task.backend, "theta12": theta_deg,
                           "status": poses.statuses.astype(str),
                           "condition_number": poses.condition,
                           "message": poses.messages.astype(str), "restart": "",
                           "wall_time_s": (time.perf_counter() - start) / max(len(theta_deg), 1)})
    return _long_frame(task.case, task.backend, theta_deg, poses.values), status


def _non_finite_errors(backend: str, statuses: np.ndarray, messages: np.ndarray,
                       values: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """A pose without a verdict whose values are not all finite is an ``error``, as ``run``
    judges a backend's Solution (:func:`mechcheck.run.finite_only`), and keeps no number:
    its rows are dropped from ``values`` (written in place)."""
    ok = statuses == "ok"
    bad = {q: ok & ~np.isfinite(v) for q, v in values.items()}
    broken = np.zeros(statuses.shape, dtype=bool)
    for hit in bad.values():
        broken |= hit
    if not broken.any():
        return statuses, messages
    statuses, messages = statuses.copy(), messages.copy()
    for index in np.flatnonzero(broken):
        statuses[index] = "error"
        messages[index] = non_finite_message(backend, [q for q, hit in bad.items() if hit[index]])
    for q, v in values.items():
        values[q] = np.where(broken, np.nan, v)
    return statuses, messages


def _not_applicable(task: SweepTask) -> tuple[pd.DataFrame, pd.DataFrame]:
    """No rows, and ``not_applicable`` at every pose: the backend has no sweep of this kind
    of case, or its method refuses the case."""
    status = pd.DataFrame({"case": task.case.name, "backend": task.backend,
                           "theta12": np.asarray(task.theta12_deg), "status": "not_applicable",
                           "condition_number": np.nan,
                           "message": "the method does not apply to this case", "restart": "",
                           "wall_time_s": 0.0})
    return pd.DataFrame(columns=RESULT_COLUMNS), status


def gated_poses(case: Case, grid: np.ndarray) -> tuple[list[str], np.ndarray]:
    """The pose gate over a sweep's grid (rad, or a linkage's first driver in rad or m): the
    reference's verdict at each pose (``""`` where it has forces) and its condition number.
    Simulators are run only where the verdict is empty, so every backend of a sweep shows
    one verdict at a pose whose forces do not exist or are not unique."""
    verdicts, _, condition = reference_verdicts(case, grid)
    return [v if v in POSE_VERDICTS else "" for v in verdicts], condition


def reference_verdicts(case: Case, grid: np.ndarray) -> tuple[list[str], list[str], np.ndarray]:
    """The reference's verdict, message and condition number at each pose of the grid."""
    reference = registry.get(REFERENCE).sweeper()
    assert reference is not None
    results = reference(case, grid)
    statuses, messages = pose_verdicts(case, results)
    return ([str(v) for v in statuses], [str(m) for m in messages],
            np.asarray(results.condition, dtype=float))


def pose_verdicts(case: Case, results: Any) -> tuple[np.ndarray, np.ndarray]:
    """Each pose's verdict (``"ok"`` where it has forces) and message in vectorised results,
    decided as ``run`` decides them for one pose."""
    if isinstance(results, DecidedPoses):
        return results.statuses, results.messages
    return linkage_verdicts(case, results)


def _run_simulator(task: SweepTask) -> tuple[pd.DataFrame, pd.DataFrame]:
    theta_deg = np.asarray(task.theta12_deg)
    sweep_fn = registry.get(task.backend).sweeper()
    if sweep_fn is None:
        return _not_applicable(task)
    grid = grid_si(task.case, theta_deg, task.unit)
    verdicts, reasons, condition = reference_verdicts(task.case, grid)
    passing = np.flatnonzero([v not in POSE_VERDICTS for v in verdicts])
    statuses = [v if v in POSE_VERDICTS else "ok" for v in verdicts]
    messages = [gated_message(m, REFERENCE) if v in POSE_VERDICTS else ""
                for v, m in zip(verdicts, reasons, strict=True)]
    conditions = condition.copy()
    restarts = [""] * len(theta_deg)
    costs = np.zeros(len(theta_deg))
    values = {q: np.full(len(theta_deg), np.nan) for q in units_of(task.case)}
    try:
        solutions: list[Solution] = sweep_fn(task.case, grid[passing], task.backend) \
            if len(passing) else []
    except Exception as error:   # as `run` does: a crash is this backend's `error` verdict
        for i in passing:
            statuses[i], messages[i] = "error", crash_message(error)
        solutions = []
    for i, s in zip(passing, solutions, strict=True):
        s = finite_only(s)
        statuses[i], messages[i] = s.status, s.message
        conditions[i] = float(s.diagnostics.get("condition_number", condition[i]))
        restarts[i] = str(s.diagnostics.get("restart", ""))
        costs[i] = float(s.diagnostics.get("wall_time_s", 0.0))
        for q, v in s.values.items():
            values[q][i] = v
    present = {q: v for q, v in values.items() if np.isfinite(v).any()}
    status = pd.DataFrame({
        "case": task.case.name, "backend": task.backend, "theta12": theta_deg,
        "status": statuses, "condition_number": conditions, "message": messages,
        "restart": restarts, "wall_time_s": costs,
    })
    return _long_frame(task.case, task.backend, theta_deg, present), status


def run_task(task: SweepTask) -> tuple[bytes, bytes]:
    """Execute one task; returns its results and statuses as Parquet bytes.

    Bytes rather than frames keep what crosses a process or Dask boundary small
    and make the worker, not the client, pay for encoding.
    """
    runner = _run_vector if registry.get(task.backend).vectorised else _run_simulator
    results, status = runner(task)
    return _parquet(results), _parquet(status)


def _parquet(frame: pd.DataFrame) -> bytes:
    buffer = io.BytesIO()
    frame.to_parquet(buffer, index=False)
    return buffer.getvalue()


class LocalExecutor(Executor):
    """Runs each task in the calling process, at submit time (``--workers 0``)."""

    def submit(self, fn: Callable[..., Any], /, *args: Any, **kwargs: Any) -> Future[Any]:
        future: Future[Any] = Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except BaseException as error:
            future.set_exception(error)
        return future


@dataclass(frozen=True)
class SweepOutcome:
    """What a sweep did: the parts it wrote now, and those an earlier run had left."""

    tasks: list[SweepTask]
    parts_dir: Path
    executed: int
    reused: int

    def read(self, *, case: str | None = None, backends: Sequence[str] | None = None,
             kind: str = "results") -> pd.DataFrame:
        """The long results (or statuses) of some cases and backends, from the parts."""
        chosen = [t for t in self.tasks if (case is None or t.case.name == case)
                  and (backends is None or t.backend in backends)]
        index = 0 if kind == "results" else 1
        columns = RESULT_COLUMNS if kind == "results" else STATUS_COLUMNS
        paths = [str(part_paths(self.parts_dir, t)[index]) for t in chosen]
        if not paths:
            return pd.DataFrame(columns=columns)
        table = pq.ParquetDataset(paths).read()
        return table.unify_dictionaries().to_pandas() if table.num_rows else pd.DataFrame(
            columns=columns)


def part_paths(out_dir: Path, task: SweepTask) -> tuple[Path, Path]:
    """The task's results part and status part: ``results/`` and ``status/`` are each a
    Parquet dataset (``pandas.read_parquet("DIR/results")`` reads them all)."""
    return (out_dir / "results" / f"{task.part_name}.parquet",
            out_dir / "status" / f"{task.part_name}.parquet")


def prune_stale_parts(parts_dir: Path, tasks: Sequence[SweepTask]) -> int:
    """Delete the parts that belong to no task of this sweep; returns how many.

    Parts of an earlier run whose case, backend, angles or software changed would
    otherwise sit beside the new ones, and ``pandas.read_parquet("DIR/results")``
    would return both. What stays is this sweep's finished work, which it resumes
    from; half-written temporary files of a killed run go too.
    """
    current = {t.part_name for t in tasks}
    removed = 0
    for folder in ("results", "status"):
        for path in (parts_dir / folder).glob("*"):
            if path.is_file() and (path.name.startswith(".") or path.stem not in current):
                try:
                    path.unlink()
                except OSError as error:
                    raise OutputError(f"--out {parts_dir}: cannot remove an earlier sweep's part "
                                      f"{path.name}: {error.strerror or error}") from None
                removed += 1
    return removed


def is_done(parts_dir: Path, task: SweepTask) -> bool:
    """A task is done when its status part exists: it is renamed into place last."""
    return part_paths(parts_dir, task)[1].exists()


def run_sweep(tasks: Sequence[SweepTask], parts_dir: Path, executor: Executor, *,
              progress: Callable[[int, int], None] | None = None,
              finished: Callable[[SweepTask, bytes], None] | None = None) -> SweepOutcome:
    """Run the tasks not yet done, writing each part the moment it arrives; ``finished``
    is told each task as it is written, with its status part (Parquet bytes).

    An interrupted sweep keeps every part already written; running the same
    sweep again executes only the missing tasks.
    """
    prune_stale_parts(parts_dir, tasks)
    todo = [t for t in tasks if not is_done(parts_dir, t)]
    total_poses = sum(len(t.theta12_deg) for t in tasks)
    done_poses = total_poses - sum(len(t.theta12_deg) for t in todo)
    if progress:
        progress(done_poses, total_poses)
    futures = {executor.submit(run_task, t): t for t in todo}
    for future in as_completed(futures):
        task = futures[future]
        results, status = future.result()
        # Results first, status last: the status part marks the task complete.
        results_path, status_path = part_paths(parts_dir, task)
        write_all(results_path.parent, {results_path.name: results})
        write_all(status_path.parent, {status_path.name: status})
        if finished:
            finished(task, status)
        done_poses += len(task.theta12_deg)
        if progress:
            progress(done_poses, total_poses)
    return SweepOutcome(list(tasks), parts_dir, len(todo), len(tasks) - len(todo))

