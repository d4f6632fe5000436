"""`mechcheck sweep` on linkages: the first driver is swept (degrees of a revolute joint, mm
of a prismatic one, from the drawn pose); a swept pose equals the same pose solved alone."""

from __future__ import annotations

import re
from pathlib import Path

import pandas as pd
import pytest
from typer.testing import CliRunner

from mechcheck import load_cases, solve
from mechcheck.cli import app

LINKAGES = Path(__file__).resolve().parents[1] / "compare" / "cases" / "linkages"


def sweep(tmp_path: Path, files: list[Path], *args: str) -> Path:
    out = tmp_path / "sweep"
    result = CliRunner().invoke(app, ["sweep", *map(str, files), "-q", "--workers", "0",
                                      "--out", str(out), *args])
    assert result.exit_code == 0, result.output
    return out


def test_a_revolute_driver_is_swept_in_degrees(tmp_path: Path) -> None:
    """The Watt six-bar's crank swept 0:100:5° from the drawn pose through three analytic
    methods: 20 poses each, they agree, and the pose at 30° is the case's own (rotation 30°)."""
    path = LINKAGES / "watt_ii_sixbar.toml"
    out = sweep(tmp_path, [path], "--driver", "0:100:5", "-b", "virtual_work", "-b",
                "superposition")
    results = pd.read_parquet(out / "results")
    q = results[results["quantity"] == "Q_O2"]
    assert sorted(q["backend"].astype(str).unique()) == ["analytic", "superposition",
                                                         "virtual_work"]
    assert (q.groupby("backend", observed=True).size() == 20).all()
    alone = solve(load_cases(path)[0]).values["Q_O2"]
    at_30 = q[(q["theta12"] == 30.0) & (q["backend"] == "analytic")]["value"].iloc[0]
    assert at_30 == pytest.approx(alone, rel=1e-9)
    assert pd.read_parquet(out / "comparison.parquet")["passed"].all()
    assert (out / "figures" / "watt-ii-demo.png").stat().st_size > 10_000


def test_a_prismatic_driver_is_swept_in_millimetres(tmp_path: Path) -> None:
    """The boom's cylinder swept 0:100:20 mm: at 80 mm it carries the force the boom-raise
    case (cylinder extended 80 mm) gives; MuJoCo settles the held boom and drives the moving
    one (a run per pose, at the case's cylinder speed) at every pose, within the policy."""
    path = LINKAGES / "cylinder_boom.toml"
    out = sweep(tmp_path, [path], "--driver", "0:100:20", "-b", "mujoco")
    results = pd.read_parquet(out / "results")
    raise_case = next(c for c in load_cases(path) if c.name == "boom-raise")
    q = results[(results["case"] == "boom-raise") & (results["quantity"] == "Q_cyl")
                & (results["theta12"] == 80.0)]["value"].iloc[0]
    assert q == pytest.approx(solve(raise_case).values["Q_cyl"], rel=1e-9)
    status = pd.read_parquet(out / "status")
    mujoco = status[status["backend"] == "mujoco"].groupby("case", observed=True)["status"]
    assert mujoco.unique().map(set).to_dict() == {"boom-hold-drawn": {"ok"},
                                                  "boom-raise": {"ok"}}
    comparison = pd.read_parquet(out / "comparison.parquet")
    assert len(comparison[comparison["backend"] == "mujoco"]) and comparison["passed"].all()


@pytest.mark.parametrize("name", ["bonnet_counterbalanced.toml", "exam_q1_slider_bar.toml"])
def test_a_linkage_without_drivers_is_refused_by_sweep(tmp_path: Path, name: str) -> None:
    """A linkage sweep moves the first driver; a file with a linkage that has none (its
    free coordinates solved case by case) is unusable input for `sweep`: exit 2, one line
    naming the file, the case and the key, nothing written (before: an internal error after
    the other cases' parts were written)."""
    out = tmp_path / "sweep"
    result = CliRunner().invoke(app, ["sweep", str(LINKAGES / name), "-q", "--workers", "0",
                                      "--out", str(out)])
    lines = result.stderr.strip().splitlines()
    assert result.exit_code == 2 and len(lines) == 1, result.output
    assert name in lines[0] and "key 'drivers'" in lines[0] and "case '" in lines[0]
    assert not out.exists()


@pytest.mark.parametrize("backend", ["mujoco", "mujoco_solve", "pymunk", "pymunk_solve"])
def test_a_simulator_sweep_past_a_lock_gives_the_pose_verdict(backend: str) -> None:
    """The simulators' own sweeps sit behind the same pose gate as the harness's. The
    locking four-bar's crank locks 61.790785° from its drawn pose (hand, in its case file):
    at 50° a simulator runs; at 70° it is not run and says `no_solution`, where the drivers
    locked on the way to 70° (before: MuJoCo's exact solve raised LinAlgError on the NaN
    pose, its settling ran 3000 steps to `not_settled`, and the message put the lock where
    the case's own 180° drive would have met it)."""
    import math

    from mechcheck.sim_models.mujoco import backend as mujoco_backend
    from mechcheck.sim_models.pymunk import backend as pymunk_backend

    module = mujoco_backend if backend.startswith("mujoco") else pymunk_backend
    case = load_cases(LINKAGES / "locking_fourbar.toml")[0]
    got = module.sweep(case, [math.radians(50.0), math.radians(70.0)], backend)
    assert got[0].status == "ok", got[0].message
    assert got[1].status == "no_solution", got[1].message
    locked = float(re.search(r"locks at rotation ([-0-9.]+)°", got[1].message).group(1))
    assert locked == pytest.approx(61.790785, abs=1e-4)
    assert not any(q.startswith("F_") for q in got[1].values)
