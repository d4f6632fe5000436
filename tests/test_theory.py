"""Mechanism theory of seed 001 (SEEDS.md): every catalogue entry, and the closed
forms against brute-force searches over θ12 with the kinematics."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings, strategies as st
from typer.testing import CliRunner

from mechcheck.analytic import theory
from mechcheck.analytic.case import Case, CaseError, FourBarGeometry, SliderCrankGeometry
from mechcheck.analytic.kinematics import pose_of
from mechcheck.analytic.presets import preset_case
from mechcheck.analytic.transmission import transmission_angle
from mechcheck.cli import app
from mechcheck.theory_cli import GRASHOF_CATALOGUE, MOBILITY_CATALOGUE, parse_joints

from .builtin import builtin
from .strategies import assembling

#: A brute-force search on a 0.001° grid locates an extreme to within the grid
#: spacing; near an extreme the function is flat, so the value is exact to
#: (grid)²-order: 1e-3° on the angle, 1e-6 rad on the value.
GRID_DEG = 1e-3


@pytest.mark.parametrize(("name", "u", "joints", "spatial", "printed"), MOBILITY_CATALOGUE,
                         ids=[m[0] for m in MOBILITY_CATALOGUE])
def test_mobility_catalogue_of_seed_001(name: str, u: int, joints: str, spatial: bool,
                                        printed: int) -> None:
    """Gruebler–Kutzbach reproduces every mobility the seed prints (seed 001, mobility table)."""
    assert theory.mobility(u, parse_joints(joints), spatial=spatial) == printed


def test_structures_are_named_as_such() -> None:
    """S = 0 is a statically determinate structure, S = −1 an indeterminate one (truss, seed 001)."""
    assert theory.mobility_meaning(0) == "statically determinate structure"
    assert "indeterminate" in theory.mobility_meaning(-1)


def test_keyed_wave_maker_formula_typo() -> None:
    """The seed writes 6(6−4−1)+7 for the keyed wave-maker; with u = 4 it is 6(4−4−1)+7 = 1.

    Its printed result 1 stands; the mistyped formula would give 6·1 + 7 = 13.
    """
    assert theory.mobility(4, {"R": 2, "S": 1, "Ss": 1}, spatial=True) == 6 * (4 - 4 - 1) + 7 == 1
    assert 6 * (6 - 4 - 1) + 7 == 13


@pytest.mark.parametrize(("crank", "coupler", "rocker", "ground", "printed"), GRASHOF_CATALOGUE,
                         ids=[g[4] for g in GRASHOF_CATALOGUE])
def test_grashof_examples_of_seed_001(crank: float, coupler: float, rocker: float,
                                      ground: float, printed: str) -> None:
    """The four Grashof examples of seed 001 get the printed class."""
    assert theory.grashof(ground=ground, crank=crank, coupler=coupler, rocker=rocker).kind == printed


def test_seed_e1_linkage_is_a_change_point() -> None:
    """80 + 140 = 100 + 120: the seed four-bar is a change-point linkage (SIMULATORS.md, SEEDS.md)."""
    assert theory.grashof(ground=140, crank=80, coupler=100, rocker=120).kind == "change-point"


def dead_example(branch: str = "open") -> Case:
    """Seed 001 dead positions: A0B0 = 80, A0A = 20, B0B = 60, AB = 50 (mm)."""
    return preset_case(name="dead", geometry=FourBarGeometry(0.08, 0.02, 0.05, 0.06), theta12=0.3,
                branch=branch)


def test_dead_position_distances_of_seed_001() -> None:
    """The limit distances are A0A + AB = 70 and AB − A0A = 30 mm (the seed prints '20': a typo)."""
    extended, folded = theory.limit_positions(dead_example())
    assert extended.distance == pytest.approx(0.070, abs=1e-15)
    assert folded.distance == pytest.approx(0.030, abs=1e-15)


@pytest.mark.parametrize("branch", ["open", "crossed"])
def test_dead_positions_are_the_rocker_extremes(branch: str) -> None:
    """At the two dead positions θ14 reaches its extremes over a full crank turn (brute force)."""
    case = dead_example(branch)
    theta = np.radians(np.arange(0.0, 360.0, GRID_DEG))
    t14 = np.unwrap(pose_of(case, theta).theta14)
    found = {(math.degrees(float(theta[i])) % 360.0, math.degrees(float(t14[i])) % 360.0)
             for i in (int(np.argmax(t14)), int(np.argmin(t14)))}
    for lp in theory.limit_positions(case):
        want = (math.degrees(lp.theta12) % 360.0, math.degrees(lp.theta14) % 360.0)
        assert any(abs(math.remainder(want[0] - f[0], 360.0)) <= GRID_DEG
                   and abs(math.remainder(want[1] - f[1], 360.0)) <= 1e-4 for f in found), (want,
                                                                                           found)


def test_no_dead_positions_for_a_double_crank() -> None:
    """A double-crank (seed 001: 300, 315, 290, 215) has no crank–coupler dead position."""
    case = preset_case(name="dc", geometry=FourBarGeometry(0.215, 0.300, 0.315, 0.290), theta12=0.3)
    assert theory.crank_turns_fully(case.preset.geometry)
    with pytest.raises(CaseError):
        theory.limit_positions(case)


def test_slider_crank_transmission_minimum_of_seed_001() -> None:
    """Centric slider-crank with a/b = 1/4: μmin = acos(1/4) ≈ 75.5° with the crank at 90°."""
    case = preset_case(name="sc", geometry=SliderCrankGeometry(0.05, 0.2), theta12=0.0)
    ext = theory.transmission_extremes(case)
    assert math.degrees(ext.mu_min) == pytest.approx(math.degrees(math.acos(0.25)), abs=1e-12)
    assert abs(math.degrees(ext.mu_min) - 75.5) < 0.05
    assert abs(math.remainder(ext.theta12_at_min - math.pi / 2, math.tau)) < 1e-12


def lengths() -> st.SearchStrategy[float]:
    return st.floats(0.05, 1.0)


@st.composite
def turning_four_bars(draw: st.DrawFn) -> FourBarGeometry:
    """A four-bar whose crank turns fully, built to be so (not filtered).

    The crank a2 turns fully iff a1 + a2 <= a3 + a4 and a1 − a2 >= |a3 − a4|, so
    a2 is drawn below min(a3 + a4 − a1, a1 − |a3 − a4|).
    """
    a1, a3, a4 = draw(lengths()), draw(lengths()), draw(lengths())
    upper = min(a3 + a4 - a1, a1 - abs(a3 - a4))
    assume(upper > 0.02)
    return assembling(FourBarGeometry, a1, draw(st.floats(0.01, upper)), a3, a4)


@settings(max_examples=80, deadline=None)
@given(turning_four_bars(), st.floats(-math.pi, math.pi), st.sampled_from(["open", "crossed"]))
def test_transmission_extremes_match_a_brute_force_search(g: FourBarGeometry, ground: float,
                                                          branch: str) -> None:
    """μmin and μmax in closed form equal the extremes of μ(θ12) over a full crank turn.

    Change-point linkages (s + l = p + q) are left out: they fold flat at one
    pose, where the branch, and so μ, is undetermined.
    """
    assert theory.crank_turns_fully(g)
    cls = theory.grashof(ground=g.a1, crank=g.a2, coupler=g.a3, rocker=g.a4)
    assume(abs(cls.s_plus_l - cls.p_plus_q) > 1e-3 * cls.s_plus_l)
    case = preset_case(name="t", geometry=g, theta12=ground + 0.5 * math.pi, ground_angle=ground,
                branch=branch)
    mu = transmission_angle(case, np.radians(np.arange(0.0, 360.0, 0.01)))
    ext = theory.transmission_extremes(case)
    assert ext.mu_min == pytest.approx(np.nanmin(mu), abs=1e-6)
    assert ext.mu_max == pytest.approx(np.nanmax(mu), abs=1e-6)


def _assembles(g: FourBarGeometry, ground: float, branch: str) -> bool:
    try:
        preset_case(name="t", geometry=g, theta12=ground + 0.5 * math.pi, ground_angle=ground,
             branch=branch)
    except CaseError:
        return False
    return True


@settings(max_examples=80, deadline=None)
@given(lengths(), lengths(), st.floats(-0.5, 0.5))
def test_slider_crank_rotates_exactly_when_every_pose_assembles(a2: float, a3: float,
                                                                e: float) -> None:
    """a2 + |e| < a3 ⇔ every θ12 assembles, and the stroke is max s14 − min s14 then."""
    g = assembling(SliderCrankGeometry, a2, a3, e)
    assume(abs(a2 + abs(e) - a3) > 1e-6)
    case_args = {"name": "s", "geometry": g}
    theta = np.radians(np.arange(0.0, 360.0, 0.01))
    probe = None
    for t in theta[::100]:
        try:
            probe = preset_case(theta12=float(t), **case_args)  # type: ignore[arg-type]
            break
        except CaseError:
            continue
    assume(probe is not None)
    assert probe is not None
    s14 = pose_of(probe, theta).s14
    assert s14 is not None
    assert theory.slider_crank_rotates(g) == bool(np.all(np.isfinite(s14)))
    if theory.slider_crank_rotates(g):
        assert theory.slider_stroke(g) == pytest.approx(np.nanmax(s14) - np.nanmin(s14), abs=1e-8)


def test_centric_stroke_is_twice_the_crank() -> None:
    """A centric slider-crank's stroke is 2·a2 (seed 001)."""
    assert theory.slider_stroke(SliderCrankGeometry(0.2, 0.8)) == pytest.approx(0.4, abs=1e-15)


def test_theory_command_line() -> None:
    """`mechcheck theory catalogue` recomputes the seed catalogue and passes; bad joints exit 2."""
    runner = CliRunner()
    result = runner.invoke(app, ["theory", "catalogue"])
    assert result.exit_code == 0 and "printed -1" in result.output
    result = runner.invoke(app, ["theory", "mobility", "--links", "4", "--joints", "3R,1X"])
    assert result.exit_code == 2 and "key 'joints'" in result.stderr
    result = runner.invoke(app, ["theory", "grashof", "--ground", "250", "--crank", "100",
                                 "--coupler", "220", "--rocker", "150"])
    assert result.output.startswith("crank-rocker")


@pytest.mark.parametrize("grid", ["-60:300:5", "-57:303:5"])
def test_a_centric_slider_cranks_toggles_are_its_dead_centres(grid: str) -> None:
    """Seed E2 as a linkage (crank 200 mm, rod 800 mm, drawn at θ12 = 55°, 100 N on the
    slider): its slider stops where x_B = a2·cos θ + √(a3² − a2²·sin² θ) has
    dx_B/dθ = −a2·sin θ·(1 + a2·cos θ / √(a3² − a2²·sin² θ)) = 0, at θ = 0 and 180° (the
    bracket is never 0 since a3 > a2): −55° and 125° from the drawing. On a grid through
    them and on one beside them; the crank's pin, which only turns, is never marked."""
    from mechcheck.analytic.theory import output_toggles
    from mechcheck.sweep import parse_range
    from mechcheck.tolerance import rule

    case = builtin("e2-linkage-frictionless")
    found = np.degrees(output_toggles(case.linkage, np.radians(parse_range(grid, "--driver"))))
    tol = rule("virtual_work", "pose", "static")   # the analytic family's: only rounding
    assert found == pytest.approx([-55.0, 125.0], rel=tol.rtol), tol.reason
