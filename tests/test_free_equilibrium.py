"""The free-coordinate search ends on a stable equilibrium wherever descent of the potential
reaches one from the drawn pose, says why where it cannot, and gives the same answer for a
drawing scaled by any factor.

Expected values are hand results from each case's potential energy, derived below.

**Exam Q1, F = 60 N, m = 2 kg** (seed 002, SEEDS.md; k = 500 N/m and l = 0.6 m chosen, the
spring's anchor on the right of the slider). A slider at x on a horizontal line, held by a
spring unstretched at x = 0, carries a uniform bar AB pinned at A, turned φ from hanging
(CCW: B toward +x), with F horizontal at B. With B = (x + l·sin φ, −l·cos φ) and the centre
of mass G halfway,

    V(x, φ) = ½·k·x² − F·(x + l·sin φ) − m·g·(l/2)·cos φ,
    ∂V/∂x = k·x − F = 0                       ⇒  x = F/k = 0.12 m,
    ∂V/∂φ = −F·l·cos φ + (m·g·l/2)·sin φ = 0  ⇒  tan φ = 2F/(m·g) = 120/19.62,
    φ = atan2(2F, m·g) = 80.7143°  or  φ − 180° = −99.2857°,
    ∂²V/∂φ² = F·l·sin φ + (m·g·l/2)·cos φ = (l/2)·√(4F² + m²g²)·cos(φ − 80.7143°),
    ∂²V/∂x² = k > 0, ∂²V/∂x∂φ = 0:

a minimum (stable) at 80.7143° and a saddle (unstable) at −99.2857°. The spring, anchored at
(0.5, 0) with free length 0.5 m, is compressed by x: S_spring = k·((0.5 − x) − 0.5) = −F.
Drawn hanging, Gauss–Newton on the stationarity condition alone ends on −99.2857°.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import mechcheck
from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage_equilibrium import _polish, _Units
from mechcheck.casefile import parse_cases, parse_toml
from mechcheck.cli import app

G = 9.81
#: The hand equations hold to rounding; the search converges to 1e-12 of the force level.
RTOL = 1e-9

Q1_FORCE, Q1_MASS, Q1_LENGTH, Q1_STIFFNESS, Q1_ANCHOR = 60.0, 2.0, 0.6, 500.0, 0.5
Q1_STABLE = math.atan2(2.0 * Q1_FORCE, Q1_MASS * G)      # 80.7143°
Q1_UNSTABLE = Q1_STABLE - math.pi                         # −99.2857°

#: The exam-Q1 variant: lengths × ``size`` (m), loads and masses × ``force``, stiffness ×
#: force/size, so that x = F/k scales with the drawing, tan φ = 2F/(m·g) stays, and every
#: energy scales by size·force.
Q1_TABLE = """
[[case]]
name = "exam-q1-f60-{tag}"
mechanism = "linkage"
length_unit = "m"
gravity = [0.0, -9.81]

[case.points]
S0 = [{anchor}, 0.0]
A = [0.0, 0.0]
B = [0.0, -{length}]
G = [0.0, -{half}]

[[case.links]]
name = "ground"
points = ["S0"]
[[case.links]]
name = "slider"
points = ["A"]
[[case.links]]
name = "bar"
points = ["A", "B", "G"]

[[case.joints]]
name = "slide"
kind = "prismatic"
links = ["ground", "slider"]
at = "A"
axis = [1.0, 0.0]
[[case.joints]]
name = "A"
kind = "revolute"
links = ["slider", "bar"]
at = "A"

[[case.masses]]
link = "bar"
mass = {mass}
com = "G"
inertia = {inertia}

[[case.springs]]
name = "spring"
ends = [["ground", "S0"], ["slider", "A"]]
stiffness = {stiffness}
free_length = {anchor}

[[case.loads]]
link = "bar"
at = "B"
force = {{ x = {load}, y = 0.0 }}
"""


def _tag(size: float, force: float) -> str:
    """A case name's suffix: the powers of ten of the scale factors."""
    return f"s{round(math.log10(size))}-f{round(math.log10(force))}"


def q1_text(size: float = 1.0, force: float = 1.0) -> str:
    return Q1_TABLE.format(
        tag=_tag(size, force), anchor=Q1_ANCHOR * size, length=Q1_LENGTH * size,
        half=0.5 * Q1_LENGTH * size, mass=Q1_MASS * force,
        inertia=Q1_MASS * force * (Q1_LENGTH * size) ** 2 / 12.0,
        stiffness=Q1_STIFFNESS * force / size, load=Q1_FORCE * force)


#: A bar pinned at O (mass M = 2 kg, centre of mass c = 0.3 m out) with a collar (m = 1 kg)
#: sliding freely along it, drawn horizontal with the collar s = 0.5 m out. With θ the bar's
#: angle and s the collar's distance from O,
#:     V(θ, s) = g·sin θ·(M·c + m·s),
#:     ∂V/∂θ = g·cos θ·(M·c + m·s) = 0, ∂V/∂s = m·g·sin θ = 0  ⇒  θ = 0, s = −M·c/m = −0.6 m,
#: Hessian [[0, m·g], [m·g, 0]] there, eigenvalues ±m·g: a saddle, the only equilibrium
#: (θ = π is the same balance on the other side). Along θ = −90° V = −g·(M·c + m·s) falls
#: without bound as the collar slides out: descent runs off along the slide.
COLLAR_TABLE = """
[[case]]
name = "collar-on-a-pivoted-bar-{tag}"
mechanism = "linkage"
length_unit = "m"
gravity = [0.0, -9.81]

[case.points]
O = [0.0, 0.0]
E = [{end}, 0.0]
G = [{com}, 0.0]
C = [{collar}, 0.0]

[[case.links]]
name = "ground"
points = ["O"]
[[case.links]]
name = "bar"
points = ["O", "E", "G"]
[[case.links]]
name = "collar"
points = ["C"]

[[case.joints]]
name = "O"
kind = "revolute"
links = ["ground", "bar"]
at = "O"
[[case.joints]]
name = "sleeve"
kind = "prismatic"
links = ["bar", "collar"]
at = "C"
axis = [1.0, 0.0]

[[case.masses]]
link = "bar"
mass = {bar_mass}
com = "G"
[[case.masses]]
link = "collar"
mass = {collar_mass}
com = "C"
"""
COLLAR_M, COLLAR_C, COLLAR_m, COLLAR_S = 2.0, 0.3, 1.0, 0.5


def collar_text(size: float = 1.0, force: float = 1.0) -> str:
    return COLLAR_TABLE.format(tag=_tag(size, force), end=size, com=COLLAR_C * size,
                               collar=COLLAR_S * size, bar_mass=COLLAR_M * force,
                               collar_mass=COLLAR_m * force)


#: A bar pinned at O (M = 2 kg, centre of mass c = 0.5 m out) passes through a sleeve pinned
#: to a block on the horizontal guide y = h = 1 m, drawn with the block at x = 0.3 m. One
#: degree of freedom, x on the whole line: sin θ = h/√(x² + h²), so
#:     V(x) = M·g·c·h/√(x² + h²),   V'(x) = −M·g·c·h·x/(x² + h²)^{3/2} = 0  ⇒  x = 0,
#:     V''(0) = −M·g·c/h² < 0:
#: the upright bar is a maximum, the only equilibrium; V falls toward 0 as |x| grows and
#: never reaches it, so descent runs off along the guide.
SLEEVE_TABLE = """
[[case]]
name = "bar-through-a-sleeve"
mechanism = "linkage"
length_unit = "m"
gravity = [0.0, -9.81]

[case.points]
O = [0.0, 0.0]
G = [{gx}, {gy}]
C = [0.3, 1.0]

[[case.links]]
name = "ground"
points = ["O"]
[[case.links]]
name = "bar"
points = ["O", "G"]
[[case.links]]
name = "sleeve"
points = ["C"]
[[case.links]]
name = "block"
points = ["C"]

[[case.joints]]
name = "O"
kind = "revolute"
links = ["ground", "bar"]
at = "O"
[[case.joints]]
name = "along"
kind = "prismatic"
links = ["bar", "sleeve"]
at = "C"
axis = [0.3, 1.0]
[[case.joints]]
name = "C"
kind = "revolute"
links = ["sleeve", "block"]
at = "C"
[[case.joints]]
name = "guide"
kind = "prismatic"
links = ["ground", "block"]
at = "C"
axis = [1.0, 0.0]

[[case.masses]]
link = "bar"
mass = 2.0
com = "G"
"""
SLEEVE_X0, SLEEVE_H, SLEEVE_C = 0.3, 1.0, 0.5


def sleeve_text() -> str:
    r = math.hypot(SLEEVE_X0, SLEEVE_H)
    return SLEEVE_TABLE.format(gx=SLEEVE_C * SLEEVE_X0 / r, gy=SLEEVE_C * SLEEVE_H / r)


#: A bar pinned at its end (m = 1 kg, l = 0.4 m) drawn pointing straight up, weight only:
#: V(θ) = m·g·(l/2)·cos θ from the upright (θ = 0 a maximum, V'' = −m·g·l/2), minimum at
#: θ = ±180°. The drawn pose is itself an equilibrium, where the gradient vanishes.
UPRIGHT_TABLE = """
[[case]]
name = "upright-pendulum"
mechanism = "linkage"
length_unit = "m"
gravity = [0.0, -9.81]

[case.points]
O = [0.0, 0.0]
T = [0.0, 0.4]
G = [0.0, 0.2]

[[case.links]]
name = "ground"
points = ["O"]
[[case.links]]
name = "bar"
points = ["O", "T", "G"]

[[case.joints]]
name = "O"
kind = "revolute"
links = ["ground", "bar"]
at = "O"

[[case.masses]]
link = "bar"
mass = 1.0
com = "G"
"""


def case_of(text: str) -> Case:
    return parse_cases(parse_toml(text, "<test>"), "<test>")[0][0]


def turn(angle: float) -> float:
    """The angle brought into (−π, π]."""
    return angle - 2.0 * math.pi * math.ceil((angle - math.pi) / (2.0 * math.pi))


def test_exam_q1_drawn_hanging_is_the_case_stationarity_alone_gets_wrong() -> None:
    """From the hanging bar, Gauss–Newton on the stationarity condition alone ends on the
    saddle φ = −99.2857°: the case tests the descent, not the drawing."""
    linkage = case_of(q1_text()).linkage
    units = _Units.of(linkage, np.zeros(0))
    q, residual = _polish(units, np.zeros(6))
    assert residual <= 1e-9
    assert turn(q[5] - Q1_UNSTABLE) == pytest.approx(0.0, abs=RTOL)


@pytest.mark.parametrize("backend", ["analytic", "superposition", "virtual_work"])
def test_exam_q1_drawn_hanging_ends_on_the_stable_equilibrium(backend: str) -> None:
    """Exam Q1 with F = 60 N, m = 2 kg drawn hanging ends on the minimum φ = 80.7143°,
    x = F/k, stable, in every analytic backend, with the spring pushing with F."""
    solution = mechcheck.solve(case_of(q1_text()), backend)
    assert solution.status == "ok", solution.message
    assert solution.diagnostics["stable"] == "yes"
    assert solution.message == ""
    assert turn(solution.values["phi_bar"] - Q1_STABLE) == pytest.approx(0.0, abs=RTOL)
    assert solution.values["q_slide"] == pytest.approx(Q1_FORCE / Q1_STIFFNESS, rel=RTOL)
    if backend != "virtual_work":  # it gives the drivers' efforts, and there are none
        assert solution.values["S_spring"] == pytest.approx(-Q1_FORCE, rel=RTOL)


def test_exam_q1_simulators_settle_where_the_search_ends(tmp_path: Path) -> None:
    """`mechcheck run` on the exam-Q1 variant passes with every backend answering (no
    verdict allowed): MuJoCo and pymunk settle the free coordinates at φ = 80.7143°."""
    path = tmp_path / "q1.toml"
    path.write_text(q1_text())
    out = tmp_path / "out"
    result = CliRunner().invoke(app, ["run", str(path), "-q", "--out", str(out), "--fail-on",
                                      "singular,indeterminate,not_settled,not_applicable,"
                                      "no_solution,error"])
    assert result.exit_code == 0, result.output
    results = pd.read_csv(out / "results.csv")
    phi = results[results["quantity"] == "phi_bar"].set_index("backend")["value"]
    for backend in ("mujoco", "pymunk"):
        assert phi[backend] == pytest.approx(math.degrees(Q1_STABLE), abs=1e-3), backend


def test_a_maximum_drawn_exactly_is_left_downhill() -> None:
    """A pendulum drawn exactly upright, where the gradient vanishes, ends hanging
    (±180°, stable): descent leaves a maximum along its negative curvature."""
    solution = mechcheck.solve(case_of(UPRIGHT_TABLE), "analytic")
    assert solution.status == "ok", solution.message
    assert solution.diagnostics["stable"] == "yes"
    assert abs(turn(solution.values["phi_bar"])) == pytest.approx(math.pi, abs=RTOL)


@pytest.mark.parametrize(("text", "joint", "expected"), [
    (collar_text(), "sleeve", {"q_sleeve": -COLLAR_M * COLLAR_C / COLLAR_m - COLLAR_S,
                               "phi_bar": 0.0}),
    (sleeve_text(), "guide", {"q_guide": -SLEEVE_X0,
                              "phi_bar": math.pi / 2 - math.atan2(SLEEVE_H, SLEEVE_X0)}),
], ids=["collar-saddle", "sleeve-maximum"])
def test_only_an_unstable_equilibrium_is_reported_with_the_reason(
        text: str, joint: str, expected: dict[str, float]) -> None:
    """Where descent runs off along a slide (the collar's saddle, the sleeve's maximum), the
    search ends on the unstable equilibrium, `stable = no`, and every analytic backend's
    message says that only an unstable one was found and along which joint the potential
    keeps falling."""
    case = case_of(text)
    for backend in ("analytic", "superposition", "virtual_work"):
        solution = mechcheck.solve(case, backend)
        assert solution.status == "ok", solution.message
        assert solution.diagnostics["stable"] == "no"
        assert solution.message.startswith("only an unstable equilibrium"), solution.message
        assert f"along {joint}" in solution.message, solution.message
        for quantity, value in expected.items():
            got = solution.values[quantity]
            if quantity.startswith("phi_"):
                got = turn(got - value) + value
            assert got == pytest.approx(value, abs=RTOL), quantity


@pytest.mark.parametrize(("size", "force"), [(1e-3, 1.0), (1e3, 1.0), (1e-3, 1e3), (1e3, 1e-3)])
def test_scaling_the_drawing_scales_the_answer(size: float, force: float) -> None:
    """Lengths × size with forces × force (stiffness × force/size): the same angles,
    displacements × size, forces × force, the same verdict, stability and message."""
    for text_of in (q1_text, collar_text):
        base = mechcheck.solve(case_of(text_of()), "analytic")
        scaled = mechcheck.solve(case_of(text_of(size, force)), "analytic")
        assert (scaled.status, scaled.diagnostics["stable"], scaled.message) \
            == (base.status, base.diagnostics["stable"], base.message)
        for quantity, value in base.values.items():
            unit = base.unit(quantity)
            factor = {"m": size, "N": force, "N*m": force * size, "deg": 1.0}[unit]
            size_of = {"m": size, "N": force * 60.0, "N*m": force * size * 60.0,
                       "deg": 1.0}[unit]
            got = scaled.values[quantity]
            if unit == "deg":
                got = turn(got - value) + value
            assert got == pytest.approx(factor * value, abs=RTOL * size_of), quantity
