"""Three mechanisms a user wrote from ``mechcheck new linkage`` (``compare/cases/users/``),
checked against the user's own hand calculations: kinematics written here from the
drawing (not the engine's), and the driver's effort by virtual work.

The hand kinematics are differentiated by central differences, extrapolated (Richardson)
from steps h and h/2: the truncation error left is O(h⁴) ≈ 1e-16 of the derivative, and the
rounding about ε·|x|/h ≈ 1e-12 of it, well inside the analytic family's 1e-9.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from mechcheck import load_cases, solve
from mechcheck.analytic.case import Case
from mechcheck.analytic.solution import Solution
from mechcheck.casefile import builtin_case_files
from mechcheck.sim_models.linkage_motion import at_first_driver
from mechcheck.sim_models.pymunk.linkage_sweep import sweep as pymunk_sweep
from mechcheck.tolerance import rule

USERS = Path(__file__).resolve().parents[1] / "compare" / "cases" / "users"
G = 9.81
Point = tuple[float, float]


def user_case(file: str, name: str) -> Case:
    return next(c for c in load_cases(USERS / file) if c.name == name)


def virtual_work_effort(positions: Callable[[float], dict[str, Point]],
                        loads: list[tuple[str, Point]], h: float = 1e-4) -> float:
    """The driver's effort Q (N·m) that holds the loads (N) at points (mm) moving with the
    crank angle: Q = −Σ F·dr/dθ, dr/dθ by Richardson-extrapolated central differences."""
    def power(step: float) -> float:
        ahead, behind = positions(step), positions(-step)
        return sum(fx * (ahead[k][0] - behind[k][0]) + fy * (ahead[k][1] - behind[k][1])
                   for k, (fx, fy) in loads) / (2.0 * step) / 1000.0
    return -(4.0 * power(h / 2.0) - power(h)) / 3.0


def whitworth_points(dth: float) -> dict[str, Point]:
    """The Whitworth's load points (mm) with the crank at 60° + dth (the user's kinematics:
    crank 100 mm about O2, slotted lever about O4 = (0, −50), arm 80 mm, rod 250 mm to the ram
    on y = −50, tool 34.06 mm behind and 30 mm below D)."""
    th = math.radians(60.0) + dth
    a = (100 * math.cos(th), 100 * math.sin(th))
    o4 = (0.0, -50.0)
    phi = math.atan2(a[1] - o4[1], a[0] - o4[0])
    u = (math.cos(phi), math.sin(phi))
    c = (o4[0] - 80 * u[0], o4[1] - 80 * u[1])
    d = (c[0] - math.sqrt(250**2 - (-50 - c[1]) ** 2), -50.0)
    return {"T": (d[0] - 34.05685402712396, d[1] - 30), "RG": (d[0], d[1] + 10),
            "LG": (o4[0] + 20 * u[0], o4[1] + 20 * u[1]),
            "KG": ((c[0] + d[0]) / 2, (c[1] + d[1]) / 2), "CG": (a[0] / 2, a[1] / 2)}


WHITWORTH_LOADS = [("T", (-800.0, 0.0)), ("CG", (0.0, -1 * G)), ("LG", (0.0, -3 * G)),
                   ("KG", (0.0, -2 * G)), ("RG", (0.0, -20 * G))]

O2, O4 = (300.0, 200.0), (0.0, 400.0)


def circle_meet(p: Point, r1: float, q: Point, r2: float, near: Point) -> Point:
    """Where circles about p (radius r1) and q (r2) meet, the crossing nearer ``near``."""
    d = math.dist(p, q)
    a = (r1 * r1 - r2 * r2 + d * d) / (2 * d)
    h = math.sqrt(r1 * r1 - a * a)
    ex = ((q[0] - p[0]) / d, (q[1] - p[1]) / d)
    m = (p[0] + a * ex[0], p[1] + a * ex[1])
    both = [(m[0] - h * ex[1], m[1] + h * ex[0]), (m[0] + h * ex[1], m[1] - h * ex[0])]
    return min(both, key=lambda x: math.dist(x, near))


def toggle_points(dth: float, beta_deg: float = 5.0) -> dict[str, Point]:
    """The toggle press's points (mm) with the crank turned dth from its drawing, whose
    toggle links stand ``beta_deg`` off their line (the user's kinematics: crank 50 mm about
    O2, upper link 200 mm about O4, lower link 200 mm to the ram on x = 0)."""
    b = math.radians(beta_deg)
    b0 = (200 * math.sin(b), 400 - 200 * math.cos(b))
    a0 = (300.0, 250.0)
    coupler = math.dist(a0, b0)
    a = (O2[0] + 50 * math.cos(math.pi / 2 + dth), O2[1] + 50 * math.sin(math.pi / 2 + dth))
    bb = circle_meet(O4, 200, a, coupler, b0)
    c = (0.0, bb[1] - math.sqrt(200**2 - bb[0] ** 2))

    def mid(p: Point, q: Point) -> Point:
        return ((p[0] + q[0]) / 2, (p[1] + q[1]) / 2)

    return {"G2": mid(O2, a), "G3": mid(a, bb), "GU": mid(O4, bb), "GL": mid(bb, c),
            "GR": (0.0, c[1] - 50), "C": c, "B": bb}


TOGGLE_LOADS = [("C", (0.0, 10000.0)), ("G2", (0.0, -2 * G)), ("G3", (0.0, -3 * G)),
                ("GU", (0.0, -4 * G)), ("GL", (0.0, -4 * G)), ("GR", (0.0, -50 * G))]


def test_the_user_mechanisms_are_built_in_examples() -> None:
    names = {p.name for p in builtin_case_files()}
    assert {"whitworth.toml", "toggle_press.toml", "scissor_lift.toml"} <= names


#: (file, case, the hand kinematics, the loads, the user's printed hand result and its
#: last digit): the Whitworth at 60° (printed 45.59453646 N·m), the press 5° off its toggle
#: (printed 81.5464691 N·m).
HAND_CHECKS = {
    "whitworth": ("whitworth.toml", "whitworth-static", whitworth_points, WHITWORTH_LOADS,
                  45.5945364, 1e-6),
    "toggle-press": ("toggle_press.toml", "toggle-press-5deg", toggle_points, TOGGLE_LOADS,
                     81.546469, 1e-5),
}


@pytest.mark.parametrize("backend", ["analytic", "virtual_work", "mujoco_solve", "pymunk"])
@pytest.mark.parametrize("mechanism", sorted(HAND_CHECKS))
def test_crank_torque_is_the_hand_virtual_work(mechanism: str, backend: str) -> None:
    file, name, points, loads, printed, digit = HAND_CHECKS[mechanism]
    hand = virtual_work_effort(points, loads)
    assert hand == pytest.approx(printed, abs=digit)
    got = solve(user_case(file, name), backend)
    assert got.status == "ok", got.message
    tol = rule(backend, "torque", "static")   # each backend judged by its own family
    assert got.values["Q_O2"] == pytest.approx(hand, rel=tol.rtol), tol.reason


def test_toggle_press_half_a_degree_off_needs_a_tenth_of_the_torque() -> None:
    """Closer to the toggle the same press force needs far less crank torque: the hand
    virtual work of the 0.5° drawing against the engine's."""
    hand = virtual_work_effort(lambda d: toggle_points(d, 0.5), TOGGLE_LOADS)
    got = solve(user_case("toggle_press.toml", "toggle-press-0p5deg"), "analytic")
    tol = rule("analytic", "torque", "static")
    assert got.values["Q_O2"] == pytest.approx(hand, rel=tol.rtol), tol.reason
    assert hand < 0.2 * virtual_work_effort(toggle_points, TOGGLE_LOADS)


def scissor_effort(ext: float) -> float:
    """The scissor lift's cylinder force (N, pushing) by virtual work, from the user's
    drawing: arm1 of length 1 m about G1 at angle θ, the cylinder from Cb = (0.3, 0) to
    Cr at 0.7 of arm1; the platform's W and PL and the arms' E rise as sin θ."""
    def length(th: float) -> float:
        return math.hypot(0.7 * math.cos(th) - 0.3, 0.7 * math.sin(th))

    def angle(extension: float) -> float:   # θ at a cylinder extension, by bisection
        target, lo, hi = length(math.radians(30.0)) + extension, 1e-6, math.pi / 2
        for _ in range(200):
            mid = (lo + hi) / 2
            lo, hi = (mid, hi) if length(mid) < target else (lo, mid)
        return (lo + hi) / 2

    def height(th: float) -> float:   # platform (200 kg + 1 kN) and arms' centres (20 kg)
        return (200 * G + 1000) * math.sin(th) + 20 * G * 0.5 * math.sin(th)

    h = 1e-6
    return (height(angle(ext + h)) - height(angle(ext - h))) / (2 * h)


def test_scissor_lift_cylinder_force_is_the_hand_virtual_work() -> None:
    hand = scissor_effort(0.0)
    got = solve(user_case("scissor_lift.toml", "scissor-lift-hold"), "analytic")
    # Bisection and a central difference of step 1e-6 m: about 1e-9 of the force.
    assert abs(got.values["Q_cyl"]) == pytest.approx(hand, rel=1e-6)


def toggle_angle() -> float:
    """The crank angle (rad from the drawing) at the toggle: upper and lower link in line,
    B on the ram's line x = 0 (bisection on the hand kinematics)."""
    lo, hi = 0.0, math.radians(60.0)
    for _ in range(100):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if toggle_points(mid)["B"][0] > 0 else (lo, mid)
    return (lo + hi) / 2


def test_the_hand_toggle_is_where_the_press_needs_no_torque_for_its_force() -> None:
    """At the toggle the ram's dC/dθ is zero: the press force does no virtual work."""
    at = toggle_angle()
    assert 0.0 < math.degrees(at) < 60.0
    only_press = [("C", (0.0, 10000.0))]
    assert abs(virtual_work_effort(lambda d: toggle_points(at + d), only_press)) < 1e-6
    assert np.isfinite(at)


def scissor_hold() -> Case:
    return user_case("scissor_lift.toml", "scissor-lift-hold")


def agrees_with_analytic(solution: Solution, reference: Solution) -> None:
    """Every force of a settled pymunk solution within the settled family's static
    tolerance of the analytic one, relative to the largest of their kind (the policy's
    scale); the platform where the analytic pose puts it."""
    tol = rule("pymunk", "force", "static")
    forces = [q for q, u in reference.units.items() if u == "N"]
    largest = max(abs(reference.values[q]) for q in forces)
    for q in forces:
        assert abs(solution.values[q] - reference.values[q]) <= tol.rtol * largest, (q, tol.reason)
    assert solution.values["y_P3"] == pytest.approx(reference.values["y_P3"], abs=1e-9)


def test_a_settled_sweep_that_jumps_branch_restarts_from_the_analytic_pose() -> None:
    """Near the top of its stroke the scissor lift's other assembly (the bottom roller on
    the other side of E) is 0.13 m away; continuing from 255 mm, the impulses carried over
    swing the 200 kg platform onto it at 260 mm. The sweep sees the pose far from the
    analytic one, runs it again alone from the analytic pose, and says so."""
    case = scissor_hold()
    first = np.array([0.255, 0.260])
    got = pymunk_sweep(case, first, "pymunk")
    assert [s.status for s in got] == ["ok", "ok"], [s.message for s in got]
    assert "restart" not in got[0].diagnostics
    why = str(got[1].diagnostics["restart"])
    assert "another branch" in why and "restarted from the analytic pose" in why
    for solution, value in zip(got, first, strict=True):
        agrees_with_analytic(solution, solve(at_first_driver(case, value), "analytic"))


@pytest.mark.parametrize("extension", [-0.060, 0.265, 0.280, 0.285])
def test_scissor_lift_hard_poses_settle(extension: float) -> None:
    """Poses where the held pymunk model swung onto the other assembly (-60 mm in a sweep,
    265 mm alone), or where the slow mode it extrapolates stops shrinking next to the top of
    the stroke (280 and 285 mm: extrapolating stops once its limit overflows), at condition
    numbers below 10³: each settles on its own assembly."""
    case = at_first_driver(scissor_hold(), extension)
    reference = solve(case, "analytic")
    assert reference.diagnostics["condition_number"] < 1e3
    got = solve(case, "pymunk")
    assert got.status == "ok", got.message
    agrees_with_analytic(got, reference)


# Slow tier: four rungs of driven runs, about 40 s on an idle machine.
@pytest.mark.slow
def test_the_turning_whitworth_at_its_hardest_pose_gets_a_driven_number() -> None:
    """At 210° (condition number about 250) pymunk's driven reading of the Whitworth turning
    at 10 rad/s moved by 1.3e-4 of the forces when its last step was solved again with more
    iterations, against the 1e-4 rule, up to 1600 iterations a step: the ladder's next rung
    settles it. Its crank torque is the analytic one within the dynamic tolerance."""
    case = user_case("whitworth.toml", "whitworth-running")
    first = np.radians([210.0])
    got = pymunk_sweep(case, first, "pymunk")[0]
    reference = solve(at_first_driver(case, float(first[0])), "analytic")
    assert reference.diagnostics["condition_number"] < 1e3
    assert got.status == "ok", got.message
    tol = rule("pymunk", "torque", "dynamic")
    scale = max(abs(v) for q, v in reference.values.items() if reference.units[q] == "N")
    # Torques judged against the largest reaction times the length scale (the policy's).
    assert abs(got.values["Q_O2"] - reference.values["Q_O2"]) <= tol.rtol * scale * case.scale
