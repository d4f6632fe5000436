"""The static fast path (:func:`mechcheck.analytic.forces.static_results`) against two
other routes to the same numbers: the benchmark's straight-line reference
(``benchmarks/reference_presets.py``, written from the free-body diagrams), and the
library's own general path (pose with velocities, b (N, 9), block elimination), which
dynamic and friction cases take."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings

from mechcheck.analytic.case import Case, FourBarGeometry, Load, Mass, SliderCrankGeometry
from mechcheck.analytic.kinematics import pose_of
from mechcheck.analytic.presets import preset_case
from mechcheck.tolerance import NEAR_SINGULAR_CONDITION, rule

from .benchmark_reference import benchmark_module
from .builtin import builtin
from .closed_form import forces
from .closed_form.equilibrium import condition, eliminate, known_vector
from .strategies import cases

#: The policy's tolerance for two analytic routes to the same equations at ordinary poses
#: (condition ≤ NEAR_SINGULAR_CONDITION, where rounding is amplified at most 1e4×).
RTOL = rule("analytic", "force", "static").rtol


REFERENCE = benchmark_module("reference_presets")

#: Every whole degree, and a stretch 1e-3° wide around 0° (where a crank passes its
#: ground line) at a finer spacing.
SWEEP = np.radians(np.concatenate([np.arange(-180.0, 180.0, 1.0), np.linspace(-1e-3, 1e-3, 11)]))


def reference_of(case: Case, theta: np.ndarray) -> dict[str, np.ndarray]:
    statics = REFERENCE.fourbar_statics if case.mechanism == "four_bar" \
        else REFERENCE.slidercrank_statics
    # Unassembled poses are NaN; a dead point's forces overflow (both left out as singular).
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        return statics(case, theta)


def check_against_reference(case: Case, theta: np.ndarray) -> None:
    ref = reference_of(case, theta)
    got = forces.solve_poses(case, theta)
    ordinary = ref["condition"] <= NEAR_SINGULAR_CONDITION
    assert set(ref) - {"condition"} == set(got.values)
    # Forces exist exactly where the reference has them, but for the reference's NaN at an
    # assembly limit the library clips to a toggle (condition beyond 1e4 there).
    has_forces = np.isfinite(got.values["F34_x"])
    assert np.array_equal(has_forces[ordinary], np.isfinite(ref["F34_x"])[ordinary])
    assert not has_forces[np.isnan(ref["condition"])].any()
    assert np.allclose(got.condition[ordinary], ref["condition"][ordinary], rtol=RTOL, atol=0.0)
    assert REFERENCE.worst_error(case, ref, got.values, ordinary) <= RTOL


def test_seed_cases_agree_with_the_reference_over_a_whole_turn() -> None:
    """E1 (four-bar, change point at 180°) and E2 without friction (slider-crank)."""
    for name in ("seed-E1-as-stated", "seed-E1-as-printed", "seed-E2-frictionless"):
        case = builtin(name)
        check_against_reference(case, SWEEP)
        assert np.isfinite(forces.solve_poses(case, SWEEP).values["T12"]).sum() >= 350


def test_the_reference_reproduces_the_printed_seed_e1() -> None:
    """The reference alone at E1's pose (θ12 = 60°) against Söylemez Ex. 6.3 as printed
    (compare/cases/seeds.toml): within half a unit of the printed last digit."""
    case = builtin("seed-E1-as-printed")
    got = {q: float(v[0]) for q, v in reference_of(case, np.array([case.preset.theta12])).items()}
    assert abs(got["T12"] - -2.90133) <= 0.5e-5
    for joint, magnitude in (("23", 139.46), ("34", 89.77), ("14", 37.74)):
        assert abs(math.hypot(got[f"F{joint}_x"], got[f"F{joint}_y"]) - magnitude) <= 0.5e-2
    assert abs(math.degrees(got["theta13"]) - 29.98) <= 0.5e-2
    assert abs(math.degrees(got["theta14"]) - 96.40) <= 0.5e-2


#: Loads with moments on every link, and weights: every term of the folded right-hand side.
LOADS = (Load(2, (0.03, -0.01), (4.0, -7.0), 0.3), Load(3, (0.05, 0.02), (-20.0, 11.0)),
         Load(4, (0.02, 0.04), (13.0, 5.0), -0.8))
MASSES = (Mass(2, 0.4, (0.02, 0.0)), Mass(3, 0.7, (0.04, 0.01)), Mass(4, 1.1, (0.03, -0.02)))


@pytest.mark.parametrize("case", [
    preset_case("rocker-driven-crossed", FourBarGeometry(0.14, 0.08, 0.10, 0.12), 1.0, branch="crossed",
         ground_angle=0.5, drive_link=4, gravity=(1.0, -9.81), loads=LOADS, masses=MASSES),
    preset_case("crank-driven-open", FourBarGeometry(0.14, 0.08, 0.10, 0.12), 1.0, ground_angle=-2.0,
         gravity=(0.0, -9.81), loads=LOADS, masses=MASSES),
    preset_case("slider-tilted-left", SliderCrankGeometry(0.08, 0.2, offset=0.03), 1.0, branch="left",
         ground_angle=0.4, gravity=(0.0, -9.81), loads=LOADS, masses=MASSES),
], ids=lambda c: c.name)
def test_every_drive_branch_and_load_term_agrees_with_the_reference(case: Case) -> None:
    check_against_reference(case, SWEEP)


@settings(max_examples=40, deadline=None)
@given(cases(friction=False, dynamic=False))
def test_random_static_cases_agree_with_the_reference(case: Case) -> None:
    """Both mechanisms, branches, ground angles, drives on 2 or 4, loads with moments and
    weights: the reference and the library agree at every ordinary pose of a turn."""
    check_against_reference(case, SWEEP)


@settings(max_examples=40, deadline=None)
@given(cases(friction=False, dynamic=False))
def test_static_path_equals_the_general_path(case: Case) -> None:
    """The fast path (positions only, fixed loads folded) and the general one (velocities, b
    (N, 9) built with moments about the global origin, block elimination) give one answer."""
    got = forces.solve_poses(case, SWEEP)
    with np.errstate(invalid="ignore", divide="ignore"):
        pose = pose_of(case, SWEEP)
        x = eliminate(case, pose, known_vector(case, pose))
        general = forces.named_values(case, pose, x)
        cond = condition(case, pose)
    ordinary = cond <= NEAR_SINGULAR_CONDITION
    assert np.array_equal(np.isfinite(got.condition), np.isfinite(cond))
    assert np.allclose(got.condition[ordinary], cond[ordinary], rtol=RTOL, atol=0.0)
    reference = general | {"condition": cond}
    assert REFERENCE.worst_error(case, reference, got.values, ordinary) <= RTOL
