"""``mechcheck sweep``: run the planned tasks, compare, draw and report."""

from __future__ import annotations

import base64
import os
import shutil
import sys
import time
from concurrent.futures import Executor, Future
from pathlib import Path
from typing import Any

import pandas as pd

from mechcheck.analytic.case import Case
from mechcheck.backends import REFERENCE
from mechcheck.casefile import AnySpec
from mechcheck.drawing import panels_png
from mechcheck.executors import executor_for
from mechcheck.figures import cycle_panels, draw_sweep, figure_file, poses_file, sweep_plot, warm_up
from mechcheck.junit import junit_sweep_xml
from mechcheck.output import OutputError, locked_folder, write_all
from mechcheck.report import render_sweep, sweep_view_model
from mechcheck.sweep import LocalExecutor, SweepOutcome, SweepTask, driver_axis, is_done, run_sweep
from mechcheck.tables import sweep_comparison
from mechcheck.verdicts import without_numbers


def compare_sweep(cases: list[Case], results: pd.DataFrame,
                  statuses: pd.DataFrame) -> pd.DataFrame:
    """Every non-reference backend's poses against the reference, all cases (``results``
    and ``statuses``: the sweep's tables, :meth:`~mechcheck.sweep.SweepOutcome.read`).

    Only a backend's poses with forces (status ``ok``) are compared: a pose with a verdict
    keeps its pose quantities (where the simulator came to rest), and comparing those
    position by position would count one unsettled pose as a dozen failures."""
    frames = []
    for case in cases:
        mine = results[results["case"] == case.name]
        ref = mine[mine["backend"] == REFERENCE]
        own = statuses[statuses["case"] == case.name]
        ref_status = own[own["backend"] == REFERENCE]
        backends = sorted({str(b) for b in mine["backend"].unique()} - {REFERENCE})
        if backends:  # all at once, each backend's rows together, in name order
            others = pd.concat([ok_rows(mine[mine["backend"] == b], own[own["backend"] == b])
                                for b in backends])
            frames.append(sweep_comparison(case, ref, ref_status, others))
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(
        columns=["case", "theta12", "quantity", "backend", "value", "reference", "abs_err",
                 "rel_err", "tolerance", "passed", "case_kind"])


def ok_rows(rows: pd.DataFrame, status: pd.DataFrame) -> pd.DataFrame:
    """One backend's result rows at the poses where its status is ``ok``."""
    return rows[rows["theta12"].isin(status.loc[status["status"] == "ok", "theta12"])]


def failed_poses(comparison: pd.DataFrame) -> int:
    """The poses (case, backend, pose) with at least one comparison outside tolerance: a
    pose counts once, however many of its quantities failed."""
    if not len(comparison):
        return 0
    failed = comparison[~comparison["passed"].astype(bool)]
    return len(failed[["case", "backend", "theta12"]].drop_duplicates())


def draw_figures(executor: Executor, cases: list[Case], results: pd.DataFrame,
                 statuses: pd.DataFrame, comparison: pd.DataFrame,
                 axes: dict[str, tuple[str, str]] | None = None) -> dict[str, Future[bytes]]:
    """Each case's figure (PNG bytes, to come), drawn in the sweep's worker pool: this
    process only reduces the tables to the thinned curves
    (:func:`mechcheck.figures.sweep_plot`); ``axes``: each case's axis (:func:`sweep_axes`)."""
    axes = axes or {}
    return {c.name: executor.submit(draw_sweep, sweep_plot(
        c, results[results["case"] == c.name], statuses[statuses["case"] == c.name],
        comparison[comparison["case"] == c.name], *axes.get(c.name, (None, None))))
        for c in cases}


def sweep_axes(tasks: list[SweepTask]) -> dict[str, tuple[str, str]]:
    """Each case's sweep axis as (label, unit): ``displacement of cyl, mm``, never θ12 for a
    linkage (:func:`~mechcheck.sweep.driver_axis`)."""
    return {t.case.name: (driver_axis(t.case, t.unit), t.unit) for t in tasks}


def draw_poses(executor: Executor, cases: list[Case], results: pd.DataFrame,
               statuses: pd.DataFrame) -> dict[str, Future[bytes]]:
    """Each case's mechanism at a few poses of its cycle (PNG bytes, to come; empty where
    the reference has no forces at any pose), drawn in the sweep's worker pool from the
    reference's own rows (:func:`mechcheck.figures.cycle_panels`)."""
    return {c.name: executor.submit(panels_png, cycle_panels(
        c, results[results["case"] == c.name], statuses[statuses["case"] == c.name]))
        for c in cases}


def attach_poses(model: dict[str, Any], pngs: dict[str, bytes]) -> None:
    """Put each case's drawn poses into the sweep report's view model: the file the
    Markdown links, the bytes the HTML inlines."""
    for view in model["cases"]:
        png = pngs.get(view["name"])
        view["poses"] = poses_file(view["name"]) if png else None
        view["poses_b64"] = base64.b64encode(png).decode() if png else None


def forget_figures(out: Path, cases: list[Case]) -> None:
    """Remove the cases' figures an earlier run drew (``--no-figures``): a report without
    them must not sit beside figures of other results."""
    for case in cases:
        for name in (figure_file(case.name), poses_file(case.name)):
            path = out / "figures" / name
            try:
                path.unlink(missing_ok=True)
            except OSError as error:
                raise OutputError(f"cannot remove {path}: {error.strerror or error}") from None


def warm_figures(executor: Executor, figures: int) -> None:
    """Have the pool's workers import matplotlib now, while this process compares: a
    resumed sweep's figures waited about 0.5 s for it (:func:`mechcheck.figures.warm_up`).
    Not in this process (``--workers 0``): it draws there itself, when it does."""
    if not isinstance(executor, LocalExecutor):
        for _ in range(figures):
            executor.submit(warm_up)


class Remaining:
    """What is left of a sweep, in seconds: each unfinished task's poses at its backend's
    measured cost per pose (the ``wall_time_s`` its finished tasks reported; a backend not
    yet measured at the dearest measured so far), shared among ``workers``. A driven pymunk
    pose can cost a thousand settled MuJoCo poses: counting poses alike misleads."""

    def __init__(self, tasks: list[SweepTask], workers: int) -> None:
        self.left = {id(t): t for t in tasks}
        self.workers = max(1, workers)
        self.cost: dict[str, float] = {}

    def finished(self, task: SweepTask, status: bytes) -> None:
        import io

        self.left.pop(id(task), None)
        spent = pd.read_parquet(io.BytesIO(status), columns=["wall_time_s"])["wall_time_s"]
        if len(spent) and float(spent.sum()) > 0.0:
            self.cost[task.backend] = float(spent.sum()) / len(spent)

    def backend(self) -> str:
        """The backend of the earliest unfinished task: the one the workers are on."""
        return next(iter(self.left.values())).backend if self.left else ""

    def seconds(self) -> float | None:
        """The estimate, or None before any cost is measured."""
        if not self.cost:
            return None
        dearest = max(self.cost.values())
        work = sum(len(t.theta12_deg) * self.cost.get(t.backend, dearest)
                   for t in self.left.values())
        return work / self.workers


def run_sweep_command(specs: list[tuple[Case, AnySpec]], tasks: list[SweepTask], n_poses: int,
                      out: Path, *, workers: int | None, dask: str | None,
                      fail_on: tuple[str, ...], junit: Path | None, quiet: bool,
                      figures: bool = True, fresh: bool = False) -> int:
    """Run, compare and report a sweep (``figures``: draw each case's; ``fresh``: discard
    the parts of an earlier run first); returns the exit status.

    The executor is reached first, so that an unreachable ``--dask`` creates nothing in
    ``out``; then ``out`` is locked (:func:`~mechcheck.output.locked_folder`) until the
    last file is written. Raises :class:`~mechcheck.output.OutputError` or
    :class:`~mechcheck.executors.ExecutorUnavailable` for the command line to report.
    """
    with executor_for(workers, dask, tasks=len(tasks)) as executor, \
            locked_folder(out, "--out"):
        if fresh:
            for folder in ("results", "status"):
                shutil.rmtree(out / folder, ignore_errors=True)
        parallel = 1 if workers == 0 else workers or os.cpu_count() or 1
        return _sweep_and_report(executor, specs, tasks, n_poses, out, fail_on=fail_on,
                                 junit=junit, quiet=quiet, figures=figures,
                                 parallel=min(parallel, max(len(tasks), 1)))


def _sweep_and_report(executor: Executor, specs: list[tuple[Case, AnySpec]],
                      tasks: list[SweepTask], n_poses: int, out: Path, *,
                      fail_on: tuple[str, ...], junit: Path | None, quiet: bool,
                      figures: bool, parallel: int = 1) -> int:
    cases = [c for c, _ in specs]
    start = time.perf_counter()
    outcome = _run_with_progress(tasks, out, executor, quiet, parallel)
    wall = time.perf_counter() - start
    if figures:
        warm_figures(executor, len(cases))
    # Each table read once from all its parts (a read per case and backend took a
    # third of a resumed sweep's comparing).
    results, statuses = outcome.read(), outcome.read(kind="status")
    comparison = compare_sweep(cases, results, statuses)
    axes = sweep_axes(tasks)
    drawing = draw_figures(executor, cases, results, statuses, comparison, axes) \
        if figures else {}
    posing = draw_poses(executor, cases, results, statuses) if figures else {}
    comparison_buffer = comparison.to_parquet(index=False)  # while the figures are drawn
    pngs = {name: future.result() for name, future in drawing.items()}
    poses = {name: png for name, future in posing.items() if (png := future.result())}
    model = sweep_view_model(cases, {c.name: s for c, s in specs}, statuses, comparison, pngs,
                             title="mechcheck sweep report", n_poses=n_poses, wall_time_s=wall,
                             executed=outcome.executed, reused=outcome.reused, fail_on=fail_on,
                             axes=axes)
    attach_poses(model, poses)
    markdown, page = render_sweep(model)
    files: dict[str, str | bytes] = {"report.md": markdown, "report.html": page}
    if figures:
        write_all(out / "figures", {figure_file(name): png for name, png in pngs.items()}
                  | {poses_file(name): png for name, png in poses.items()})
    else:
        forget_figures(out, cases)
    assert comparison_buffer is not None
    files["comparison.parquet"] = comparison_buffer
    write_all(out, files)
    if junit is not None:
        write_all(junit.parent, {junit.name: junit_sweep_xml(comparison, statuses, fail_on, wall)})
    failed = failed_poses(comparison)
    failing = int(statuses["status"].isin(fail_on).sum()) if len(statuses) else 0
    status = 1 if failed or failing else 0
    print(_summary_line(len(cases), n_poses, len(comparison), failed, failing, statuses,
                        f"{outcome.executed} tasks run, {outcome.reused} reused, {wall:.1f} s "
                        f"-> {out}/report.md ({'PASS' if status == 0 else 'FAIL'})"))
    return status


def _run_with_progress(tasks: list[SweepTask], out: Path, executor: Executor, quiet: bool,
                       parallel: int) -> SweepOutcome:
    """The sweep's tasks run (:func:`run_sweep`), with a progress bar unless ``quiet``
    whose estimate weighs each backend's measured cost per pose."""
    remaining = Remaining([t for t in tasks if not is_done(out, t)], parallel)
    bar = None
    if not quiet:
        from tqdm import tqdm  # only for the progress bar

        # tqdm's own estimate assumes every pose costs the same: ours weighs them.
        bar = tqdm(total=1, unit="pose", file=sys.stderr, dynamic_ncols=True,
                   bar_format="{l_bar}{bar}| {n_fmt}/{total_fmt} poses [{elapsed}{postfix}]")

    def progress(done: int, total: int) -> None:
        if bar is not None:
            bar.total = total
            bar.n = done
            left = remaining.seconds()
            bar.set_postfix_str(
                f"on {remaining.backend() or '-'}, "
                + (f"≈{tqdm.format_interval(left)} left" if left is not None
                   else "measuring the cost per pose"), refresh=False)
            bar.refresh()

    try:
        return run_sweep(tasks, out, executor, progress=progress, finished=remaining.finished)
    except OutputError as error:
        raise OutputError(f"{error} (the parts already finished are kept: the same command "
                          "resumes from them)") from None
    finally:
        if bar is not None:
            bar.close()


def _summary_line(n_cases: int, n_poses: int, compared: int, failed: int, failing: int,
                  statuses: pd.DataFrame, tail: str) -> str:
    """The sweep's one-line summary: counts, the verdicts that gave no number, ``tail``."""
    absent = without_numbers(zip(statuses["status"].astype(str), statuses["case"].astype(str),
                                 strict=True)) if len(statuses) else ""
    return (f"{n_cases} case{'s' * (n_cases != 1)} x {n_poses} poses, {compared} "
            f"comparisons, {failed} poses outside tolerance, {failing} poses with a failing "
            f"verdict{f' (poses without numbers: {absent})' if absent else ''}; {tail}")
