"""Sweep figures: thinned curves keep their extremes; drawn in the sweep's worker pool."""

from __future__ import annotations

import itertools
import math
import re
import subprocess
import sys
from concurrent.futures import Future
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest

from mechcheck import sweep_run
from mechcheck.figures import MAX_POINTS, draw_sweep, sweep_plot, thin
from mechcheck.sweep import LocalExecutor, parse_range, plan, run_sweep
from mechcheck.tolerance import NEAR_SINGULAR_CONDITION, rule

from .builtin import builtin
from .test_user_mechanisms import toggle_angle, user_case


def bucket_extremes(y: np.ndarray, edges: np.ndarray) -> list[tuple[float, float]]:
    """Each run's smallest and largest value, by a plain loop over the runs."""
    return [(float(np.nanmin(y[a:b])), float(np.nanmax(y[a:b])))
            for a, b in itertools.pairwise(edges)]


def test_a_short_curve_is_not_thinned() -> None:
    x = np.arange(10.0)
    assert thin(x, x**2, limit=40)[0] is x


@pytest.mark.parametrize("n", [4001, 10_007, 1_000_000])
def test_thinning_keeps_every_runs_extremes_and_both_ends(n: int) -> None:
    """At most the limit of points, the first and last, and in every run of consecutive
    points its smallest and largest value (checked run by run with a loop)."""
    x = np.linspace(0.0, 360.0, n, endpoint=False)
    y = np.sin(np.radians(7 * x)) + np.random.default_rng(n).normal(0.0, 0.3, n)
    y[n // 3] = 50.0  # one spike, narrower than a run
    tx, ty = thin(x, y)
    assert len(tx) <= MAX_POINTS
    assert (tx[0], tx[-1]) == (x[0], x[-1])
    assert np.all(np.diff(tx) > 0.0)
    assert ty.max() == 50.0 and ty.min() == y.min()
    # The runs: MAX_POINTS // 4 of consecutive points, as equal as whole points allow.
    edges = (np.arange(MAX_POINTS // 4 + 1) * n) // (MAX_POINTS // 4)
    for (a, b), (low, high) in zip(itertools.pairwise(edges),
                                   bucket_extremes(y, edges), strict=True):
        inside = ty[(tx >= x[a]) & (tx <= x[b - 1])]
        assert inside.min() == low and inside.max() == high


def test_thinning_ignores_nans_as_extremes() -> None:
    x = np.arange(20_000.0)
    y = np.cos(x / 1000.0)
    y[::7] = np.nan
    _, ty = thin(x, y)
    assert np.nanmax(ty) == np.nanmax(y) and np.nanmin(ty) == np.nanmin(y)


def test_a_large_sweeps_figure_keeps_the_curves_extremes(tmp_path: Path) -> None:
    """An analytic sweep of 100 000 poses: every curve drawn has at most MAX_POINTS points
    and reaches the drive torque's largest and smallest value in the results."""
    case = builtin("seed-E1-as-stated")
    outcome = run_sweep(plan([case], [], parse_range("0:360:0.0036")), tmp_path, LocalExecutor())
    results = outcome.read()
    plot = sweep_plot(case, results, outcome.read(kind="status"), pd.DataFrame(
        columns=["backend", "theta12", "rel_err", "tolerance"]))
    curves = [*plot.drive, *plot.reactions, plot.lower]
    assert all(len(c.x) <= MAX_POINTS for c in curves)
    t12 = results.loc[results["quantity"] == "T12", "value"]
    (drive,) = plot.drive
    assert (drive.y.max(), drive.y.min()) == (t12.max(), t12.min())


class CountingExecutor(LocalExecutor):
    """Runs in this process, counting what it is given to run."""

    def __init__(self) -> None:
        self.calls: list[str] = []

    def submit(self, fn: Any, /, *args: Any, **kwargs: Any) -> Future[Any]:
        self.calls.append(fn.__name__)
        return super().submit(fn, *args, **kwargs)


def test_figures_are_drawn_by_the_sweeps_executor(tmp_path: Path) -> None:
    """Each case's figure is a task of the executor that ran the sweep (its worker pool),
    and is a PNG."""
    cases = [builtin("seed-E1-as-stated")]
    outcome = run_sweep(plan(cases, [], parse_range("0:360:10")), tmp_path, LocalExecutor())
    executor = CountingExecutor()
    results, statuses = outcome.read(), outcome.read(kind="status")
    figures = sweep_run.draw_figures(executor, cases, results, statuses,
                                     sweep_run.compare_sweep(cases, results, statuses))
    assert executor.calls == ["draw_sweep"]
    assert figures[cases[0].name].result().startswith(b"\x89PNG")


def test_the_sweep_command_does_not_import_matplotlib() -> None:
    """Only the workers that draw import matplotlib: the resume path does not pay for it."""
    code = ("import sys, mechcheck.cli, mechcheck.sweep_run; "
            "print('matplotlib' in sys.modules)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    assert done.stdout.strip() == "False"


def test_a_sweep_without_figures_reports_the_same_without_them(tmp_path: Path) -> None:
    """``--no-figures``: the same comparison and exit status, a report with no image, and
    no figure left from an earlier run of the same directory; drawing them again puts
    them back."""
    from typer.testing import CliRunner

    from mechcheck.cli import app

    def sweep(*options: str) -> int:
        done = CliRunner().invoke(app, ["sweep", "-b", "virtual_work", "--theta12", "0:360:30",
                                        "--workers", "0", "-q", "--out", str(tmp_path),
                                        *options])
        assert done.exit_code in (0, 1), done.output
        return done.exit_code

    assert sweep() == 0
    figures = sorted(p.name for p in (tmp_path / "figures").glob("*.png"))
    assert len(figures) >= 3
    drawn = pd.read_parquet(tmp_path / "comparison.parquet")
    assert "data:image/png" in (tmp_path / "report.html").read_text()
    # Each image a paragraph of its own in the Markdown (a line glued to the next is not).
    paragraphs = re.findall(r"\n\n!\[[^]]+\]\(figures/[^)]+\.png\)\n\n",
                            (tmp_path / "report.md").read_text())
    assert len(paragraphs) == len(figures)
    assert sweep("--no-figures") == 0
    pd.testing.assert_frame_equal(pd.read_parquet(tmp_path / "comparison.parquet"), drawn)
    assert not list((tmp_path / "figures").glob("*.png"))
    assert "data:image/png" not in (tmp_path / "report.html").read_text()
    assert "](figures/" not in (tmp_path / "report.md").read_text()
    assert sweep() == 0
    assert sorted(p.name for p in (tmp_path / "figures").glob("*.png")) == figures


def test_the_toggle_panel_marks_the_presss_output_toggle_at_the_hand_angle(
        tmp_path: Path) -> None:
    """The toggle press swept ±30° about its drawing: the fourth panel keeps the condition
    number (flat through the toggle, below the near-singular line) and marks one output
    toggle, where the ram stops, at the hand toggle (crank 19.94° from the drawing: upper
    and lower link in line, by bisection on the user's hand kinematics)."""
    case = user_case("toggle_press.toml", "toggle-press-5deg")
    grid = parse_range("-30:30:5", "--driver")
    outcome = run_sweep(plan([case], [], grid, grid), tmp_path, LocalExecutor())
    plot = sweep_plot(case, outcome.read(), outcome.read(kind="status"), pd.DataFrame(
        columns=["backend", "theta12", "rel_err", "tolerance"]), "rotation of O2, deg", "deg")
    assert plot.lower_is_condition and plot.lower.y.max() < NEAR_SINGULAR_CONDITION
    assert math.degrees(toggle_angle()) == pytest.approx(19.94, abs=0.005)
    tol = rule("virtual_work", "pose", "static")   # the analytic family's: only rounding
    assert len(plot.toggles) == 1
    assert math.radians(plot.toggles[0]) == pytest.approx(toggle_angle(), rel=tol.rtol), \
        tol.reason
    assert draw_sweep(plot).startswith(b"\x89PNG")


def test_a_sweep_whose_loads_never_stop_marks_no_toggle(tmp_path: Path) -> None:
    """The press swept −10° to 10°: its ram moves all the way (the toggle is at 19.94°), so
    no toggle is marked; neither is the crank's weight, which turns but never stops."""
    case = user_case("toggle_press.toml", "toggle-press-5deg")
    grid = parse_range("-10:10:5", "--driver")
    outcome = run_sweep(plan([case], [], grid, grid), tmp_path, LocalExecutor())
    plot = sweep_plot(case, outcome.read(), outcome.read(kind="status"), pd.DataFrame(
        columns=["backend", "theta12", "rel_err", "tolerance"]))
    assert plot.toggles.size == 0
