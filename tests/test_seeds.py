"""The seed documents' worked examples (SEEDS.md), as printed or as corrected.

Where the seed is right its printed numbers are asserted to their printed
precision; where it is wrong the corrected value is asserted, and the printed
one is shown to follow from the printed (wrong) formula.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from .builtin import builtin
from .closed_form import forces, superposition, virtual_work

#: Printed answers are rounded to 2 decimals (N, degrees, N·mm): half a unit.
HALF_2DP = 0.005
#: SEEDS.md's corrected values carry 3 decimals.
HALF_3DP = 0.0005


def magnitude_angle(values: dict[str, float], name: str) -> tuple[float, float]:
    x, y = values[f"{name}_x"], values[f"{name}_y"]
    return math.hypot(x, y), math.degrees(math.atan2(y, x))


def angle_diff(a: float, b: float) -> float:
    return (a - b + 180.0) % 360.0 - 180.0


PRINTED_E1 = {"F14": (37.74, -43.52), "F34": (89.77, 42.10), "F23": (139.46, 44.93)}


def test_e1_as_printed_reproduces_every_printed_number() -> None:
    """Söylemez 6.3 with the loads at 230°/200° gives the seed's printed reactions and 2901.33 N·mm CW."""
    values = forces.solve(builtin("seed-E1-as-printed")).values
    for name, (mag, ang) in PRINTED_E1.items():
        m, a = magnitude_angle(dict(values), name)
        assert abs(m - mag) <= HALF_2DP, name
        assert abs(angle_diff(a, ang)) <= HALF_2DP, name
    assert abs(values["T12"] * 1000.0 - (-2901.33)) <= HALF_2DP


def test_e1_as_stated_reverses_every_reaction() -> None:
    """With the loads as stated, T12 = +2.90133 N·m CCW and each reaction is 180° from the print."""
    values = forces.solve(builtin("seed-E1-as-stated")).values
    assert abs(values["T12"] - 2.90133) <= HALF_2DP / 1000.0
    for name, (mag, ang) in PRINTED_E1.items():
        m, a = magnitude_angle(dict(values), name)
        assert abs(m - mag) <= HALF_2DP, name
        assert abs(angle_diff(a, ang + 180.0)) <= HALF_2DP, name


def test_e1_pose_matches_print() -> None:
    """θ13 = 29.98°, θ14 = 96.40° on the open branch (seed E1)."""
    values = forces.solve(builtin("seed-E1-as-stated")).values
    assert abs(math.degrees(values["theta13"]) - 29.98) <= HALF_2DP
    assert abs(math.degrees(values["theta14"]) - 96.40) <= HALF_2DP


def test_e1_superposition_gives_the_same_numbers() -> None:
    """Method 2 of the seed (superposition) gives Method 1's numbers (frictionless)."""
    a = forces.solve(builtin("seed-E1-as-stated")).values
    b = superposition.solve(builtin("seed-E1-as-stated")).values
    for q in a:
        assert b[q] == pytest.approx(a[q], rel=1e-12, abs=1e-12)


def seed_e2_chain(theta13_ba: float) -> tuple[float, float, float, float]:
    """The seed's own E2 computation (its Matlab code), in N and mm, from a given θ13 (B→A, rad).

    f = θ13 + asin(−30/800) is the direction of F43 tangent to the friction
    circles at A (μr = 25) and B (μr = 5); K = [−cos f, −0.1; −sin f, 1],
    G = [100; 0] balances the slider; T12 = −200·F34·sin(f − θ12) − 30·F34.
    """
    theta12 = math.radians(55.0)
    f = theta13_ba + math.asin(-30.0 / 800.0)
    k = np.array([[-math.cos(f), -0.1], [-math.sin(f), 1.0]])
    f34, g14 = np.linalg.solve(k, np.array([100.0, 0.0]))
    t12 = -200.0 * f34 * math.sin(f - theta12) - 30.0 * f34
    return math.degrees(f), float(f34), float(g14), t12 / 1000.0


def test_e2_printed_answers_follow_from_the_typo() -> None:
    """The seed's θ13 formula (a2·sinθ12 for a2·cosθ12) gives its printed 167.4165°, 165.27°, −23.11 N·m."""
    a2, a3, theta12, s14 = 200.0, 800.0, math.radians(55.0), 897.7604
    wrong = math.atan2(a2 * math.sin(theta12) / a3, (a2 * math.sin(theta12) - s14) / a3)
    assert abs(math.degrees(wrong) - 167.4165) <= 5e-5
    f, f34, g14, t12 = seed_e2_chain(wrong)
    assert abs(f - 165.27) <= HALF_2DP
    assert abs(f34 - 106.19) <= HALF_2DP
    assert abs(g14 - 27.01) <= HALF_2DP
    assert abs(t12 - (-23.11)) <= HALF_2DP


def test_e2_corrected_matches_the_seed_chain_with_the_right_formula() -> None:
    """With a2·cosθ12 the seed's own chain and the matrix method agree: T12 = −22.897 N·m (crank CW)."""
    a2, a3, theta12, s14 = 200.0, 800.0, math.radians(55.0), 897.7604
    right = math.atan2(a2 * math.sin(theta12) / a3, (a2 * math.cos(theta12) - s14) / a3)
    f, f34, g14, t12_chain = seed_e2_chain(right)
    values = forces.solve(builtin("seed-E2-friction")).values
    assert abs(t12_chain - (-22.897)) <= HALF_3DP
    assert abs(values["T12"] - (-22.897)) <= HALF_3DP
    assert abs(f - 166.034) <= HALF_3DP
    m, _ = magnitude_angle(dict(values), "F34")
    assert abs(m - 105.674) <= HALF_3DP
    assert abs(abs(values["F14_y"]) - 25.504) <= HALF_3DP  # the normal force G14 (slide along x)
    assert abs(f34 - m) <= 1e-3 and abs(g14 - abs(values["F14_y"])) <= 1e-3


def test_e2_frictionless_torque() -> None:
    """Without friction the same pose needs T12 = −18.783 N·m (SEEDS.md E2)."""
    assert abs(forces.solve(builtin("seed-E2-frictionless")).values["T12"] - (-18.783)) <= HALF_3DP


def test_e2_normal_force_position_matches_the_seed_s() -> None:
    """The seed's s = 15.717 mm (where the normal force acts, friction at the face) follows from M14."""
    values = forces.solve(builtin("seed-E2-friction")).values
    normal = abs(values["F14_y"])
    friction = abs(values["F14_x"])
    # Moment balance about B: N·(s + 5) = μr_B·|F34| = −M14, and the seed moves the
    # friction force to the face 50 mm below B: N·s + f·50 = −M14·1000 (N·mm).
    s = (-values["M14"] * 1000.0 - friction * 50.0) / normal
    assert abs(s - 15.717) <= HALF_3DP


def test_exam_q3_drive_on_link_4_by_power_balance() -> None:
    """Exam Q3: the moment on link 4 is 29.17 N·m unrounded (printed 28.73 after rounding the velocities).

    Hand calculation as in the exam, unrounded: M·ω4 + P·v_A − F·ẏ_B − m g ẏ_S2 − m i² α2 ω2 = 0.
    """
    t2, t3, t4 = map(math.radians, (30.0, 38.62, 92.02))
    a2, a3, a4, w2, al2, m, i = 0.05, 0.2, 0.151, 10.0, 196.75, 1.0, 0.032
    w3 = -a2 * w2 * math.sin(t4 - t2) / (a3 * math.sin(t4 - t3))
    w4 = a2 * w2 * math.sin(t3 - t2) / (a4 * math.sin(t3 - t4))
    v_a = (-a2 * w2 * math.sin(t2), a2 * w2 * math.cos(t2))
    p = (45.0 * math.cos(t2 + math.pi / 2), 45.0 * math.sin(t2 + math.pi / 2))
    y_b_dot = a2 * w2 * math.cos(t2) + a3 * w3 * math.cos(t3)
    y_s_dot = 0.025 * w2 * math.cos(t2)
    power = p[0] * v_a[0] + p[1] * v_a[1] - 100.0 * y_b_dot - m * 9.81 * y_s_dot \
        - m * i**2 * al2 * w2
    hand = -power / w4
    assert abs(hand - 29.17) <= HALF_2DP
    case = builtin("seed-exam-Q3")
    assert forces.solve(case).values["T14"] == pytest.approx(hand, rel=2e-4)  # printed angles: 4 digits
    assert virtual_work.solve(case).values["T14"] == pytest.approx(hand, rel=2e-4)
    assert abs(forces.solve(case).values["T14"] - 29.17) <= HALF_2DP


def test_exam_q3_rounded_velocities_give_the_printed_28_73() -> None:
    """The exam's printed 28.7292 N·m follows from its rounded ω4 = −0.62, ẏB = 0.0033, Py = 38.7."""
    printed = (22.5 * 0.25 + 38.7 * 0.43 - 100 * 0.0033 - 9.81 * 0.215
               - 0.032**2 * 196.75 * 10) / 0.62
    assert abs(printed - 28.7292) <= 5e-5
