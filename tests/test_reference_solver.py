"""Sanity of the independent reference solver itself, without the analytic backend.

The reference (tests/reference_solver.py) is checked against the seeds' worked
examples (SEEDS.md E1, E2, exam Q3) to their printed precision, against hand
power balances, against finite differences of its own position solve, and
against free-body equilibrium of each link written out here.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from mechcheck.analytic.case import (
    Case,
    FourBarGeometry,
    Friction,
    Load,
    Mass,
    Motion,
    SliderCrankGeometry,
)
from mechcheck.analytic.presets import preset_case, redrawn

from . import reference_solver as ref

#: Printed answers carry 2 decimals (N, degrees, N·mm): half a unit of the last digit.
PRINTED_2DP = 0.005
#: SEEDS.md's corrected E2 values carry 3 decimals.
PRINTED_3DP = 0.0005
#: Identities that hold exactly in exact arithmetic (power balance, free-body
#: sums, the same number by two routes) are met to rounding: the systems here are
#: well conditioned (cond < 1e3), so 1e-10 relative leaves a wide margin over
#: cond × 2.2e-16.
IDENTITY_RTOL = 1e-10
#: Central differences with h = 1e-6 rad have truncation error ~h² ≈ 1e-12 and
#: rounding error ~eps/h ≈ 1e-10 relative.
FINITE_DIFF_RTOL = 1e-7
#: Second differences with h = 1e-4 rad: truncation ~h² ≈ 1e-8, rounding ~eps/h² ≈ 2e-8.
SECOND_DIFF_RTOL = 1e-6


def polar(magnitude: float, degrees: float) -> tuple[float, float]:
    """A force of the given magnitude and direction (degrees from +x)."""
    a = math.radians(degrees)
    return (magnitude * math.cos(a), magnitude * math.sin(a))


def magnitude_angle(values: dict[str, float], name: str) -> tuple[float, float]:
    """|F| (N) and direction (degrees) of a reported reaction."""
    x, y = values[f"{name}_x"], values[f"{name}_y"]
    return math.hypot(x, y), math.degrees(math.atan2(y, x))


def angle_diff_deg(a: float, b: float) -> float:
    """a − b wrapped into (−180°, 180°]."""
    return (a - b + 180.0) % 360.0 - 180.0


# -- SEEDS.md E1 -------------------------------------------------------------------------
E1_ALPHA = math.acos((-80.0**2 + 100.0**2 + 70.0**2) / (2.0 * 70.0 * 100.0))
E1_C = (0.070 * math.cos(E1_ALPHA), 0.070 * math.sin(E1_ALPHA))  # coupler point, link-3 frame
E1_D = (0.090, 0.0)  # rocker point, link-4 frame


def e1_case(coupler_load_deg: float, rocker_load_deg: float) -> Case:
    return preset_case(
        name="E1",
        geometry=FourBarGeometry(a1=0.140, a2=0.080, a3=0.100, a4=0.120),
        theta12=math.radians(60.0),
        loads=(Load(3, E1_C, polar(50.0, coupler_load_deg)),
               Load(4, E1_D, polar(100.0, rocker_load_deg))),
    )


def test_e1_loads_as_stated() -> None:
    """With the loads at 50° and 20° (force by the outside on the link), E1 needs
    T12 = +2.90133 N·m CCW and every reaction is 180° from the printed direction."""
    r = ref.solve(e1_case(50.0, 20.0)).values
    assert math.degrees(r["theta13"]) == pytest.approx(29.98, abs=PRINTED_2DP)
    assert math.degrees(r["theta14"]) == pytest.approx(96.40, abs=PRINTED_2DP)
    assert r["T12"] * 1000.0 == pytest.approx(2901.33, abs=PRINTED_2DP)
    for name, printed_mag, printed_dir in (("F14", 37.74, -43.52), ("F34", 89.77, 42.10),
                                           ("F23", 139.46, 44.93)):
        mag, direction = magnitude_angle(r, name)
        assert mag == pytest.approx(printed_mag, abs=PRINTED_2DP), name
        assert abs(angle_diff_deg(direction, printed_dir + 180.0)) <= PRINTED_2DP, name
    # The crank carries only F12 and F32: F12 = F23 (link 2 is a two-force member here).
    assert r["F12_x"] == pytest.approx(r["F23_x"], rel=IDENTITY_RTOL)
    assert r["F12_y"] == pytest.approx(r["F23_y"], rel=IDENTITY_RTOL)


def test_e1_seed_sign_reading() -> None:
    """With the loads entered at 230° and 200° (the seed's sign), the printed directions
    and the printed 2901.33 N·mm clockwise come out exactly."""
    r = ref.solve(e1_case(230.0, 200.0)).values
    assert r["T12"] * 1000.0 == pytest.approx(-2901.33, abs=PRINTED_2DP)
    for name, printed_mag, printed_dir in (("F14", 37.74, -43.52), ("F34", 89.77, 42.10),
                                           ("F23", 139.46, 44.93)):
        mag, direction = magnitude_angle(r, name)
        assert mag == pytest.approx(printed_mag, abs=PRINTED_2DP), name
        assert abs(angle_diff_deg(direction, printed_dir)) <= PRINTED_2DP, name


def test_e1_virtual_work() -> None:
    """E1's drive torque equals minus the loads' virtual power per unit crank speed."""
    case = e1_case(50.0, 20.0)
    unit_speed = ref.solve(redrawn(case, motion=Motion(omega=1.0)))
    _, v_c = ref.point_state(unit_speed, 3, E1_C)
    _, v_d = ref.point_state(unit_speed, 4, E1_D)
    power = np.dot(polar(50.0, 50.0), v_c) + np.dot(polar(100.0, 20.0), v_d)
    assert ref.solve(case).values["T12"] == pytest.approx(-power, rel=IDENTITY_RTOL)


# -- SEEDS.md E2 -------------------------------------------------------------------------
E2_RADII = {"A0": 0.050, "A": 0.250, "B": 0.050}
#: Distance of the slider's contact face from the pin (the seed's a = 50 mm).
E2_FACE = 0.050


def e2_case(friction: bool) -> Case:
    return preset_case(
        name="E2",
        geometry=SliderCrankGeometry(a2=0.200, a3=0.800),
        theta12=math.radians(55.0),
        loads=(Load(4, (0.0, 0.0), polar(100.0, 180.0)),),
        friction=Friction(mu=0.1, pin_radius=E2_RADII, direction=-1) if friction else None,
    )


def test_e2_friction_circle() -> None:
    """E2 (corrected): with μ = 0.1 everywhere and the crank turning clockwise the drive
    needs T12 = −22.897 N·m, |F34| = 105.674 N, N = 25.504 N, and the normal force acts
    15.717 mm from the pin when the slide friction acts at the contact face."""
    r = ref.solve(e2_case(friction=True)).values
    assert r["s14"] * 1000.0 == pytest.approx(897.76, abs=PRINTED_2DP)
    assert math.degrees(r["theta13"]) == pytest.approx(-11.817, abs=PRINTED_3DP)
    assert r["T12"] == pytest.approx(-22.897, abs=PRINTED_3DP)
    mag34, dir34 = magnitude_angle(r, "F34")
    assert mag34 == pytest.approx(105.674, abs=PRINTED_3DP)
    # The seed's "friction direction" f is the line of the rod force on the coupler, F43.
    assert abs(angle_diff_deg(dir34 + 180.0, 166.034)) <= PRINTED_3DP
    # Horizontal slide: u = +x, n = +y, so N = F14_y and the friction force f = F14_x.
    normal, friction = r["F14_y"], r["F14_x"]
    assert normal == pytest.approx(25.504, abs=PRINTED_3DP)
    assert friction == pytest.approx(-0.1 * abs(normal), rel=IDENTITY_RTOL)  # opposes ṡ > 0
    # Moments about B of the guide's reaction: normal N at x along u on the face at
    # −a·n, friction f there: M14 = x·N + a·f (the contract puts f through B instead,
    # so M14 holds both terms); solve for x.
    x = (r["M14"] - E2_FACE * friction) / normal
    assert abs(x) * 1000.0 == pytest.approx(15.717, abs=PRINTED_3DP)


def test_e2_frictionless() -> None:
    """Without friction the E2 pose needs T12 = −18.783 N·m."""
    assert ref.solve(e2_case(friction=False)).values["T12"] == pytest.approx(-18.783,
                                                                            abs=PRINTED_3DP)


def test_e2_friction_dissipates() -> None:
    """In E2 the drive's power exceeds the load's by exactly the friction losses
    Σ μ·r·|F|·|ω_rel| + μ·|N|·|ṡ| (per unit crank speed)."""
    case = e2_case(friction=True)
    sol = ref.solve(case)
    kin = ref.solve(redrawn(case, friction=None, motion=Motion(omega=-1.0)))
    w2, w3 = kin.qd[2], kin.qd[5]
    s_dot = kin.qd[6]
    v = sol.values
    load_power = -100.0 * s_dot
    losses = (0.1 * E2_RADII["A0"] * math.hypot(v["F12_x"], v["F12_y"]) * abs(w2)
              + 0.1 * E2_RADII["A"] * math.hypot(v["F23_x"], v["F23_y"]) * abs(w3 - w2)
              + 0.1 * E2_RADII["B"] * math.hypot(v["F34_x"], v["F34_y"]) * abs(w3)
              + 0.1 * abs(v["F14_y"]) * abs(s_dot))
    assert v["T12"] * w2 + load_power == pytest.approx(losses, rel=IDENTITY_RTOL)


# -- Exam Q3 (drive on link 4) ---------------------------------------------------------
Q3_A2, Q3_A3, Q3_A4 = 0.050, 0.200, 0.151
Q3_TH2, Q3_TH3, Q3_TH4 = (math.radians(d) for d in (30.0, 38.62, 92.02))
Q3_W2, Q3_AL2 = 10.0, 196.75
Q3_M2, Q3_I_A0 = 1.0, 1.0 * 0.032**2  # kg; m·i² about A0
Q3_P, Q3_F, Q3_G = 45.0, 100.0, 9.81


def q3_case() -> Case:
    """Exam Q3. The ground link follows from the loop A0 + a2e2 + a3e3 − a4e4 = B0.
    F = 100 N downward at B is put on the rocker (link 4) at its point B = (a4, 0); B is
    shared with the coupler, so T14 is the same either way (only F34 changes)."""
    e = lambda t: np.array([math.cos(t), math.sin(t)])  # noqa: E731
    b0 = Q3_A2 * e(Q3_TH2) + Q3_A3 * e(Q3_TH3) - Q3_A4 * e(Q3_TH4)
    return preset_case(
        name="Q3",
        geometry=FourBarGeometry(a1=float(np.hypot(*b0)), a2=Q3_A2, a3=Q3_A3, a4=Q3_A4),
        theta12=Q3_TH2,
        ground_angle=math.atan2(b0[1], b0[0]),
        drive_link=4,
        gravity=(0.0, -Q3_G),
        masses=(Mass(2, Q3_M2, (Q3_A2 / 2.0, 0.0), Q3_I_A0 - Q3_M2 * (Q3_A2 / 2.0) ** 2),),
        loads=(Load(2, (Q3_A2, 0.0), polar(Q3_P, 30.0 + 90.0)),
               Load(4, (Q3_A4, 0.0), (0.0, -Q3_F))),
        motion=Motion(omega=Q3_W2, alpha=Q3_AL2),
    )


def test_q3_ground_from_loop() -> None:
    """Q3's ground link A0B0 is ≈ 204.9 mm at −0.30°, and the reference reassembles the
    printed angles θ3 = 38.62°, θ4 = 92.02° and speeds ω3 = −2.75, ω4 = −0.62 rad/s."""
    case = q3_case()
    assert isinstance(case.preset.geometry, FourBarGeometry)
    assert case.preset.geometry.a1 * 1000.0 == pytest.approx(204.9, abs=0.05)
    assert math.degrees(case.preset.ground_angle) == pytest.approx(-0.30, abs=PRINTED_2DP)
    sol = ref.solve(case)
    assert sol.q[5] == pytest.approx(Q3_TH3, abs=1e-12)
    assert sol.q[8] == pytest.approx(Q3_TH4, abs=1e-12)
    assert sol.qd[5] == pytest.approx(-2.75, abs=PRINTED_2DP)
    assert sol.qd[8] == pytest.approx(-0.62, abs=PRINTED_2DP)


def test_q3_power_balance() -> None:
    """Q3's drive moment on link 4 is 29.17 N·m, equal to the exam's power balance
    T14·ω4 + P·v_A + F·v_B + W·v_G = d(KE)/dt written out by hand."""
    # Hand calculation, as in the exam. Velocity loop projected on e3:
    #   ω4 = a2·ω2·sin(θ3 − θ2) / (a4·sin(θ3 − θ4))
    w4 = Q3_A2 * Q3_W2 * math.sin(Q3_TH3 - Q3_TH2) / (Q3_A4 * math.sin(Q3_TH3 - Q3_TH4))
    p_power = Q3_P * Q3_A2 * Q3_W2                 # P ∥ v_A (both at θ2 + 90°)
    f_power = -Q3_F * Q3_A4 * w4 * math.cos(Q3_TH4)  # F = (0, −F), v_B = a4ω4(−sinθ4, cosθ4)
    w_power = -Q3_M2 * Q3_G * (Q3_A2 / 2.0) * Q3_W2 * math.cos(Q3_TH2)  # weight at S2
    kinetic_rate = Q3_I_A0 * Q3_W2 * Q3_AL2        # d/dt(½·I_A0·ω2²); links 3, 4 massless
    hand_t14 = (kinetic_rate - p_power - f_power - w_power) / w4
    assert hand_t14 == pytest.approx(29.17, abs=PRINTED_2DP)
    t14 = ref.solve(q3_case()).values["T14"]
    assert t14 == pytest.approx(29.17, abs=PRINTED_2DP)
    assert t14 == pytest.approx(hand_t14, rel=IDENTITY_RTOL)


# -- Generic checks of the method ------------------------------------------------------
def generic_cases() -> list[Case]:
    """Frictionless dynamic cases with loads, masses and gravity on every link."""
    loads = (Load(2, (0.03, 0.01), (12.0, -7.0), 0.4), Load(3, (0.05, -0.02), (-20.0, 9.0)),
             Load(4, (0.02, 0.015), (5.0, 16.0), -0.3))
    masses = (Mass(2, 0.8, (0.02, 0.005), 2e-4), Mass(3, 1.3, (0.04, 0.01), 9e-4),
              Mass(4, 0.6, (0.03, -0.01), 3e-4))
    common = {"loads": loads, "masses": masses, "gravity": (1.5, -9.81),
              "motion": Motion(omega=-7.0, alpha=35.0)}
    return [
        preset_case(name="fb", geometry=FourBarGeometry(0.13, 0.05, 0.11, 0.09),
             theta12=1.1, ground_angle=0.3, **common),
        preset_case(name="fb4", geometry=FourBarGeometry(0.13, 0.05, 0.11, 0.09), branch="crossed",
             theta12=2.3, drive_link=4, **common),
        preset_case(name="sc", geometry=SliderCrankGeometry(0.05, 0.16, 0.02), branch="left",
             theta12=-0.7, ground_angle=-0.4, **common),
    ]


@pytest.mark.parametrize("case", generic_cases(), ids=lambda c: c.name)
def test_power_balance(case: Case) -> None:
    """Without friction the drive's power plus every applied force's power equals the
    rate of change of kinetic energy (the constraint forces do no work)."""
    sol = ref.solve(case)
    power = sol.values[f"T1{case.preset.drive_link}"] * sol.qd[ref.COL[case.preset.drive_link] + 2]
    for ld in case.preset.loads:
        _, v = ref.point_state(sol, ld.link, ld.at)
        power += float(np.dot(ld.force, v)) + ld.torque * sol.qd[ref.COL[ld.link] + 2]
    kinetic_rate = 0.0
    for m in case.preset.masses:
        c = ref.COL[m.link]
        rc = ref.rot(sol.q[c + 2]) @ np.asarray(m.com)
        _, v_g = ref.point_state(sol, m.link, m.com)
        a_g = sol.qdd[c:c + 2] + ref.perp(rc) * sol.qdd[c + 2] - rc * sol.qd[c + 2] ** 2
        power += float(np.dot(m.mass * np.asarray(case.gravity), v_g))
        kinetic_rate += m.mass * float(np.dot(a_g, v_g)) + m.inertia * sol.qd[c + 2] * sol.qdd[
            c + 2]
    assert power == pytest.approx(kinetic_rate, rel=IDENTITY_RTOL, abs=IDENTITY_RTOL)


@pytest.mark.parametrize("case", generic_cases(), ids=lambda c: c.name)
def test_free_body_equilibrium(case: Case) -> None:
    """Each link, loaded by the reported reactions (F_ij on j, −F_ij on i), the drive,
    the loads and its weight, satisfies Newton–Euler: ΣF = m·a_G and ΣM_G = I_G·α."""
    sol = ref.solve(case)
    v = sol.values
    joints = {"A0": (1, 2), "A": (2, 3), "B": (3, 4)}
    force = {name: np.array([v[f"F{i}{j}_x"], v[f"F{i}{j}_y"]])
             for name, (i, j) in joints.items()}
    at = {"A0": (2, (0.0, 0.0)), "A": (3, (0.0, 0.0)), "B": (4, (0.0, 0.0))}
    g = case.preset.geometry
    if isinstance(g, FourBarGeometry):
        joints["B0"] = (1, 4)
        force["B0"] = np.array([v["F14_x"], v["F14_y"]])
        at["B0"] = (4, (0.0, 0.0))
        at["B"] = (4, (g.a4, 0.0))
    drive = v[f"T1{case.preset.drive_link}"]
    for link in (2, 3, 4):
        c = ref.COL[link]
        m = case.preset.mass_of(link)
        com = (0.0, 0.0) if m is None else m.com
        p_g, _ = ref.point_state(sol, link, com)
        rc = ref.rot(sol.q[c + 2]) @ np.asarray(com)
        a_g = sol.qdd[c:c + 2] + ref.perp(rc) * sol.qdd[c + 2] - rc * sol.qd[c + 2] ** 2
        total_f = np.zeros(2)
        total_m = drive if link == case.preset.drive_link else 0.0
        if link == 4 and "M14" in v:
            total_m += v["M14"]
        applied: list[tuple[np.ndarray, np.ndarray]] = []
        for name, (i, j) in joints.items():
            point, _ = ref.point_state(sol, *at[name])
            if j == link:
                applied.append((point, force[name]))
            elif i == link:
                applied.append((point, -force[name]))
        if link == 4 and "M14" in v:
            applied.append((ref.point_state(sol, 4, (0.0, 0.0))[0],
                            np.array([v["F14_x"], v["F14_y"]])))
        for ld in case.preset.loads:
            if ld.link == link:
                applied.append((ref.point_state(sol, link, ld.at)[0], np.asarray(ld.force)))
                total_m += ld.torque
        if m is not None:
            applied.append((p_g, m.mass * np.asarray(case.gravity)))
        for point, f in applied:
            total_f += f
            total_m += ref.cross2(point - p_g, f)
        mass = 0.0 if m is None else m.mass
        inertia = 0.0 if m is None else m.inertia
        scale = max(float(np.max(np.abs(list(v.values())))), 1.0)
        np.testing.assert_allclose(total_f, mass * a_g, atol=IDENTITY_RTOL * scale)
        assert total_m == pytest.approx(inertia * sol.qdd[c + 2], abs=IDENTITY_RTOL * scale)


@pytest.mark.parametrize("case", generic_cases(), ids=lambda c: c.name)
def test_velocities_match_finite_differences(case: Case) -> None:
    """The velocity solve Φ_q q̇ = −Φ_t equals ω times the derivative of the position
    solve with respect to θ12, and the acceleration solve Φ_q q̈ = γ equals
    ω²·q'' + α·q'."""
    h = 1e-6
    sol = ref.solve(case)
    plus = ref.solve(redrawn(case, theta12=case.preset.theta12 + h))
    minus = ref.solve(redrawn(case, theta12=case.preset.theta12 - h))
    w, a = case.preset.motion.omega, case.preset.motion.alpha
    dq = (plus.q - minus.q) / (2 * h)
    np.testing.assert_allclose(sol.qd, w * dq, rtol=FINITE_DIFF_RTOL, atol=1e-9)
    # The second difference needs a larger step (rounding ~eps/h², truncation ~h²).
    h2 = 1e-4
    plus = ref.solve(redrawn(case, theta12=case.preset.theta12 + h2))
    minus = ref.solve(redrawn(case, theta12=case.preset.theta12 - h2))
    d2q = (plus.q - 2 * sol.q + minus.q) / h2**2
    np.testing.assert_allclose(sol.qdd, w**2 * d2q + a * dq, rtol=SECOND_DIFF_RTOL, atol=1e-6)


def test_branches_are_mirror_images() -> None:
    """The open and crossed four-bar poses are mirror images in the line A–B0, with
    B on the clockwise side of B0→A for open; the slider's right branch has the larger s14."""
    g = FourBarGeometry(0.14, 0.08, 0.10, 0.12)
    base = preset_case(name="b", geometry=g, theta12=1.0, ground_angle=0.4)
    qo = ref.solve(base).q
    qc = ref.solve(redrawn(base, branch="crossed")).q
    a = qo[3:5]
    b0 = qo[6:8]
    b_open = b0 + g.a4 * np.array([math.cos(qo[8]), math.sin(qo[8])])
    b_crossed = b0 + g.a4 * np.array([math.cos(qc[8]), math.sin(qc[8])])
    assert ref.cross2(a - b0, b_open - b0) < 0.0 < ref.cross2(a - b0, b_crossed - b0)
    e = (a - b0) / np.linalg.norm(a - b0)
    mirror = b0 + 2 * np.dot(b_open - b0, e) * e - (b_open - b0)
    np.testing.assert_allclose(b_crossed, mirror, atol=1e-14)
    sc = preset_case(name="s", geometry=SliderCrankGeometry(0.05, 0.12, 0.01), theta12=0.8)
    assert ref.solve(sc).values["s14"] > ref.solve(redrawn(sc, branch="left")).values["s14"]
