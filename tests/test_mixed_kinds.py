"""Random linkages that mix the pin in a slot and gear meshes with revolute and prismatic
joints, against methods that share nothing with the engine: a random crank-shaper (a crank
whose pin slides in a slotted lever driving a ram through a rod) against the independent
Lagrange-multiplier reference (tests/linkage_reference.py), moving, loaded and heavy; random
three-gear trains against their hand solution (moment balances of the three gears, the
radial parts on the separating side); random planetary trains against Willis' formula and
the power balance; and the random crank-shapers and gear trains through both simulators,
held and solved at the pose."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from hypothesis import HealthCheck, assume, given, settings, strategies as st

import mechcheck
from mechcheck.analytic.case import Case
from mechcheck.analytic.joint_kinds import GEAR, REVOLUTE, GearMesh
from mechcheck.analytic.linkage import Driver, Joint, Link, Linkage, PointLoad
from mechcheck.analytic.linkage_forces import solve_linkage
from mechcheck.casefile import parse_cases
from mechcheck.testing import assert_solution_close

from .test_linkage_against_reference import assert_agree

#: Poses this close to a toggle are the singular-pose tests' (forces amplified by cond × eps).
MAX_CONDITION = 1e4


@st.composite
def crank_shapers(draw: st.DrawFn) -> dict[str, Any]:
    """A crank O2-A (r < |O2O4|, so it turns fully) whose pin A slides in the lever O4-B; the
    lever drives a ram C along y = h through the rod B-C; random loads, masses, gravity and
    crank motion. As a case table (the reference reads the same table)."""
    d = draw(st.floats(0.15, 0.4))
    r = draw(st.floats(0.2, 0.8)) * d
    theta = draw(st.floats(-math.pi, math.pi))
    lever = draw(st.floats(1.3, 2.0)) * (d + r)
    o2, o4 = (0.0, d), (0.0, 0.0)
    a = (o2[0] + r * math.cos(theta), o2[1] + r * math.sin(theta))
    u = np.subtract(a, o4) / math.hypot(*a)
    b = (lever * u[0], lever * u[1])
    h = draw(st.floats(0.8, 1.1)) * lever
    rod = draw(st.floats(0.5, 1.0)) * lever
    assume(rod > abs(h - b[1]) * 1.05)
    c = (b[0] + math.sqrt(rod**2 - (h - b[1]) ** 2), h)
    joint = {"kind": "revolute"}
    table: dict[str, Any] = {
        "name": "random-crank-shaper", "mechanism": "linkage",
        "gravity": [0.0, -9.81 * draw(st.sampled_from([0.0, 1.0]))],
        "points": {"O2": list(o2), "O4": list(o4), "A": list(a), "B": list(b), "C": list(c)},
        "links": [{"name": "ground", "points": ["O2", "O4"]},
                  {"name": "crank", "points": ["O2", "A"]},
                  {"name": "lever", "points": ["O4", "B"]},
                  {"name": "rod", "points": ["B", "C"]},
                  {"name": "ram", "points": ["C"]}],
        "joints": [joint | {"name": "O2", "links": ["ground", "crank"], "at": "O2"},
                   joint | {"name": "O4", "links": ["ground", "lever"], "at": "O4"},
                   {"name": "A", "kind": "pin_in_slot", "links": ["lever", "crank"], "at": "A",
                    "axis": [float(u[0]), float(u[1])]},
                   joint | {"name": "B", "links": ["lever", "rod"], "at": "B"},
                   joint | {"name": "C", "links": ["rod", "ram"], "at": "C"},
                   {"name": "slide", "kind": "prismatic", "links": ["ground", "ram"], "at": "C",
                    "axis": [1.0, 0.0]}],
        "drivers": [{"joint": "O2", "rotation": 0.0, "velocity": draw(st.floats(-12.0, 12.0)),
                     "acceleration": draw(st.floats(-50.0, 50.0))}],
        "loads": [{"link": "ram", "at": "C",
                   "force": {"x": draw(st.floats(-800.0, 800.0)), "y": 0.0}},
                  {"link": "lever", "at": "B", "torque": draw(st.floats(-20.0, 20.0))}],
        "masses": [{"link": name, "mass": draw(st.floats(0.2, 5.0)), "com": point,
                    "inertia": draw(st.floats(0.0, 0.05))}
                   for name, point in (("crank", "A"), ("lever", "B"), ("rod", "C"), ("ram", "C"))],
    }
    if draw(st.booleans()):
        table["friction"] = {"viscous": {"A": draw(st.floats(0.0, 20.0))}}
    return table


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(crank_shapers())
def test_random_crank_shapers_equal_the_independent_reference(table: dict[str, Any]) -> None:
    """Same verdict and every quantity within 1e-9 of its scale, as for the built-in files."""
    ((case, _),) = parse_cases({"case": [table]}, "random")
    assume(mechcheck.solve(case).diagnostics["condition_number"] < MAX_CONDITION)
    assert_agree(case, table)


def gear_train(radii: tuple[float, float, float], turns: tuple[float, float], torque: float,
               pressure: float) -> Linkage:
    """Gears 1, 2, 3 on fixed bearings c1, c2, c3 (c2 in direction turns[0] from c1, c3 in
    direction turns[1] from c2, each a pitch-circle sum away), 1 driven, 3 loaded."""
    r1, r2, r3 = radii
    c1 = np.zeros(2)
    c2 = c1 + (r1 + r2) * np.array([math.cos(turns[0]), math.sin(turns[0])])
    c3 = c2 + (r2 + r3) * np.array([math.cos(turns[1]), math.sin(turns[1])])
    points = {"c1": tuple(c1), "c2": tuple(c2), "c3": tuple(c3)}
    alpha = math.radians(pressure)
    return Linkage(
        points=points,
        links=(Link("ground", ("c1", "c2", "c3")), Link("g1", ("c1",)), Link("g2", ("c2",)),
               Link("g3", ("c3",))),
        joints=(*(Joint(f"b{k}", REVOLUTE, ("ground", f"g{k}"), f"c{k}") for k in (1, 2, 3)),
                Joint("m12", GEAR, ("g1", "g2"), "c1", mesh=GearMesh(("c1", "c2"), (r1, r2), alpha)),
                Joint("m23", GEAR, ("g2", "g3"), "c2", mesh=GearMesh(("c2", "c3"), (r2, r3), alpha))),
        drivers=(Driver("b1", 0.3),),
        loads=(PointLoad("g3", points["c3"], (0.0, 0.0), torque),))


@settings(max_examples=60, deadline=None)
@given(st.tuples(*[st.floats(0.01, 0.2)] * 3), st.floats(-math.pi, math.pi),
       st.floats(-2.6, 2.6), st.floats(-50.0, 50.0), st.floats(0.0, 30.0))
def test_random_gear_trains_have_the_hand_solution(radii: tuple[float, float, float],
                                                   first: float, bend: float, torque: float,
                                                   pressure: float) -> None:
    """Gear 3 about c3: F_t23 = T/r3; the idler about c2: F_t12 = −F_t23; gear 1 about c1:
    Q = r1·F_t12 = −T·r1/r3. Each tooth force adds tan α·|F_t| along e (c_a → c_b) on the
    driven gear of the mesh; the idler's bearing carries −(F_12 − F_23)."""
    assume(abs(bend) > 0.4)   # gears 1 and 3 may not overlap
    v = {q: float(a[0]) for q, a in solve_linkage(
        gear_train(radii, (first, first + bend), torque, pressure)).values.items()}
    r1, _, r3 = radii
    tan = math.tan(math.radians(pressure))
    e12 = np.array([math.cos(first), math.sin(first)])
    e23 = np.array([math.cos(first + bend), math.sin(first + bend)])

    def tooth(e: np.ndarray, f_t: float) -> np.ndarray:
        return f_t * np.array([-e[1], e[0]]) + tan * abs(f_t) * e

    f23 = torque / r3
    f12 = -f23
    scale = max(abs(f23), 1e-3) * (1.0 + tan)
    expected = {"Q_b1": r1 * f12, "F_m23_t": f23, "F_m12_t": f12,
                "F_m23_r": tan * abs(f23), "F_m12_r": tan * abs(f12)}
    bearing2 = -(tooth(e12, f12) - tooth(e23, f23))
    expected |= {"F_b2_x": bearing2[0], "F_b2_y": bearing2[1]}
    for q, want in expected.items():
        size = scale * (r1 if q.startswith("Q_") else 1.0)
        assert abs(v[q] - want) <= 1e-9 * size, (q, v[q], want)


@settings(max_examples=40, deadline=None)
@given(st.floats(0.01, 0.1), st.floats(1.5, 6.0), st.floats(-8.0, 8.0), st.floats(-30.0, 30.0))
def test_random_planetary_trains_follow_willis(sun: float, ratio: float, carrier: float,
                                               torque: float) -> None:
    """Ring fixed (radius R = ratio·S): the sun turns (1 + R/S) times the carrier, and the
    carrier's drive balances the sun's torque by power, Q = −T·(1 + R/S)."""
    ring = ratio * sun
    planet = (ring - sun) / 2
    linkage = Linkage(
        points={"O": (0.0, 0.0), "C": (sun + planet, 0.0)},
        links=(Link("ground", ("O",)), Link("sun", ("O",)), Link("arm", ("O", "C")),
               Link("planet", ("C",))),
        joints=(Joint("Os", REVOLUTE, ("ground", "sun"), "O"),
                Joint("Oa", REVOLUTE, ("ground", "arm"), "O"),
                Joint("C", REVOLUTE, ("arm", "planet"), "C"),
                Joint("sp", GEAR, ("sun", "planet"), "O", mesh=GearMesh(("O", "C"), (sun, planet))),
                Joint("pr", GEAR, ("planet", "ground"), "C",
                      mesh=GearMesh(("C", "O"), (planet, ring), internal=True))),
        drivers=(Driver("Oa", carrier, 1.0),),
        loads=(PointLoad("sun", (0.0, 0.0), (0.0, 0.0), torque),))
    v = mechcheck.solve(Case("planetary", linkage)).values
    willis = 1.0 + ring / sun
    assert abs(v["phi_sun"] - math.remainder(carrier * willis, math.tau)) <= 1e-9 * willis \
        or abs(math.remainder(v["phi_sun"] - carrier * willis, math.tau)) <= 1e-9 * willis
    assert abs(v["Q_Oa"] + torque * willis) <= 1e-12 * max(abs(torque) * willis, 1e-3)



@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(crank_shapers(), st.sampled_from(["mujoco_solve", "pymunk_solve", "mujoco", "pymunk"]))
def test_random_crank_shapers_in_the_simulators(table: dict[str, Any], backend: str) -> None:
    """Each simulator, held or solved at the pose (the crank at rest), reads every quantity
    of a random crank-shaper within the policy's tolerance of the analytic backend."""
    table = table | {"drivers": [{"joint": "O2", "rotation": 0.0}]}
    table.pop("friction", None)
    ((case, _),) = parse_cases({"case": [table]}, "random")
    assume(mechcheck.solve(case).diagnostics["condition_number"] < MAX_CONDITION)
    assert_solution_close(case, mechcheck.solve(case, backend), complete=True)


@settings(max_examples=12, deadline=None)
@given(st.tuples(*[st.floats(0.02, 0.2)] * 3), st.floats(-math.pi, math.pi),
       st.floats(0.6, 2.6), st.floats(-50.0, 50.0), st.floats(0.0, 30.0),
       st.sampled_from(["mujoco_solve", "pymunk_solve", "mujoco", "pymunk"]))
def test_random_gear_trains_in_the_simulators(radii: tuple[float, float, float], first: float,
                                              bend: float, torque: float, pressure: float,
                                              backend: str) -> None:
    """Each simulator reads a random three-gear train (tooth forces, bearings, the drive
    torque) within the policy's tolerance of the analytic backend."""
    assume(abs(torque) > 0.1)
    case = Case("train", gear_train(radii, (first, first + bend), torque, pressure))
    assert_solution_close(case, mechcheck.solve(case, backend), complete=True)
