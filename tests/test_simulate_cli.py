"""``mechcheck simulate`` and ``mechcheck.simulate``: the harness between the trajectory
backends and the user, run on fakes (:mod:`tests.fake_trajectories`) whose errors are known
by construction: the refusals, the verdicts and exit statuses, the tables, JUnit and the
report.
"""

from __future__ import annotations

import math
import sys
import textwrap
import xml.etree.ElementTree as ET
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import mechcheck
import mechcheck.analytic.trajectory as trajectory_module
import mechcheck.casefile as casefile
import mechcheck.sim_models as simulators
from mechcheck import backends as registry
from mechcheck.analytic.values import CaseError
from mechcheck.cli import TRAJECTORIES as TRAJECTORIES_FILE
from mechcheck.simulate_report import ladder_lines
from mechcheck.simulate_run import RUNS_FILE

from . import fake_trajectories as fake
from .builtin import rocker_load_case
from .test_edges import one_line, run_cli

#: Every file a simulate run writes in its --out folder (figures/ aside).
WRITTEN = {"comparison.csv", "diagnostics.csv", "report.html", "report.md", RUNS_FILE,
           TRAJECTORIES_FILE}


@pytest.fixture
def fakes(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """The fake reference as ``analytic``'s trajectory run, the fake simulators as a package
    under ``mechcheck.sim_models`` (registry discovered again), the block's case file in a
    fresh folder. Undone afterwards."""
    monkeypatch.setattr(trajectory_module, "simulate", fake.reference)
    package = tmp_path / "sim_models" / "fakesims"
    package.mkdir(parents=True)
    (package / "__init__.py").write_text(textwrap.dedent(fake.PACKAGE))
    monkeypatch.setattr(simulators, "__path__", [*simulators.__path__, str(package.parent)])
    monkeypatch.setattr(registry, "REGISTRY", registry.discovered())
    monkeypatch.chdir(tmp_path)
    (tmp_path / "block.toml").write_text(fake.block_case())
    yield tmp_path
    sys.modules.pop(f"{simulators.__name__}.fakesims", None)


def simulate(*args: str) -> tuple[int, str, str]:
    return run_cli(["simulate", "-q", *args])


# -- the verdicts -------------------------------------------------------------------------

def test_a_simulator_within_the_tolerance_at_its_finest_run_passes(fakes: Path) -> None:
    """Finest run 2e-4 off (within 1e-3): exit 0, one comparison row per position quantity,
    each error the offset put in, 2e-4 (x_A and q_slide over the scale; y_A, phi_block 0)."""
    code, out, err = simulate("block.toml", "-b", "fakesim", "-o", "out")
    assert code == 0, err
    assert out.startswith("1 case, ") and "(PASS)" in out
    table = pd.read_csv(fakes / "out" / "comparison.csv")
    mine = table[table["backend"] == "fakesim"].set_index("quantity")
    assert set(mine.index) == {"x_A", "y_A", "phi_block", "q_slide"}  # W1, W2 on the ground
    assert mine.loc["x_A", "rel_err"] == pytest.approx(2e-4, rel=1e-9)
    assert mine.loc["q_slide", "rel_err"] == pytest.approx(2e-4, rel=1e-9)
    assert mine.loc["y_A", "rel_err"] == 0.0 and mine.loc["phi_block", "rel_err"] == 0.0
    assert (mine["tolerance"] == 1e-3).all() and mine["passed"].all()
    assert set(WRITTEN) <= {p.name for p in (fakes / "out").iterdir()}


def test_a_simulator_2e_3_off_at_its_finest_run_fails_and_the_report_says_why(
        fakes: Path) -> None:
    """Finest run 2e-3 off: exit 1, its x_A and q_slide outside 1e-3; the report says it never
    reaches the tolerance, with its smallest error and that run's closure gap."""
    code, out, _ = simulate("block.toml", "-b", "fakesim_off", "-o", "out")
    assert code == 1 and "(FAIL)" in out
    table = pd.read_csv(fakes / "out" / "comparison.csv")
    failed = table[~table["passed"].astype(bool)]
    assert set(failed["quantity"]) == {"x_A", "q_slide"}
    assert failed["rel_err"].to_numpy() == pytest.approx([2e-3, 2e-3], rel=1e-9)
    report = (fakes / "out" / "report.md").read_text()
    assert "fakesim_off never reaches the tolerance 1e-03 at any of its 3 settings: its " \
           "smallest error is 2.0e-03 (dt=0.0001, integrator=Euler" in report
    assert "closure_gap_m = 2e-09" in report


def test_a_tolerance_set_in_the_case_file_judges_the_finest_run(fakes: Path) -> None:
    """``[[case.tolerance]]`` on the position kind: the 2e-3 run passes under 5e-3, and the rows
    say the tolerance was the case file's."""
    extra = '[[case.tolerance]]\nbackend = "fakesim_off"\nquantity = "pose"\nrtol = 5e-3\n' \
            "# the fake's known offset, to test the override\n"
    (fakes / "loose.toml").write_text(fake.block_case(extra=extra))
    result = mechcheck.simulate(mechcheck.load_cases("loose.toml"), backends=["fakesim_off"])
    assert result.exit_status == 0
    rows = result.detail[result.detail["backend"] == "fakesim_off"]
    assert rows["overridden"].all() and (rows["tolerance"] == 5e-3).all()


def test_a_simulator_giving_nan_fails_whatever_its_status_says(fakes: Path) -> None:
    """A finest run that claims ok with NaN coordinates is an error verdict, which fails the
    run, and no number of it is compared."""
    code, out, _ = simulate("block.toml", "-b", "fakesim_nan", "-o", "out")
    assert code == 1 and "1 failing verdicts" in out
    diagnostics = pd.read_csv(fakes / "out" / "diagnostics.csv")
    row = diagnostics[(diagnostics["backend"] == "fakesim_nan") & (diagnostics["key"] == "message")]
    assert row["status"].item() == "error" and "non-finite" in row["value"].item()
    table = pd.read_csv(fakes / "out" / "comparison.csv")
    assert not (table["backend"] == "fakesim_nan").any()


def test_a_simulator_without_a_number_says_why(fakes: Path) -> None:
    """No number and a reason: not_applicable, named in the summary, its message in the report;
    not a failure by default."""
    code, out, _ = simulate("block.toml", "-b", "fakesim_none", "-o", "out")
    assert code == 0
    assert "no numbers: not_applicable ×1 (block-springs)" in out
    report = (fakes / "out" / "report.md").read_text()
    assert "models no spring between a slide and the ground" in report
    code, _, _ = simulate("block.toml", "-b", "fakesim_none", "-o", "strict",
                          "--fail-on", "not_applicable")
    assert code == 1


def test_a_backend_without_a_run_over_time_is_not_applicable(fakes: Path) -> None:
    result = mechcheck.simulate(mechcheck.load_cases("block.toml"), backends=["virtual_work"])
    verdict = next(s for s in result.solutions if s.backend == "virtual_work")
    assert verdict.status == "not_applicable" and "no run over time" in verdict.message
    assert result.exit_status == 0


def test_the_reference_energy_balance_is_checked(fakes: Path,
                                                 monkeypatch: pytest.MonkeyPatch) -> None:
    """The closed form's T + V is constant (½ (k1 + k2) X0² = 0.4 J): its residual is rounding.
    A reference whose balance is off by 1e-6 of it fails the policy's 1e-8."""
    result = mechcheck.simulate(mechcheck.load_cases("block.toml"), backends=[])
    energy = result.detail.set_index("quantity").loc["energy_residual"]
    assert energy["rel_err"] < 1e-14 and bool(energy["passed"])

    def leaky(case: mechcheck.Case) -> tuple[trajectory_module.Trajectory, ...]:
        (run,) = fake.reference(case)
        assert run.energy is not None
        lost = run.energy.dissipated + 0.4e-6 * (run.times > 0)
        return (trajectory_module.Trajectory(
            run.backend, run.times, run.coordinates,
            energy=trajectory_module.EnergyBalance(run.energy.kinetic, run.energy.potential,
                                                   run.energy.work, lost)),)

    monkeypatch.setattr(trajectory_module, "simulate", leaky)
    result = mechcheck.simulate(mechcheck.load_cases("block.toml"), backends=[])
    energy = result.detail.set_index("quantity").loc["energy_residual"]
    # 0.4e-6 J of 0.4 J (the 26 samples miss the energy's exact peak by < 1e-3 of it).
    assert energy["rel_err"] == pytest.approx(1e-6, rel=1e-3)
    assert result.exit_status == 1


def test_a_crashing_reference_is_an_error_verdict(fakes: Path,
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    def crash(case: mechcheck.Case) -> tuple[trajectory_module.Trajectory, ...]:
        raise FloatingPointError("step size underflow")

    monkeypatch.setattr(trajectory_module, "simulate", crash)
    result = mechcheck.simulate(mechcheck.load_cases("block.toml"), backends=["fakesim"])
    reference = result.solutions[0]
    assert reference.status == "error" and "step size underflow" in reference.message
    assert result.exit_status == 1 and not len(result.comparison)


def test_the_accuracy_against_cost_lines_follow_the_settings_that_vary_at_one_step() -> None:
    """MuJoCo-like runs: two integrators at each of two steps, a time constant that follows
    the step: one line per integrator; pymunk-like: two iteration counts at each step."""
    t, xy = np.zeros(1), np.zeros((1, 3))

    def run(**settings: object) -> trajectory_module.Trajectory:
        return trajectory_module.Trajectory("sim", t, xy, settings=settings)

    mujoco_like = tuple(run(dt=dt, integrator=i, timeconst=2 * dt)
                        for dt in (1e-3, 5e-4) for i in ("Euler", "RK4"))
    assert ladder_lines(mujoco_like) == {"sim Euler": [0, 2], "sim RK4": [1, 3]}
    pymunk_like = tuple(run(dt=dt, iterations=n, integrator="Euler")
                        for dt in (1e-3, 5e-4) for n in (10, 100))
    assert ladder_lines(pymunk_like) == {"sim iterations=10": [0, 2],
                                         "sim iterations=100": [1, 3]}
    assert ladder_lines(tuple(run(dt=dt) for dt in (1e-3, 5e-4))) == {"sim": [0, 1]}


# -- the tables ---------------------------------------------------------------------------

def test_the_runs_table_holds_every_rung_with_its_error_and_cost(fakes: Path) -> None:
    code, _, err = simulate("block.toml", "-b", "fakesim", "-o", "out")
    assert code == 0, err
    runs = pd.read_csv(fakes / "out" / RUNS_FILE)
    mine = runs[runs["backend"] == "fakesim"]
    assert mine["rung"].tolist() == [0, 1, 2]
    assert mine["error"].to_numpy() == pytest.approx([1e-2, 3e-3, 2e-4], rel=1e-9)
    assert mine["default"].tolist() == [False, True, False]
    assert mine["settings"].tolist() == [f"dt={dt:g}, integrator=Euler"
                                         for dt in (1e-2, 1e-3, 1e-4)]
    assert mine["steps"].tolist() == [50, 500, 5000]
    assert runs.loc[runs["backend"] == "analytic", "settings"].item() == "method=closed form"


def test_the_trajectories_table_reads_every_run_in_table_units(fakes: Path) -> None:
    """One row per (backend, run, time, quantity); the reference's x_A is X0·cos(ωt) in m."""
    code, _, err = simulate("block.toml", "-b", "fakesim", "-o", "out")
    assert code == 0, err
    table = pd.read_parquet(fakes / "out" / TRAJECTORIES_FILE)
    quantities = {"x_W1", "y_W1", "x_W2", "y_W2", "x_A", "y_A", "phi_block", "q_slide"}
    assert set(table["quantity"]) == quantities
    assert len(table) == (1 + 3) * 26 * len(quantities)
    x = table[(table["backend"] == "analytic") & (table["quantity"] == "x_A")]
    t = np.linspace(0.0, 0.5, 26)
    assert x["time"].to_numpy() == pytest.approx(t, abs=1e-15)
    assert x["value"].to_numpy() == pytest.approx(0.040 * np.cos(math.sqrt(250.0) * t),
                                                  abs=1e-15)


def test_no_trajectories_leaves_the_long_table_out(fakes: Path) -> None:
    code, _, err = simulate("block.toml", "-b", "fakesim", "-o", "out", "--no-trajectories")
    assert code == 0, err
    assert {p.name for p in (fakes / "out").iterdir()} >= WRITTEN - {TRAJECTORIES_FILE}
    assert not (fakes / "out" / TRAJECTORIES_FILE).exists()


def test_junit_holds_each_comparison_and_each_verdict(fakes: Path) -> None:
    code, _, _ = simulate("block.toml", "-b", "fakesim_off", "-b", "fakesim_none", "-o", "out",
                          "--junit", "junit.xml")
    assert code == 1
    suite = ET.parse(fakes / "junit.xml").getroot()
    failures = [c.get("name") for c in suite if c.find("failure") is not None]
    assert sorted(failures) == ["fakesim_off:q_slide", "fakesim_off:x_A"]
    skipped = [c.get("name") for c in suite if c.find("skipped") is not None]
    assert skipped == ["fakesim_none:verdict"]


def test_the_report_shows_the_first_screen_figure_and_runs(fakes: Path) -> None:
    code, _, _ = simulate("block.toml", "-b", "fakesim", "-b", "fakesim_off", "-o", "out")
    assert code == 1
    page = (fakes / "out" / "report.html").read_text()
    assert 'class="banner fail"' in page and 'class="matrix"' in page
    assert page.count('class="trajectory-figure"') == 1
    markdown = (fakes / "out" / "report.md").read_text()
    assert "![block-springs: trajectories" in markdown
    assert (fakes / "out" / "figures" / "block-springs.png").stat().st_size > 10_000
    assert "| `fakesim` | 2 | dt=0.0001, integrator=Euler |  | ok | 2.0e-04 |" in markdown


# -- the refusals -------------------------------------------------------------------------

def refused(folder: Path, text: str, *fragments: str, command: str = "simulate") -> None:
    """The case file ``text`` refused by ``command``: exit 2, one line naming the file, the
    case and every fragment (the key), nothing written."""
    (folder / "bad.toml").write_text(text)
    code, _, err = run_cli([command, "bad.toml", "-q", "-o", "written"])
    one_line(code, err, "bad.toml", "case 'bad'", *fragments)
    assert not (folder / "written").exists()


TORQUE_ON_PIN = """
[[case]]
name = "bad"
mechanism = "linkage"
[case.points]
O = [0.0, 0.0]
A = [1.0, 0.0]
[[case.links]]
name = "ground"
points = ["O"]
[[case.links]]
name = "bar"
points = ["O", "A"]
[[case.joints]]
name = "pin"
kind = "revolute"
links = ["ground", "bar"]
at = "O"
[[case.drivers]]
joint = "pin"
torque = {torque}
[[case.masses]]
link = "bar"
mass = 1.0
com = "A"
{simulate}
"""
SIMULATE = "[case.simulate]\nend = 1.0\noutputs = 11\n"


@pytest.mark.parametrize(("label", "text", "fragments"), [
    ("effort without [case.simulate]", TORQUE_ON_PIN.format(torque="0.5", simulate=""),
     ("key 'drivers[0].torque'", "[case.simulate]")),
    ("torque on a prismatic joint",
     fake.block_case("bad", '[[case.drivers]]\njoint = "slide"\ntorque = 1.0\n'),
     ("key 'drivers[0].torque'", "'force'")),
    ("outputs beyond end", fake.block_case("bad").replace("outputs = 26", "outputs = [0.1, 0.6]"),
     ("key 'simulate.outputs'", "within 0")),
    ("outputs not increasing",
     fake.block_case("bad").replace("outputs = 26", "outputs = [0.1, 0.3, 0.2]"),
     ("key 'simulate.outputs'", "increase")),
    ("unknown rate joint", fake.block_case("bad").replace("outputs = 26",
                                                          "outputs = 26\nrates = { hinge = 1.0 }"),
     ("key 'simulate.rates.hinge'", "unknown joint")),
    ("NaN in an effort table", TORQUE_ON_PIN.format(torque="[[0.0, 1.0], [0.5, nan]]",
                                                    simulate=SIMULATE),
     ("key 'drivers[0].torque[1][1]'", "must be finite")),
    ("inf in an effort table's times", TORQUE_ON_PIN.format(torque="[[0.0, 1.0], [inf, 2.0]]",
                                                            simulate=SIMULATE),
     ("key 'drivers[0].torque[1][0]'", "must be finite")),
    ("1e300 in an effort table", TORQUE_ON_PIN.format(torque="[[0.0, 1e300]]", simulate=SIMULATE),
     ("key 'drivers[0].torque'",)),
    ("NaN end", fake.block_case("bad").replace("end = 0.5", "end = nan"),
     ("key 'simulate.end'",)),
    ("1e300 end", fake.block_case("bad").replace("end = 0.5", "end = 1e300"),
     ("key 'simulate.end'",)),
    ("inf end", fake.block_case("bad").replace("end = 0.5", "end = inf"),
     ("key 'simulate.end'",)),
])
def test_unusable_trajectory_input_is_one_line(fakes: Path, label: str, text: str,
                                               fragments: tuple[str, ...]) -> None:
    refused(fakes, text, *fragments)


def test_each_command_refuses_the_other_kind_of_case(fakes: Path) -> None:
    """run and sweep refuse a trajectory case, simulate a case at one pose, each naming the
    key ``simulate`` and the command that runs it; validate accepts both."""
    trajectory = fake.block_case("bad")
    refused(fakes, trajectory, "key 'simulate'", "run it with mechcheck simulate", command="run")
    refused(fakes, trajectory, "key 'simulate'", "run it with mechcheck simulate",
            command="sweep")
    refused(fakes, rocker_load_case("bad"), "key 'simulate'", "mechcheck run")
    (fakes / "pose.toml").write_text(rocker_load_case("pose"))
    code, out, err = run_cli(["validate", "block.toml", "pose.toml"])
    assert code == 0, err
    assert out.strip() == "2 cases in 2 files: valid"


def test_the_api_refuses_the_other_kind_of_case_too(fakes: Path) -> None:
    (fakes / "pose.toml").write_text(rocker_load_case("pose"))
    with pytest.raises(mechcheck.CaseError, match=r"key 'simulate'.*mechcheck simulate"):
        mechcheck.check(mechcheck.load_cases("block.toml"), ["virtual_work"])
    with pytest.raises(mechcheck.CaseError, match=r"key 'simulate'.*mechcheck run"):
        mechcheck.simulate(mechcheck.load_cases("pose.toml"), [])


def test_without_files_and_without_built_in_trajectories_it_says_so(
        fakes: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(casefile, "builtin_trajectory_files", list)
    code, _, err = simulate("-o", "out")
    one_line(code, err, "no case file given", "no built-in trajectory cases")
    assert not (fakes / "out").exists()


def test_without_files_it_runs_the_built_in_trajectory_cases(
        fakes: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(casefile, "builtin_trajectory_files", lambda: [fakes / "block.toml"])
    code, out, err = simulate("-b", "fakesim", "-o", "out")
    assert code == 0, err
    assert out.startswith("1 case, ")
    assert mechcheck.simulate(backends=[]).cases[0].name == "block-springs"


def test_the_pose_api_refuses_a_trajectory_case(tmp_path: Path) -> None:
    """``mechcheck.solve`` and ``solve_poses`` refuse a trajectory case as ``run`` does,
    naming the key and the command that runs it."""
    (tmp_path / "block.toml").write_text(fake.block_case())
    (case,) = mechcheck.load_cases(tmp_path / "block.toml")
    for call in (lambda: mechcheck.solve(case), lambda: mechcheck.solve_poses(case, [0.0])):
        with pytest.raises(CaseError, match="simulate"):
            call()
