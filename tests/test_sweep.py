"""Sweeps: resumable Parquet parts, executors (local, Dask), comparison and verdict."""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from mechcheck import sweep as sweep_module
from mechcheck.analytic import forces
from mechcheck.executors import executor_for
from mechcheck.sweep import LocalExecutor, parse_range, plan, run_sweep

from .builtin import builtin


class Killed(RuntimeError):
    """Stands for the process being killed in the middle of a sweep."""


def small_plan(monkeypatch: pytest.MonkeyPatch) -> list[sweep_module.SweepTask]:
    """Seed E1 over a full turn in 2° steps, 20 poses per task: 9 tasks per backend."""
    monkeypatch.setattr(sweep_module, "VECTOR_CHUNK", 20)
    return plan([builtin("seed-E1-as-stated")], ["superposition"], parse_range("0:360:2"))


def sorted_results(frame: pd.DataFrame) -> pd.DataFrame:
    out = frame.astype({c: str for c in ("case", "backend", "quantity", "unit")})
    return out.sort_values(["backend", "quantity", "theta12"]).reset_index(drop=True)


def test_parse_range_excludes_stop() -> None:
    """0:360:1 is 360 poses 0°…359°; bad ranges are refused with the option named."""
    grid = parse_range("0:360:1")
    assert len(grid) == 360 and grid[0] == 0.0 and grid[-1] == 359.0
    with pytest.raises(ValueError, match="--theta12"):
        parse_range("10:0:1")


def test_sweep_values_are_the_vectorised_solver_values(tmp_path: Path,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    """The long Parquet results hold, in table units, exactly what the solver computes per pose."""
    tasks = small_plan(monkeypatch)
    outcome = run_sweep(tasks, tmp_path, LocalExecutor())
    results = outcome.read(backends=["analytic"])
    t12 = results[results["quantity"] == "T12"].sort_values("theta12")
    theta = np.radians(t12["theta12"].to_numpy())
    expected = forces.solve_poses(builtin("seed-E1-as-stated"), theta).values["T12"]
    assert np.array_equal(t12["value"].to_numpy(), expected)
    angles = results[results["quantity"] == "theta13"].sort_values("theta12")
    assert angles["unit"].astype(str).unique().tolist() == ["deg"]
    # 180° is the change point: no force rows there, and a singular status row.
    status = outcome.read(backends=["analytic"], kind="status")
    assert status.loc[status["theta12"] == 180.0, "status"].tolist() == ["singular"]
    assert not ((t12["theta12"] == 180.0).any())


def test_killed_sweep_resumes_with_the_remaining_tasks_only(tmp_path: Path,
                                                           monkeypatch: pytest.MonkeyPatch) -> None:
    """A sweep interrupted midway keeps its finished parts; re-running computes only the rest."""
    tasks = small_plan(monkeypatch)
    calls = {"n": 0}
    real = sweep_module.run_task

    def dies_on_the_seventh(task: sweep_module.SweepTask) -> tuple[bytes, bytes]:
        calls["n"] += 1
        if calls["n"] == 7:
            raise Killed("killed")
        return real(task)

    monkeypatch.setattr(sweep_module, "run_task", dies_on_the_seventh)
    with ThreadPoolExecutor(max_workers=1) as pool, pytest.raises(Killed):
        run_sweep(tasks, tmp_path, pool)
    finished = len(list((tmp_path / "status").glob("*.parquet")))
    assert 0 < finished < len(tasks)
    # Nothing half-written: every status part has its results part, and no temporary files.
    assert len(list((tmp_path / "results").glob("*.parquet"))) >= finished
    assert not list(tmp_path.rglob(".*"))

    monkeypatch.setattr(sweep_module, "run_task", real)
    outcome = run_sweep(tasks, tmp_path, LocalExecutor())
    assert outcome.reused == finished and outcome.executed == len(tasks) - finished
    fresh = run_sweep(tasks, tmp_path / "fresh", LocalExecutor())
    assert fresh.executed == len(tasks)
    pd.testing.assert_frame_equal(sorted_results(outcome.read()), sorted_results(fresh.read()))


def test_changed_case_does_not_reuse_stale_parts(tmp_path: Path,
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    """Parts are keyed by a digest of case, backend and angles: a changed load recomputes."""
    tasks = small_plan(monkeypatch)
    run_sweep(tasks, tmp_path, LocalExecutor())
    case = builtin("seed-E1-as-stated")
    heavier = case.with_(loads=tuple(ld.__class__(ld.link, ld.at, (2 * ld.force[0], 2 * ld.force[1]))
                                     for ld in case.loads))
    again = plan([heavier], ["superposition"], parse_range("0:360:2"))
    outcome = run_sweep(again, tmp_path, LocalExecutor())
    assert outcome.reused == 0


def test_dask_local_cluster_gives_results_identical_to_local_processes(tmp_path: Path) -> None:
    """The same sweep on a 2-worker Dask LocalCluster and on local processes: identical tables."""
    distributed = pytest.importorskip("distributed")
    cases = [builtin("seed-E1-as-stated"), builtin("seed-E2-frictionless")]
    tasks = plan(cases, ["superposition", "virtual_work", "pymunk_solve"], parse_range("0:360:5"))
    with executor_for(workers=2) as pool:
        local = run_sweep(tasks, tmp_path / "local", pool)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            executor_for(dask_address=cluster.scheduler_address) as executor:
        remote = run_sweep(tasks, tmp_path / "dask", executor)
    assert remote.executed == len(tasks)
    pd.testing.assert_frame_equal(sorted_results(local.read()), sorted_results(remote.read()))
    a, b = (o.read(kind="status").sort_values(["case", "backend", "theta12"])
            .reset_index(drop=True).astype({"case": str, "backend": str, "status": str})
            for o in (local, remote))
    pd.testing.assert_frame_equal(a, b)


def test_singular_pose_condition_is_recorded(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Every pose's condition number is in the status table, infinite at the change point."""
    outcome = run_sweep(small_plan(monkeypatch), tmp_path, LocalExecutor())
    status = outcome.read(backends=["analytic"], kind="status").set_index("theta12")
    assert math.isinf(status.loc[180.0, "condition_number"])
    assert status.loc[60.0, "condition_number"] < 10.0
