"""The pytest plugin, run by pytest's own ``pytester``: a user's case files as test items."""

from __future__ import annotations

import pytest
from typer.testing import CliRunner

# pytester's in-process runs forget the modules they imported, and numpy cannot be
# loaded twice in one process: import here everything the plugin's items will use.
import mechcheck.analytic.linkage_backends
import mechcheck.analytic.presets
import mechcheck.run
import mechcheck.testing  # noqa: F401
from mechcheck import backends as registry
from mechcheck.analytic.case import Case
from mechcheck.analytic.contract import Backend
from mechcheck.analytic.solution import Solution
from mechcheck.cli import app

from .builtin import rocker_load_case
from .fake_trajectories import block_case

GOOD = rocker_load_case("e1-rocker")
#: No method meets a relative tolerance of 1e-30 unless bit-identical (as in test_cli).
TIGHT = rocker_load_case("e1-tight") + """
[[case.tolerance]]
backend = "virtual_work"
quantity = "T12"
rtol = 1e-30
"""
BAD = rocker_load_case("e1-bad") + 'colour = "red"\n'
ANALYTIC_METHODS = ("--mechcheck-backend", "virtual_work", "--mechcheck-backend", "superposition")


def test_named_case_files_are_collected_and_pass(pytester: pytest.Pytester) -> None:
    """Files named *.mechcheck.toml become one item per case × backend, with readable ids."""
    pytester.makefile(".mechcheck.toml", arm=GOOD)
    pytester.makefile(".toml", other=GOOD)  # not named so, and no --mechcheck: not collected
    result = pytester.runpytest("-v", *ANALYTIC_METHODS)
    result.assert_outcomes(passed=3)
    result.stdout.fnmatch_lines([
        "*arm.mechcheck.toml::e1-rocker[[]analytic[]] PASSED*",
        "*arm.mechcheck.toml::e1-rocker[[]virtual_work[]] PASSED*",
        "*arm.mechcheck.toml::e1-rocker[[]superposition[]] PASSED*",
    ])


def test_mechcheck_option_collects_a_directory_of_case_files(pytester: pytest.Pytester) -> None:
    """`pytest --mechcheck cases/` takes every .toml holding [[case]] tables, nothing else, and
    `-k` selects by case name and backend."""
    cases = pytester.mkdir("cases")
    (cases / "one.toml").write_text(GOOD)
    (cases / "two.toml").write_text(rocker_load_case("e1-second"))
    (cases / "settings.toml").write_text('[tool.other]\nkey = 1\n')
    result = pytester.runpytest("--mechcheck", "cases", *ANALYTIC_METHODS)
    result.assert_outcomes(passed=6)
    selected = pytester.runpytest("--mechcheck", "cases", "-v", "-k", "e1-second and virtual_work",
                                  *ANALYTIC_METHODS)
    selected.assert_outcomes(passed=1)
    selected.stdout.fnmatch_lines(["*two.toml::e1-second[[]virtual_work[]] PASSED*"])
    assert pytester.runpytest("cases", *ANALYTIC_METHODS).ret == pytest.ExitCode.NO_TESTS_COLLECTED


def test_a_disagreement_fails_with_case_quantity_values_unit_and_tolerance(
        pytester: pytest.Pytester) -> None:
    """An injected disagreement fails its item; the message is the policy's, without a traceback."""
    pytester.makefile(".mechcheck.toml", tight=TIGHT)
    result = pytester.runpytest("--mechcheck-backend", "virtual_work")
    result.assert_outcomes(passed=1, failed=1)
    result.stdout.fnmatch_lines([
        "*e1-tight [[]virtual_work[]]: 1 of * quantities outside tolerance",
        "*T12: * N*m vs analytic * N*m; relative error * > tolerance 1.0e-30 (static: *",
    ])
    assert "Traceback" not in result.stdout.str() and "runtest" not in result.stdout.str()


def test_a_bad_case_file_is_a_collection_error_with_the_cli_line(pytester: pytest.Pytester) -> None:
    """A file that cannot be used is a collection error carrying exactly the CLI's one line."""
    pytester.makefile(".mechcheck.toml", bad=BAD)
    result = pytester.runpytest("--mechcheck-backend", "virtual_work")
    result.assert_outcomes(errors=1)
    cli = CliRunner().invoke(app, ["run", "bad.mechcheck.toml", "-q"])
    line = cli.output.strip()
    assert cli.exit_code == 2 and line.startswith("mechcheck: error: bad.mechcheck.toml")
    assert "colour" in line
    result.stdout.fnmatch_lines([line.replace("[", "[[]")])
    assert "Traceback" not in result.stdout.str()


FAKE_STATUS = {"status": "ok"}


def fake_backend(case: Case) -> Solution:
    """A backend that gives the verdict the test chose, and no numbers."""
    status = FAKE_STATUS["status"]
    return Solution(case.name, "fake", {}, status=status, message=f"because {status}")  # type: ignore[arg-type]


@pytest.mark.parametrize(("status", "outcome"), [
    ("not_settled", "failed"), ("error", "failed"),
    ("singular", "skipped"), ("indeterminate", "skipped"), ("not_applicable", "skipped"),
    ("no_solution", "skipped"),
])
def test_verdicts_fail_or_skip_with_their_reason(pytester: pytest.Pytester,
                                                 monkeypatch: pytest.MonkeyPatch,
                                                 status: str, outcome: str) -> None:
    """not_settled and error fail; the verdicts that leave nothing to compare skip, saying why."""
    monkeypatch.setitem(registry.REGISTRY, "fake", Backend("fake", f"{__name__}:fake_backend", "settled"))
    monkeypatch.setitem(FAKE_STATUS, "status", status)
    pytester.makefile(".mechcheck.toml", arm=GOOD)
    result = pytester.runpytest("-rs", "--mechcheck-backend", "fake")
    result.assert_outcomes(passed=1, **{outcome: 1})
    result.stdout.fnmatch_lines([f"*e1-rocker [[]fake[]]: {status}: because {status}*"])


def test_a_crashing_backend_is_an_error_verdict(pytester: pytest.Pytester,
                                                monkeypatch: pytest.MonkeyPatch) -> None:
    """A backend that raises fails its item with the exception, as `mechcheck run`'s error verdict."""
    # sqrt(case) raises TypeError
    monkeypatch.setitem(registry.REGISTRY, "boom", Backend("boom", "math:sqrt", "settled"))
    pytester.makefile(".mechcheck.toml", arm=GOOD)
    result = pytester.runpytest("--mechcheck-backend", "boom")
    result.assert_outcomes(passed=1, failed=1)
    result.stdout.fnmatch_lines(["*e1-rocker [[]boom[]]: error: TypeError*"])


def test_an_unknown_backend_is_a_usage_error(pytester: pytest.Pytester) -> None:
    """`--mechcheck-backend` with a name no backend has stops the run with the known names."""
    pytester.makefile(".mechcheck.toml", arm=GOOD)
    result = pytester.runpytest("--mechcheck-backend", "nope")
    assert result.ret != 0
    assert "unknown backend 'nope'" in result.stderr.str() + result.stdout.str()


def test_a_trajectory_file_is_checked_over_time(pytester: pytest.Pytester) -> None:
    """A trajectory case's items run as ``mechcheck simulate`` runs it: the reference
    (its energy balance) passes, a backend that does not simulate skips with why."""
    pytester.makefile(".mechcheck.toml", block=block_case())
    # In a subprocess: the run imports modules (scipy's integrators) that an in-process run
    # would forget, and numpy cannot be loaded twice in one process.
    result = pytester.runpytest_subprocess("-v", "-rs", "-p", "no:xdist",
                                           "--mechcheck-backend", "virtual_work")
    result.assert_outcomes(passed=1, skipped=1)
    result.stdout.fnmatch_lines(["*block-springs*analytic*PASSED*",
                                 "*virtual_work*not_applicable*no run over time*"])
