"""The seed 001 catalogue rows with gear contacts and the statically indeterminate one
(compare/cases/catalogue/gear_pair.toml, mixed.toml, over_constrained.toml), each file's
analytic solution against a derivation written here: the gear pair by the gears' moment
balances, the mixed mechanism by the power balance with the rates of a velocity analysis
by hand (the gear ratios and two slider-cranks), the over-constrained structure by the
displacement method (the free nodes' stiffness matrix, K u = P, each bar's force
(E·A/L)·e·Δu), its supports balancing the loads."""

from __future__ import annotations

import math
import tomllib
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import mechcheck
from mechcheck.analytic.case import Case
from mechcheck.tolerance import rule

CATALOGUE = Path(__file__).resolve().parents[1] / "compare" / "cases" / "catalogue"
#: The analytic engine meets an independent derivation within the policy's tolerance.
RTOL = rule("analytic", "force", "static").rtol
G = 9.81
K = np.array([0.0, 0.0, 1.0])


def table_of(stem: str) -> dict[str, Any]:
    (table,) = tomllib.loads((CATALOGUE / f"{stem}.toml").read_text(encoding="utf-8"))["case"]
    return dict(table)


def values_of(stem: str) -> dict[str, float]:
    (case,) = mechcheck.load_cases(CATALOGUE / f"{stem}.toml")
    assert isinstance(case, Case)
    solution = mechcheck.solve(case)
    assert solution.status == "ok", solution.message
    return {q: float(v) for q, v in solution.values.items()}


def metres(table: dict[str, Any]) -> dict[str, np.ndarray]:
    """The file's points in metres (its drawings are in mm)."""
    assert table["length_unit"] == "mm"
    return {name: 1e-3 * np.array(xy, dtype=float) for name, xy in table["points"].items()}


def turned(omega: float, r: np.ndarray) -> np.ndarray:
    """ω k × r: the velocity of a point at r from a centre turning at ω."""
    return omega * np.array([-r[1], r[0]])


def cross(r: np.ndarray, f: np.ndarray) -> float:
    return float(r[0] * f[1] - r[1] * f[0])


# -- the gear pair: the gears' moment balances -----------------------------------------------
GEAR_POINTS = {"Pa": [0.0, 0.0], "Pb": [160.0, 120.0], "H": [260.0, 120.0]}
RA, RB = 0.05, 0.15
ROPE = np.array([0.0, -1500.0])
GEAR_MASSES = {"pinion": 1.5, "wheel": 14.0}


def test_the_gear_pair_file_is_the_drawing_of_the_hand_calculation() -> None:
    table = table_of("gear_pair")
    assert table["points"] == GEAR_POINTS
    (mesh,) = [j for j in table["joints"] if j["kind"] == "gear"]
    assert (mesh["links"], mesh["centres"], mesh["pitch_radii"], mesh["pressure_angle"]) == \
        (["pinion", "wheel"], ["Pa", "Pb"], [50.0, 150.0], 20.0)
    assert {m["link"]: (m["mass"], m["com"]) for m in table["masses"]} == \
        {"pinion": (1.5, "Pa"), "wheel": (14.0, "Pb")}
    (load,) = table["loads"]
    assert (load["link"], load["at"], load["force"]) == ("wheel", "H", {"x": 0.0, "y": -1500.0})
    assert [d["joint"] for d in table["drivers"]] == ["Pa"]


def test_the_gear_pair_has_the_hand_solution() -> None:
    """e = (Pb − Pa)/200 mm = (0.8, 0.6), t = e turned +90° = (−0.6, 0.8); the pitch point
    P = Pa + ra·e = Pb − rb·e. The wheel about Pb (its weight on the bearing has no moment):
    the rope's moment M = (H − Pb) × F = 0.1·(−1500) = −150 N·m and the tooth force's
    tangential part at lever −rb·e, −rb·F_t + M = 0: F_t = M/rb = −1000 N. The pinion about
    Pa: Q − ra·F_t = 0, Q = −50 N·m. The radial part tan 20°·|F_t| pushes the wheel along
    +e. The bearings: the wheel's F_Pb = −(F + rope + W_wheel), the pinion's
    F_Pa = F − W_pinion, with F = F_t·t + F_r·e the tooth force on the wheel."""
    p = {k: 1e-3 * np.array(v) for k, v in GEAR_POINTS.items()}
    e = (p["Pb"] - p["Pa"]) / np.hypot(*(p["Pb"] - p["Pa"]))
    t = np.array([-e[1], e[0]])
    f_t = cross(p["H"] - p["Pb"], ROPE) / RB
    f_r = math.tan(math.radians(20.0)) * abs(f_t)
    tooth = f_t * t + f_r * e
    w_pinion, w_wheel = (np.array([0.0, -G * GEAR_MASSES[k]]) for k in ("pinion", "wheel"))
    expected = {"F_mesh_t": f_t, "F_mesh_r": f_r, "F_mesh_x": tooth[0], "F_mesh_y": tooth[1],
                "Q_Pa": RA * f_t}
    bearing_b, bearing_a = -(tooth + ROPE + w_wheel), tooth - w_pinion
    expected |= {"F_Pb_x": bearing_b[0], "F_Pb_y": bearing_b[1],
                 "F_Pa_x": bearing_a[0], "F_Pa_y": bearing_a[1]}
    assert (f_t, RA * f_t) == pytest.approx((-1000.0, -50.0), rel=1e-12)
    got = values_of("gear_pair")
    scale = abs(f_t)
    for q, want in expected.items():
        assert abs(got[q] - want) <= RTOL * scale, (q, got[q], want)


# -- the mixed mechanism: the power balance ---------------------------------------------------
#: The drawing (mm), pitch radii (m), masses (kg) and loads (N) as written in mixed.toml.
MIXED_POINTS = {"O2": [-160.0, 0.0], "O3": [0.0, 0.0], "O6": [120.0, 160.0],
                "O7": [300.0, 300.0], "A": [48.0, -64.0], "B": [0.0, -300.0],
                "T": [0.0, -400.0], "C": [160.0, 190.0], "D": [500.0, 150.0],
                "E7": [620.0, 60.0]}
R2, R3, R6 = 0.04, 0.12, 0.08
RAM_AXIS, ARM_AXIS = np.array([0.0, 1.0]), np.array([0.8, -0.6])
MIXED_MASSES = {"pinion": (0.8, "O2"), "gear3": (6.0, "O3"), "rod4": (1.5, [24.0, -182.0]),
                "ram": (10.0, [0.0, -350.0]), "gear6": (2.5, "O6"),
                "arm7": (3.0, [460.0, 180.0]), "rod8": (1.2, [330.0, 170.0]),
                "slider9": (0.6, "D")}
MIXED_LOADS = {("ram", "T"): np.array([0.0, 3000.0]), ("slider9", "D"): np.array([-320.0, 240.0])}


def test_the_mixed_file_is_the_drawing_of_the_velocity_analysis() -> None:
    table = table_of("mixed")
    assert table["points"] == MIXED_POINTS
    meshes = {j["name"]: (j["links"], j["centres"], j["pitch_radii"])
              for j in table["joints"] if j["kind"] == "gear"}
    assert meshes == {"mesh23": (["pinion", "gear3"], ["O2", "O3"], [40.0, 120.0]),
                      "mesh36": (["gear3", "gear6"], ["O3", "O6"], [120.0, 80.0])}
    slides = {j["name"]: (j["links"], j["at"], j["axis"])
              for j in table["joints"] if j["kind"] == "prismatic"}
    assert slides == {"ram_guide": (["ground", "ram"], "B", [0.0, 1.0]),
                      "slide9": (["arm7", "slider9"], "D", [4.0, -3.0])}
    assert {m["link"]: (m["mass"], m["com"]) for m in table["masses"]} == MIXED_MASSES
    loads = {(ld["link"], ld["at"]): [ld["force"]["x"], ld["force"]["y"]] for ld in table["loads"]}
    assert loads == {k: list(v) for k, v in MIXED_LOADS.items()}
    assert [d["joint"] for d in table["drivers"]] == ["O2", "O7"]


def slide_and_rod(axis: np.ndarray, v_guide: np.ndarray, v_crank: np.ndarray,
                  rod: np.ndarray) -> tuple[float, float]:
    """The slide rate s and the rod's ω where a rod from a crank pin (velocity v_crank) ends
    on a block sliding along ``axis`` on a guide whose point there moves at v_guide:
    v_guide + s·axis = v_crank + ω k × rod, two equations for (s, ω)."""
    matrix = np.column_stack([axis, -turned(1.0, rod)])
    s, omega = np.linalg.solve(matrix, v_crank - v_guide)
    return float(s), float(omega)


def motor_velocities(p: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Every mass centre's and load point's velocity with the pinion at ω2 = 1 rad/s and the
    arm held: ω3 = −ω2·r2/r3 and ω6 = −ω3·r3/r6 (external meshes on fixed centres), then each
    crank pin drives its rod and block."""
    w3 = -R2 / R3
    w6 = -w3 * R3 / R6
    v_a = turned(w3, p["A"] - p["O3"])
    s5, w4 = slide_and_rod(RAM_AXIS, np.zeros(2), v_a, p["B"] - p["A"])
    v_c = turned(w6, p["C"] - p["O6"])
    s9, w8 = slide_and_rod(ARM_AXIS, np.zeros(2), v_c, p["D"] - p["C"])
    return {"rod4": v_a + turned(w4, p["rod4"] - p["A"]), "ram": s5 * RAM_AXIS,
            "rod8": v_c + turned(w8, p["rod8"] - p["C"]), "slider9": s9 * ARM_AXIS,
            "T": s5 * RAM_AXIS, "D": s9 * ARM_AXIS}


def arm_velocities(p: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The same with the arm at ω7 = 1 rad/s and the pinion held: the gears, rod 4 and the
    ram stand still; slider 9 turns with the arm and slides along it, where rod 8 turns
    about the resting pin C."""
    v_guide = turned(1.0, p["D"] - p["O7"])
    s9, w8 = slide_and_rod(ARM_AXIS, v_guide, np.zeros(2), p["D"] - p["C"])
    v_d = v_guide + s9 * ARM_AXIS
    return {"arm7": turned(1.0, p["arm7"] - p["O7"]), "rod8": turned(w8, p["rod8"] - p["C"]),
            "slider9": v_d, "D": v_d}


def power(velocities: dict[str, np.ndarray]) -> float:
    """The power of the loads and the weights (W) at these velocities; a mass centre or load
    point not named stands still."""
    total = 0.0
    for link, (mass, _) in MIXED_MASSES.items():
        total += float(np.array([0.0, -G * mass]) @ velocities.get(link, np.zeros(2)))
    for (_, at), force in MIXED_LOADS.items():
        total += float(force @ velocities.get(at, np.zeros(2)))
    return total


def mixed_points() -> dict[str, np.ndarray]:
    p = {k: 1e-3 * np.array(v) for k, v in MIXED_POINTS.items()}
    for link, (_, com) in MIXED_MASSES.items():
        p[link] = p[com] if isinstance(com, str) else 1e-3 * np.array(com)
    return p


def test_the_mixed_mechanism_balances_power_with_a_hand_velocity_analysis() -> None:
    """Ideal joints and meshes do no work, so for each driver moved alone at unit rate (the
    other held) its effort plus the power of the loads and weights is zero:
    Q_O2·1 + P_motor = 0 and Q_O7·1 + P_arm = 0, with the rates from the velocity analysis
    above, not from the engine."""
    p = mixed_points()
    got = values_of("mixed")
    for driver, velocities in (("Q_O2", motor_velocities(p)), ("Q_O7", arm_velocities(p))):
        p_loads = power(velocities)
        assert abs(p_loads) > 1.0, "the loads work under this motion: the check can fail"
        assert abs(got[driver] + p_loads) <= RTOL * abs(p_loads), (driver, got[driver], p_loads)


def test_the_mixed_mechanism_gear_six_turns_by_the_ratio() -> None:
    """The gear ratio the velocity analysis uses, seen in the engine's pose: the pinion driven
    30° from the drawing (the arm held) turns gear 3 by −30°·r2/r3 and gear 6 by
    +30°·r2/r6."""
    (case,) = mechcheck.load_cases(CATALOGUE / "mixed.toml")
    assert isinstance(case, Case)
    motor, arm = case.linkage.drivers
    linkage = replace(case.linkage, drivers=(replace(motor, value=math.radians(30.0)), arm))
    got = mechcheck.solve(replace(case, geometry=linkage)).values
    assert got["phi_gear3"] == pytest.approx(math.radians(-30.0 * R2 / R3), rel=1e-12)
    assert got["phi_gear6"] == pytest.approx(math.radians(30.0 * R2 / R6), rel=1e-12)


# -- the over-constrained structure: the displacement method ----------------------------------
#: Bars (from the wall point or first node to the second node), their cross-sections (mm²)
#: and masses (kg), and the load (N), as written in over_constrained.toml.
BARS = {"bar_ad": ("A", "D", 800.0, 9.7492), "bar_bd": ("B", "D", 500.0, 6.6725),
        "bar_de": ("D", "E", 400.0, 4.396), "bar_be": ("B", "E", 600.0, 7.6092),
        "bar_ce": ("C", "E", 700.0, 8.8774)}
E_STEEL = 210e9
FREE = ("D", "E")
HOIST = np.array([0.0, -10000.0])
WALL_JOINTS = {"A_g_ad": "bar_ad", "B_g_bd": "bar_bd", "B_g_be": "bar_be", "C_g_ce": "bar_ce"}


def test_the_over_constrained_file_is_the_drawing_of_the_displacement_method() -> None:
    table = table_of("over_constrained")
    links = {lk["name"]: lk for lk in table["links"]}
    for name, (i, j, area, _) in BARS.items():
        assert links[name]["points"] == [i, j]
        assert links[name]["axial_stiffness"] == pytest.approx(E_STEEL * area * 1e-6, rel=1e-15)
    assert {m["link"]: m["mass"] for m in table["masses"]} == {k: v[3] for k, v in BARS.items()}
    for m in table["masses"]:   # each bar's weight at its middle
        ends = (table["points"][end] for end in BARS[m["link"]][:2])
        assert m["com"] == [0.5 * (a + b) for a, b in zip(*ends, strict=True)]
    (load,) = table["loads"]
    assert (load["at"], load["force"]) == ("D", {"x": 0.0, "y": -10000.0})
    assert "drivers" not in table
    wall = [(j["name"], j["links"][1]) for j in table["joints"] if j["links"][0] == "ground"]
    assert dict(wall) == WALL_JOINTS


def unit_and_stiffness(p: dict[str, np.ndarray], bar: str) -> tuple[np.ndarray, float]:
    """A bar's unit vector from its first end to its second and its axial stiffness E·A/L."""
    i, j, area, _ = BARS[bar]
    length = float(np.hypot(*(p[j] - p[i])))
    return (p[j] - p[i]) / length, E_STEEL * area * 1e-6 / length


def free_node_system(p: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """K and P of the free nodes D, E (x, y each): each bar adds (E·A/L)·e eᵀ on the diagonal
    blocks of its free ends and −(E·A/L)·e eᵀ between them (a wall end does not move); P
    holds the hoist and half of each bar's weight at each free end (a pinned bar's weight at
    its middle)."""
    index = {node: 2 * k for k, node in enumerate(FREE)}
    stiffness, loads = np.zeros((4, 4)), np.zeros(4)
    loads[index["D"]:index["D"] + 2] += HOIST
    for bar, (i, j, _, mass) in BARS.items():
        e, k = unit_and_stiffness(p, bar)
        ends = [index[n] for n in (i, j) if n in index]
        for a in ends:
            loads[a:a + 2] += [0.0, -0.5 * G * mass]
            for b in ends:
                stiffness[a:a + 2, b:b + 2] += (1.0 if a == b else -1.0) * k * np.outer(e, e)
    return stiffness, loads


def displacement_method(p: dict[str, np.ndarray]) -> dict[str, float]:
    """The seed's method: the free nodes' displacements u from K u = P, then each bar's
    tension (E·A/L)·e·(u_j − u_i)."""
    u = np.linalg.solve(*free_node_system(p))
    moved = {node: u[2 * k:2 * k + 2] for k, node in enumerate(FREE)}
    out = {}
    for bar, (i, j, _, _) in BARS.items():
        e, k = unit_and_stiffness(p, bar)
        out[bar] = k * float(e @ (moved.get(j, np.zeros(2)) - moved.get(i, np.zeros(2))))
    return out


def test_the_over_constrained_bars_carry_the_displacement_methods_forces() -> None:
    """Every bar's N_<bar> is the displacement method's; the wall's reaction on each bar is
    its axial pull back from the wall, −N·e, plus half its weight held up, −W/2."""
    p = metres(table_of("over_constrained"))
    expected = displacement_method(p)
    got = values_of("over_constrained")
    scale = abs(HOIST[1])
    for name, tension in expected.items():
        assert abs(got[f"N_{name}"] - tension) <= RTOL * scale, (name, got[f"N_{name}"], tension)
    assert min(expected.values()) < -1000.0 and max(expected.values()) > 1000.0, \
        "struts push and ties pull"
    for joint, bar in WALL_JOINTS.items():
        i, j, _, mass = BARS[bar]
        e = (p[j] - p[i]) / np.hypot(*(p[j] - p[i]))
        want = -expected[bar] * e - 0.5 * np.array([0.0, -G * mass])
        reaction = np.array([got[f"F_{joint}_x"], got[f"F_{joint}_y"]])
        assert np.all(np.abs(reaction - want) <= RTOL * scale), (joint, reaction, want)


def test_the_over_constrained_supports_balance_the_loads() -> None:
    """The wall's reactions balance the hoist and every bar's weight, forces and moments
    about A, to 1e-12 of the total load."""
    table = table_of("over_constrained")
    p = metres(table)
    got = values_of("over_constrained")
    forces = [(p[table_joint_at(table, joint)], np.array([got[f"F_{joint}_x"], got[f"F_{joint}_y"]]))
              for joint in WALL_JOINTS]
    forces.append((p["D"], HOIST))
    forces += [(1e-3 * np.array(m["com"]), np.array([0.0, -G * m["mass"]])) for m in table["masses"]]
    total = abs(HOIST[1]) + G * sum(m["mass"] for m in table["masses"])
    net = sum(f for _, f in forces)
    moment = sum(cross(r, f) for r, f in forces)
    assert np.all(np.abs(net) <= 1e-12 * total), net
    assert abs(moment) <= 1e-12 * total * 2.4, moment   # 2.4 m: the bracket's height


def table_joint_at(table: dict[str, Any], name: str) -> str:
    (joint,) = [j for j in table["joints"] if j["name"] == name]
    return str(joint["at"])


def test_the_over_constrained_stretches_are_small() -> None:
    """The statics is that of the drawing: the largest strain |N|/(E·A) is the diagnostic,
    and small (below 1e-4)."""
    (case,) = mechcheck.load_cases(CATALOGUE / "over_constrained.toml")
    solution = mechcheck.solve(case)
    expected = displacement_method(metres(table_of("over_constrained")))
    strain = max(abs(n) / (E_STEEL * BARS[b][2] * 1e-6) for b, n in expected.items())
    assert solution.diagnostics["max_strain"] == pytest.approx(strain, rel=RTOL)
    assert strain < 1e-4


# -- every backend --------------------------------------------------------------------------
@pytest.mark.parametrize("stem", ["gear_pair", "mixed", "over_constrained"])
def test_mechcheck_run_passes_the_file_on_every_backend(stem: str, tmp_path: Path) -> None:
    """`mechcheck run FILE` on every available backend: each comparison within the policy's
    tolerance, and a backend that does not model gears or elastic redundancy answers
    not_applicable with its reason; exit 0."""
    from typer.testing import CliRunner

    from mechcheck.cli import app

    result = CliRunner().invoke(app, ["run", "-q", str(CATALOGUE / f"{stem}.toml"),
                                      "-o", str(tmp_path)])
    assert result.exit_code == 0, result.output


# -- the over-constrained structure: its exact equilibrium, the small-displacement bound -----
def exact_equilibrium(p: dict[str, np.ndarray]) -> tuple[dict[str, np.ndarray], dict[str, float]]:
    """The bracket's equilibrium on its stretched geometry, with no linearisation: the free
    nodes where each bar, a spring N = (E·A/L)·(ℓ − L) along its own deformed line ℓ, with
    half its weight at each end, balances the hoist; solved by least squares (scipy) on the
    free nodes' positions. The nodes' positions and each bar's N."""
    from scipy.optimize import least_squares

    def placed(u: np.ndarray) -> dict[str, np.ndarray]:
        return {**p, **{node: p[node] + u[2 * k:2 * k + 2] for k, node in enumerate(FREE)}}

    def tension(at: dict[str, np.ndarray], bar: str) -> tuple[float, np.ndarray]:
        i, j, area, _ = BARS[bar]
        rest, d = float(np.hypot(*(p[j] - p[i]))), at[j] - at[i]
        length = float(np.hypot(*d))
        return E_STEEL * area * 1e-6 * (length - rest) / rest, d / length

    def unbalanced(u: np.ndarray) -> np.ndarray:
        at = placed(u)
        net = {node: np.zeros(2) for node in FREE}
        net["D"] += HOIST
        for bar, (i, j, _, mass) in BARS.items():
            n, e = tension(at, bar)
            for end, pull in ((i, n * e), (j, -n * e)):
                if end in net:
                    net[end] += pull + np.array([0.0, -0.5 * G * mass])
        return np.concatenate([net[node] for node in FREE]) / abs(HOIST[1])

    fit = least_squares(unbalanced, np.zeros(2 * len(FREE)), x_scale=1e-4, xtol=1e-15,
                        ftol=1e-15, gtol=1e-15)
    assert np.max(np.abs(unbalanced(fit.x))) < 1e-12
    at = placed(fit.x)
    return at, {bar: tension(at, bar)[0] for bar in BARS}


def exact_values(p: dict[str, np.ndarray]) -> dict[str, float]:
    """The exact equilibrium as the backends name it: N_<bar>, each joint's F (on its
    links[1], a bar: its pull −N·e at its first end, +N·e at its second, and half its weight
    held up, along the deformed e), the free nodes' positions and each bar's angle turned
    from the drawing (phi_<bar>)."""
    at, tensions = exact_equilibrium(p)
    table = table_of("over_constrained")
    out = {f"N_{bar}": n for bar, n in tensions.items()}
    for joint in table["joints"]:
        bar = joint["links"][1]
        i, j, _, mass = BARS[bar]
        e = (at[j] - at[i]) / np.hypot(*(at[j] - at[i]))
        pull = -tensions[bar] * e if joint["at"] == i else tensions[bar] * e
        out[f"F_{joint['name']}_x"], out[f"F_{joint['name']}_y"] = pull + np.array([0.0, 0.5 * G * mass])
    for node in FREE:
        out[f"x_{node}"], out[f"y_{node}"] = at[node]
    for bar, (i, j, _, _) in BARS.items():
        drawn, now = p[j] - p[i], at[j] - at[i]
        out[f"phi_{bar}"] = math.atan2(cross(drawn, now), float(drawn @ now))
    return out


def over_constrained() -> Case:
    (case,) = mechcheck.load_cases(CATALOGUE / "over_constrained.toml")
    assert isinstance(case, Case)
    return case


def relative_errors(values: dict[str, float], reference: dict[str, float], scale: float,
                    length: float) -> dict[str, float]:
    """Each quantity of ``reference`` as the comparison measures it: forces against the
    largest reference force, positions against the bracket's size, angles against 1 rad."""
    def size(q: str) -> float:
        return scale if q[0] in "FN" else length if q[0] in "xy" else 1.0
    return {q: abs(values[q] - v) / size(q) for q, v in reference.items()}


def test_the_linear_answer_is_within_the_small_displacement_bound_of_the_exact_one() -> None:
    """The analytic answer (equilibrium on the drawn geometry, small displacements) against the
    exact equilibrium on the stretched bars: forces, node positions and bar angles differ by
    more than the settled tolerance (so the comparison needs the bound), by less than
    STRAIN_FACTOR × max_strain (the policy's small-displacement bound)."""
    from mechcheck.tolerance import STRAIN_FACTOR

    case = over_constrained()
    linear = mechcheck.solve(case)
    exact = exact_values(metres(table_of("over_constrained")))
    scale = max(abs(v) for q, v in linear.values.items() if q[0] in "FN")
    errors = relative_errors(linear.values, exact, scale, case.linkage.scale)
    strain = float(linear.diagnostics["max_strain"])
    worst = max(errors, key=errors.__getitem__)
    assert errors[worst] > rule("mujoco", "force", "static").rtol, (worst, errors[worst])
    assert errors[worst] <= STRAIN_FACTOR * strain, (worst, errors[worst], strain)
    for kind in "FNxyp":   # every kind of quantity is within it, not only the worst
        assert max(e for q, e in errors.items() if q[0] == kind) <= STRAIN_FACTOR * strain, kind


@pytest.mark.parametrize("backend", ["mujoco", "pymunk"])
def test_each_simulator_settles_to_the_exact_equilibrium(backend: str) -> None:
    """Each simulator's settled bracket, measured from its own springs and constraints, is the
    exact equilibrium within the settled tolerance, and so the linear answer within the
    policy's small-displacement bound (every quantity the analytic backend reports)."""
    from mechcheck.testing import assert_solution_close

    case = over_constrained()
    if backend not in mechcheck.available_backends():
        pytest.skip(f"{backend} is not installed")
    settled = mechcheck.solve(case, backend)
    assert settled.status == "ok", settled.message
    exact = exact_values(metres(table_of("over_constrained")))
    scale = max(abs(v) for q, v in exact.items() if q[0] in "FN")
    errors = relative_errors(settled.values, exact, scale, case.linkage.scale)
    tol = rule(backend, "force", "static")
    assert max(errors.values()) <= tol.rtol, max(errors.items(), key=lambda kv: kv[1])
    assert_solution_close(case, settled, complete=True)


@pytest.mark.parametrize("stem", ["shaper", "gear_pair"])
def test_a_sweep_of_a_pin_in_slot_or_a_gear_mesh_agrees_in_every_simulator(
        stem: str, tmp_path: Path) -> None:
    """The new kinds sweep as R/P linkages do: the shaper (a pin in a slot) and the gear
    pair over a stretch of their drivers, each pose compared in both simulators' exact
    solves within the policy; a disagreement would exit 1."""
    from typer.testing import CliRunner

    from mechcheck.cli import app

    out = tmp_path / stem
    result = CliRunner().invoke(app, [
        "sweep", str(CATALOGUE / f"{stem}.toml"), "--driver", "0:40:10", "--workers", "0",
        "-b", "virtual_work", "-b", "mujoco_solve", "-b", "pymunk_solve", "-q",
        "--no-figures", "--out", str(out)])
    assert result.exit_code == 0, result.output
    import pandas as pd

    compared = set(pd.read_parquet(out / "comparison.parquet")["backend"])
    assert {"virtual_work", "mujoco_solve", "pymunk_solve"} <= compared, compared
