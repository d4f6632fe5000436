"""`mechanism = "linkage"` case files (LINKAGES.md): every error the contract lists is one
line naming the file, the case and the key, exit 2, nothing written; a valid file runs
through the analytic backends, which agree."""

from __future__ import annotations

import math
from pathlib import Path

import pandas as pd
import pytest
from typer.testing import CliRunner

from mechcheck.analytic.presets import preset_case
from mechcheck.cli import app


def drawn_four_bar() -> str:
    """Seed E1's four-bar (a1..a4 = 140, 80, 100, 120 mm) drawn at θ12 = 60° on the open
    branch, with a rocker load of 100 N at 20° at D, 90 mm from B0 along the rocker: the
    points come from the closed-form position analysis, in mm."""
    from mechcheck.analytic.case import FourBarGeometry
    from mechcheck.analytic.kinematics import pose_of

    pose = pose_of(preset_case("e1", FourBarGeometry(0.14, 0.08, 0.10, 0.12), math.radians(60.0)))
    p = {name: 1000 * xy[0] for name, xy in pose.joints.items()}
    p["D"] = p["B0"] + 0.75 * (p["B"] - p["B0"])
    points = "\n".join(f"{n} = [{float(v[0])!r}, {float(v[1])!r}]" for n, v in p.items())
    return FOUR_BAR_TEMPLATE.replace("POINTS", points)


FOUR_BAR_TEMPLATE = """
[[case]]
name = "four-bar"
mechanism = "linkage"
length_unit = "mm"
[case.points]
POINTS
[[case.links]]
name = "ground"
points = ["A0", "B0"]
[[case.links]]
name = "crank"
points = ["A0", "A"]
[[case.links]]
name = "coupler"
points = ["A", "B"]
[[case.links]]
name = "rocker"
points = ["B0", "B", "D"]
[[case.joints]]
name = "A0"
kind = "revolute"
links = ["ground", "crank"]
at = "A0"
[[case.joints]]
name = "A"
kind = "revolute"
links = ["crank", "coupler"]
at = "A"
[[case.joints]]
name = "B"
kind = "revolute"
links = ["coupler", "rocker"]
at = "B"
[[case.joints]]
name = "B0"
kind = "revolute"
links = ["ground", "rocker"]
at = "B0"
[[case.drivers]]
joint = "A0"
rotation = 0.0
[[case.loads]]
link = "rocker"
at = "D"
force = { magnitude = 100.0, angle = 20.0 }
"""
FOUR_BAR = drawn_four_bar()

#: A pendulum hung from the rocker at D: one more degree of freedom than drivers.
TAIL = """
[[case.links]]
name = "tail"
points = ["D", "T"]
[[case.joints]]
name = "D"
kind = "revolute"
links = ["rocker", "tail"]
at = "D"
"""

SPRING = """
[[case.springs]]
name = "s"
ends = [["crank", "A"], ["rocker", "D"]]
stiffness = 100.0
free_length = 80.0
"""


def run_cli(args: list[str]) -> tuple[int, str, str]:
    result = CliRunner().invoke(app, args)
    return result.exit_code, result.stdout, result.stderr


# (id, file text, key, a fragment of the message)
BAD = [
    ("point-no-link-carries", FOUR_BAR.replace("[case.points]", "[case.points]\nE = [1.0, 2.0]"),
     "points.E", "no link carries"),
    ("revolute-point-not-on-both", FOUR_BAR.replace('links = ["coupler", "rocker"]\nat = "B"',
                                                    'links = ["coupler", "rocker"]\nat = "A"'),
     "joints[2].at", "both links must carry"),
    ("prismatic-at-not-on-links1", FOUR_BAR.replace(
        'name = "B0"\nkind = "revolute"\nlinks = ["ground", "rocker"]\nat = "B0"',
        'name = "B0"\nkind = "prismatic"\nlinks = ["ground", "rocker"]\nat = "A0"\naxis = [1.0, 0.0]'),
     "joints[3].at", "must carry point 'A0'"),
    ("zero-axis", FOUR_BAR.replace(
        'name = "B0"\nkind = "revolute"\nlinks = ["ground", "rocker"]\nat = "B0"',
        'name = "B0"\nkind = "prismatic"\nlinks = ["ground", "rocker"]\nat = "B0"\naxis = [0.0, 0.0]'),
     "joints[3].axis", "zero"),
    ("link-without-points", FOUR_BAR.replace('name = "coupler"\npoints = ["A", "B"]',
                                             'name = "coupler"\npoints = []'),
     "links[2].points", "at least one point"),
    ("no-ground", FOUR_BAR.replace('"ground"', '"base"'), "links", "'ground'"),
    ("shared-point-not-joined", FOUR_BAR.replace('points = ["A0", "A"]', 'points = ["A0", "A", "D"]'),
     "points.D", "not all joined"),
    ("disconnected", FOUR_BAR.replace(
        '[[case.drivers]]', '[[case.links]]\nname = "loose"\npoints = ["F"]\n[[case.drivers]]')
     .replace("[case.points]", "[case.points]\nF = [500.0, 500.0]"),
     "joints", "not connected"),
    ("spring-on-one-link", FOUR_BAR + SPRING.replace('["crank", "A"]', '["rocker", "B"]'),
     "springs[0].ends", "one link"),
    ("unknown-link", FOUR_BAR.replace('link = "rocker"', 'link = "lever"'), "loads[0].link",
     "unknown link"),
    ("unknown-point", FOUR_BAR.replace('at = "D"', 'at = "Z"'), "loads[0].at", "unknown point"),
    ("driver-on-missing-joint", FOUR_BAR.replace('joint = "A0"', 'joint = "O9"'),
     "drivers[0].joint", "unknown joint"),
    ("joint-driven-twice", FOUR_BAR + '[[case.drivers]]\njoint = "A0"\nrotation = 5.0\n',
     "drivers[1].joint", "driven twice"),
    ("more-drivers-than-dof", FOUR_BAR + '[[case.drivers]]\njoint = "B0"\nrotation = 5.0\n',
     "drivers", "2 drivers for 1 degree"),
    ("free-coordinate-with-motion",
     FOUR_BAR.replace("rotation = 0.0", "rotation = 0.0\nvelocity = 1.0").replace(
         "[case.points]", "[case.points]\nT = [200.0, 0.0]") + TAIL,
     "drivers", "free coordinate(s) with motion"),
    ("coulomb-driver-at-rest-without-sense",
     FOUR_BAR + "[case.friction]\nmu = 0.1\npin_radius = { A = 5.0 }\n",
     "drivers[0].sense", "increasing"),
    ("four-bar-key-in-a-linkage", FOUR_BAR.replace('length_unit = "mm"',
                                                   'length_unit = "mm"\ntheta12 = 60.0'),
     "theta12", "unknown key"),
    ("rotation-on-a-prismatic", FOUR_BAR.replace("rotation = 0.0", "displacement = 1.0"),
     "drivers[0].displacement", "driven by 'rotation'"),
    ("bad-identifier", FOUR_BAR.replace('name = "crank"\npoints', 'name = "2crank"\npoints'),
     "links[1].name", "identifier"),
]


@pytest.mark.parametrize(("text", "key", "fragment"), [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_every_linkage_error_is_one_line_naming_file_case_and_key(
        tmp_path: Path, text: str, key: str, fragment: str) -> None:
    """Each error LINKAGES.md lists exits 2 with one line: the file, the case, the key."""
    path = tmp_path / "bad.toml"
    path.write_text(text)
    out = tmp_path / "out"
    code, _, err = run_cli(["run", str(path), "-q", "--out", str(out)])
    lines = err.strip().splitlines()
    assert code == 2, err
    assert len(lines) == 1, err
    assert str(path) in lines[0] and "case 'four-bar'" in lines[0], lines[0]
    assert f"key '{key}'" in lines[0] and fragment in lines[0], lines[0]
    assert not out.exists()


def test_the_four_bar_drawn_as_a_linkage_gives_seed_e1s_rocker_load_torque(tmp_path: Path) -> None:
    """E1's geometry with only the rocker load (100 N at 20° at D) has T12 = Q_A0 from the
    closed form (the built-in four-bar case `rocker_load_case`); virtual work and
    superposition agree with the matrix method to rounding."""
    from mechcheck.casefile import load_cases

    from .builtin import rocker_load_case

    closed = tmp_path / "closed.toml"
    closed.write_text(rocker_load_case("closed"))
    drawn = tmp_path / "drawn.toml"
    drawn.write_text(FOUR_BAR)
    out = tmp_path / "o"
    code, stdout, _ = run_cli(["run", str(closed), str(drawn), "-q", "-b", "virtual_work", "-b",
                               "superposition", "--out", str(out)])
    assert code == 0, stdout
    results = pd.read_csv(out / "results.csv").set_index(["case", "backend", "quantity"])["value"]
    t12 = results[("closed", "analytic", "T12")]
    for backend in ("analytic", "virtual_work", "superposition"):
        assert results[("four-bar", backend, "Q_A0")] == pytest.approx(t12, rel=1e-9)
    for legacy, name in (("F12", "A0"), ("F23", "A"), ("F34", "B"), ("F14", "B0")):
        for c in "xy":
            assert results[("four-bar", "analytic", f"F_{name}_{c}")] == pytest.approx(
                results[("closed", "analytic", f"{legacy}_{c}")], rel=1e-9, abs=1e-9)
    assert load_cases(drawn)[0].linkage.dof == 1
