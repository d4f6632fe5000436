"""Drawings of a mechanism (``mechcheck draw``, :mod:`mechcheck.drawing`): the joints sit
where the pose analysis puts them, the picture does not depend on where the drawing sits or
how large it is, no two labels overlap on any built-in case, and the command line writes a
drawing or refuses in one line."""

from __future__ import annotations

import itertools
import math
import tomllib
from pathlib import Path
from typing import Any

import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.transforms import Bbox

from mechcheck import solve
from mechcheck.analytic.case import Case
from mechcheck.analytic.joint_kinds.drawing import Pin, PitchCircle, Slide, rotated
from mechcheck.analytic.solution import Solution
from mechcheck.casefile import builtin_case_files, catalogue_case_files, load_cases, parse_cases
from mechcheck.drawing import LABEL_GID, draw_case, panels_png, render, scene_of
from mechcheck.figures import cycle_panels
from mechcheck.sweep import LocalExecutor, parse_range, plan, run_sweep
from mechcheck.tolerance import rule
from tests.test_edges import one_line, run_cli
from tests.test_invariance import transformed

CASES_DIR = Path(__file__).parent.parent / "compare"
#: The pose analysis and the drawing are the same equations read two ways: only rounding
#: separates them (the analytic family's rule, compare/tolerance.py).
RTOL = rule("analytic", "pose", "static").rtol


def builtin_files() -> list[Path]:
    """Every case file shipped: the suite, the seeds, the linkages, the catalogue and
    ``mechcheck new``'s examples."""
    return [*builtin_case_files(), *catalogue_case_files(),
            *sorted((CASES_DIR / "examples").glob("*.toml"))]


@pytest.fixture(scope="module")
def solved() -> dict[str, tuple[Case, Solution]]:
    """Every built-in case at one pose with its analytic solution, solved once for the
    module (a trajectory case has no pose solution: the API refuses it)."""
    cases = [c for path in builtin_files() for c in load_cases(path) if not c.is_trajectory]
    return {c.name: (c, solve(c)) for c in cases}


def close(a: tuple[float, float], b: tuple[float, float], size: float) -> bool:
    return math.dist(a, b) <= RTOL * size


# -- the joints where the analysis puts them ------------------------------------------------

def e1_points(t12: float) -> dict[str, tuple[float, float]]:
    """Seed E1's pins at θ12 (rad), open branch: A0 at the origin, B0 at (a1, 0),
    A = a2·(cos θ12, sin θ12), B = B0 + a4·(cos θ14, sin θ14) with θ14 from the seed's closed
    form (CONVENTIONS.md, "Branches")."""
    a1, a2, a3, a4 = 0.140, 0.080, 0.100, 0.120
    c = a1**2 + a2**2 + a4**2 - a3**2 - 2 * a1 * a2 * math.cos(t12)
    a = -2 * a1 * a4 + 2 * a2 * a4 * math.cos(t12)
    b = 2 * a2 * a4 * math.sin(t12)
    t14 = math.atan2(b, a) - math.acos(c / math.hypot(a, b))
    return {"A0": (0.0, 0.0), "A": (a2 * math.cos(t12), a2 * math.sin(t12)),
            "B0": (a1, 0.0), "B": (a1 + a4 * math.cos(t14), a4 * math.sin(t14))}


def test_seed_fourbar_is_drawn_at_its_hand_closed_form(solved: dict[str, Any]) -> None:
    """Seed E1 (a1 = 140, a2 = 80, a3 = 100, a4 = 120 mm, θ12 = 60°, open) is drawn with its
    pins at the hand closed form (:func:`e1_points`), and each reaction arrow along the
    solution's F_ij from its pin."""
    case, solution = solved["seed-E1-as-stated"]
    a1 = 0.140
    expected = e1_points(math.radians(60.0))
    scene = scene_of(case, solution)
    for name, point in expected.items():
        assert close(scene.points[name], point, a1), (name, scene.points[name], point)
    pins = [m.at for j in scene.joints for m in j.marks if isinstance(m, Pin)]
    assert len(pins) == 4 and all(any(close(p, q, a1) for p in pins) for q in expected.values())
    # F_A is F23 (by the crank on the coupler), F_B F34, F_B0 F14, F_A0 F12 (presets.py).
    legacy = {"A0": "F12", "A": "F23", "B": "F34", "B0": "F14"}
    arrows = {a.label.split()[0]: a for a in scene.arrows if a.role == "reaction"}
    for pin, name in legacy.items():
        arrow = arrows[f"F_{pin}"]
        force = (solution.values[f"{name}_x"], solution.values[f"{name}_y"])
        assert close(arrow.at, expected[pin], a1)
        assert arrow.force == force
        assert math.isclose(arrow.vector[0] * force[1], arrow.vector[1] * force[0],
                            abs_tol=RTOL * scene.extent * math.hypot(*force))


def test_a_sweep_draws_its_cycle_at_evenly_spread_poses(tmp_path: Path) -> None:
    """A sweep of seed E1 every 30° draws four poses from its own analytic rows: 180° is its
    change point (singular, no forces), so of the eleven poses with forces (0°–150°,
    210°–330°) the 0th, 2nd, 5th and 8th; each with its pins at the hand closed form and
    the reactions a solve at that θ12 gives."""
    case = load_cases(CASES_DIR / "cases" / "seeds.toml")[0]
    outcome = run_sweep(plan([case], [], parse_range("0:360:30")), tmp_path, LocalExecutor())
    panels = cycle_panels(case, outcome.read(), outcome.read(kind="status"))
    assert [title for *_, title in panels] == ["θ12 = 0°", "θ12 = 60°", "θ12 = 150°",
                                              "θ12 = 270°"]
    for (at, solution, _), theta in zip(panels, (0.0, 60.0, 150.0, 270.0), strict=True):
        scene = scene_of(at, solution)
        for name, point in e1_points(math.radians(theta)).items():
            assert close(scene.points[name], point, 0.14), (theta, name)
        alone = scene_of(at, solve(at))
        largest = max(math.hypot(*a.force) for a in alone.arrows)
        for a, b in zip(scene.arrows, alone.arrows, strict=True):
            assert a.label.split()[0] == b.label.split()[0]
            assert math.dist(a.force, b.force) <= RTOL * largest, (theta, a.label)
    assert panels_png(panels).startswith(b"\x89PNG")


def linkage_names(solved: dict[str, Any]) -> list[str]:
    return [n for n, (c, s) in solved.items() if not c.is_preset and s.status == "ok"]


def test_linkages_are_drawn_at_their_solved_points(solved: dict[str, Any]) -> None:
    """Every built-in linkage: each point of the scene is the solution's x_/y_, each pin and
    slide sits at its joint's point, a slide's axis is its drawn axis turned by phi of the
    guide, and a gear's reaction acts on its line of centres, ra from gear a's centre."""
    names = linkage_names(solved)
    assert len(names) >= 20
    for name in names:
        case, solution = solved[name]
        values, linkage = solution.values, case.linkage
        scene = scene_of(case, solution)
        at = {p: (values[f"x_{p}"], values[f"y_{p}"]) for p in linkage.points}
        assert dict(scene.points) == at, name
        for joint, sketch in zip(linkage.joints, scene.joints, strict=True):
            for mark in sketch.marks:
                if isinstance(mark, (Pin, Slide)):
                    assert mark.at == at[joint.at], (name, joint.name)
                if isinstance(mark, Slide):
                    assert joint.axis is not None
                    turn = values.get(f"phi_{joint.links[0]}", 0.0)
                    assert close(mark.axis, rotated(turn, joint.axis), 1.0), (name, joint.name)
            if joint.mesh is not None:
                pa, pb = (at[c] for c in joint.mesh.centres)
                ra = joint.mesh.pitch_radii[0]
                radii = sorted(m.radius for m in sketch.marks if isinstance(m, PitchCircle))
                assert radii == sorted(joint.mesh.pitch_radii)
                assert math.isclose(math.dist(sketch.acts_at, pa), ra, rel_tol=RTOL)
                cross = ((pb[0] - pa[0]) * (sketch.acts_at[1] - pa[1])
                         - (pb[1] - pa[1]) * (sketch.acts_at[0] - pa[0]))
                assert abs(cross) <= RTOL * math.dist(pa, pb) ** 2


def test_the_drawn_pose_is_the_files_points() -> None:
    """Without a solution the scene is the file as written: Watt's six-bar's points in mm."""
    case = load_cases(CASES_DIR / "cases" / "linkages" / "watt_ii_sixbar.toml")[0]
    table = tomllib.loads((CASES_DIR / "cases" / "linkages" / "watt_ii_sixbar.toml").read_text())
    written = table["case"][0]["points"]
    scene = scene_of(case)
    for name, (x, y) in written.items():
        assert close(scene.points[name], (x / 1000, y / 1000), 0.4)
    assert not any(a.role == "reaction" for a in scene.arrows)


# -- where a drawing sits and how large it is ------------------------------------------------

#: Cases with moments, springs, plates and slides, whose tables `transformed` can carry along.
INVARIANT = [("linkages/watt_ii_sixbar.toml", 0), ("linkages/bonnet_counterbalanced.toml", 0),
             ("linkages/seed_e1_fourbar.toml", 0), ("catalogue/shaper.toml", 0)]
OFFSET = (1000.0, -500.0)
SCALE = 1000.0


def moved_case(relative: str, index: int) -> tuple[Case, Case, float]:
    """A case and the same drawn ×1000 and moved by (1000, −500) length units; the file's
    metres per length unit."""
    table = tomllib.loads((CASES_DIR / "cases" / relative).read_text())["case"][index]
    for load in table.get("loads", []):   # `transformed` turns forces given as components
        force = load.get("force", {})
        if "magnitude" in force:
            angle = math.radians(force["angle"])
            load["force"] = {"x": force["magnitude"] * math.cos(angle),
                             "y": force["magnitude"] * math.sin(angle)}
    unit = 1e-3 if table.get("length_unit") == "mm" else 1.0
    original = parse_cases({"case": [table]}, relative)[0][0]
    moved = parse_cases({"case": [transformed(table, OFFSET, 0.0, SCALE)]}, relative)[0][0]
    return original, moved, unit


def mapped(p: tuple[float, float], unit: float) -> tuple[float, float]:
    return (SCALE * p[0] + OFFSET[0] * unit, SCALE * p[1] + OFFSET[1] * unit)


@pytest.mark.parametrize(("relative", "index"), INVARIANT, ids=[r for r, _ in INVARIANT])
def test_a_drawing_moved_and_scaled_is_the_same_picture(relative: str, index: int) -> None:
    """The same linkage drawn 1000 times as large and 1000 length units away: every point and
    arrow tail maps by that affine map, every arrow is the same fraction of the extent, the
    force labels read the same, and the rendered labels land on the same pixels."""
    original, moved, unit = moved_case(relative, index)
    first, second = scene_of(original, solve(original)), scene_of(moved, solve(moved))
    size = SCALE * first.extent
    assert math.isclose(second.extent, size, rel_tol=RTOL)
    for name, p in first.points.items():
        assert close(second.points[name], mapped(p, unit), size), name
    assert [a.label for a in first.arrows] == [a.label for a in second.arrows]
    for a, b in zip(first.arrows, second.arrows, strict=True):
        assert close(b.at, mapped(a.at, unit), size)
        assert close((b.vector[0] / second.extent, b.vector[1] / second.extent),
                     (a.vector[0] / first.extent, a.vector[1] / first.extent), 1.0)
    for a, b in zip(label_boxes(render(first)), label_boxes(render(second)), strict=True):
        assert a[0] == b[0]
        assert max(abs(u - v) for u, v in zip(a[1].extents, b[1].extents, strict=True)) < 1.0


# -- labels ----------------------------------------------------------------------------------

def label_boxes(fig: Figure) -> list[tuple[str, Bbox]]:
    """Every placed label's text and box (display pixels) once the figure is laid out as
    it is drawn."""
    fig.draw_without_rendering()
    renderer = fig.canvas.get_renderer()   # type: ignore[attr-defined]
    return [(t.get_text(), t.get_window_extent(renderer)) for ax in fig.axes for t in ax.texts
            if t.get_gid() == LABEL_GID]


def overlapping(boxes: list[tuple[str, Bbox]]) -> list[tuple[str, str]]:
    return [(a, b) for (a, p), (b, q) in itertools.combinations(boxes, 2) if p.overlaps(q)]


def test_no_two_labels_overlap_on_any_builtin_case(solved: dict[str, Any]) -> None:
    """Every built-in case drawn at the default size, at its solved pose (as drawn where the
    analysis gives none): no label's box meets another's or the title's."""
    assert len(solved) >= 39
    for name, (case, solution) in solved.items():
        if case.geometry is None:
            continue
        try:
            fig = draw_case(case, solution)
        except ValueError:   # no pose from the analysis
            fig = draw_case(case)
        boxes = label_boxes(fig)
        title = fig.axes[0].title
        boxes.append((title.get_text(), title.get_window_extent()))
        assert len(boxes) > len(case.linkage.points), name
        assert overlapping(boxes) == [], name


def test_the_label_check_sees_an_overlap() -> None:
    """Two labels at one spot, unplaced, are caught by the check above."""
    fig = Figure()
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    for text in ("F_A 1 N", "F_B 2 N"):
        ax.text(0.5, 0.5, text, gid=LABEL_GID)
    assert overlapping(label_boxes(fig)) == [("F_A 1 N", "F_B 2 N")]


# -- the command line ------------------------------------------------------------------------

def test_draw_writes_svg_and_png(tmp_path: Path) -> None:
    """``mechcheck draw`` writes an SVG document and a PNG file, named as asked."""
    file = str(CASES_DIR / "examples" / "slider_crank.toml")
    svg, png = tmp_path / "sc.svg", tmp_path / "sc.PNG"
    code, _, err = run_cli(["draw", file, "-o", str(svg)])
    assert code == 0, err
    assert "<svg" in svg.read_text()[:2000] and svg.read_text().rstrip().endswith("</svg>")
    watt = str(CASES_DIR / "cases" / "linkages" / "watt_ii_sixbar.toml")
    code, _, err = run_cli(["draw", watt, "-o", str(png), "--backend", "superposition"])
    assert code == 0, err
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    code, _, err = run_cli(["draw", file, "-o", str(tmp_path / "drawn.svg"), "--drawn"])
    assert code == 0, err


def test_draw_writes_the_case_name_by_default(tmp_path: Path,
                                              monkeypatch: pytest.MonkeyPatch) -> None:
    """Without ``-o`` the drawing is ``<case>.svg`` in the current folder."""
    monkeypatch.chdir(tmp_path)
    code, _, err = run_cli(["draw", str(CASES_DIR / "examples" / "four_bar.toml")])
    assert code == 0, err
    assert [p.name for p in tmp_path.iterdir()] == ["my-four-bar.svg"]


SEEDS = str(CASES_DIR / "cases" / "seeds.toml")
SUITE = str(CASES_DIR / "cases" / "suite.toml")


@pytest.mark.parametrize(("args", "fragments"), [
    (["missing.toml"], ["missing.toml", "no such file"]),
    ([SEEDS], ["holds 5 cases", "--case", "seed-E1-as-stated, seed-E1-as-printed"]),
    ([SEEDS, "--case", "nope"], ["no case 'nope'", "seed-E2-friction"]),
    ([SEEDS, "-c", "seed-E1-as-stated", "-o", "{tmp}/x.pdf"], ["x.pdf", ".svg or .png"]),
    ([SEEDS, "-c", "seed-E1-as-stated", "-b", "nobody"], ["unknown backend 'nobody'"]),
    ([SEEDS, "-c", "seed-E1-as-stated", "-b", "virtual_work"],
     ["seed-E1-as-stated", "virtual_work gives no reactions", "no joint forces"]),
    ([SUITE, "-c", "fourbar-change-point"], ["fourbar-change-point", "singular"]),
    ([SEEDS, "-c", "seed-E1-as-stated", "--drawn", "-b", "mujoco"], ["--drawn"]),
], ids=["missing", "several", "unknown-case", "suffix", "unknown-backend", "no-reactions",
        "singular", "drawn-backend"])
def test_draw_refuses_in_one_line_and_writes_nothing(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                      args: list[str], fragments: list[str]) -> None:
    """Each unusable request: exit 2, one line naming what is wrong, no file written."""
    monkeypatch.chdir(tmp_path)
    code, _, err = run_cli(["draw", *(a.replace("{tmp}", str(tmp_path)) for a in args)])
    one_line(code, err, *fragments)
    assert list(tmp_path.iterdir()) == []
