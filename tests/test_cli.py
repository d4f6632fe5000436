"""The command line end to end: outputs, exit statuses, JUnit, an injected disagreement."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import pandas as pd
from typer.testing import CliRunner

from mechcheck.cli import app

from .builtin import rocker_load_case

CASE = rocker_load_case("e1")

#: No method can meet a relative tolerance of 1e-30 unless it is bit-identical: this
#: injects a disagreement without touching any solver.
TIGHTENED = CASE + """
[[case.tolerance]]
backend = "virtual_work"
quantity = "T12"
rtol = 1e-30
"""


def invoke(args: list[str]) -> tuple[int, str]:
    result = CliRunner().invoke(app, args)
    return result.exit_code, result.output


def test_builtin_suite_passes_and_writes_every_output(tmp_path: Path) -> None:
    """`mechcheck run` on the built-in suite (analytic methods) exits 0 and writes all five files."""
    code, output = invoke(["run", "-q", "-b", "superposition", "-b", "virtual_work",
                           "--out", str(tmp_path)])
    assert code == 0, output
    for name in ("results.csv", "comparison.csv", "diagnostics.csv", "report.md", "report.html"):
        assert (tmp_path / name).stat().st_size > 0, name
    comparison = pd.read_csv(tmp_path / "comparison.csv")
    assert list(comparison.columns) == ["case", "quantity", "backend", "value", "reference",
                                        "abs_err", "rel_err", "tolerance", "passed"]
    assert comparison["passed"].all()
    results = pd.read_csv(tmp_path / "results.csv")
    assert list(results.columns) == ["case", "backend", "quantity", "value", "unit"]
    assert results["value"].notna().all(), "absent quantities have no row, never NaN"
    report = (tmp_path / "report.md").read_text()
    assert report.index("Verdict") < report.index("## Cases")
    assert "seed-E2-friction" in report and "a2·cosθ12" in report


def test_injected_disagreement_turns_the_run_red(tmp_path: Path) -> None:
    """A tolerance tightened in the case file fails the run (exit 1), in JUnit and in the report."""
    path = tmp_path / "tight.toml"
    path.write_text(TIGHTENED)
    junit = tmp_path / "junit.xml"
    code, _ = invoke(["run", str(path), "-q", "-b", "virtual_work", "--out", str(tmp_path / "o"),
                      "--junit", str(junit)])
    assert code == 1
    suite = ET.parse(junit).getroot()
    failed = [c.get("name") for c in suite.iter("testcase") if c.find("failure") is not None]
    assert failed == ["virtual_work:T12"] and suite.get("failures") == "1"
    report = (tmp_path / "o" / "report.md").read_text()
    assert "**Verdict: FAIL**" in report and "(case file)" in report and "**FAIL**" in report
    # The same file without the override passes: the failure is the injected tolerance.
    path.write_text(CASE)
    code, _ = invoke(["run", str(path), "-q", "-b", "virtual_work", "--out", str(tmp_path / "p")])
    assert code == 0


def test_fail_on_controls_singular_verdicts(tmp_path: Path) -> None:
    """A singular pose is reported, not failed, unless --fail-on lists singular."""
    path = tmp_path / "c.toml"
    path.write_text(CASE.replace("theta12 = 60.0", "theta12 = 180.0"))
    out = str(tmp_path / "o")
    assert invoke(["run", str(path), "-q", "-b", "virtual_work", "--out", out])[0] == 0
    assert invoke(["run", str(path), "-q", "-b", "virtual_work", "--out", out,
                   "--fail-on", "singular"])[0] == 1
    diagnostics = pd.read_csv(Path(out) / "diagnostics.csv")
    assert set(diagnostics.loc[diagnostics["key"] == "message", "status"]) == {"singular"}


def test_sweep_command_with_an_injected_disagreement(tmp_path: Path) -> None:
    """`mechcheck sweep` writes Parquet, figures and reports; a tightened tolerance exits 1."""
    path = tmp_path / "tight.toml"
    path.write_text(TIGHTENED)
    junit = tmp_path / "sweep.xml"
    out = tmp_path / "sweep"
    code, output = invoke(["sweep", str(path), "--theta12", "0:360:10", "-b", "virtual_work",
                           "--workers", "0", "-q", "--out", str(out), "--junit", str(junit)])
    assert code == 1, output
    assert (out / "figures" / "e1.png").stat().st_size > 10_000
    results = pd.read_parquet(out / "results")
    assert set(results["backend"].astype(str)) == {"analytic", "virtual_work"}
    comparison = pd.read_parquet(out / "comparison.parquet")
    # Exactly the T12 rows that are not bit-identical fail (1e-30 admits only zero error);
    # every other quantity keeps the policy's tolerance and passes.
    t12 = comparison["quantity"] == "T12"
    assert (~comparison["passed"] == (t12 & (comparison["abs_err"] > 0))).all()
    assert (t12 & (comparison["abs_err"] > 0)).sum() > 20
    suite = ET.parse(junit).getroot()
    assert int(suite.get("failures", "0")) == int((~comparison["passed"]).sum())
    assert "**Verdict: FAIL**" in (out / "report.md").read_text()
    assert "data:image/png;base64," in (out / "report.html").read_text()
