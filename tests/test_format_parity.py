"""The two case-file formats refuse alike: every class of value the four-bar format refuses is
refused in the linkage format, and the other way round, each with exit 2 and one line naming
the file, the case and the key as the file spells it; a Linkage built in Python refuses the
same values; the linkage format's own bounds (driver travel, spacing of points, springs)
hold; and valid files still pass."""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from mechcheck.analytic.linkage import Linkage
from mechcheck.analytic.values import CaseError
from mechcheck.casefile import load_cases
from mechcheck.cli import app

from .builtin import rocker_load_case

#: Seed E1's four-bar (SEEDS.md) with every table the format has: a load with a torque, a
#: mass, gravity, motion and friction (ω > 0 agrees with `ccw`).
FOUR_BAR = rocker_load_case("parity").replace(
    "theta12 = 60.0", "theta12 = 60.0\nground_angle = 0.0\ngravity = [0.0, -9.81]") + """\
torque = 0.5
[[case.masses]]
link = 3
mass = 0.5
com = [50.0, 0.0]
inertia = 1.0e-4
[case.motion]
omega = 2.0
alpha = 0.0
[case.friction]
mu = 0.1
pin_radius = { A = 5.0 }
viscous = { B = 0.001 }
direction = "ccw"
"""

#: An offset slider-crank drawn as a linkage, in mm, with every key of the format: named
#: and [x, y] points for loads, masses and spring ends, polar and Cartesian forces, a
#: linear and a torsional spring, and every friction table.
LINKAGE = """
[[case]]
name = "parity"
mechanism = "linkage"
length_unit = "mm"
gravity = [0.0, -9.81]
[case.points]
O = [0.0, 0.0]
A = [30.0, 40.0]
B = [150.0, 10.0]
S = [250.0, 10.0]
K = [90.0, 25.0]
[[case.links]]
name = "ground"
points = ["O", "S"]
[[case.links]]
name = "crank"
points = ["O", "A"]
[[case.links]]
name = "rod"
points = ["A", "B", "K"]
[[case.links]]
name = "slider"
points = ["B"]
[[case.joints]]
name = "O"
kind = "revolute"
links = ["ground", "crank"]
at = "O"
[[case.joints]]
name = "A"
kind = "revolute"
links = ["crank", "rod"]
at = "A"
[[case.joints]]
name = "B"
kind = "revolute"
links = ["rod", "slider"]
at = "B"
[[case.joints]]
name = "slide"
kind = "prismatic"
links = ["ground", "slider"]
at = "B"
axis = [1.0, 0.0]
[[case.drivers]]
joint = "O"
rotation = 30.0
velocity = 0.0
acceleration = 0.0
sense = "decreasing"
[[case.loads]]
link = "slider"
at = "B"
force = { magnitude = 200.0, angle = 180.0 }
torque = 0.0
[[case.loads]]
link = "rod"
at = [90.0, 30.0]
force = { x = 10.0, y = -5.0 }
[[case.masses]]
link = "rod"
mass = 0.6
com = "K"
inertia = 8.0e-4
[[case.masses]]
link = "crank"
mass = 0.2
com = [15.0, 20.0]
inertia = 1.0e-5
[[case.springs]]
name = "pull"
ends = [["ground", "S"], ["slider", [150.0, 10.0]]]
stiffness = 2000.0
free_length = 80.0
damping = 0.5
[[case.springs]]
name = "wind"
joint = "A"
stiffness = 1.5
free_rotation = 10.0
damping = 0.01
[case.friction]
mu = 0.1
pin_radius = { O = 5.0, A = 5.0 }
joint_mu = { slide = 0.15 }
viscous = { B = 0.001 }
"""

#: A block on a slide between two ground points 200 mm apart, driven along the slide. Its
#: size is 200 mm however it is measured (the extent in x; twice the largest distance from
#: the centroid (0, 0)), so its driver may travel ±2000 mm.
SLIDE = """
[[case]]
name = "parity"
mechanism = "linkage"
length_unit = "mm"
[case.points]
W1 = [-100.0, 0.0]
W2 = [100.0, 0.0]
P = [0.0, 0.0]
[[case.links]]
name = "ground"
points = ["W1", "W2"]
[[case.links]]
name = "block"
points = ["P"]
[[case.joints]]
name = "slide"
kind = "prismatic"
links = ["ground", "block"]
at = "P"
axis = [1.0, 0.0]
[[case.drivers]]
joint = "slide"
displacement = 0.0
[[case.loads]]
link = "block"
at = "P"
force = { x = 10.0, y = 0.0 }
"""

#: A 400-digit integer: TOML integers are Python integers, unbounded.
HUGE = "9" * 400
#: LINKAGE's spring end given as coordinates (mm).
END = '"slider", [150.0, 10.0]'


def edit(text: str, old: str, new: str) -> str:
    """``text`` with its single ``old`` replaced (a test that misses its target fails)."""
    assert text.count(old) == 1, (old, text.count(old))
    return text.replace(old, new)


def run_cli(args: list[str]) -> tuple[int, str]:
    result = CliRunner().invoke(app, args)
    return result.exit_code, result.stderr


def assert_refused(tmp_path: Path, text: str, key: str, *fragments: str) -> str:
    """Exit 2 and one line naming the file, case 'parity' and ``key``; nothing written."""
    path = tmp_path / "bad.toml"
    path.write_text(text)
    out = tmp_path / "out"
    code, err = run_cli(["run", str(path), "-q", "-b", "analytic", "--out", str(out)])
    lines = err.strip().splitlines()
    assert code == 2, err
    assert len(lines) == 1, err
    assert str(path) in lines[0] and "case 'parity'" in lines[0], lines[0]
    assert f"key '{key}'" in lines[0], lines[0]
    for fragment in fragments:
        assert fragment in lines[0], lines[0]
    assert not out.exists()
    return lines[0]


# -- both formats ------------------------------------------------------------------------------
# (id, four-bar edit (old, new), its key, linkage edit (old, new), its key, a fragment of both
# messages). Each class of value one format refuses, written in each format.
PARITY: list[tuple[str, tuple[str, str], str, tuple[str, str], str, str]] = [
    ("nan-angle", ("theta12 = 60.0", "theta12 = nan"), "theta12",
     ("rotation = 30.0", "rotation = nan"), "drivers[0].rotation", "finite"),
    ("inf-force", ("magnitude = 100.0", "magnitude = inf"), "loads[0].force.magnitude",
     ("magnitude = 200.0", "magnitude = inf"), "loads[0].force.magnitude", "finite"),
    ("nan-point", ("at = [90.0, 0.0]", "at = [nan, 0.0]"), "loads[0].at[0]",
     ("at = [90.0, 30.0]", "at = [nan, 30.0]"), "loads[1].at", "finite"),
    ("nan-gravity", ("gravity = [0.0, -9.81]", "gravity = [0.0, nan]"), "gravity[1]",
     ("gravity = [0.0, -9.81]", "gravity = [0.0, nan]"), "gravity[1]", "finite"),
    ("huge-length", ("a1 = 140.0", "a1 = 1e158"), "geometry.a1",
     ("A = [30.0, 40.0]", "A = [1e158, 40.0]"), "points.A[0]", "at most 1e+12"),
    ("huge-force-x", ("force = { magnitude = 100.0, angle = 20.0 }", "force = { x = 1e13, y = 0.0 }"),
     "loads[0].force.x", ("x = 10.0", "x = 1e13"), "loads[1].force.x", "at most 1e+12"),
    ("huge-force-magnitude", ("magnitude = 100.0", "magnitude = 1e13"), "loads[0].force.magnitude",
     ("magnitude = 200.0", "magnitude = 1e13"), "loads[0].force.magnitude", "at most 1e+12"),
    ("huge-torque", ("torque = 0.5", "torque = 1e13"), "loads[0].torque",
     ("torque = 0.0", "torque = 1e13"), "loads[0].torque", "at most 1e+12"),
    ("huge-load-point", ("at = [90.0, 0.0]", "at = [1e16, 0.0]"), "loads[0].at[0]",
     ("at = [90.0, 30.0]", "at = [1e16, 30.0]"), "loads[1].at[0]", "at most 1e+12"),
    ("huge-mass", ("mass = 0.5", "mass = 1e13"), "masses[0].mass",
     ("mass = 0.6", "mass = 1e13"), "masses[0].mass", "at most 1e+12"),
    ("huge-com", ("com = [50.0, 0.0]", "com = [1e16, 0.0]"), "masses[0].com[0]",
     ("com = [15.0, 20.0]", "com = [1e16, 20.0]"), "masses[1].com[0]", "at most 1e+12"),
    ("huge-inertia", ("inertia = 1.0e-4", "inertia = 1e13"), "masses[0].inertia",
     ("inertia = 8.0e-4", "inertia = 1e13"), "masses[0].inertia", "at most 1e+12"),
    ("huge-gravity", ("gravity = [0.0, -9.81]", "gravity = [0.0, -1e13]"), "gravity[1]",
     ("gravity = [0.0, -9.81]", "gravity = [0.0, -1e13]"), "gravity[1]", "at most 1e+12"),
    ("huge-velocity", ("omega = 2.0", "omega = 1e13"), "motion.omega",
     ("velocity = 0.0", "velocity = -1e13"), "drivers[0].velocity", "at most 1e+12"),
    ("huge-acceleration", ("alpha = 0.0", "alpha = 1e13"), "motion.alpha",
     ("acceleration = 0.0", "acceleration = 1e13"), "drivers[0].acceleration", "at most 1e+12"),
    ("huge-mu", ("mu = 0.1", "mu = 1e13"), "friction.mu",
     ("mu = 0.1", "mu = 1e13"), "friction.mu", "at most 1e+12"),
    ("huge-pin-radius", ("pin_radius = { A = 5.0 }", "pin_radius = { A = 1e300 }"),
     "friction.pin_radius.A", ("A = 5.0 }", "A = 1e300 }"), "friction.pin_radius.A", "at most 1e+12"),
    ("huge-viscous", ("B = 0.001", "B = 1e13"), "friction.viscous.B",
     ("B = 0.001", "B = 1e13"), "friction.viscous.B", "at most 1e+12"),
    # 1e-4 mm = 1e-7 m: a link below a micrometre, or two points of one link that close.
    ("link-below-a-micrometre", ("a3 = 100.0", "a3 = 1e-4"), "geometry.a3",
     ("K = [90.0, 25.0]", "K = [30.0, 40.0001]"), "points.K", "a micrometre"),
    ("zero-mass", ("mass = 0.5", "mass = 0.0"), "masses[0].mass",
     ("mass = 0.6", "mass = 0.0"), "masses[0].mass", "> 0"),
    ("negative-mass", ("mass = 0.5", "mass = -0.5"), "masses[0].mass",
     ("mass = 0.6", "mass = -0.6"), "masses[0].mass", "> 0"),
    ("negative-inertia", ("inertia = 1.0e-4", "inertia = -1.0e-4"), "masses[0].inertia",
     ("inertia = 8.0e-4", "inertia = -8.0e-4"), "masses[0].inertia", ">= 0"),
    ("boolean-number", ("mass = 0.5", "mass = true"), "masses[0].mass",
     ("mass = 0.6", "mass = true"), "masses[0].mass", "must be a number"),
    ("boolean-pair", ("at = [90.0, 0.0]", "at = [true, false]"), "loads[0].at[0]",
     ("at = [90.0, 30.0]", "at = [true, false]"), "loads[1].at", "must be a number"),
    ("boolean-in-a-table", ("pin_radius = { A = 5.0 }", "pin_radius = { A = true }"),
     "friction.pin_radius.A", ("A = 5.0 }", "A = true }"), "friction.pin_radius.A",
     "must be a number"),
    ("text-for-a-number", ("theta12 = 60.0", "theta12 = 'sixty'"), "theta12",
     ("rotation = 30.0", "rotation = 'sixty'"), "drivers[0].rotation", "must be a number"),
    ("list-for-a-number", ("mass = 0.5", "mass = [0.5]"), "masses[0].mass",
     ("mass = 0.6", "mass = [0.6]"), "masses[0].mass", "must be a number"),
    ("force-angle-beyond-bound", ("angle = 20.0", "angle = 1e6"), "loads[0].force.angle",
     ("angle = 180.0", "angle = 1e6"), "loads[0].force.angle", "±100000°"),
    ("fixed-angle-beyond-bound", ("ground_angle = 0.0", "ground_angle = 1e6"), "ground_angle",
     ("free_rotation = 10.0", "free_rotation = 1e6"), "springs[1].free_rotation", "±100000°"),
    # The pose angle: θ12 within ±100 000°, a driver's rotation within ±3600° (continuation).
    ("pose-angle-beyond-bound", ("theta12 = 60.0", "theta12 = 1e6"), "theta12",
     ("rotation = 30.0", "rotation = 1e6"), "drivers[0].rotation", "got 1e+06°"),
    ("negative-mu", ("mu = 0.1", "mu = -0.1"), "friction.mu",
     ("mu = 0.1", "mu = -0.1"), "friction.mu", ">= 0"),
    ("negative-pin-radius", ("pin_radius = { A = 5.0 }", "pin_radius = { A = -5.0 }"),
     "friction.pin_radius.A", ("A = 5.0 }", "A = -5.0 }"), "friction.pin_radius.A", ">= 0"),
    ("negative-viscous", ("B = 0.001", "B = -0.001"), "friction.viscous.B",
     ("B = 0.001", "B = -0.001"), "friction.viscous.B", ">= 0"),
    ("negative-joint-mu", ("mu = 0.1", "mu = 0.1\nslide_mu = -0.1"), "friction.slide_mu",
     ("slide = 0.15", "slide = -0.15"), "friction.joint_mu.slide", ">= 0"),
    ("negative-force-magnitude", ("magnitude = 100.0", "magnitude = -100.0"),
     "loads[0].force.magnitude", ("magnitude = 200.0", "magnitude = -200.0"),
     "loads[0].force.magnitude", ">= 0"),
    ("load-without-force-or-torque",
     ("force = { magnitude = 100.0, angle = 20.0 }\ntorque = 0.5\n", ""), "loads[0].force",
     ("force = { magnitude = 200.0, angle = 180.0 }\ntorque = 0.0\n", ""), "loads[0].force",
     "neither"),
    ("unknown-key", ("mass = 0.5", "mass = 0.5\ncolour = 'red'"), "masses[0].colour",
     ("mass = 0.6", "mass = 0.6\ncolour = 'red'"), "masses[0].colour", "unknown key"),
    ("missing-key", ("mass = 0.5\n", ""), "masses[0].mass",
     ("mass = 0.6\n", ""), "masses[0].mass", "required"),
]


@pytest.mark.parametrize(("text", "key", "fragment"), [
    pytest.param(edit(base, *change), key, fragment, id=f"{name}-{fmt}")
    for name, four_bar_change, four_bar_key, linkage_change, linkage_key, fragment in PARITY
    for fmt, base, change, key in (("four_bar", FOUR_BAR, four_bar_change, four_bar_key),
                                   ("linkage", LINKAGE, linkage_change, linkage_key))])
def test_each_class_of_refusal_holds_in_both_formats(tmp_path: Path, text: str, key: str,
                                                     fragment: str) -> None:
    """A value of a class one format refuses is refused by the other too: exit 2, one line
    naming the file, the case and the key as that file spells it."""
    assert_refused(tmp_path, text, key, fragment)


@pytest.mark.parametrize(("base", "args"), [
    pytest.param(FOUR_BAR, ["-b", "analytic"], id="four_bar"),
    pytest.param(LINKAGE, ["-b", "analytic"], id="linkage"),
    pytest.param(SLIDE, ["-b", "analytic"], id="slide"),
])
def test_the_files_the_refusals_are_made_from_pass(tmp_path: Path, base: str,
                                                   args: list[str]) -> None:
    """Each base file is valid and runs (exit 0): every refusal above is its one edit."""
    path = tmp_path / "good.toml"
    path.write_text(base)
    code, err = run_cli(["run", str(path), "-q", "--out", str(tmp_path / "o"), *args])
    assert code == 0, err


def test_every_built_in_case_still_loads() -> None:
    """The built-in cases (seeds, suite, linkages) and the examples pass the new checks."""
    from mechcheck.casefile import builtin_case_files

    examples = sorted((Path(__file__).resolve().parents[1] / "compare" / "examples").glob("*.toml"))
    files = [*builtin_case_files(), *examples]
    tables = sum(len(re.findall(r"^\[\[case\]\]", f.read_text(), re.MULTILINE)) for f in files)
    assert len(load_cases(*files)) == tables > 20


# -- the linkage format's own holes, each named ------------------------------------------------
# (id, file, edit (old, new), key, fragments)
LINKAGE_ONLY: list[tuple[str, str, tuple[str, str], str, tuple[str, ...]]] = [
    # 1e308 anywhere a number is due (the same values 1e300 gave as a drive moment of 7.5e280 N·m)
    *[(f"1e308-{name}", LINKAGE, (old, new), key, ("at most 1e+12",)) for name, old, new, key in [
        ("mass", "mass = 0.6", "mass = 1e308", "masses[0].mass"),
        ("com", "com = [15.0, 20.0]", "com = [1e308, 20.0]", "masses[1].com[0]"),
        ("inertia", "inertia = 8.0e-4", "inertia = 1e308", "masses[0].inertia"),
        ("load-point", "at = [90.0, 30.0]", "at = [1e308, 30.0]", "loads[1].at[0]"),
        ("force-x", "x = 10.0", "x = 1e308", "loads[1].force.x"),
        ("force-magnitude", "magnitude = 200.0", "magnitude = 1e308", "loads[0].force.magnitude"),
        ("torque", "torque = 0.0", "torque = 1e308", "loads[0].torque"),
        ("linear-stiffness", "stiffness = 2000.0", "stiffness = 1e308", "springs[0].stiffness"),
        ("torsional-stiffness", "stiffness = 1.5", "stiffness = 1e308", "springs[1].stiffness"),
        ("linear-damping", "damping = 0.5", "damping = 1e308", "springs[0].damping"),
        ("torsional-damping", "damping = 0.01", "damping = 1e308", "springs[1].damping"),
        ("free-length", "free_length = 80.0", "free_length = 1e308", "springs[0].free_length"),
        ("spring-end", END, '"slider", [1e308, 10.0]', "springs[0].ends[1]"),
        ("mu", "mu = 0.1", "mu = 1e308", "friction.mu"),
        ("pin-radius", "A = 5.0 }", "A = 1e300 }", "friction.pin_radius.A"),
        ("joint-mu", "slide = 0.15", "slide = 1e308", "friction.joint_mu.slide"),
        ("viscous", "B = 0.001", "B = 1e308", "friction.viscous.B"),
        ("gravity", "gravity = [0.0, -9.81]", "gravity = [0.0, 1e308]", "gravity[1]"),
        ("point", "S = [250.0, 10.0]", "S = [1e308, 10.0]", "points.S[0]"),
        ("velocity", "velocity = 0.0", "velocity = -1e308", "drivers[0].velocity"),
        ("acceleration", "acceleration = 0.0", "acceleration = 1e308", "drivers[0].acceleration"),
    ]],
    ("1e308-free-rotation", LINKAGE, ("free_rotation = 10.0", "free_rotation = 1e308"),
     "springs[1].free_rotation", ("±100000°",)),
    ("huge-integer-spring-end", LINKAGE, (END, f'"slider", [{HUGE}, 10.0]'), "springs[0].ends[1]",
     ("finite",)),
    # Not finite in a spring end: exit 2, not an `error` verdict with exit 1.
    ("nan-spring-end", LINKAGE, (END, '"slider", [nan, 10.0]'), "springs[0].ends[1]", ("finite",)),
    ("inf-spring-end", LINKAGE, (END, '"slider", [150.0, -inf]'), "springs[0].ends[1]",
     ("finite",)),
    # Booleans are not numbers, wherever a number is due.
    ("boolean-spring-end", LINKAGE, (END, '"slider", [true, false]'), "springs[0].ends[1]",
     ("must be a number, got True",)),
    ("boolean-stiffness", LINKAGE, ("stiffness = 2000.0", "stiffness = true"),
     "springs[0].stiffness", ("must be a number",)),
    ("boolean-point", LINKAGE, ("S = [250.0, 10.0]", "S = [true, false]"), "points.S[0]",
     ("must be a number",)),
    ("text-point-ref", LINKAGE, ("at = [90.0, 30.0]", "at = 5.0"), "loads[1].at",
     ("a point name or [x, y]",)),
    # 1e-9 mm = 1e-12 m between two points of the rod, quoted in the file's mm.
    ("points-1e-12-m-apart", LINKAGE, ("K = [90.0, 25.0]", "K = [30.000000001, 40.0]"),
     "points.K", ("from 'A'", "rod", "0.001 mm (a micrometre)")),
    ("negative-linear-stiffness", LINKAGE, ("stiffness = 2000.0", "stiffness = -2000.0"),
     "springs[0].stiffness", (">= 0",)),
    ("negative-torsional-stiffness", LINKAGE, ("stiffness = 1.5", "stiffness = -1.5"),
     "springs[1].stiffness", (">= 0",)),
    ("negative-linear-damping", LINKAGE, ("damping = 0.5", "damping = -0.5"),
     "springs[0].damping", (">= 0",)),
    ("negative-torsional-damping", LINKAGE, ("damping = 0.01", "damping = -0.01"),
     "springs[1].damping", (">= 0",)),
    ("negative-free-length", LINKAGE, ("free_length = 80.0", "free_length = -80.0"),
     "springs[0].free_length", (">= 0, got -80 mm",)),
    ("load-with-neither", LINKAGE, ('at = [90.0, 30.0]\nforce = { x = 10.0, y = -5.0 }\n',
                                    'at = [90.0, 30.0]\n'), "loads[1].force", ("'torque'",)),
    ("axis-on-a-revolute", LINKAGE, ('links = ["crank", "rod"]\nat = "A"',
                                     'links = ["crank", "rod"]\nat = "A"\naxis = [1.0, 0.0]'),
     "joints[1].axis", ("revolute",)),
    # 1e8° took 3.7 GB before; ten turns and a thousandth of a degree more is refused.
    ("rotation-1e8-deg", LINKAGE, ("rotation = 30.0", "rotation = 1e8"), "drivers[0].rotation",
     ("±3600°", "got 1e+08°", "continuation")),
    ("rotation-past-ten-turns", LINKAGE, ("rotation = 30.0", "rotation = -3600.001"),
     "drivers[0].rotation", ("±3600°",)),
    # 1e9 mm ran for minutes; the bound is 10 × 200 mm (SLIDE's size).
    ("displacement-1e9-mm", SLIDE, ("displacement = 0.0", "displacement = 1e9"),
     "drivers[0].displacement", ("±10 × the linkage's size (±2000 mm)", "got 1e+09 mm",
                                 "continuation")),
    ("displacement-past-ten-sizes", SLIDE, ("displacement = 0.0", "displacement = -2000.01"),
     "drivers[0].displacement", ("±2000 mm",)),
    ("huge-displacement-velocity", SLIDE, ("displacement = 0.0", "displacement = 0.0\nvelocity = 1e13"),
     "drivers[0].velocity", ("at most 1e+12",)),
]


@pytest.mark.parametrize(("text", "key", "fragments"), [
    pytest.param(edit(base, *change), key, fragments, id=name)
    for name, base, change, key, fragments in LINKAGE_ONLY])
def test_the_linkage_format_refuses_what_it_once_took(tmp_path: Path, text: str, key: str,
                                                       fragments: tuple[str, ...]) -> None:
    """Each value the linkage format accepted and should not (non-physical magnitudes, NaN
    and booleans in spring ends, points closer than a micrometre, negative springs, empty
    loads, an axis on a revolute joint, unbounded driver travel) exits 2 naming its key."""
    assert_refused(tmp_path, text, key, *fragments)


def test_a_drawing_smaller_than_a_micrometre_is_refused(tmp_path: Path) -> None:
    """A bar whose two points are at one place (allowed on one link) makes a drawing 0 m
    across: refused under the key 'points'."""
    text = edit(edit(SLIDE, "W1 = [-100.0, 0.0]", "W1 = [0.0, 0.0]"), "W2 = [100.0, 0.0]",
                "W2 = [0.0, 0.0]")
    assert_refused(tmp_path, text, "points", "a micrometre")


@pytest.mark.parametrize(("base", "change"), [
    # K on the pin A: two points of one link at exactly one place are allowed.
    pytest.param(LINKAGE, ("K = [90.0, 25.0]", "K = [30.0, 40.0]"), id="point-on-a-pin"),
    # 0.001 mm = 1e-6 m apart: exactly the least spacing.
    pytest.param(LINKAGE, ("K = [90.0, 25.0]", "K = [30.0, 40.001]"), id="points-a-micrometre-apart"),
    pytest.param(LINKAGE, ("rotation = 30.0", "rotation = -3600.0"), id="rotation-ten-turns"),
    pytest.param(SLIDE, ("displacement = 0.0", "displacement = 2000.0"), id="displacement-ten-sizes"),
    pytest.param(LINKAGE, ("stiffness = 2000.0", "stiffness = 0.0"), id="zero-stiffness"),
    pytest.param(LINKAGE, ("torque = 0.0", "torque = 1e12"), id="torque-at-the-bound"),
    pytest.param(LINKAGE, ('at = [90.0, 30.0]\nforce = { x = 10.0, y = -5.0 }\n',
                           'at = [90.0, 30.0]\ntorque = 2.0\n'), id="load-with-a-torque-only"),
])
def test_values_at_the_bounds_are_taken(tmp_path: Path, base: str, change: tuple[str, str]) -> None:
    """The bounds are inclusive and refuse nothing physical: each file loads."""
    path = tmp_path / "good.toml"
    path.write_text(edit(base, *change))
    assert [c.name for c in load_cases(path)] == ["parity"]


# -- a Linkage built in Python refuses the same values ------------------------------------------

def _linkage(tmp_path: Path) -> Linkage:
    path = tmp_path / "good.toml"
    path.write_text(LINKAGE)
    return load_cases(path)[0].linkage


def _replace_first(items: tuple[Any, ...], **changes: Any) -> tuple[Any, ...]:
    return (dataclasses.replace(items[0], **changes), *items[1:])


#: (id, the fields to change given the valid linkage, the key, a fragment of the message).
PYTHON: list[tuple[str, Any, str, str]] = [
    ("mass-bool", lambda lk: {"masses": _replace_first(lk.masses, mass=True)}, "masses[0].mass",
     "number"),
    ("mass-1e308", lambda lk: {"masses": _replace_first(lk.masses, mass=1e308)}, "masses[0].mass",
     "at most"),
    ("com-nan", lambda lk: {"masses": _replace_first(lk.masses, com=(math.nan, 0.0))},
     "masses[0].com[0]", "finite"),
    ("inertia-negative", lambda lk: {"masses": _replace_first(lk.masses, inertia=-1.0)},
     "masses[0].inertia", ">= 0"),
    ("force-inf", lambda lk: {"loads": _replace_first(lk.loads, force=(math.inf, 0.0))},
     "loads[0].force.x", "finite"),
    ("load-point-bool", lambda lk: {"loads": _replace_first(lk.loads, at=(True, False))},
     "loads[0].at[0]", "number"),
    ("torque-1e308", lambda lk: {"loads": _replace_first(lk.loads, torque=1e308)},
     "loads[0].torque", "at most"),
    ("gravity-bool", lambda lk: {"gravity": (False, True)}, "gravity[0]", "number"),
    ("stiffness-negative", lambda lk: {"springs": _replace_first(lk.springs, stiffness=-1.0)},
     "springs[0].stiffness", ">= 0"),
    ("spring-end-nan", lambda lk: {"springs": _replace_first(
        lk.springs, ends=(lk.springs[0].ends[0], ("slider", (math.nan, 0.0))))},
     "springs[0].ends[1]", "finite"),
    ("free-rotation-beyond", lambda lk: {"springs": (lk.springs[0], dataclasses.replace(
        lk.springs[1], free_rotation=1e308))}, "springs[1].free_rotation", "±100000°"),
    ("mu-negative", lambda lk: {"friction": dataclasses.replace(lk.friction, mu=-0.1)},
     "friction.mu", ">= 0"),
    ("pin-radius-1e300", lambda lk: {"friction": dataclasses.replace(
        lk.friction, pin_radius={"A": 1e300})}, "friction.pin_radius.A", "at most"),
    ("viscous-bool", lambda lk: {"friction": dataclasses.replace(
        lk.friction, viscous={"B": True})}, "friction.viscous.B", "number"),
    ("rotation-beyond", lambda lk: {"drivers": _replace_first(
        lk.drivers, value=math.radians(3600.001))}, "drivers[0].rotation", "±3600°"),
    ("sense-bool", lambda lk: {"drivers": _replace_first(lk.drivers, sense=True)},
     "drivers[0].sense", "increasing"),
    ("revolute-axis", lambda lk: {"joints": _replace_first(lk.joints, axis=(1.0, 0.0))},
     "joints[0].axis", "revolute"),
    ("points-too-close", lambda lk: {"points": {**lk.points, "K": (lk.points["A"][0] + 1e-12,
                                                                   lk.points["A"][1])}},
     "points.K", "1e-06 m (a micrometre)"),
]


@pytest.mark.parametrize(("change", "key", "fragment"),
                         [pytest.param(*row[1:], id=row[0]) for row in PYTHON])
def test_a_linkage_built_in_python_refuses_the_same_values(tmp_path: Path, change: Any, key: str,
                                                           fragment: str) -> None:
    """The checks live in the Linkage value, not only in the file's parser: a Linkage built
    in code with a refused value raises one CaseError naming the same key (lengths in m)."""
    linkage = _linkage(tmp_path)
    with pytest.raises(CaseError) as caught:
        dataclasses.replace(linkage, **change(linkage))
    assert caught.value.key == key and fragment in caught.value.message, str(caught.value)
