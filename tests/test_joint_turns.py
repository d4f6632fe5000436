"""Joint coordinates keep their turns in every table (docs/case-files.md, "What comes out"):
a driver turned 400° reports q = 400°, from every backend, while a link's rotation, a
direction, is wrapped to [−180°, 180°)."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import pandas as pd
import pytest
from typer.testing import CliRunner

import mechcheck
from mechcheck.analytic.case import Case
from mechcheck.cli import app
from mechcheck.run import RunResult
from mechcheck.tables import comparison_rows, results_frame
from mechcheck.tolerance import tolerance_for

from .test_linkage_file import FOUR_BAR_TEMPLATE

#: The driver's rotation written in the file, degrees: more than a turn.
TURNED_DEG = 400.0

#: A Grashof crank-rocker (s + l = 40 + 140 < 100 + 120, the crank beside the ground), so
#: its crank turns fully: drawn at θ12 = 0, B = (112, 96) closes |AB| = 120, |B0B| = 100;
#: D halfway along the rocker. The linkage test's four-bar format, driven 400°.
CRANK_ROCKER = FOUR_BAR_TEMPLATE.replace("POINTS", """A0 = [0.0, 0.0]
B0 = [140.0, 0.0]
A = [40.0, 0.0]
B = [112.0, 96.0]
D = [126.0, 48.0]""").replace("rotation = 0.0", f"rotation = {TURNED_DEG}")


@pytest.fixture(scope="module")
def turned(tmp_path_factory: pytest.TempPathFactory) -> tuple[Case, RunResult]:
    path: Path = tmp_path_factory.mktemp("turns") / "turned.toml"
    path.write_text(CRANK_ROCKER)
    (case,) = mechcheck.load_cases(path)
    return case, mechcheck.check([case])


def test_a_driver_turned_400_degrees_reads_400_in_every_backend(
        turned: tuple[Case, RunResult]) -> None:
    """Every backend's q_A0 in the results table is the file's own 400° (an identity: the
    driver prescribes it), not 40°; the crank's rotation, a direction, reads 40°."""
    case, result = turned
    table = results_frame(result.solutions).set_index(["backend", "quantity"])["value"]
    backends = sorted({s.backend for s in result.solutions})
    assert len(backends) >= 3, backends
    for backend in backends:
        tol = tolerance_for(case, backend, "q_A0", case.kind, "pose")
        # Angles are judged against 1 rad (tables.error_scale): in degrees, that many.
        allowed = tol.rtol * math.degrees(1.0)
        assert abs(table[(backend, "q_A0")] - TURNED_DEG) <= allowed, (backend, tol.reason)
        assert abs(table[(backend, "phi_crank")] - (TURNED_DEG - 360.0)) <= allowed, backend


def test_every_backend_agrees_on_the_turns(turned: tuple[Case, RunResult]) -> None:
    """The comparison of q_A0 with the reference passes for every backend, with no error to
    speak of: no backend lost or added a turn."""
    _, result = turned
    rows = result.comparison[result.comparison["quantity"] == "q_A0"]
    assert len(rows) == len({s.backend for s in result.solutions}) - 1
    assert rows["passed"].all()


def test_a_backend_that_loses_a_turn_fails_the_comparison(turned: tuple[Case, RunResult]) -> None:
    """A joint coordinate one turn short (40° for 400°) fails its comparison, while the same
    turn on a link's rotation, a direction, is no error."""
    case, result = turned
    reference = next(s for s in result.solutions if s.backend == "analytic")
    short = dict(reference.values)
    short["q_A0"] -= math.tau
    short["phi_crank"] -= math.tau
    wrapped = dataclasses.replace(reference, backend="pymunk_solve", values=short)
    rows = {r["quantity"]: r for r in comparison_rows(case, reference, wrapped)}
    assert not rows["q_A0"]["passed"]
    assert rows["q_A0"]["abs_err"] == pytest.approx(360.0)
    assert rows["phi_crank"]["passed"] and rows["phi_crank"]["abs_err"] < 1e-9


def test_a_sweep_past_a_turn_keeps_counting(tmp_path: Path) -> None:
    """Swept from the drawn pose over two turns, every backend's q_A0 at each pose is that
    pose's driver value (720° short of nothing), and every comparison passes."""
    path = tmp_path / "crank.toml"
    path.write_text(CRANK_ROCKER.replace(f"rotation = {TURNED_DEG}", "rotation = 0.0"))
    out = tmp_path / "o"
    result = CliRunner().invoke(app, ["sweep", str(path), "-q", "--workers", "0", "--driver",
                                      "0:720:135", "--no-figures", "--out", str(out)])
    assert result.exit_code == 0, result.output
    comparison = pd.read_parquet(out / "comparison.parquet")
    q = comparison[comparison["quantity"] == "q_A0"]
    assert sorted(set(q["theta12"])) == [0.0, 135.0, 270.0, 405.0, 540.0, 675.0]
    assert len(set(q["backend"])) >= 2
    case = mechcheck.load_cases(path)[0]
    for row in q.itertuples():
        allowed = tolerance_for(case, str(row.backend), "q_A0", case.kind, "pose").rtol
        assert abs(row.value - row.theta12) <= allowed * math.degrees(1.0), row
    assert comparison["passed"].all()
