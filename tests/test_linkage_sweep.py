"""`mechcheck sweep` on linkages: the first driver is swept (degrees of a revolute joint, mm
of a prismatic one, from the drawn pose); a swept pose equals the same pose solved alone."""

from __future__ import annotations

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
