"""A linkage written as a sketch with dimensions (docs/case-files.md, "Writing a linkage as
a sketch with dimensions"): mechcheck assembles it where the closed-form trigonometry written
here puts it, on the branch the sketch shows, and solves it exactly as the same linkage
written with exact coordinates; a sketch that does not assemble is refused in one line
naming the dimension or link at fault."""

from __future__ import annotations

import doctest
import math
from pathlib import Path

import pandas as pd
import pytest
from typer.testing import CliRunner

import mechcheck
from mechcheck.analytic.linkage import Linkage
from mechcheck.cli import app, example_path
from mechcheck.tolerance import rule

#: Coordinates and forces of one geometry found two ways (by hand, by the assembly): the
#: policy's analytic rule, only rounding between them.
RTOL = rule("analytic", "pose", "static").rtol

#: Seed E1's four-bar, mm: ground a1, crank a2, coupler a3, rocker a4, crank at 60°.
A1, A2, A3, A4, THETA = 140.0, 80.0, 100.0, 120.0, 60.0


def four_bar_by_hand(upper: bool) -> dict[str, tuple[float, float]]:
    """The four-bar's points by trigonometry: A on the crank's circle at θ, B where the
    coupler's circle about A meets the rocker's about B0, the upper or the lower meeting."""
    t = math.radians(THETA)
    a = (A2 * math.cos(t), A2 * math.sin(t))
    dx, dy = A1 - a[0], -a[1]
    d = math.hypot(dx, dy)
    ux, uy = dx / d, dy / d
    along = (A3**2 - A4**2 + d**2) / (2 * d)        # from A towards B0, to the chord
    half = math.sqrt(A3**2 - along**2)              # half the chord
    mx, my = a[0] + along * ux, a[1] + along * uy
    meetings = [(mx - half * uy, my + half * ux), (mx + half * uy, my - half * ux)]
    b = max(meetings, key=lambda p: p[1]) if upper else min(meetings, key=lambda p: p[1])
    return {"A0": (0.0, 0.0), "B0": (A1, 0.0), "A": a, "B": b}


FOUR_BAR = """
[[case]]
name = "NAME"
mechanism = "linkage"
length_unit = "mm"
gravity = [0.0, -9.81]
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
points = ["B0", "B"]
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
velocity = -10.0
[[case.loads]]
link = "rocker"
at = "B"
force = { magnitude = 100.0, angle = 20.0 }
[[case.masses]]
link = "coupler"
mass = 0.5
com = "A"
inertia = 1.0e-3
DIMENSIONS
"""

FOUR_BAR_DIMENSIONS = f"""
[[case.dimensions]]
points = ["A0", "A"]
length = {A2}
[[case.dimensions]]
points = ["A0", "A"]
angle = {THETA}
[[case.dimensions]]
points = ["A", "B"]
length = {A3}
[[case.dimensions]]
points = ["B0", "B"]
length = {A4}
"""

#: Hand sketches: the ground exact, A and B roughly where the open (B above the ground
#: line) and the crossed (B below it) assemblies put them.
OPEN_SKETCH = {"A0": (0.0, 0.0), "B0": (140.0, 0.0), "A": (50.0, 60.0), "B": (120.0, 100.0)}
CROSSED_SKETCH = {"A0": (0.0, 0.0), "B0": (140.0, 0.0), "A": (50.0, 60.0), "B": (30.0, -40.0)}


def points_text(points: dict[str, tuple[float, float]]) -> str:
    return "\n".join(f"{n} = [{x!r}, {y!r}]" for n, (x, y) in points.items())


def four_bar(name: str, points: dict[str, tuple[float, float]], dimensions: str = "") -> str:
    return (FOUR_BAR.replace("NAME", name).replace("POINTS", points_text(points))
            .replace("DIMENSIONS", dimensions))


def load_one(tmp_path: Path, text: str) -> mechcheck.Case:
    path = tmp_path / "case.toml"
    path.write_text(text)
    return mechcheck.load_cases(path)[0]


def drawn_mm(linkage: Linkage) -> dict[str, tuple[float, float]]:
    """The drawn pose in the file's frame and unit."""
    return {n: (1e3 * linkage.drawn(p)[0], 1e3 * linkage.drawn(p)[1])
            for n, p in linkage.points.items()}


def assert_points_close(got: dict[str, tuple[float, float]],
                        want: dict[str, tuple[float, float]], size: float) -> None:
    assert got.keys() == want.keys()
    for name, (x, y) in want.items():
        assert got[name] == pytest.approx((x, y), rel=0.0, abs=RTOL * size), name


@pytest.mark.parametrize(("sketch", "upper"), [(OPEN_SKETCH, True), (CROSSED_SKETCH, False)],
                         ids=["open", "crossed"])
def test_a_four_bar_sketch_assembles_where_trigonometry_puts_it_on_the_sketched_branch(
        tmp_path: Path, sketch: dict[str, tuple[float, float]], upper: bool) -> None:
    """The four-bar sketched with B above the ground line assembles at the upper meeting of
    the coupler's and rocker's circles, sketched below it at the lower one (the crossed
    branch): the assembly nearest the sketch."""
    case = load_one(tmp_path, four_bar("sketch", sketch, FOUR_BAR_DIMENSIONS))
    assert_points_close(drawn_mm(case.linkage), four_bar_by_hand(upper), A1)


def test_a_sketch_solves_as_the_same_linkage_written_exactly(tmp_path: Path) -> None:
    """Every number of the sketched four-bar (reactions, drive torque, with a coupler mass
    and a crank speed) is the exactly written four-bar's, whose points are the hand
    trigonometry's."""
    sketched = load_one(tmp_path, four_bar("sketch", OPEN_SKETCH, FOUR_BAR_DIMENSIONS))
    exact = load_one(tmp_path, four_bar("exact", four_bar_by_hand(upper=True)))
    got, want = mechcheck.solve(sketched), mechcheck.solve(exact)
    assert got.status == want.status == "ok"
    assert got.values.keys() == want.values.keys()
    scale = max(abs(v) for v in want.values.values())
    for quantity, value in want.values.items():
        assert got.values[quantity] == pytest.approx(value, rel=RTOL, abs=RTOL * scale), quantity


def test_the_format_references_example_assembles_where_trigonometry_puts_it(tmp_path: Path) -> None:
    """The sketched four-bar of docs/case-files.md reads, assembles at the hand
    trigonometry's open pose, and gives the B it quotes."""
    docs = (Path(__file__).parents[1] / "docs" / "case-files.md").read_text(encoding="utf-8")
    block = docs.split('name = "sketched-four-bar"', 1)[1].split("```", 1)[0]
    case = load_one(tmp_path, '[[case]]\nname = "sketched-four-bar"' + block)
    by_hand = four_bar_by_hand(upper=True)
    assert_points_close(drawn_mm(case.linkage), by_hand, A1)
    assert "B at ({:.3f}, {:.3f}) mm".format(*by_hand["B"]) in " ".join(docs.split())


def test_the_slider_crank_template_assembles_where_trigonometry_puts_it() -> None:
    """`mechcheck new linkage_sketch`'s offset slider-crank (crank 50 mm at 120°, rod 180 mm,
    slide 20 mm above O, K 100 mm from A and from B): A = 50(cos 120°, sin 120°), B on the
    slide's line y = 20 at x = x_A + √(180² − (20 − y_A)²), K on the perpendicular bisector
    of AB, √(100² − 90²) from its middle, on the side sketched (above the rod)."""
    t = math.radians(120.0)
    ax, ay = 50.0 * math.cos(t), 50.0 * math.sin(t)
    bx, by = ax + math.sqrt(180.0**2 - (20.0 - ay) ** 2), 20.0
    ux, uy = (bx - ax) / 180.0, (by - ay) / 180.0
    rise = math.sqrt(100.0**2 - 90.0**2)
    k = ((ax + bx) / 2 - rise * uy, (ay + by) / 2 + rise * ux)
    case = mechcheck.load_cases(example_path("linkage_sketch"))[0]
    assert_points_close(drawn_mm(case.linkage),
                        {"O": (0.0, 0.0), "A": (ax, ay), "B": (bx, by), "K": k}, 180.0)


def test_the_sketch_template_passes_analytic_and_a_simulator(tmp_path: Path) -> None:
    """`mechcheck run` on the sketch template: MuJoCo's constraint forces at the assembled
    pose agree with the analytic reference, every number within the policy's tolerances."""
    out = tmp_path / "out"
    result = CliRunner().invoke(app, ["run", str(example_path("linkage_sketch")), "-q",
                                      "-b", "mujoco_solve", "--out", str(out)])
    assert result.exit_code == 0, result.stdout + result.stderr
    comparison = pd.read_csv(out / "comparison.csv")
    compared = comparison[comparison["backend"] == "mujoco_solve"]
    assert {"Q_O", "F_A_x", "F_slide_y"} <= set(compared["quantity"])
    assert compared["passed"].all()


# -- refused ------------------------------------------------------------------------------

TERNARY = FOUR_BAR_DIMENSIONS + """
[[case.dimensions]]
points = ["B0", "D"]
length = 60.0
"""


def with_rocker_point(text: str) -> str:
    """The four-bar's rocker made a triangle B0, B, D (D sketched beside it)."""
    return (text.replace('name = "rocker"\npoints = ["B0", "B"]',
                         'name = "rocker"\npoints = ["B0", "B", "D"]')
            .replace('B = [120.0, 100.0]', 'B = [120.0, 100.0]\nD = [170.0, 60.0]'))


BAD = [
    ("a-link-not-rigid", with_rocker_point(four_bar("bad", OPEN_SKETCH, TERNARY)),
     "links[3]", "link 'rocker' is not rigid: its 3 points need 3 independent dimensions"),
    ("a-triangle-that-cannot-close", with_rocker_point(four_bar("bad", OPEN_SKETCH, TERNARY + """
[[case.dimensions]]
points = ["B", "D"]
length = 300.0
""")), "dimensions[", "does not assemble"),
    ("a-dimension-across-links", four_bar("bad", OPEN_SKETCH, FOUR_BAR_DIMENSIONS.replace(
        'points = ["B0", "B"]', 'points = ["A0", "B"]')),
     "dimensions[3].points", "'A0' and 'B' are on different links"),
    ("a-dimension-on-the-ground", four_bar("bad", OPEN_SKETCH, FOUR_BAR_DIMENSIONS + """
[[case.dimensions]]
points = ["A0", "B0"]
length = 140.0
"""), "dimensions[4].points", "both on the ground"),
    ("no-crank-angle", four_bar("bad", OPEN_SKETCH, FOUR_BAR_DIMENSIONS.replace(
        "angle = 60.0", "length = 80.0")),
     "dimensions[1]", "repeats what the other dimensions of link 'crank'"),
    ("a-free-coordinate-left", four_bar("bad", OPEN_SKETCH, FOUR_BAR_DIMENSIONS.replace(
        '[[case.dimensions]]\npoints = ["A0", "A"]\nangle = 60.0\n', "")),
     "dimensions", "1 degree(s) of freedom"),
    ("an-angle-too-many", four_bar("bad", OPEN_SKETCH, FOUR_BAR_DIMENSIONS + """
[[case.dimensions]]
points = ["B0", "B"]
angle = 70.0
"""), "dimensions[4]", "one dimension too many"),
    ("a-rocker-too-short-to-reach", four_bar("bad", OPEN_SKETCH, FOUR_BAR_DIMENSIONS.replace(
        "length = 120.0", "length = 20.0")),
     "dimensions[3]", "the sketch does not assemble"),
    ("a-flat-triangle", with_rocker_point(four_bar("bad", OPEN_SKETCH, TERNARY.replace(
        "length = 60.0", "length = 180.0") + """
[[case.dimensions]]
points = ["B", "D"]
length = 60.0
""")).replace("D = [170.0, 60.0]", "D = [120.0, 175.0]"),
     "dimensions'", "do not fix the points firmly"),
    ("a-crank-sketched-the-other-way", four_bar("bad", OPEN_SKETCH, FOUR_BAR_DIMENSIONS.replace(
        "angle = 60.0", "angle = 240.0")),
     "dimensions[1]", "A0→A points at 60°, not 240°"),
    ("a-point-sketched-far-from-its-place", four_bar("bad", OPEN_SKETCH | {"B": (200.0, 60.0)},
                                                     FOUR_BAR_DIMENSIONS),
     "points.B", "draw it nearer its place"),
    ("a-load-at-coordinates", four_bar("bad", OPEN_SKETCH, FOUR_BAR_DIMENSIONS).replace(
        'at = "B"\nforce', 'at = [120.0, 100.0]\nforce'),
     "loads[0].at", "in a sketch, name a point"),
    ("length-and-angle", four_bar("bad", OPEN_SKETCH, FOUR_BAR_DIMENSIONS.replace(
        "length = 80.0", "length = 80.0\nangle = 10.0")),
     "dimensions[0]", "a length or an angle"),
]


@pytest.mark.parametrize(("text", "key", "fragment"), [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_a_sketch_that_does_not_assemble_is_refused_in_one_line(
        tmp_path: Path, text: str, key: str, fragment: str) -> None:
    """Exit 2, one line naming the file, the case and the key, nothing written."""
    path = tmp_path / "bad.toml"
    path.write_text(text)
    out = tmp_path / "out"
    result = CliRunner().invoke(app, ["run", str(path), "-q", "--out", str(out)])
    lines = result.stderr.strip().splitlines()
    assert result.exit_code == 2, result.stderr
    assert len(lines) == 1, result.stderr
    assert str(path) in lines[0] and "case 'bad'" in lines[0], lines[0]
    assert f"key '{key}" in lines[0] and fragment in lines[0], lines[0]
    assert not out.exists()


def test_the_impossible_triangle_names_one_of_its_own_sides(tmp_path: Path) -> None:
    """A rocker triangle whose sides 120, 60 and 300 mm break the triangle inequality is
    refused naming one of those three dimensions (indices 3, 4, 5), not the crank's."""
    path = tmp_path / "bad.toml"
    path.write_text(BAD[1][1])
    with pytest.raises(mechcheck.CaseError) as error:
        mechcheck.load_cases(path)
    assert error.value.key in ("dimensions[3]", "dimensions[4]", "dimensions[5]"), str(error.value)


def test_the_modules_example_runs() -> None:
    """The crank of the assembly module's docstring assembles at (0, 1), as it shows."""
    from mechcheck.analytic import sketch

    result = doctest.testmod(sketch)
    assert result.attempted > 0 and result.failed == 0
