"""The edges a hostile tester found (issue 10): no input crashes mechcheck or makes it lie.

Each test names the class of input it covers; every one of them failed before its fix.
"""

from __future__ import annotations

import math
import os
import stat
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from mechcheck import backends as registry
from mechcheck.analytic.case import Case
from mechcheck.analytic.contract import Backend
from mechcheck.analytic.solution import Solution
from mechcheck.cli import app
from mechcheck.output import write_all
from mechcheck.sweep import parse_range

from .builtin import rocker_load_case

GOOD = rocker_load_case("demo")


def run_cli(args: list[str]) -> tuple[int, str, str]:
    result = CliRunner().invoke(app, args)
    return result.exit_code, result.stdout, result.stderr


def one_line(code: int, err: str, *fragments: str) -> str:
    """Exit 2 and exactly one line on stderr, the CLI's, holding every fragment."""
    lines = err.strip().splitlines()
    assert code == 2, err
    assert len(lines) == 1, err
    assert lines[0].startswith("mechcheck: error: "), lines[0]
    for fragment in fragments:
        assert fragment in lines[0], lines[0]
    return lines[0]


def assert_refused(args: list[str], *fragments: str) -> str:
    """Exit 2, exactly one line on stderr holding every fragment, and no traceback."""
    code, _, err = run_cli(args)
    return one_line(code, err, *fragments)


def case_file(tmp_path: Path, text: str = GOOD, name: str = "c.toml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


# -- 1. unreadable input ------------------------------------------------------------------

@pytest.mark.parametrize(("label", "content", "fragment"), [
    ("latin-1", GOOD.replace("demo", "démo").encode("latin-1"), "not UTF-8"),
    ("utf-16", GOOD.encode("utf-16"), "not UTF-8"),
    ("binary", bytes(range(256)), "not UTF-8"),
])
def test_files_that_are_not_utf8_are_one_line(tmp_path: Path, label: str, content: bytes,
                                              fragment: str) -> None:
    """A case file in another encoding, or not text at all, is refused in one line naming it."""
    path = tmp_path / f"{label}.toml"
    path.write_bytes(content)
    assert_refused(["run", str(path), "-q", "--out", str(tmp_path / "o")], str(path), fragment)
    assert not (tmp_path / "o").exists()


def test_a_utf8_byte_order_mark_is_accepted(tmp_path: Path) -> None:
    """A UTF-8 file that starts with a byte-order mark (as some editors save it) simply works."""
    path = tmp_path / "bom.toml"
    path.write_bytes(b"\xef\xbb\xbf" + GOOD.encode())
    code, _, err = run_cli(["run", str(path), "-q", "-b", "analytic", "--out", str(tmp_path / "o")])
    assert code == 0, err


def test_a_directory_a_symlink_loop_and_an_unreadable_file(tmp_path: Path,
                                                           monkeypatch: pytest.MonkeyPatch) -> None:
    """Paths that are not readable files are refused in one line naming them."""
    folder = tmp_path / "folder"
    folder.mkdir()
    assert_refused(["run", str(folder), "-q"], str(folder), "is a directory")
    (tmp_path / "a").symlink_to(tmp_path / "b")
    (tmp_path / "b").symlink_to(tmp_path / "a")
    assert_refused(["run", str(tmp_path / "a"), "-q"], str(tmp_path / "a"), "cannot be read")
    locked = case_file(tmp_path, name="locked.toml")
    real = os.open

    def denied(path: Any, flags: int, *args: Any, **kwargs: Any) -> int:
        if Path(path) == locked:  # as root, chmod 000 would not stop the read
            raise PermissionError(13, "Permission denied", str(path))
        return real(path, flags, *args, **kwargs)

    monkeypatch.setattr(os, "open", denied)
    assert_refused(["run", str(locked), "-q", "--out", str(tmp_path / "o")], str(locked),
                   "permission denied")


# -- 2. extreme magnitudes ------------------------------------------------------------------

@pytest.mark.parametrize(("old", "new", "key"), [
    ("a1 = 140.0", "a1 = 1e158", "geometry.a1"),        # 1e155 m overflowed when squared
    ("a3 = 100.0", "a3 = 1e-297", "geometry.a3"),       # 1e-300 m divided by zero
    ("magnitude = 100.0", "magnitude = 1e200", "loads[0].force.magnitude"),  # gave NaN
    ("angle = 20.0", "angle = 1e300", "loads[0].force.angle"),
    ("theta12 = 60.0", "theta12 = 1e300", "theta12"),
    ("at = [90.0, 0.0]", "at = [9e300, 0.0]", "loads[0].at[0]"),
])
def test_non_physical_magnitudes_are_refused_naming_the_key(tmp_path: Path, old: str, new: str,
                                                            key: str) -> None:
    """Values no machine has, which overflow or underflow the arithmetic, are refused at
    validation with the key named; never a traceback, never NaN."""
    path = case_file(tmp_path, GOOD.replace(old, new))
    assert_refused(["run", str(path), "-q", "--out", str(tmp_path / "o")], f"key '{key}'")


def test_arrays_nested_without_end_are_refused(tmp_path: Path) -> None:
    """A file with arrays nested thousands deep is refused in one line, not a RecursionError."""
    path = case_file(tmp_path, GOOD.replace("at = [90.0, 0.0]", "at = " + "[" * 5000 + "]" * 5000))
    assert_refused(["run", str(path), "-q"], str(path), "nested too deeply")


# -- 3. output paths ----------------------------------------------------------------------

def test_unwritable_outputs_are_refused_before_computing(tmp_path: Path) -> None:
    """An --out that is a file or lies under one, and a --junit that is a directory, exit 2
    at once, leaving what was there untouched."""
    path = case_file(tmp_path)
    blocker = tmp_path / "taken"
    blocker.write_text("keep me")
    assert_refused(["run", str(path), "-q", "--out", str(blocker)], "--out", "not a directory")
    assert_refused(["run", str(path), "-q", "--out", str(blocker / "sub")], "--out",
                   "cannot write there")
    assert_refused(["run", str(path), "-q", "--out", str(tmp_path / "o"), "--junit",
                    str(tmp_path)], "--junit", "is a directory")
    assert_refused(["sweep", str(path), "-q", "--out", str(blocker), "-b", "analytic"], "--out")
    assert blocker.read_text() == "keep me"
    assert not (tmp_path / "o" / "results.csv").exists()


def test_a_long_case_name_gives_bounded_file_names(tmp_path: Path) -> None:
    """A 300-character case name sweeps: part and figure names are short and unique."""
    name = "n" * 300
    path = case_file(tmp_path, GOOD.replace('"demo"', f'"{name}"'))
    out = tmp_path / "sweep"
    code, _, err = run_cli(["sweep", str(path), "-q", "-b", "analytic", "--workers", "0",
                            "--theta12", "0:30:10", "--out", str(out)])
    assert code == 0, err
    assert max(len(p.name) for p in out.rglob("*")) < 200
    assert len(pd.read_parquet(out / "results").query("quantity == 'T12'")) == 3


# -- 4 and 6. sweep grids -----------------------------------------------------------------

@pytest.mark.parametrize(("grid", "fragment"), [
    ("0:inf:1", "finite"), ("nan:10:1", "finite"), ("0:1e12:1", "±100000°"),
    ("0:100000:0.001", "at most 10,000,000"), ("0:10", "START:STOP:STEP"),
    ("10:0:1", "STOP > START"),
])
def test_bad_sweep_grids_are_refused_naming_the_option(tmp_path: Path, grid: str,
                                                       fragment: str) -> None:
    """Non-finite, endless or huge grids give a one-line error that names --theta12."""
    path = case_file(tmp_path)
    assert_refused(["sweep", str(path), "-q", "--theta12", grid, "--out", str(tmp_path / "o")],
                   "--theta12", fragment)


def test_the_grid_keeps_its_last_pose() -> None:
    """START:STOP:STEP visits every START + k·STEP below STOP: 0:10:3 ends at 9; 0:360:7 has
    52 poses (0 … 357); 0:360:1 has 360 and leaves 360° out (it is 0° again)."""
    assert parse_range("0:10:3").tolist() == [0.0, 3.0, 6.0, 9.0]
    assert len(parse_range("0:360:7")) == 52 and parse_range("0:360:7")[-1] == 357.0
    grid = parse_range("0:360:1")
    assert len(grid) == 360 and grid[-1] == 359.0
    assert len(parse_range("0:360:0.00036")) == 1_000_000


# -- 5. stray workers ---------------------------------------------------------------------

#: A sweep that keeps two workers busy for several seconds: driven pymunk runs, one per pose.
DRIVEN = GOOD + "[[case.masses]]\nlink = 3\nmass = 1.0\n[case.motion]\nomega = 5.0\n"


def children(pid: int) -> list[int]:
    out = []
    for stat_file in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat_file.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            out.append(int(stat_file.parent.name))
    return out


def running(pid: int) -> bool:
    """Alive and not a zombie (a dead process nobody has reaped yet)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


@pytest.mark.slow
@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads processes from /proc")
@pytest.mark.parametrize("signal_name", ["SIGTERM", "SIGKILL"])
def test_sweep_workers_die_with_the_sweep(tmp_path: Path, signal_name: str) -> None:
    """However `mechcheck sweep` dies (SIGTERM: it shuts its pool down; SIGKILL: each worker
    sees its parent gone), no worker process is left behind."""
    import signal
    import subprocess
    import sys
    import time

    path = case_file(tmp_path, DRIVEN)
    sweep = subprocess.Popen(
        [sys.executable, "-m", "mechcheck", "sweep", str(path), "-q", "-b", "pymunk",
         "--workers", "2", "--theta12", "0:360:0.5", "--out", str(tmp_path / "o")],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 60
    workers: list[int] = []
    while len(workers) < 2 and time.monotonic() < deadline and sweep.poll() is None:
        time.sleep(0.2)
        workers = children(sweep.pid)
    assert len(workers) == 2, "the sweep never started its two workers"
    time.sleep(1.0)  # busy with their tasks
    sweep.send_signal(getattr(signal, signal_name))
    sweep.wait(timeout=30)
    deadline = time.monotonic() + 10
    while any(running(w) for w in workers) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not any(running(w) for w in workers), f"workers outlived a {signal_name}"

# -- 7. a changed case --------------------------------------------------------------------

def test_a_changed_case_is_read_once(tmp_path: Path) -> None:
    """After a case changes and the sweep runs again into the same directory, the Parquet
    dataset README tells users to read holds the new numbers only."""
    path = case_file(tmp_path)
    out = tmp_path / "sweep"
    args = ["sweep", str(path), "-q", "-b", "analytic", "--workers", "0", "--theta12", "0:30:10",
            "--out", str(out)]
    assert run_cli(args)[0] == 0
    path.write_text(GOOD.replace("magnitude = 100.0", "magnitude = 200.0"))
    assert run_cli(args)[0] == 0
    t12 = pd.read_parquet(out / "results").query("quantity == 'T12'")
    assert len(t12) == 3 and t12["theta12"].is_unique
    status = pd.read_parquet(out / "status")
    assert len(status) == 3


# -- 8. a case without loads --------------------------------------------------------------

UNLOADED = GOOD.split("[[case.loads]]")[0].replace('"demo"', '"unloaded-fourbar"') + """
[[case]]
name = "unloaded-slider"
mechanism = "slider_crank"
theta12 = 50.0
[case.geometry]
a2 = 0.1
a3 = 0.3
"""


def test_a_case_without_loads_passes_in_every_backend(tmp_path: Path) -> None:
    """With no load every force is zero; every backend says so (settling too) and passes:
    simulator rounding noise is judged against the policy's force floor, not against zero."""
    path = case_file(tmp_path, UNLOADED)
    out = tmp_path / "o"
    code, stdout, _ = run_cli(["run", str(path), "-q", "--out", str(out)])
    assert code == 0, stdout
    diagnostics = pd.read_csv(out / "diagnostics.csv")
    assert set(diagnostics["status"]) == {"ok"}
    comparison = pd.read_csv(out / "comparison.csv")
    assert comparison["passed"].all() and len(comparison) > 100


# -- 10. numbers that are not finite ------------------------------------------------------

FAKE = {"value": math.nan}


def non_finite_backend(case: Case) -> Solution:
    """A broken backend: claims ``ok`` with a non-finite drive torque (a four-bar's crank
    joint is ``A0``: its effort reads as T12)."""
    return Solution(case.name, "broken", {"Q_A0": FAKE["value"], "phi_coupler": 0.5},
                    units={"Q_A0": "N*m", "phi_coupler": "deg"})


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf])
def test_a_non_finite_number_never_passes(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                          value: float) -> None:
    """A backend that produces NaN or ±inf gets the verdict `error`, naming the quantity;
    the run fails and no table holds a non-finite number."""
    monkeypatch.setitem(registry.REGISTRY, "broken",
                        Backend("broken", f"{__name__}:non_finite_backend", "settled"))
    monkeypatch.setitem(FAKE, "value", value)
    path = case_file(tmp_path)
    out = tmp_path / "o"
    code, _, _ = run_cli(["run", str(path), "-q", "-b", "broken", "--out", str(out)])
    assert code == 1
    diagnostics = pd.read_csv(out / "diagnostics.csv")
    broken = diagnostics[diagnostics["backend"] == "broken"]
    assert set(broken["status"]) == {"error"}
    assert "non-finite T12" in broken[broken["key"] == "message"]["value"].iloc[0]
    for table in ("results.csv", "comparison.csv"):
        numbers = pd.read_csv(out / table).select_dtypes("number")
        assert np.isfinite(numbers.to_numpy()).all(), table


def test_a_verdict_keeps_only_finite_numbers() -> None:
    """A backend with a verdict simply has no number for what is not finite: no NaN row."""
    from mechcheck.run import finite_only

    withheld = Solution("c", "b", {"theta13": math.nan, "theta14": 1.0}, status="singular")
    assert dict(finite_only(withheld).values) == {"theta14": 1.0}
    assert finite_only(withheld).status == "singular"


# -- 11. names ----------------------------------------------------------------------------

def test_a_name_with_a_trailing_newline_is_refused(tmp_path: Path) -> None:
    """``"demo\\n"`` is not a name (``$`` matched before the newline); the error stays one line."""
    path = case_file(tmp_path, GOOD.replace('"demo"', '"demo\\n"'))
    assert_refused(["run", str(path), "-q"], "key 'name'", "demo\\n")


# -- 12. one angle, one spelling ----------------------------------------------------------

def test_angles_are_wrapped_alike_for_every_backend(tmp_path: Path) -> None:
    """θ14 of seed E1's geometry on the crossed branch is −165.83° in every backend's rows
    (MuJoCo and pymunk used to write 194.17°)."""
    path = case_file(tmp_path, GOOD.replace("theta12 = 60.0", 'theta12 = 60.0\nbranch = "crossed"'))
    out = tmp_path / "o"
    code, _, _ = run_cli(["run", str(path), "-q", "-b", "mujoco_solve", "-b", "pymunk_solve",
                          "--out", str(out)])
    assert code == 0
    results = pd.read_csv(out / "results.csv")
    theta14 = results[results["quantity"] == "theta14"]["value"]
    assert len(theta14) == 3
    assert theta14.between(-180.0, 180.0, inclusive="left").all()
    assert theta14.max() - theta14.min() < 1e-9


# -- 13 and 14. poses without a position --------------------------------------------------

SQUARE = """
[[case]]
name = "square"
mechanism = "four_bar"
theta12 = 0.0
[case.geometry]
a1 = 1.0
a2 = 1.0
a3 = 1.0
a4 = 1.0
[[case.loads]]
link = 4
at = [0.5, 0.0]
force = { x = 0.0, y = 10.0 }
"""


def test_a_change_point_is_called_one(tmp_path: Path) -> None:
    """A square linkage at θ12 = 0 is a change point: `singular`, said so, never "cannot be
    assembled … every θ12 assembles"."""
    path = case_file(tmp_path, SQUARE)
    out = tmp_path / "o"
    code, _, _ = run_cli(["run", str(path), "-q", "--out", str(out)])
    assert code == 0
    diagnostics = pd.read_csv(out / "diagnostics.csv")
    assert set(diagnostics["status"]) == {"singular"}
    messages = diagnostics[diagnostics["key"] == "message"]["value"]
    assert all("change point" in m and "cannot be assembled" not in m for m in messages)


def test_sweep_and_theory_take_a_case_whose_nominal_pose_does_not_assemble(tmp_path: Path) -> None:
    """The nominal θ12 of a file matters to neither a sweep nor the theory: both accept it."""
    # a1 = 300, a2 = 100, a3 = 150, a4 = 100 assembles for |θ12| ≤ 51.32° (test_casefile).
    text = (GOOD.replace("a1 = 140.0", "a1 = 300.0").replace("a2 = 80.0", "a2 = 100.0")
            .replace("a3 = 100.0", "a3 = 150.0").replace("a4 = 120.0", "a4 = 100.0")
            .replace("theta12 = 60.0", "theta12 = 120.0"))
    path = case_file(tmp_path, text)
    out = tmp_path / "sweep"
    code, _, err = run_cli(["sweep", str(path), "-q", "-b", "analytic", "--workers", "0",
                            "--theta12", "0:90:30", "--out", str(out)])
    assert code == 0, err
    status = pd.read_parquet(out / "status").set_index("theta12")["status"]
    assert status.to_dict() == {0.0: "ok", 30.0: "ok", 60.0: "no_solution"}
    code, stdout, _ = run_cli(["theory", "case", str(path)])
    assert code == 0 and "[-51.3178°, 51.3178°]" in stdout


# -- 16. theory grashof -------------------------------------------------------------------

@pytest.mark.parametrize(("lengths", "fragment"), [
    (["inf", "1", "1", "1"], "finite"),
    (["1000", "1", "1", "1"], "cannot close a loop"),
    (["3", "1", "1", "1"], "cannot close a loop"),
])
def test_grashof_refuses_lengths_that_are_no_four_bar(lengths: list[str], fragment: str) -> None:
    """An infinite length, or a longest link not shorter than the other three together, is
    no four-bar: refused with the reason instead of classified."""
    ground, crank, coupler, rocker = lengths
    assert_refused(["theory", "grashof", "--ground", ground, "--crank", crank, "--coupler",
                    coupler, "--rocker", rocker], fragment)


# -- 19. file modes -----------------------------------------------------------------------

def test_outputs_respect_the_umask(tmp_path: Path) -> None:
    """Outputs get 0666 less the umask, like any file the user writes (mkstemp gave 0600)."""
    old = os.umask(0o022)
    try:
        write_all(tmp_path, {"a.csv": "x"})
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "a.csv").stat().st_mode) == 0o644


# -- 21. an empty pass --------------------------------------------------------------------

def test_a_run_with_nothing_to_compare_says_so(tmp_path: Path) -> None:
    """An analytic-only run says that nothing was compared, on the console and in the report."""
    path = case_file(tmp_path)
    out = tmp_path / "o"
    code, stdout, _ = run_cli(["run", str(path), "-q", "-b", "analytic", "--out", str(out)])
    assert code == 0
    assert "nothing compared: only the reference backend (analytic) ran" in stdout
    assert "nothing compared" in (out / "report.md").read_text()
    assert "0 comparisons" not in stdout + (out / "report.md").read_text()


# -- 17. the format reference and a starting file -----------------------------------------

@pytest.mark.parametrize("mechanism", ["four_bar", "slider_crank", "linkage", "linkage_sketch"])
def test_mechcheck_new_writes_a_commented_example_that_runs(tmp_path: Path, mechanism: str) -> None:
    """`mechcheck new KIND > my.toml` gives a file that runs as it is, and whose commented-out
    optional keys are valid too once uncommented."""
    code, text, _ = run_cli(["new", mechanism])
    assert code == 0 and text.count("#") > 20
    path = case_file(tmp_path, text)
    assert run_cli(["run", str(path), "-q", "-b", "analytic", "--out", str(tmp_path / "a")])[0] == 0
    uncommented = "\n".join(line[2:] if line.startswith("# ") and ("=" in line or line.startswith("# ["))
                            and not line.startswith("# A ") else line for line in text.splitlines())
    full = case_file(tmp_path, uncommented, "full.toml")
    code, _, err = run_cli(["run", str(full), "-q", "-b", "analytic", "--out", str(tmp_path / "b")])
    assert code == 0, err
    assert_refused(["new", "six_bar"], "four_bar, slider_crank, linkage")


def test_readme_holds_the_case_file_reference() -> None:
    """The case-file format is documented in the repository (README links its reference
    page, docs/case-files.md), not behind a link out of it."""
    root = Path(__file__).resolve().parents[1]
    readme = (root / "README.md").read_text(encoding="utf-8")
    reference = (root / "docs" / "case-files.md").read_text(encoding="utf-8")
    assert "docs/case-files.md" in readme
    assert "../shared" not in readme + reference
    for key in ("length_unit", "pin_radius", "[case.seed]", "[[case.tolerance]]", "drive_link"):
        assert key in reference, key


# -- 18. units in the API -----------------------------------------------------------------

def test_the_api_names_its_units() -> None:
    """Vectorised solvers take ``theta12_rad``; a Solution's values are SI and radians, and
    ``in_table_units`` gives the tables' degrees, wrapped."""
    import mechcheck

    from .closed_form import forces

    case = mechcheck.load_cases()[0]
    results = forces.solve_poses(case, theta12_rad=[case.preset.theta12])
    assert results.values["theta13"][0] == mechcheck.solve(case).values["theta13"]
    solution = Solution("c", "b", {"theta14": 3.5, "T12": 2.0})
    assert solution.in_table_units() == pytest.approx({"theta14": math.degrees(3.5) - 360.0,
                                                       "T12": 2.0})


# -- 22. a report that scales -------------------------------------------------------------

def test_the_report_indexes_every_case_and_echoes_its_inputs(tmp_path: Path) -> None:
    """The report starts with an index linking to every case; each case's section echoes its
    inputs as written; past 50 cases passing sections fold; seed deviations carry units."""
    lines = GOOD.strip().splitlines()
    body = "\n".join(line for line in lines if not line.startswith("name"))
    many = "\n".join(body.replace("[[case]]", f'[[case]]\nname = "c{i:03d}"') for i in range(60))
    path = case_file(tmp_path, many)
    out = tmp_path / "o"
    assert run_cli(["run", str(path), "-q", "-b", "virtual_work", "--out", str(out)])[0] == 0
    for report, link in (("report.md", "](#case-c{:03d})"), ("report.html", 'href="#case-c{:03d}"')):
        text = (out / report).read_text()
        assert all(link.format(i) in text for i in range(60)), report
        assert text.count("<details><summary>Inputs and values") == 60
        assert "geometry: a1 = 140, a2 = 80, a3 = 100, a4 = 120" in text
    suite = tmp_path / "suite"
    assert run_cli(["run", "-q", "-b", "analytic", "--out", str(suite)])[0] == 0
    assert "| seed-E1-as-stated | F14 | N | 37.74 |" in (suite / "report.md").read_text()
