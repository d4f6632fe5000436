"""Sweeps: resumable Parquet parts, executors (local, Dask), comparison and verdict."""

from __future__ import annotations

import math
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from mechcheck import backends as registry, sweep as sweep_module, sweep_run
from mechcheck.analytic.presets import redrawn
from mechcheck.analytic.solution import Solution, unit_factor
from mechcheck.backends import REFERENCE
from mechcheck.casefile import load_cases
from mechcheck.executors import executor_for
from mechcheck.sweep import LocalExecutor, parse_range, plan, run_sweep

from .builtin import builtin, rocker_load_case


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
    """The long Parquet results hold, in table units, exactly what the solver computes per pose
    (task by task: each task's poses are one call of the solver)."""
    tasks = small_plan(monkeypatch)
    outcome = run_sweep(tasks, tmp_path, LocalExecutor())
    results = outcome.read(backends=["analytic"])
    t12 = results[results["quantity"] == "T12"].sort_values("theta12")
    solver = registry.get("analytic").sweeper()
    assert solver is not None
    theta = np.concatenate([t.theta12_deg for t in tasks if t.backend == "analytic"])
    expected = np.concatenate([solver(t.case, np.radians(t.theta12_deg)).values["T12"]
                               for t in tasks if t.backend == "analytic"])
    kept = np.isin(theta, t12["theta12"].to_numpy())
    assert np.array_equal(t12["value"].to_numpy(), expected[kept])
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
    heavier = redrawn(case, loads=tuple(ld.__class__(ld.link, ld.at, (2 * ld.force[0], 2 * ld.force[1]))
                                     for ld in case.preset.loads))
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
    # Everything but what each pose cost: a wall time is measured, never reproduced.
    a, b = (o.read(kind="status").drop(columns="wall_time_s")
            .sort_values(["case", "backend", "theta12"])
            .reset_index(drop=True).astype({"case": str, "backend": str, "status": str})
            for o in (local, remote))
    pd.testing.assert_frame_equal(a, b)


def test_singular_pose_condition_is_recorded(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Every pose's condition number is in the status table: past the singular line (1e8)
    at the change point, of order ten at a regular pose."""
    outcome = run_sweep(small_plan(monkeypatch), tmp_path, LocalExecutor())
    status = outcome.read(backends=["analytic"], kind="status").set_index("theta12")
    assert not status.loc[180.0, "condition_number"] <= 1e8
    assert status.loc[60.0, "condition_number"] < 100.0


def pose_solutions(case_name: str, results: pd.DataFrame, statuses: pd.DataFrame,
                   theta: float) -> dict[str, Solution]:
    """Each backend's Solution at one pose, rebuilt from the sweep's tables (SI values)."""
    rows = results[(results["case"] == case_name) & (results["theta12"] == theta)]
    solutions = {}
    for backend, mine in rows.groupby("backend", observed=True):
        status = statuses[(statuses["case"] == case_name) & (statuses["backend"] == backend)
                          & (statuses["theta12"] == theta)]
        units = dict(zip(mine["quantity"].astype(str), mine["unit"].astype(str), strict=True))
        values = {q: v / unit_factor(units[q])
                  for q, v in zip(mine["quantity"].astype(str), mine["value"], strict=True)}
        solutions[str(backend)] = Solution(
            case_name, str(backend), values, units=units,
            diagnostics={"condition_number": float(status["condition_number"].iloc[0])})
    return solutions


def test_the_sweep_comparison_is_the_per_pose_comparison(tmp_path: Path) -> None:
    """The vectorised sweep comparison (:func:`mechcheck.tables.sweep_comparison`, numpy
    over integer codes) gives, at every pose, the rows :func:`comparison_rows` gives for
    that pose alone: the same quantities, errors, tolerances, verdicts and case kinds.
    Poses: a coarse turn plus seed E1 next to its change point (condition number above
    1e4: near-singular tolerances), angles (deg), a length (s14, m) and a linkage's
    quantities; backends with errors of 1e-16 (virtual work) and 1e-12 (mujoco_solve).
    A moment on the crank with a feeble force on the rocker leaves the reactions small:
    forces are then measured against the drive torque over the longest link."""
    from mechcheck.tables import comparison_rows

    path = tmp_path / "moment.toml"
    path.write_text(rocker_load_case("crank-moment").split("[[case.loads]]")[0]
                    + "[[case.loads]]\nlink = 2\nat = [0.0, 0.0]\ntorque = 5.0\n"
                    + "[[case.loads]]\nlink = 4\nat = [90.0, 0.0]\n"
                    + "force = { magnitude = 0.01, angle = 20.0 }\n")
    cases = [builtin("seed-E1-as-stated"), builtin("seed-E2-frictionless"),
             builtin("watt-ii-demo"), *load_cases(path)]
    grid = np.concatenate([np.arange(0.0, 360.0, 30.0), [179.99, 180.01]])
    outcome = run_sweep(plan(cases, ["virtual_work", "mujoco_solve"], grid,
                             np.arange(-20.0, 21.0, 10.0)), tmp_path, LocalExecutor())
    results, statuses = outcome.read(), outcome.read(kind="status")
    swept = sweep_run.compare_sweep(cases, results, statuses)
    expected = []
    for case in cases:
        for theta in np.unique(results.loc[results["case"] == case.name, "theta12"]):
            found = pose_solutions(case.name, results, statuses, float(theta))
            for backend in ("mujoco_solve", "virtual_work"):
                if REFERENCE in found and backend in found:
                    expected += [{**row, "theta12": theta} for row in
                                 comparison_rows(case, found[REFERENCE], found[backend])]
    per_pose = pd.DataFrame(expected)
    keys = ["case", "backend", "theta12", "quantity"]
    a, b = (f.sort_values(keys).reset_index(drop=True) for f in (swept, per_pose))
    assert len(a) == len(b) > 700 and (a["case_kind"] == "near_singular").sum() >= 20
    assert set(a["quantity"]) >= {"theta13", "s14"}  # an angle and a length compared
    assert a[keys].astype(str).equals(b[keys].astype(str))
    # Errors to rounding: the tables hold degrees, which the per-pose path turns back into
    # radians, moving each angle (≤ π rad, error scale 1 rad) by up to an ulp, 4.4e-16.
    assert np.allclose(a["rel_err"], b["rel_err"], rtol=1e-9, atol=8 * np.finfo(float).eps)
    assert np.array_equal(a["tolerance"], b["tolerance"])
    assert a["passed"].tolist() == b["passed"].tolist()
    assert a["case_kind"].tolist() == b["case_kind"].tolist()
    # The same table whether the names arrive as shared categories or as plain strings.
    plain = results.astype({c: str for c in ("case", "backend", "quantity", "unit")})
    pd.testing.assert_frame_equal(sweep_run.compare_sweep(cases, plain, statuses), swept)


def test_angles_are_compared_across_the_wrap() -> None:
    """θ13 of 180° − 1e-9 rad against −180° + 1e-9 rad is 2e-9 rad apart, not a turn:
    the sweep comparison says so as :func:`comparison_rows` does."""
    from mechcheck.tables import comparison_rows, sweep_comparison

    case = builtin("seed-E1-as-stated")
    reference = Solution(case.name, REFERENCE, {"theta13": math.pi - 1e-9, "T12": 1.0},
                         diagnostics={"condition_number": 2.0})
    other = Solution(case.name, "mujoco_solve", {"theta13": -math.pi + 1e-9, "T12": 1.0})

    def table(s: Solution) -> pd.DataFrame:
        return pd.DataFrame({"theta12": 60.0, "backend": s.backend, "quantity": list(s.values),
                             "value": list(s.in_table_units().values()),
                             "unit": [s.unit(q) for q in s.values]})

    swept = sweep_comparison(case, table(reference),
                             pd.DataFrame({"theta12": [60.0], "condition_number": [2.0]}),
                             table(other)).set_index("quantity")
    expected = {r["quantity"]: r for r in comparison_rows(case, reference, other)}
    assert math.isclose(expected["theta13"]["rel_err"], 2e-9, rel_tol=1e-6)
    assert math.isclose(swept.loc["theta13", "rel_err"], 2e-9, rel_tol=1e-6)
    assert swept["passed"].tolist() == [expected[q]["passed"] for q in swept.index]
