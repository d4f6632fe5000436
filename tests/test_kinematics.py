"""Closed-form kinematics against finite differences of the closed-form positions, and the loop."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import example, given, settings

from mechcheck.analytic.case import Case, FourBarGeometry, Motion, SliderCrankGeometry
from mechcheck.analytic.kinematics import pose_of
from mechcheck.analytic.presets import preset_case

from .strategies import cases

#: First derivatives: central differences with h = 1e-4 rad, Richardson-extrapolated
#: to h/2. Rounding ~eps·|q|/h ≈ 1e-12; truncation O(h⁴·|q⁽⁵⁾|) ≈ 1e-16·|q⁽⁵⁾|, small even
#: next to an assembly limit. (A plain central difference with h = 1e-5 left 3.6e-7 on a
#: slider-crank with a2 = 3.3·a3 at cos θ13 = 0.19, where h²·|q⁽³⁾|/6 is not small.)
FD_RTOL = 1e-7
H = 1e-4
#: Second derivatives: h = 2e-4 rad with Richardson extrapolation to h/2. Rounding
#: ~(16/3)·eps·|q|/h² ≈ 1e-7·|q| (|q| ≤ π here), truncation O(h⁴·|q⁽⁶⁾|) ≈ 1e-9 even
#: where d²θ13/dθ12² reaches 400 (a slider-crank with a2 = 4·a3; h = 2e-3 left 1.4e-5).
FD2_RTOL = 1e-6
H2 = 2e-4


def positions(case: Case, theta12: np.ndarray) -> np.ndarray:
    p = pose_of(case, theta12, omega=0.0, alpha=0.0)
    rows = [p.theta13, p.theta14 if p.s14 is None else p.s14 / case.scale]
    rows += [p.point(k, (0.03, -0.02))[0][:, i] / case.scale for k in (2, 3, 4)
             for i in (0, 1)]
    return np.stack(rows, axis=1)


def first_difference(case: Case, h: float) -> np.ndarray:
    """dq/dθ12 by the central difference with step h."""
    q = np.unwrap(positions(case, np.array([case.preset.theta12 - h, case.preset.theta12 + h])), axis=0)
    return (q[1] - q[0]) / (2 * h)


def second_difference(case: Case, h: float) -> np.ndarray:
    """d²q/dθ12² by the central second difference with step h."""
    t = case.preset.theta12
    q = np.unwrap(positions(case, np.array([t - h, t, t + h])), axis=0)
    return (q[2] - 2 * q[1] + q[0]) / h**2


#: The draw whose positions round to ~100 eps (see the test).
THIN_CROSSED = preset_case("thin-crossed", FourBarGeometry(0.05965875594280917, 0.7130397078480268,
                                                    0.05, 0.7130397078480268),
                    0.0, branch="crossed", ground_angle=1.330078125, motion=Motion(1.0, 0.0))


@settings(max_examples=60, deadline=None)
@given(cases(friction=False, dynamic=True))
@example(case=THIN_CROSSED)
def test_velocities_and_accelerations_are_derivatives_of_positions(case: Case) -> None:
    """ω, α of links 3 and 4, slider ṡ, s̈ and any body point's v, a equal d/dt of the positions."""
    w, a = case.preset.motion.omega, case.preset.motion.alpha
    # Next to an assembly limit q' grows like 1/c and q changes its character within
    # Δθ12 ~ c² (c: the distance in cos θ13), so the steps shrink like 1/|q'|², with
    # |q'| taken from a plain difference of the positions, never from the code under test.
    shrink = max(1.0, float(np.abs(first_difference(case, 1e-7)).max()) / 4) ** 2
    h, h2 = H / shrink, H2 / shrink
    dq = (4 * first_difference(case, h / 2) - first_difference(case, h)) / 3   # dq/dθ12
    # The second difference's rounding, ~ε_q/h² for positions rounded to ε_q, is not
    # eps·|q| everywhere: a four-bar with a 0.05 m coupler between two 0.713 m links, drawn
    # crossed, rounds its positions to ~100 eps (acos of a thin triangle), and read α3
    # 2.4e-6 off at h = 1e-4 but 1e-8 at h = 5e-4 (a random draw, 2026-11-26). Steps
    # shrunk for a steep q' raise it with the shrink squared: a slider-crank with a2 = 19·a3
    # at θ12 = 0 (shrink 23) read 2.3e-5 off the exact s̈ = −a2·ω²·(1 + a2/a3). So d²q is
    # estimated at three step sizes, a factor 2 apart, the middle one taken; where they
    # disagree (rounding at the small steps, truncation at the large), twice their spread
    # is allowed too.
    estimates = [(4 * second_difference(case, k * h2 / 2) - second_difference(case, k * h2)) / 3
                 for k in (1.0, 2.0, 4.0)]
    d2q = estimates[1]
    d2q_error = np.max([np.abs(e - d2q) for e in estimates], axis=0)
    p = pose_of(case)
    rate = [p.links[3].omega, p.links[4].omega if p.s14 is None else p.s14_dot / case.scale]
    rate += [p.point(k, (0.03, -0.02))[1][:, i] / case.scale for k in (2, 3, 4)
             for i in (0, 1)]
    acc = [p.links[3].alpha, p.links[4].alpha if p.s14 is None else p.s14_ddot / case.scale]
    acc += [p.point(k, (0.03, -0.02))[2][:, i] / case.scale for k in (2, 3, 4)
            for i in (0, 1)]
    expected_rate = dq * w
    expected_acc = d2q * w**2 + dq * a
    scale_v = max(1.0, np.abs(dq).max()) * max(abs(w), 1.0)
    scale_a = max(1.0, np.abs(d2q).max()) * max(w * w + abs(a), 1.0)
    assert np.allclose(np.concatenate(rate), expected_rate, atol=FD_RTOL * scale_v, rtol=0)
    allowance = FD2_RTOL * scale_a + 2.0 * d2q_error * w**2
    assert np.all(np.abs(np.concatenate(acc) - expected_acc) <= allowance)


def test_a_short_rod_at_dead_centre_has_the_closed_form_acceleration() -> None:
    """The random draw whose shrunk steps met the second difference's rounding: s =
    a2·cos θ + √(a3² − a2²·sin²θ), so at θ = 0 s̈ = −a2·ω²·(1 + a2/a3) exactly."""
    case = preset_case("short-rod", SliderCrankGeometry(0.96875, 0.05), 0.0, motion=Motion(1.0, 0.0))
    p = pose_of(case)
    assert p.s14_ddot is not None
    assert float(p.s14_ddot[0]) == pytest.approx(-0.96875 * (1 + 0.96875 / 0.05), rel=1e-12)
    test_velocities_and_accelerations_are_derivatives_of_positions.hypothesis.inner_test(case)


@settings(max_examples=60, deadline=None)
@given(cases(friction=False))
def test_pose_closes_the_loop_with_the_right_lengths(case: Case) -> None:
    """|AB| = a3, |B0B| = a4 (or B on the slide line at the offset), on the stated branch."""
    p = pose_of(case)
    g = case.preset.geometry
    a, b = p.joints["A"][0], p.joints["B"][0]
    assert np.isclose(np.linalg.norm(b - a), g.a3, rtol=1e-12)
    assert np.isclose(np.linalg.norm(a), g.a2, rtol=1e-12)
    if case.mechanism == "four_bar":
        assert np.isclose(np.linalg.norm(b - p.joints["B0"][0]), g.a4, rtol=1e-12)
        # The branches are mirror images across the line AB0; the seed's "f − acos"
        # (open) puts B to the left of A→B0, as in seed E1 (B above the line there).
        b0 = p.joints["B0"][0]
        d, e = b0 - a, b - a
        side = d[0] * e[1] - d[1] * e[0]
        assert (side >= 0) if case.preset.branch == "open" else (side <= 0)
    else:
        u = np.array([np.cos(case.preset.ground_angle), np.sin(case.preset.ground_angle)])
        n = np.array([-u[1], u[0]])
        assert np.isclose(b @ n, g.offset, atol=1e-12 * g.scale)
        along = (b - a) @ u
        assert (along >= 0) if case.preset.branch == "right" else (along <= 0)
