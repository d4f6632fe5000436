"""Sanity of the independent linkage reference (tests/linkage_reference.py) on its own.

The reference is checked against the seeds' worked examples (SEEDS.md E1, E2, exam Q1,
Q2) to their printed precision, against hand calculations written out here (a boom's
moment balance, a pendulum's stiffness, a non-Grashof four-bar's limit angle), and
against identities evaluated here from its reported numbers: free-body equilibrium of
every link, virtual work and power balances with velocities and accelerations taken by
finite differences of its positions (not from its own kinematics), and invariance under
rotating the drawing. No expected value is taken from the reference's own output.
"""

from __future__ import annotations

import copy
import math
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from . import linkage_reference as ref

CASES = Path(__file__).resolve().parents[1] / "compare" / "cases" / "linkages"

#: Printed answers carry 2 decimals (N, degrees): half a unit of the last digit.
PRINTED_2DP = 0.005
#: SEEDS.md's corrected E2 values and the frictionless torque carry 3 decimals.
PRINTED_3DP = 0.0005
#: E1's T12 = 2.90133 N·m (2901.33 N·mm) carries 5 decimals in N·m.
PRINTED_5DP = 0.000005
#: Identities exact in exact arithmetic (free-body sums, the same number by two routes),
#: relative to the largest force or moment involved: the systems are well conditioned
#: (condition numbers below 50), so 1e-9 leaves a wide margin over cond × 2.2e-16, and
#: over the 1e-8 mm rounding of drawn points (which changes the geometry, not the balance).
IDENTITY_RTOL = 1e-9
#: Central differences of positions with h = 1e-3° (1.7e-5 rad) or 1e-3 mm: truncation
#: ~h² ≈ 3e-10, rounding (positions solved to ~1e-14 relative) ~1e-14/h ≈ 1e-9 relative.
FIRST_DIFF_RTOL = 1e-7
#: Five-point time differences with τ = 1 ms: truncation ~τ⁴ ω⁶/90 ≈ 3e-8 for ω = 12 rad/s,
#: rounding ~eps/τ² ≈ 2e-10 relative.
POWER_RTOL = 1e-6


# -- helpers --------------------------------------------------------------------------
def load(file: str, name: str | None = None) -> dict[str, Any]:
    """A deep copy of one case of tests/linkages/<file>.toml (the first if no name)."""
    with open(CASES / f"{file}.toml", "rb") as fh:
        cases = tomllib.load(fh)["case"]
    for c in cases:
        if name is None or c["name"] == name:
            return copy.deepcopy(c)
    raise KeyError(name)


def unit_of(case: dict[str, Any]) -> float:
    return 1e-3 if case.get("length_unit") == "mm" else 1.0


def polar(values: dict[str, float], joint: str) -> tuple[float, float]:
    """|F| (N) and direction (degrees) of a reported reaction."""
    x, y = values[f"F_{joint}_x"], values[f"F_{joint}_y"]
    return math.hypot(x, y), math.degrees(math.atan2(y, x))


def angle_diff_deg(a: float, b: float) -> float:
    """a − b wrapped into [−180°, 180°)."""
    return (a - b + 180.0) % 360.0 - 180.0


def rotation(phi: float) -> np.ndarray:
    return np.array([[math.cos(phi), -math.sin(phi)], [math.sin(phi), math.cos(phi)]])


def drawn(case: dict[str, Any], where: Any) -> np.ndarray:
    """A point name or [x, y] of the case as a drawn position in metres."""
    xy = case["points"][where] if isinstance(where, str) else where
    return unit_of(case) * np.asarray(xy, dtype=float)


def solved_point(case: dict[str, Any], values: dict[str, float], link: str, where: Any
                 ) -> np.ndarray:
    """Where a point fixed to ``link`` (drawn at ``where``) is at the solved pose: carried
    rigidly from one of the link's named points by the link's reported rotation."""
    p0 = drawn(case, where)
    if link == "ground":
        return p0
    carrier = next(lk for lk in case["links"] if lk["name"] == link)["points"][0]
    base = np.array([values[f"x_{carrier}"], values[f"y_{carrier}"]])
    return np.asarray(base + rotation(values[f"phi_{link}"]) @ (p0 - drawn(case, carrier)))


def force_of(load_table: dict[str, Any]) -> np.ndarray:
    f = load_table.get("force")
    if f is None:
        return np.zeros(2)
    if "x" in f:
        return np.array([f["x"], f["y"]], dtype=float)
    a = math.radians(f["angle"])
    return np.asarray(f["magnitude"] * np.array([math.cos(a), math.sin(a)]))


def cross(r: np.ndarray, f: np.ndarray) -> float:
    return float(r[0] * f[1] - r[1] * f[0])


def free_body_sums(case: dict[str, Any], values: dict[str, float]) -> dict[str, np.ndarray]:
    """ΣFx, ΣFy and ΣM (about the origin) on each moving link of a static case, built
    from the reported reactions, efforts and spring forces and the case's own loads."""
    links = [lk["name"] for lk in case["links"] if lk["name"] != "ground"]
    sums = {name: np.zeros(3) for name in links}

    def push(link: str, at: np.ndarray, force: np.ndarray, couple: float = 0.0) -> None:
        if link != "ground":
            sums[link] += [force[0], force[1], cross(at, force) + couple]

    joints = {j["name"]: j for j in case["joints"]}
    for j in case["joints"]:
        a, b = j["links"]
        at = np.array([values[f"x_{j['at']}"], values[f"y_{j['at']}"]])
        f = np.array([values[f"F_{j['name']}_x"], values[f"F_{j['name']}_y"]])
        m = values.get(f"M_{j['name']}", 0.0)
        push(b, at, f, m)
        push(a, at, -f, -m)
    for d in case.get("drivers", []):
        j = joints[d["joint"]]
        a, b = j["links"]
        at = np.array([values[f"x_{j['at']}"], values[f"y_{j['at']}"]])
        q = values[f"Q_{j['name']}"]
        if j["kind"] == "revolute":
            push(b, at, np.zeros(2), q)
            push(a, at, np.zeros(2), -q)
        else:
            axis = np.asarray(j["axis"], dtype=float) / np.linalg.norm(j["axis"])
            u = axis if a == "ground" else rotation(values[f"phi_{a}"]) @ axis
            push(b, at, q * u)
            push(a, at, -q * u)
    for ld in case.get("loads", []):
        at = solved_point(case, values, ld["link"], ld.get("at", [0.0, 0.0]))
        push(ld["link"], at, force_of(ld), ld.get("torque", 0.0))
    g = np.asarray(case.get("gravity", [0.0, 0.0]), dtype=float)
    for m in case.get("masses", []):
        push(m["link"], solved_point(case, values, m["link"], m["com"]), m["mass"] * g)
    for sp in case.get("springs", []):
        s = values[f"S_{sp['name']}"]
        if "ends" in sp:
            (l0, w0), (l1, w1) = sp["ends"]
            p0, p1 = solved_point(case, values, l0, w0), solved_point(case, values, l1, w1)
            e = (p1 - p0) / np.linalg.norm(p1 - p0)
            push(l0, p0, s * e)
            push(l1, p1, -s * e)
        else:
            a, b = joints[sp["joint"]]["links"]
            push(b, np.zeros(2), np.zeros(2), -s)
            push(a, np.zeros(2), np.zeros(2), s)
    return sums


def force_scale(values: dict[str, float]) -> float:
    """The largest reported force or moment: the scale of a free-body residual."""
    return max(abs(v) for k, v in values.items() if k[:2] in ("F_", "M_", "Q_", "S_"))


def make_static(case: dict[str, Any]) -> dict[str, Any]:
    for d in case.get("drivers", []):
        d.pop("velocity", None)
        d.pop("acceleration", None)
    return case


def with_drivers(case: dict[str, Any], shift: dict[str, float]) -> dict[str, Any]:
    """The case with each named driver's rotation/displacement moved by ``shift`` (file units)."""
    c = copy.deepcopy(case)
    for d in c["drivers"]:
        key = "rotation" if "rotation" in d else "displacement"
        d[key] += shift.get(d["joint"], 0.0)
    return c


def solved(case: dict[str, Any]) -> dict[str, float]:
    result = ref.solve(case)
    assert result.status == "ok", (case["name"], result.status, result.message)
    return result.values


def applied_power_terms(case: dict[str, Any], values: dict[str, float],
                        rate: Any) -> tuple[float, float]:
    """(power of loads, weights and springs; largest single term) for the velocities
    ``rate(key)`` of reported positions (x_, y_, phi_, q_) and spring values S_."""

    def velocity(link: str, where: Any) -> np.ndarray:
        """v of a point fixed to a link, from the rates of its carrier point and angle."""
        if link == "ground":
            return np.zeros(2)
        carrier = next(lk for lk in case["links"] if lk["name"] == link)["points"][0]
        p = solved_point(case, values, link, where)
        base = np.array([values[f"x_{carrier}"], values[f"y_{carrier}"]])
        w = rate(f"phi_{link}")
        r = p - base
        return np.array([rate(f"x_{carrier}") - w * r[1], rate(f"y_{carrier}") + w * r[0]])

    terms = []
    for ld in case.get("loads", []):
        terms.append(float(force_of(ld) @ velocity(ld["link"], ld.get("at", [0.0, 0.0]))))
        if ld["link"] != "ground":
            terms.append(ld.get("torque", 0.0) * rate(f"phi_{ld['link']}"))
    g = np.asarray(case.get("gravity", [0.0, 0.0]), dtype=float)
    for m in case.get("masses", []):
        terms.append(float(m["mass"] * g @ velocity(m["link"], m["com"])))
    for sp in case.get("springs", []):
        s = values[f"S_{sp['name']}"]
        if "ends" in sp:
            (l0, w0), (l1, w1) = sp["ends"]
            p0, p1 = solved_point(case, values, l0, w0), solved_point(case, values, l1, w1)
            e = (p1 - p0) / np.linalg.norm(p1 - p0)
            terms.append(-s * float(e @ (velocity(l1, w1) - velocity(l0, w0))))
        else:
            terms.append(-s * rate(f"q_{sp['joint']}"))
    return sum(terms), max((abs(t) for t in terms), default=0.0)


# -- SEEDS.md E1 ------------------------------------------------------------------------
E1_PRINTED = (("B0", 37.74, -43.52), ("B", 89.77, 42.10), ("A", 139.46, 44.93))  # G14, F34, F23


def test_e1_loads_as_stated() -> None:
    """With the loads at 50° and 20° (force by the outside on the link), E1 needs
    Q_A0 = T12 = +2.90133 N·m CCW and every reaction is 180° from the printed direction."""
    v = solved(load("seed_e1_fourbar", "e1-linkage"))
    assert v["Q_A0"] == pytest.approx(2.90133, abs=PRINTED_5DP)
    for joint, magnitude, direction in E1_PRINTED:
        mag, ang = polar(v, joint)
        assert mag == pytest.approx(magnitude, abs=PRINTED_2DP), joint
        assert abs(angle_diff_deg(ang, direction + 180.0)) <= PRINTED_2DP, joint


def test_e1_seed_sign_reading() -> None:
    """With the loads at 230° and 200° (the seed's sign) the printed reactions and the
    printed 2901.33 N·mm clockwise come out."""
    v = solved(load("seed_e1_fourbar", "e1-linkage-seed-sign"))
    assert v["Q_A0"] == pytest.approx(-2.90133, abs=PRINTED_5DP)
    for joint, magnitude, direction in E1_PRINTED:
        mag, ang = polar(v, joint)
        assert mag == pytest.approx(magnitude, abs=PRINTED_2DP), joint
        assert abs(angle_diff_deg(ang, direction)) <= PRINTED_2DP, joint


def test_e1_reached_by_driving_from_another_drawing() -> None:
    """E1 drawn at θ12 = 90° and driven −30° arrives at θ13 = 29.98°, θ14 = 96.40° (its
    drawn angles plus the reported rotations) and needs the same T12 = +2.90133 N·m."""
    case = load("seed_e1_fourbar", "e1-linkage-driven-from-90")
    v = solved(case)
    a, b, b0 = (drawn(case, p) for p in ("A", "B", "B0"))
    theta13_drawn = math.atan2(*(b - a)[::-1])
    theta14_drawn = math.atan2(*(b - b0)[::-1])
    assert math.degrees(theta13_drawn + v["phi_coupler"]) == pytest.approx(29.98, abs=PRINTED_2DP)
    assert math.degrees(theta14_drawn + v["phi_rocker"]) == pytest.approx(96.40, abs=PRINTED_2DP)
    assert v["Q_A0"] == pytest.approx(2.90133, abs=PRINTED_5DP)
    assert v["q_A0"] == pytest.approx(math.radians(-30.0), abs=1e-12)


def test_e1_change_point_is_singular() -> None:
    """E1 is a Grashof change-point linkage (80 + 140 = 100 + 120): driving the crank from
    60° through 180°, where all four pins fall on one line, passes a singular pose."""
    case = load("seed_e1_fourbar", "e1-linkage")
    case["drivers"][0]["rotation"] = 150.0
    result = ref.solve(case)
    assert result.status == "singular"
    # θ12 = 180° is rotation 120°; the drawn points' 1e-8 mm rounding splits the exact
    # crossing by a few thousandths of a degree.
    assert math.degrees(result.diagnostics["singular_at"]["A0"]) == pytest.approx(120.0, abs=0.01)


# -- SEEDS.md E2 ------------------------------------------------------------------------
def test_e2_frictionless() -> None:
    """Without friction the E2 pose needs T12 = −18.783 N·m, and the slider, loaded only
    along the slide, gets no moment from the guide."""
    v = solved(load("seed_e2_slider_crank", "e2-linkage-frictionless"))
    assert v["Q_A0"] == pytest.approx(-18.783, abs=PRINTED_3DP)
    assert v["x_B"] * 1000.0 == pytest.approx(897.76, abs=PRINTED_2DP)
    assert v["M_slide"] == pytest.approx(0.0, abs=1e-9)


def test_e2_friction_circle() -> None:
    """E2 (corrected) with μ = 0.1 everywhere and the crank turning clockwise needs
    T12 = −22.897 N·m, |F34| = 105.674 N and N = 25.504 N; the slide friction μ|N| opposes
    the slider's outward motion."""
    v = solved(load("seed_e2_slider_crank", "e2-linkage-friction"))
    assert v["Q_A0"] == pytest.approx(-22.897, abs=PRINTED_3DP)
    assert polar(v, "B")[0] == pytest.approx(105.674, abs=PRINTED_3DP)
    assert v["F_slide_y"] == pytest.approx(25.504, abs=PRINTED_3DP)
    assert v["F_slide_x"] == pytest.approx(-0.1 * abs(v["F_slide_y"]), rel=IDENTITY_RTOL)


# -- Seed 002 exam Q1 and Q2 ------------------------------------------------------------
def test_exam_q1_equilibrium() -> None:
    """Exam Q1: the free slider and hanging bar settle at tan φ = 2F/(mg) (φ = atan 0.68)
    with the spring carrying F = k·x, and the pose is stable."""
    force, mass, g, k = 10.0, 3.0, 9.81, 500.0
    result = ref.solve(load("exam_q1_slider_bar"))
    assert result.status == "ok"
    v = result.values
    assert v["phi_bar"] == pytest.approx(math.atan(2.0 * force / (mass * g)), abs=1e-10)
    assert math.degrees(v["phi_bar"]) == pytest.approx(34.2, abs=0.05)  # printed ≈ 34.2°
    assert v["q_slide"] == pytest.approx(force / k, abs=1e-12)
    assert v["S_spring"] == pytest.approx(force, abs=1e-9)
    assert result.diagnostics["dof"] == 2 and result.diagnostics["stable"] is True


@pytest.mark.parametrize(("x_mm", "speed", "accel"), [(40.0, 0.5, 3.0), (-25.0, -1.2, -7.0),
                                                     (10.0, 0.0, 0.0)],
                         ids=["seed-numbers", "leftward", "at-rest"])
def test_exam_q2_equation_of_motion(x_mm: float, speed: float, accel: float) -> None:
    """Exam Q2 without friction: the pushing force is F = m ẍ + (k1 + k2) x."""
    case = load("exam_q2_mass_springs", "exam-q2-frictionless")
    case["drivers"][0].update(displacement=x_mm, velocity=speed, acceleration=accel)
    v = solved(case)
    m, k1, k2 = 2.0, 300.0, 200.0
    assert v["Q_slide"] == pytest.approx(m * accel + (k1 + k2) * x_mm / 1000.0, abs=1e-10)


def test_exam_q2_with_friction() -> None:
    """Exam Q2 as printed: F = m ẍ + (k1 + k2) x + μ m g while the mass moves toward +x."""
    v = solved(load("exam_q2_mass_springs", "exam-q2-friction"))
    assert v["Q_slide"] == pytest.approx(2.0 * 3.0 + 500.0 * 0.040 + 0.1 * 2.0 * 9.81, abs=1e-10)


# -- hand calculations ----------------------------------------------------------------
def test_boom_moment_balance() -> None:
    """A massless cylinder is a two-force member: its push Q times its lever arm about the
    boom pivot balances the payload's and the boom weight's moments."""
    case = load("cylinder_boom", "boom-hold-drawn")
    e, p, t, g_point = (drawn(case, n) for n in ("E", "P", "T", "G"))
    u = (e - p) / np.linalg.norm(e - p)
    weights = cross(t, np.array([0.0, -1500.0])) + cross(g_point, np.array([0.0, -60.0 * 9.81]))
    v = solved(case)
    assert v["Q_cyl"] == pytest.approx(-weights / cross(e, u), rel=IDENTITY_RTOL)
    assert v["Q_cyl"] == pytest.approx(7252.42, abs=PRINTED_2DP)  # the file's comment
    assert v["M_cyl"] == pytest.approx(0.0, abs=1e-9)


def test_locking_at_the_limit_angle() -> None:
    """A non-Grashof four-bar (100, 80, 60, 70) driven 180° from θ12 = 30° locks where
    coupler and rocker stretch in line: cos θ12 = (a1² + a2² − (a3 + a4)²)/(2 a1 a2)."""
    a1, a2, a3, a4 = 100.0, 80.0, 60.0, 70.0
    limit = math.acos((a1**2 + a2**2 - (a3 + a4) ** 2) / (2.0 * a1 * a2))
    result = ref.solve(load("locking_fourbar"))
    assert result.status == "no_solution"
    assert result.diagnostics["lock"]["O2"] == pytest.approx(limit - math.radians(30.0), abs=1e-8)
    assert "locks at rotation 61.79" in result.message


def test_cylinder_locks_at_full_reach() -> None:
    """The boom's cylinder extended 800 mm stops where the boom points straight away from
    the barrel pivot: displacement |OP| + |OE| − |PE| (fully stretched triangle O, P, E)."""
    case = load("cylinder_boom", "boom-hold-drawn")
    case["drivers"][0]["displacement"] = 800.0
    o, p, e = (drawn(case, n) for n in ("O", "P", "E"))
    reach = np.linalg.norm(p - o) + np.linalg.norm(e - o) - np.linalg.norm(e - p)
    result = ref.solve(case)
    assert result.status == "no_solution"
    assert result.diagnostics["lock"]["cyl"] == pytest.approx(reach, abs=1e-10)


def test_pendulum_stiffness_and_stability() -> None:
    """A bar of mass m pinned at one end is in equilibrium hanging or standing; its
    stiffness about the pin is +m g l/2 hanging (stable) and −m g l/2 standing (unstable),
    and the pin carries its weight."""
    mass, length, g = 2.0, 0.5, 9.81

    def bar(tip_y: float) -> dict[str, Any]:
        return {"name": "pendulum", "mechanism": "linkage", "gravity": [0.0, -g],
                "points": {"O": [0.0, 0.0], "T": [0.0, tip_y], "G": [0.0, tip_y / 2.0]},
                "links": [{"name": "ground", "points": ["O"]},
                          {"name": "bar", "points": ["O", "T", "G"]}],
                "joints": [{"name": "O", "kind": "revolute", "links": ["ground", "bar"],
                            "at": "O"}],
                "masses": [{"link": "bar", "mass": mass, "com": "G"}]}

    hanging, standing = ref.solve(bar(-length)), ref.solve(bar(length))
    assert hanging.diagnostics["stable"] is True
    assert standing.diagnostics["stable"] is False
    # The eigenvalue's size depends on the basis of the free directions; its sign does not.
    assert hanging.diagnostics["reduced_stiffness_eigenvalues"][0] > 0.0
    assert standing.diagnostics["reduced_stiffness_eigenvalues"][0] < 0.0
    assert hanging.values["F_O_y"] == pytest.approx(mass * g, rel=1e-12)


def test_redundant_parallelogram_is_indeterminate() -> None:
    """Three equal parallel cranks under one coupler: Gruebler says 0, the rank says 1 DOF;
    the reactions are not unique, but the coupler still translates without turning."""
    case = {"name": "triple-parallelogram", "mechanism": "linkage", "length_unit": "mm",
            "points": {"O1": [0.0, 0.0], "O2": [100.0, 0.0], "O3": [200.0, 0.0],
                       "A1": [30.0, 80.0], "A2": [130.0, 80.0], "A3": [230.0, 80.0]},
            "links": [{"name": "ground", "points": ["O1", "O2", "O3"]},
                      {"name": "c1", "points": ["O1", "A1"]},
                      {"name": "c2", "points": ["O2", "A2"]},
                      {"name": "c3", "points": ["O3", "A3"]},
                      {"name": "coupler", "points": ["A1", "A2", "A3"]}],
            "joints": [{"name": n, "kind": "revolute", "links": list(pair), "at": n}
                       for n, pair in (("O1", ("ground", "c1")), ("O2", ("ground", "c2")),
                                       ("O3", ("ground", "c3")), ("A1", ("c1", "coupler")),
                                       ("A2", ("c2", "coupler")), ("A3", ("c3", "coupler")))],
            "drivers": [{"joint": "O1", "rotation": 25.0}]}
    result = ref.solve(case)
    assert result.status == "indeterminate"
    assert result.diagnostics["gruebler"] == 0 and result.diagnostics["dof"] == 1
    assert result.diagnostics["redundant_joints"]
    assert result.values["phi_coupler"] == pytest.approx(0.0, abs=1e-12)
    assert not any(k.startswith("F_") for k in result.values)


def test_coulomb_reversal_is_indeterminate() -> None:
    """With crank and coupler in line the rocker of E1 stands still: friction at its pivot
    B0 has no sense, so the forces are indeterminate."""
    a1, a2, a3, a4 = 140.0, 80.0, 100.0, 120.0
    # B at distance a2 + a3 from A0 and a4 from B0 (upper intersection), A on A0B.
    x = ((a2 + a3) ** 2 - a4**2 + a1**2) / (2.0 * a1)
    b = np.array([x, math.sqrt((a2 + a3) ** 2 - x**2)])
    a = b * a2 / (a2 + a3)
    case = load("seed_e1_fourbar", "e1-linkage")
    case["points"].update(A=list(a), B=list(b))
    case["points"].pop("C")
    case["links"][2]["points"] = ["A", "B"]
    case["loads"] = [{"link": "rocker", "at": "D", "force": {"magnitude": 100.0, "angle": 20.0}}]
    case["drivers"][0]["sense"] = "increasing"
    case["friction"] = {"mu": 0.1, "pin_radius": {"B0": 5.0}}
    assert ref.solve(case).status == "indeterminate"
    case["friction"] = {"mu": 0.1, "pin_radius": {"A0": 5.0}}  # the crank does turn
    assert ref.solve(case).status == "ok"


# -- identities -----------------------------------------------------------------------
STATIC_CASES = [("watt_ii_sixbar", None), ("five_bar_two_drivers", None),
                ("crank_shaper", None), ("cylinder_boom", "boom-raise"),
                ("bonnet_counterbalanced", "bonnet-hold"), ("stephenson_iii_sixbar", None),
                ("exam_q1_slider_bar", None), ("bonnet_counterbalanced", "bonnet-free")]


@pytest.mark.parametrize(("file", "name"), STATIC_CASES,
                         ids=[f"{f}:{n}" if n else f for f, n in STATIC_CASES])
def test_free_body_equilibrium(file: str, name: str | None) -> None:
    """In a static case every link is in equilibrium (ΣF = 0, ΣM = 0) under the reported
    reactions, driver efforts and spring forces and the case's loads and weights."""
    case = make_static(load(file, name))
    v = solved(case)
    scale = force_scale(v)
    for link, sums in free_body_sums(case, v).items():
        assert np.max(np.abs(sums)) <= IDENTITY_RTOL * scale, (link, sums)


VIRTUAL_WORK_CASES = [("five_bar_two_drivers", None), ("watt_ii_sixbar", None),
                      ("crank_shaper", None), ("cylinder_boom", "boom-raise"),
                      ("bonnet_counterbalanced", "bonnet-hold")]


@pytest.mark.parametrize(("file", "name"), VIRTUAL_WORK_CASES,
                         ids=[f"{f}:{n}" if n else f for f, n in VIRTUAL_WORK_CASES])
def test_virtual_work(file: str, name: str | None) -> None:
    """Static case: for a virtual motion of each driver alone, Σ Q·q̇ + Σ loads·v +
    weights·v − springs' S·L̇ = 0, with the velocities by central differences of the
    reference's positions."""
    case = make_static(load(file, name))
    v = solved(case)
    unit = unit_of(case)
    for d in case["drivers"]:
        revolute = "rotation" in d
        h = 1e-3  # degrees or file length units
        plus = solved(with_drivers(case, {d["joint"]: h}))
        minus = solved(with_drivers(case, {d["joint"]: -h}))
        step = 2.0 * (math.radians(h) if revolute else h * unit)  # per unit driver rate

        def rate(key: str, plus: dict[str, float] = plus, minus: dict[str, float] = minus,
                 step: float = step) -> float:
            diff = plus[key] - minus[key]
            if key.startswith(("phi_", "q_")) and abs(diff) > math.pi:
                diff = angle_diff_deg(math.degrees(plus[key]), math.degrees(minus[key]))
                diff = math.radians(diff)
            return diff / step

        power, largest = applied_power_terms(case, v, rate)
        driver_power = v[f"Q_{d['joint']}"] * 1.0
        assert driver_power + power == pytest.approx(0.0, abs=FIRST_DIFF_RTOL * max(
            largest, abs(driver_power))), d["joint"]


DYNAMIC_CASES = [("crank_shaper", None), ("cylinder_boom", "boom-raise"),
                 ("stephenson_iii_sixbar", None), ("five_bar_two_drivers", None)]


@pytest.mark.parametrize(("file", "name"), DYNAMIC_CASES,
                         ids=[f"{f}:{n}" if n else f for f, n in DYNAMIC_CASES])
def test_power_balance_in_motion(file: str, name: str | None) -> None:
    """In motion, the drives' power plus the loads', weights' and springs' power equals the
    rate of kinetic energy Σ m a_G·v_G + I_G α ω, with every velocity and acceleration
    taken by five-point time differences of the reference's positions along the drivers'
    prescribed motions."""
    case = load(file, name)
    v = solved(case)
    tau = 1e-3
    samples = []
    for k in (-2, -1, 1, 2):
        shift = {}
        for d in case["drivers"]:
            t = k * tau
            change = d.get("velocity", 0.0) * t + 0.5 * d.get("acceleration", 0.0) * t * t
            shift[d["joint"]] = math.degrees(change) if "rotation" in d else change / unit_of(case)
        samples.append(solved(with_drivers(case, shift)))
    m2, m1, p1, p2 = samples

    def unwrap(key: str, value: float) -> float:
        if key.startswith(("phi_", "q_")):
            return v[key] + math.radians(angle_diff_deg(math.degrees(value), math.degrees(v[key])))
        return value

    def rate(key: str) -> float:
        f = [unwrap(key, s[key]) for s in (m2, m1, p1, p2)]
        return (f[0] - 8.0 * f[1] + 8.0 * f[2] - f[3]) / (12.0 * tau)

    def second(key: str) -> float:
        f = [unwrap(key, s[key]) for s in (m2, m1, p1, p2)]
        return (-f[0] + 16.0 * f[1] - 30.0 * v[key] + 16.0 * f[2] - f[3]) / (12.0 * tau**2)

    power, largest = applied_power_terms(case, v, rate)
    drives = sum(v[f"Q_{d['joint']}"] * d.get("velocity", 0.0) for d in case["drivers"])
    kinetic = 0.0
    for m in case.get("masses", []):
        link = m["link"]
        carrier = next(lk for lk in case["links"] if lk["name"] == link)["points"][0]
        r = solved_point(case, v, link, m["com"]) - np.array([v[f"x_{carrier}"], v[f"y_{carrier}"]])
        w, alpha = rate(f"phi_{link}"), second(f"phi_{link}")
        vel = np.array([rate(f"x_{carrier}"), rate(f"y_{carrier}")]) + w * np.array([-r[1], r[0]])
        acc = (np.array([second(f"x_{carrier}"), second(f"y_{carrier}")])
               + alpha * np.array([-r[1], r[0]]) - w * w * r)
        kinetic += m["mass"] * float(acc @ vel) + m.get("inertia", 0.0) * alpha * w
    scale = max(largest, abs(drives), abs(kinetic))
    assert drives + power == pytest.approx(kinetic, abs=POWER_RTOL * scale)


def rotate_case(case: dict[str, Any], degrees: float) -> dict[str, Any]:
    """The same case drawn turned by ``degrees`` about the origin: points, axes, [x, y]
    attachments, load directions and gravity."""
    c = copy.deepcopy(case)
    turn = rotation(math.radians(degrees))

    def turned(xy: Any) -> list[float]:
        return [float(x) for x in turn @ np.asarray(xy, dtype=float)]

    c["points"] = {k: turned(xy) for k, xy in c["points"].items()}
    for j in c["joints"]:
        if "axis" in j:
            j["axis"] = turned(j["axis"])
    for ld in c.get("loads", []):
        if not isinstance(ld.get("at", "name"), str):
            ld["at"] = turned(ld["at"])
        if "force" in ld:
            f = ld["force"]
            if "angle" in f:
                f["angle"] += degrees
            else:
                f["x"], f["y"] = turned([f["x"], f["y"]])
    for m in c.get("masses", []):
        if not isinstance(m["com"], str):
            m["com"] = turned(m["com"])
    for sp in c.get("springs", []):
        for end in sp.get("ends", []):
            if not isinstance(end[1], str):
                end[1] = turned(end[1])
    if "gravity" in c:
        c["gravity"] = turned(c["gravity"])
    return c


@pytest.mark.parametrize("file", ["five_bar_two_drivers", "crank_shaper", "exam_q1_slider_bar"])
def test_rotating_the_drawing_rotates_the_answer(file: str) -> None:
    """Turning the whole drawing (with its loads and gravity) by 37° turns every reaction
    and point by 37° and leaves efforts, moments, spring forces and rotations unchanged."""
    case = load(file)
    v = solved(case)
    w = solved(rotate_case(case, 37.0))
    turn = rotation(math.radians(37.0))
    scale = force_scale(v)
    for key, value in v.items():
        if key.startswith("F_") and key.endswith("_x"):
            pair, tol = (key, key[:-2] + "_y"), IDENTITY_RTOL * scale
        elif key.startswith("x_"):
            pair, tol = (key, "y_" + key[2:]), 1e-12
        elif key.startswith(("M_", "Q_", "S_")):
            assert w[key] == pytest.approx(value, abs=IDENTITY_RTOL * scale), key
            continue
        elif key.startswith(("phi_", "q_")):
            assert w[key] == pytest.approx(value, abs=1e-9), key
            continue
        else:
            continue
        expected = turn @ np.array([v[pair[0]], v[pair[1]]])
        assert w[pair[0]] == pytest.approx(expected[0], abs=tol), pair[0]
        assert w[pair[1]] == pytest.approx(expected[1], abs=tol), pair[1]


def test_full_turns_follow_the_linkage() -> None:
    """Driving the Stephenson III crank 900° lands where 180° does: the crank-rocker six-bar
    turns fully and comes back to the same pose every turn."""
    case = make_static(load("stephenson_iii_sixbar"))
    case["drivers"][0]["rotation"] = 900.0
    long_way = solved(case)
    case["drivers"][0]["rotation"] = 180.0
    short_way = solved(case)
    for key in ("phi_output", "phi_coupler", "x_F", "y_F", "Q_O2"):
        assert long_way[key] == pytest.approx(short_way[key], abs=1e-9), key


def test_free_equilibrium_is_where_the_holding_torque_vanishes() -> None:
    """The bonnet released from its drawn pose settles where the torque needed to hold it
    is zero, and it is stable because that torque rises with the hinge angle there."""
    free = ref.solve(load("bonnet_counterbalanced", "bonnet-free"))
    assert free.status == "ok" and free.diagnostics["stable"] is True
    angle = math.degrees(free.values["q_G1"])
    hold = load("bonnet_counterbalanced", "bonnet-hold")
    at = solved(with_drivers(hold, {"G1": angle + 20.0}))  # the file drives −20°
    assert at["Q_G1"] == pytest.approx(0.0, abs=1e-8)
    above = solved(with_drivers(hold, {"G1": angle + 20.0 + 0.5}))["Q_G1"]
    below = solved(with_drivers(hold, {"G1": angle + 20.0 - 0.5}))["Q_G1"]
    assert above > 0.0 > below
    for key in ("phi_bonnet", "S_strut", "S_hinge", "F_G1_x", "F_H2_y"):
        assert at[key] == pytest.approx(free.values[key], abs=1e-8 * force_scale(at)), key


# -- the contract's refusals ----------------------------------------------------------
def test_refusals() -> None:
    """More drivers than degrees of freedom, free coordinates in motion, and Coulomb
    friction with a resting driver and no sense are refused."""
    five_bar = load("five_bar_two_drivers")
    extra = copy.deepcopy(five_bar)
    extra["drivers"].append({"joint": "C", "rotation": 1.0})
    with pytest.raises(ref.LinkageInputError, match="drivers"):
        ref.solve(extra)
    one_driver = copy.deepcopy(five_bar)
    one_driver["drivers"].pop()
    with pytest.raises(ref.LinkageInputError, match="free coordinates with motion"):
        ref.solve(one_driver)
    resting = load("seed_e2_slider_crank", "e2-linkage-friction")
    del resting["drivers"][0]["sense"]
    with pytest.raises(ref.LinkageInputError, match="sense"):
        ref.solve(resting)
