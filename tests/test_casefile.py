"""Bad input fails clearly: one line naming the file, the case and the key, exit 2, no output."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest
from typer.testing import CliRunner

from mechcheck.cli import app

from .builtin import rocker_load_case

GOOD = rocker_load_case("good")

SLIDER = """
[[case]]
name = "bad"
mechanism = "slider_crank"
theta12 = 55.0
[case.geometry]
a2 = 0.2
a3 = 0.8
[[case.loads]]
link = 4
force = { x = -100.0, y = 0.0 }
"""

FOURBAR = GOOD.replace('"good"', '"bad"')

# (id, file text, expected key, a fragment of the message)
BAD_INPUTS = [
    ("unknown-key", FOURBAR.replace("theta12 = 60.0", "theta12 = 60.0\ncolour = 'red'"),
     "colour", "unknown key"),
    ("unknown-nested-key", FOURBAR.replace("link = 4", "link = 4\nlever = 2.0"),
     "loads[0].lever", "unknown key"),
    ("missing-key", FOURBAR.replace("theta12 = 60.0\n", ""), "theta12", "required"),
    ("missing-geometry-key", FOURBAR.replace("a4 = 120.0\n", ""), "geometry.a4", "required"),
    ("wrong-type", FOURBAR.replace("theta12 = 60.0", "theta12 = 'sixty'"), "theta12", "number"),
    ("non-finite", FOURBAR.replace("theta12 = 60.0", "theta12 = nan"), "theta12", "finite"),
    ("infinite-force", FOURBAR.replace("magnitude = 100.0", "magnitude = inf"),
     "loads[0].force.magnitude", "finite"),
    ("zero-length", FOURBAR.replace("a3 = 100.0", "a3 = 0.0"), "geometry.a3", "> 0"),
    ("negative-length", FOURBAR.replace("a1 = 140.0", "a1 = -140.0"), "geometry.a1", "> 0"),
    ("zero-mass", FOURBAR + "[[case.masses]]\nlink = 3\nmass = 0.0\n", "masses[0].mass", "> 0"),
    ("negative-inertia", FOURBAR + "[[case.masses]]\nlink = 3\nmass = 1.0\ninertia = -1e-3\n",
     "masses[0].inertia", ">= 0"),
    ("link-out-of-range", FOURBAR.replace("link = 4", "link = 7"), "loads[0].link", "2, 3 or 4"),
    ("link-ground", FOURBAR.replace("link = 4", "link = 1"), "loads[0].link", "2, 3 or 4"),
    ("drive-4-on-slider", SLIDER.replace("theta12 = 55.0", "theta12 = 55.0\ndrive_link = 4"),
     "drive_link", "four_bar"),
    ("friction-without-direction",
     SLIDER + "[case.friction]\nmu = 0.1\npin_radius = { A = 0.05 }\n",
     "friction.direction", "required"),
    ("friction-direction-disagrees",
     SLIDER + "[case.motion]\nomega = 3.0\n[case.friction]\nmu = 0.1\n"
     "pin_radius = { A = 0.05 }\ndirection = 'cw'\n", "friction.direction", "other way"),
    ("slide-mu-on-four-bar", FOURBAR + "[case.friction]\nslide_mu = 0.1\ndirection = 'cw'\n",
     "friction.slide_mu", "no slide"),
    ("unknown-pin", SLIDER + "[case.friction]\nmu = 0.1\npin_radius = { B0 = 0.05 }\n"
     "direction = 'cw'\n", "friction.pin_radius.B0", "unknown pin"),
    ("bad-branch", FOURBAR.replace("theta12 = 60.0", "theta12 = 60.0\nbranch = 'left'"),
     "branch", "open"),
    ("bad-name", FOURBAR.replace('name = "bad"', 'name = "bad name!"'), "name", "letters"),
    ("never-assembles", FOURBAR.replace("a1 = 140.0", "a1 = 340.0"), "geometry",
     "cannot be assembled at any θ12: a link is longer than the other three together"),
    ("bad-force-form", FOURBAR.replace("force = { magnitude = 100.0, angle = 20.0 }",
                                       "force = { r = 1.0 }"), "loads[0].force", "magnitude"),
]


def run_cli(args: list[str]) -> tuple[int, str]:
    result = CliRunner().invoke(app, args)
    return result.exit_code, result.stderr


@pytest.mark.parametrize(("text", "key", "fragment"), [b[1:] for b in BAD_INPUTS],
                         ids=[b[0] for b in BAD_INPUTS])
def test_bad_input_exits_2_naming_file_case_and_key(tmp_path: Path, text: str, key: str,
                                                   fragment: str) -> None:
    """Each kind of bad input gives exit 2 and one line with the file, the case and the key."""
    path = tmp_path / "cases.toml"
    path.write_text(GOOD + text)   # one good case before the bad one
    out = tmp_path / "out"
    code, err = run_cli(["run", str(path), "--out", str(out), "-q", "-b", "analytic"])
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert str(path) in lines[0] and "case 'bad" in lines[0] and f"key '{key}'" in lines[0], err
    assert fragment in lines[0], err
    assert not out.exists(), "a file with a bad case must produce no output at all"


def test_unassemblable_pose_is_a_no_solution_verdict_naming_the_range(tmp_path: Path) -> None:
    """A θ12 outside the range that assembles is a `no_solution` verdict for that case, stating
    the θ12 range that does assemble (rounded inward), while the other cases of the run still run."""
    # a1 = 300, a2 = 100, a3 = 150, a4 = 100: d = |AB0| must lie in [50, 250];
    # d² = 300² + 100² − 2·300·100·cos θ12 = 100000 − 60000 cos θ12 ≤ 62500 needs
    # cos θ12 ≥ 0.625, i.e. |θ12| ≤ acos(0.625) = 51.3178125°, printed inward as 51.3178°.
    path = tmp_path / "c.toml"
    path.write_text(GOOD + FOURBAR.replace("a1 = 140.0", "a1 = 300.0")
                    .replace("a2 = 80.0", "a2 = 100.0").replace("a3 = 100.0", "a3 = 150.0")
                    .replace("a4 = 120.0", "a4 = 100.0").replace("theta12 = 60.0", "theta12 = 120.0"))
    out = tmp_path / "o"
    code, _ = run_cli(["run", str(path), "-q", "-b", "virtual_work", "--out", str(out)])
    assert code == 0
    diagnostics = pd.read_csv(out / "diagnostics.csv")
    bad = diagnostics[(diagnostics["case"] == "bad") & (diagnostics["key"] == "message")]
    assert set(diagnostics[diagnostics["case"] == "bad"]["status"]) == {"no_solution"}
    assert len(bad) == 2 and all("[-51.3178°, 51.3178°]" in m for m in bad["value"])
    assert set(pd.read_csv(out / "comparison.csv")["case"]) == {"good"}
    code, _ = run_cli(["run", str(path), "-q", "-b", "virtual_work", "--out", str(out),
                       "--fail-on", "no_solution"])
    assert code == 1


def test_printed_range_endpoints_assemble(tmp_path: Path) -> None:
    """Entering an endpoint of the printed range is accepted: the endpoints are rounded inward."""
    path = tmp_path / "c.toml"
    geometry = (FOURBAR.replace("a1 = 140.0", "a1 = 300.0").replace("a2 = 80.0", "a2 = 100.0")
                .replace("a3 = 100.0", "a3 = 150.0").replace("a4 = 120.0", "a4 = 100.0"))
    path.write_text(geometry.replace("theta12 = 60.0", "theta12 = 51.3178"))
    out = tmp_path / "o"
    assert run_cli(["run", str(path), "-q", "-b", "analytic", "--out", str(out)])[0] == 0
    assert set(pd.read_csv(out / "diagnostics.csv")["status"]) == {"ok"}


def test_duplicate_case_names_across_files(tmp_path: Path) -> None:
    """Two cases with one name in a run are refused, naming the second file."""
    first, second = tmp_path / "a.toml", tmp_path / "b.toml"
    first.write_text(GOOD)
    second.write_text(GOOD)
    code, err = run_cli(["run", str(first), str(second), "-q", "--out", str(tmp_path / "o")])
    assert code == 2 and str(second) in err and "duplicate" in err and "key 'name'" in err


def test_missing_file_and_bad_toml(tmp_path: Path) -> None:
    """A missing file or broken TOML is named in a one-line error, exit 2."""
    code, err = run_cli(["run", str(tmp_path / "nope.toml"), "-q"])
    assert code == 2 and "nope.toml" in err
    broken = tmp_path / "broken.toml"
    broken.write_text("[[case]\nname=")
    code, err = run_cli(["run", str(broken), "-q"])
    assert code == 2 and "broken.toml" in err and "TOML" in err


def test_unknown_backend_is_refused_clearly(tmp_path: Path) -> None:
    """Asking for a backend that does not exist names it and lists the known ones."""
    path = tmp_path / "c.toml"
    path.write_text(GOOD)
    code, err = run_cli(["run", str(path), "-b", "bullet", "-q", "--out", str(tmp_path / "o")])
    assert code == 2 and "'bullet'" in err and "analytic" in err

