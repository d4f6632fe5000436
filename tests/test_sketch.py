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
from hypothesis import assume, given, settings, strategies as st
from typer.testing import CliRunner

import mechcheck
from mechcheck.analytic.linkage import Joint, Link, Linkage
from mechcheck.analytic.sketch import MAX_SKETCH_POINTS, Dimension, assembled
from mechcheck.cli import app, example_path
from mechcheck.tolerance import rule

from .test_edges import assert_refused, case_file
from .test_gear import GEAR_FILE
from .test_linkage_file import FOUR_BAR_TEMPLATE
from .test_pin_in_slot import CASE_FILE as SLOTTED_LEVER

#: Coordinates and forces of one geometry found two ways (by hand, by the assembly): the
#: policy's analytic rule, only rounding between them.
RTOL = rule("analytic", "pose", "static").rtol

#: Seed E1's four-bar, mm: ground a1, crank a2, coupler a3, rocker a4, crank at 60°.
A1, A2, A3, A4, THETA = 140.0, 80.0, 100.0, 120.0, 60.0


def four_bar_by_hand(upper: bool, a1: float = A1, a2: float = A2, a3: float = A3,
                     a4: float = A4, theta: float = THETA) -> dict[str, tuple[float, float]]:
    """The four-bar's points by trigonometry: A on the crank's circle at θ, B where the
    coupler's circle about A meets the rocker's about B0, on the left of the line A→B0
    (``upper``: for E1, above the ground line) or on its right."""
    t = math.radians(theta)
    a = (a2 * math.cos(t), a2 * math.sin(t))
    dx, dy = a1 - a[0], -a[1]
    d = math.hypot(dx, dy)
    ux, uy = dx / d, dy / d
    along = (a3**2 - a4**2 + d**2) / (2 * d)        # from A towards B0, to the chord
    half = math.sqrt(a3**2 - along**2)              # half the chord
    side = 1.0 if upper else -1.0
    b = (a[0] + along * ux - side * half * uy, a[1] + along * uy + side * half * ux)
    return {"A0": (0.0, 0.0), "B0": (a1, 0.0), "A": a, "B": b}


#: A coupler mass on the four-bar of the linkage-file tests.
COUPLER_MASS = """
[[case.masses]]
link = "coupler"
mass = 0.5
com = "A"
inertia = 1.0e-3
"""

def dimension(first: str, second: str, key: str, value: float) -> str:
    """One ``[[case.dimensions]]`` entry: ``key`` is ``length`` or ``angle``."""
    return f'\n[[case.dimensions]]\npoints = ["{first}", "{second}"]\n{key} = {value!r}\n'


FOUR_BAR_DIMENSIONS = (dimension("A0", "A", "length", A2) + dimension("A0", "A", "angle", THETA)
                       + dimension("A", "B", "length", A3) + dimension("B0", "B", "length", A4))

#: Hand sketches: the ground exact, A and B roughly where the open (B above the ground
#: line) and the crossed (B below it) assemblies put them.
OPEN_SKETCH = {"A0": (0.0, 0.0), "B0": (140.0, 0.0), "A": (50.0, 60.0), "B": (120.0, 100.0)}
CROSSED_SKETCH = {"A0": (0.0, 0.0), "B0": (140.0, 0.0), "A": (50.0, 60.0), "B": (30.0, -40.0)}


def points_text(points: dict[str, tuple[float, float]]) -> str:
    return "\n".join(f"{n} = [{x!r}, {y!r}]" for n, (x, y) in points.items())


def four_bar(name: str, points: dict[str, tuple[float, float]], dimensions: str = "") -> str:
    """The linkage-file tests' four-bar with its rocker a bar B0–B loaded at B, under
    gravity, with a coupler mass and the crank turning at −10 rad/s, at ``points``."""
    return (FOUR_BAR_TEMPLATE.replace('name = "four-bar"', f'name = "{name}"')
            .replace('points = ["B0", "B", "D"]', 'points = ["B0", "B"]')
            .replace('at = "D"', 'at = "B"')
            .replace('length_unit = "mm"', 'length_unit = "mm"\ngravity = [0.0, -9.81]')
            .replace("rotation = 0.0", "rotation = 0.0\nvelocity = -10.0")
            .replace("POINTS", points_text(points)) + COUPLER_MASS + dimensions)


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

def bad(dimensions: str, sketch: dict[str, tuple[float, float]] = OPEN_SKETCH,
        rocker_point: tuple[float, float] | None = None) -> str:
    """A four-bar sketch that must be refused; given ``rocker_point``, the rocker is a
    triangle B0, B, D with D sketched there."""
    text = four_bar("bad", sketch | ({} if rocker_point is None else {"D": rocker_point}),
                    dimensions)
    if rocker_point is None:
        return text
    return text.replace('name = "rocker"\npoints = ["B0", "B"]',
                        'name = "rocker"\npoints = ["B0", "B", "D"]')


#: The rocker made a triangle B0, B, D: one side short of rigid.
TRIANGLE = FOUR_BAR_DIMENSIONS + dimension("B0", "D", "length", 60.0)
D_BESIDE = (170.0, 60.0)

BAD = [
    ("a-link-not-rigid", bad(TRIANGLE, rocker_point=D_BESIDE),
     "links[3]", "link 'rocker' is not rigid: its 3 points need 3 independent dimensions"),
    ("a-triangle-that-cannot-close",
     bad(TRIANGLE + dimension("B", "D", "length", 300.0), rocker_point=D_BESIDE),
     "dimensions[", "does not assemble"),
    ("a-dimension-across-links", bad(FOUR_BAR_DIMENSIONS.replace('["B0", "B"]', '["A0", "B"]')),
     "dimensions[3].points", "'A0' and 'B' are on different links"),
    ("a-dimension-on-the-ground", bad(FOUR_BAR_DIMENSIONS + dimension("A0", "B0", "length", A1)),
     "dimensions[4].points", "both on the ground"),
    ("no-crank-angle", bad(FOUR_BAR_DIMENSIONS.replace("angle = 60.0", "length = 80.0")),
     "dimensions[1]", "repeats what the other dimensions of link 'crank'"),
    ("a-free-coordinate-left",
     bad(FOUR_BAR_DIMENSIONS.replace(dimension("A0", "A", "angle", THETA), "")),
     "dimensions", "1 degree(s) of freedom"),
    ("an-angle-too-many", bad(FOUR_BAR_DIMENSIONS + dimension("B0", "B", "angle", 70.0)),
     "dimensions[4]", "one dimension too many"),
    ("a-rocker-too-short-to-reach", bad(FOUR_BAR_DIMENSIONS.replace("length = 120.0", "length = 20.0")),
     "dimensions[3]", "the sketch does not assemble"),
    ("a-flat-triangle", bad(FOUR_BAR_DIMENSIONS + dimension("B0", "D", "length", A4 + 60.0)
                            + dimension("B", "D", "length", 60.0), rocker_point=(120.0, 175.0)),
     "dimensions'", "do not fix the points firmly"),
    ("a-crank-sketched-the-other-way", bad(FOUR_BAR_DIMENSIONS.replace("angle = 60.0", "angle = 240.0")),
     "dimensions[1]", "A0→A points at 60°, not 240°"),
    ("a-point-sketched-far-from-its-place", bad(FOUR_BAR_DIMENSIONS, OPEN_SKETCH | {"B": (200.0, 60.0)}),
     "points.B", "draw it nearer its place"),
    ("a-load-at-coordinates",
     bad(FOUR_BAR_DIMENSIONS).replace('at = "B"\nforce', 'at = [120.0, 100.0]\nforce'),
     "loads[0].at", "in a sketch, name a point"),
    ("a-negative-length", bad(FOUR_BAR_DIMENSIONS.replace("length = 80.0", "length = -80.0")),
     "dimensions[0].length", "must be at least 0.001 mm (a micrometre), got -80 mm"),
    ("an-angle-beyond-bounds", bad(FOUR_BAR_DIMENSIONS.replace("angle = 60.0", "angle = 1e9")),
     "dimensions[1].angle", "must be within ±100000°"),
    ("length-and-angle", bad(FOUR_BAR_DIMENSIONS.replace("length = 80.0", "length = 80.0\nangle = 10.0")),
     "dimensions[0]", "a length or an angle"),
]


@pytest.mark.parametrize(("text", "key", "fragment"), [b[1:] for b in BAD], ids=[b[0] for b in BAD])
def test_a_sketch_that_does_not_assemble_is_refused_in_one_line(
        tmp_path: Path, text: str, key: str, fragment: str) -> None:
    """Exit 2, one line naming the file, the case and the key, nothing written."""
    path, out = case_file(tmp_path, text, "bad.toml"), tmp_path / "out"
    assert_refused(["run", str(path), "-q", "--out", str(out)],
                   str(path), "case 'bad'", f"key '{key}", fragment)
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


@pytest.mark.parametrize(("text", "key", "fragment"), [
    (GEAR_FILE + dimension("Pa", "Pb", "length", 150.0), "joints[2].kind",
     "a gear joint cannot be sketched"),
    (SLOTTED_LEVER + dimension("O2", "A", "length", 100.0), "joints[2].links",
     "a pin_in_slot joint's guide (links[0]) is the ground"),
], ids=["a-gear-mesh", "a-slot-in-a-moving-link"])
def test_what_spans_two_links_is_not_sketched(tmp_path: Path, text: str, key: str,
                                              fragment: str) -> None:
    """A gear mesh (its centre distance set by its pitch radii) and a slot in a moving link
    (its line turns with that link) are refused in a sketch, naming the joint."""
    path = case_file(tmp_path, text, "bad.toml")
    assert_refused(["run", str(path), "-q", "--out", str(tmp_path / "out")],
                   str(path), f"key '{key}'", fragment)


def test_a_sketch_drawn_elsewhere_assembles_moved_with_it(tmp_path: Path) -> None:
    """The open sketch moved 5 m right and 3 m down (the ground with it) assembles at the
    hand trigonometry's points moved the same: where a sketch sits changes nothing."""
    shift = (5000.0, -3000.0)
    moved = {n: (x + shift[0], y + shift[1]) for n, (x, y) in OPEN_SKETCH.items()}
    case = load_one(tmp_path, four_bar("moved", moved, FOUR_BAR_DIMENSIONS))
    by_hand = {n: (x + shift[0], y + shift[1]) for n, (x, y) in four_bar_by_hand(True).items()}
    assert_points_close(drawn_mm(case.linkage), by_hand, A1)


def chain(links: int) -> str:
    """An open chain of ``links`` bars from the ground, each 1 m long along +x: a length and
    an angle per bar."""
    parts = ['[[case]]\nname = "chain"\nmechanism = "linkage"\n[case.points]']
    parts += [f"P{i} = [{i}.0, 0.1]" for i in range(links + 1)]
    parts.append('[[case.links]]\nname = "ground"\npoints = ["P0"]')
    for i in range(1, links + 1):
        parent = "ground" if i == 1 else f"b{i - 1}"
        parts.append(f'[[case.links]]\nname = "b{i}"\npoints = ["P{i - 1}", "P{i}"]\n'
                     f'[[case.joints]]\nname = "J{i}"\nkind = "revolute"\n'
                     f'links = ["{parent}", "b{i}"]\nat = "P{i - 1}"')
        parts.append(dimension(f"P{i - 1}", f"P{i}", "length", 1.0)
                     + dimension(f"P{i - 1}", f"P{i}", "angle", 0.0))
    return "\n".join(parts) + "\n"


def test_a_sketch_too_large_to_assemble_is_refused_before_the_work(tmp_path: Path) -> None:
    """A chain of 401 bars (401 moving points, one past the bound) is refused in one line,
    naming the bound, before any decomposition that grows as the cube of its size."""
    path = case_file(tmp_path, chain(MAX_SKETCH_POINTS + 1), "chain.toml")
    assert_refused(["run", str(path), "-q", "--out", str(tmp_path / "out")], str(path),
                   "key 'dimensions'", f"at most {MAX_SKETCH_POINTS} moving points")


def test_a_small_chain_assembles_straight(tmp_path: Path) -> None:
    """Three bars sketched 0.1 m above +x, each 1 m at 0°, assemble on the x axis at
    x = 1, 2, 3 (the ground point P0 stays where it is sketched, at (0, 0.1))."""
    case = load_one(tmp_path, chain(3))
    got = {n: case.linkage.drawn(p) for n, p in case.linkage.points.items()}
    for i in range(4):
        assert got[f"P{i}"] == pytest.approx((float(i), 0.1), rel=0.0, abs=RTOL), i


@settings(max_examples=40, deadline=None)
@given(a2=st.floats(20.0, 100.0), a3=st.floats(60.0, 200.0), a4=st.floats(60.0, 200.0),
       theta=st.floats(0.0, 360.0), upper=st.booleans(),
       noise=st.lists(st.floats(-1.0, 1.0), min_size=4, max_size=4))
def test_random_four_bar_sketches_assemble_where_trigonometry_puts_them(
        a2: float, a3: float, a4: float, theta: float, upper: bool, noise: list[float]) -> None:
    """Any four-bar (ground 140 mm) that assembles with its coupler and rocker at least 10 %
    of the coupler from one line, sketched with A and B off by up to 5 % of the crank,
    assembles at the hand trigonometry's points on the side of A→B0 the sketch shows."""
    t = math.radians(theta)
    d = math.hypot(A1 - a2 * math.cos(t), a2 * math.sin(t))
    along = (a3**2 - a4**2 + d**2) / (2 * d)
    assume(a3**2 - along**2 > (0.1 * a3) ** 2)
    hand = four_bar_by_hand(upper, A1, a2, a3, a4, theta)
    off = 0.05 * a2
    sketch = hand | {"A": (hand["A"][0] + off * noise[0], hand["A"][1] + off * noise[1]),
                     "B": (hand["B"][0] + off * noise[2], hand["B"][1] + off * noise[3])}
    shape = Linkage(points={n: (x * 1e-3, y * 1e-3) for n, (x, y) in sketch.items()},
                    links=tuple(Link(n, p) for n, p in FOUR_BAR_LINKS.items()),
                    joints=tuple(Joint(n, "revolute", ends, n) for n, ends in FOUR_BAR_JOINTS.items()))
    got = assembled(shape, (Dimension(("A0", "A"), length=a2 * 1e-3),
                            Dimension(("A0", "A"), angle=t),
                            Dimension(("A", "B"), length=a3 * 1e-3),
                            Dimension(("B0", "B"), length=a4 * 1e-3)))
    assert_points_close({n: (1e3 * x, 1e3 * y) for n, (x, y) in got.items()}, hand, A1)


FOUR_BAR_LINKS = {"ground": ("A0", "B0"), "crank": ("A0", "A"), "coupler": ("A", "B"),
                  "rocker": ("B0", "B")}
FOUR_BAR_JOINTS = {"A0": ("ground", "crank"), "A": ("crank", "coupler"), "B": ("coupler", "rocker"),
                   "B0": ("ground", "rocker")}
