"""Exam Q1 and Q2 of seed 002 (SEEDS.md) as linkages, in the analytic engine and in both
simulators (issue 12, item 4: the bespoke exam models retired).

Every expected value is the exam's own hand result, written here: Q1's equilibrium
x = F/k, tan φ = 2F/(m·g), spring force F, and the free-body balance of bar and slider;
Q2's Lagrange–d'Alembert drive force F = m·ẍ + (k1 + k2)·x + μ·m·g·sign(ẋ). The systems
beyond the exam's own numbers (other springs, bars, masses, signs of F; other masses,
springs, friction and both strokes of a sine motion) are those the bespoke models were
checked on. The simulators see the linkage and, for Q1, a start pose that is never the
equilibrium; for Q2, the prescribed x, ẋ, ẍ at the instant read.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

import mechcheck
from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage import (
    Driver,
    Joint,
    JointFriction,
    LinearSpring,
    Link,
    Linkage,
    LinkMass,
    PointLoad,
)
from mechcheck.analytic.linkage_backends import analytic_results
from mechcheck.analytic.values import CaseError
from mechcheck.sim_models.mujoco.linkage_free import settle_free
from mechcheck.sim_models.pymunk import linkage as pymunk_linkage
from mechcheck.tolerance import rule

from .builtin import builtin

G = 9.81
#: The exam prints φ to one decimal (34,2°) and tan φ to two (0,68): half a unit.
PRINTED_DEG, PRINTED_DEG_HALF = 34.2, 0.05
PRINTED_TAN, PRINTED_TAN_HALF = 0.68, 0.005
#: Hand identities hold to rounding; the quantities are O(1…100) in SI.
IDENTITY_TOL = 1e-9


def q1(force: float = 10.0, mass: float = 3.0, length: float = 0.6, stiffness: float = 500.0,
       slider_mass: float = 0.0, drawn: float = 0.0, name: str = "q1") -> Case:
    """Exam Q1 as a linkage (SI): a slider on a horizontal line held by a spring k
    (unstretched at x = 0), a uniform bar of mass m and length l pinned to it at A, a
    horizontal force F at its end B; drawn at x = 0 with the bar turned ``drawn`` rad
    from hanging straight down (CCW: B toward +x)."""
    # The spring's anchor lies beyond any stretch F/k the slider may reach, and beyond
    # the tests' start poses (else the line spring would pass through it).
    free = 2.0 * (length + abs(force) / stiffness)
    end = (length * math.sin(drawn), -length * math.cos(drawn))
    masses = [LinkMass("bar", mass, (0.5 * end[0], 0.5 * end[1]), mass * length**2 / 12.0)]
    if slider_mass:
        masses.append(LinkMass("slider", slider_mass, (0.0, 0.0), 0.0))
    linkage = Linkage(
        points={"S0": (-free, 0.0), "A": (0.0, 0.0), "B": end},
        links=(Link("ground", ("S0",)), Link("slider", ("A",)), Link("bar", ("A", "B"))),
        joints=(Joint("slide", "prismatic", ("ground", "slider"), "A", (1.0, 0.0)),
                Joint("A", "revolute", ("slider", "bar"), "A")),
        loads=(PointLoad("bar", end, (force, 0.0)),),
        masses=tuple(masses),
        springs=(LinearSpring("spring", (("ground", (-free, 0.0)), ("slider", (0.0, 0.0))),
                              stiffness, free),),
        gravity=(0.0, -G),
    )
    return Case(name=name, geometry=linkage)


def q1_hand(case: Case) -> dict[str, float]:
    """The exam's equilibrium: x = F/k, tan φ = 2F/(m·g) (φ CCW from hanging: B swings
    toward +x for F > 0), the spring's tension F; the bar's pin force by the slider
    (−F, m·g) and the guide's force on the slider (0, (m + m_s)·g), from the free bodies."""
    linkage = case.linkage
    force = linkage.loads[0].force[0]
    mass = {m.link: m.mass for m in linkage.masses}
    k = linkage.springs[0].stiffness
    ax, ay = linkage.points["A"]
    bx, by = linkage.points["B"]
    drawn = math.atan2(bx - ax, -(by - ay))  # phi_bar is the turn from the drawn pose
    return {"q_slide": force / k, "phi_bar": math.atan2(2.0 * force, mass["bar"] * G) - drawn,
            "S_spring": force, "F_A_x": -force, "F_A_y": mass["bar"] * G, "F_slide_x": 0.0,
            "F_slide_y": (mass["bar"] + mass.get("slider", 0.0)) * G}


def assert_q1_hand(case: Case, values: dict[str, float], backend: str) -> None:
    """Every hand quantity within the policy's static tolerance (forces relative to the
    case's largest)."""
    hand = q1_hand(case)
    scale = max(abs(v) for q, v in hand.items() if q[0] in "FS")
    bad = []
    for q, expected in hand.items():
        kind = "pose" if q in ("q_slide", "phi_bar") else "force"
        tol = rule(backend, kind, "static").rtol
        got = values[q]
        if q == "phi_bar":  # a bar that swung over the top rests at φ + 2π·n
            got = expected + turn(got - expected)
        size = case.linkage.scale if q == "q_slide" else (scale if kind == "force" else 1.0)
        if not abs(got - expected) <= tol * max(abs(expected), size):
            bad.append(f"{q}: {got:.10g} vs hand {expected:.10g}")
    assert not bad, f"{case.name} [{backend}]: " + "; ".join(bad)


#: Q1 systems: the exam's data with other k, l; then other springs, bars, masses, signs of F.
Q1_SYSTEMS = {
    "exam-k200-l0.5": q1(stiffness=200.0, length=0.5),
    "exam-k1000-l0.2": q1(stiffness=1000.0, length=0.2),
    # Drawn part of the way toward the answer (−77° and 81°).
    "stiff-short-F-negative": q1(force=-25.0, mass=1.2, length=0.2, stiffness=1500.0,
                                 slider_mass=0.1, drawn=math.radians(-40.0)),
    "heavy-long-soft": q1(force=4.0, mass=8.0, length=1.5, stiffness=50.0, slider_mass=2.0),
    "large-angle": q1(force=60.0, mass=2.0, length=0.8, stiffness=300.0,
                      drawn=math.radians(40.0)),
}
#: Start poses (x m, φ rad) the simulators settle from; none is an equilibrium above.
Q1_STARTS = {"far-left-swung-back": (-0.3, -1.2), "nearly-upright": (0.2, 2.8)}


def test_q1_reproduces_the_printed_angle() -> None:
    """F = 10 N, m = 3 kg, g = 9.81: tan φ = 2F/(m·g) = 0.68, φ ≈ 34.2°, as the exam prints;
    the built-in case file and this module's Q1 give the same pose."""
    for case in (q1(), builtin("exam-q1-slider-bar")):
        phi = mechcheck.solve(case, "analytic").values["phi_bar"]
        assert abs(math.tan(phi) - PRINTED_TAN) <= PRINTED_TAN_HALF
        assert abs(math.degrees(phi) - PRINTED_DEG) <= PRINTED_DEG_HALF


@pytest.mark.parametrize("length", [0.1, 0.5, 2.0])
@pytest.mark.parametrize("stiffness", [50.0, 200.0, 5000.0])
def test_q1_angle_does_not_depend_on_k_or_l(stiffness: float, length: float) -> None:
    """φ depends only on F/(m·g), so the exam could leave k and l open; x = F/k on k alone."""
    values = mechcheck.solve(q1(stiffness=stiffness, length=length), "analytic").values
    assert values["phi_bar"] == pytest.approx(math.atan(2.0 * 10.0 / (3.0 * G)), abs=IDENTITY_TOL)
    assert values["q_slide"] == pytest.approx(10.0 / stiffness, rel=IDENTITY_TOL)


@settings(max_examples=40, deadline=None)
@given(force=st.floats(-100.0, 100.0).filter(lambda f: abs(f) > 1e-3),
       mass=st.floats(0.1, 50.0), length=st.floats(0.05, 5.0), stretch=st.floats(0.0, 1.0),
       slider_mass=st.floats(0.01, 10.0))
def test_q1_equilibrium_balances_every_body(force: float, mass: float, length: float,
                                            stretch: float, slider_mass: float) -> None:
    """The analytic engine's equilibrium, reached from the drawn pose, is the exam's:
    x = F/k, tan φ = 2F/(m·g), and bar and slider each balance (their hand free-body
    forces). The spring's stretch F/k is drawn up to one bar length (k = |F|/(stretch·l)):
    the exam's regime. The search descends the potential, so it ends on the stable, hanging
    branch; were it to end on the upright one, φ + π, it would have to call it unstable."""
    stiffness = abs(force) / max(stretch * length, 1e-3 * length)
    case = q1(force, mass, length, stiffness, slider_mass)
    solution = mechcheck.solve(case, "analytic")
    assert solution.status == "ok", solution.message
    values = dict(solution.values)
    hand = q1_hand(case)
    upright = abs(turn(values["phi_bar"] - hand["phi_bar"])) > 0.5 * math.pi
    assert solution.diagnostics["stable"] == ("no" if upright else "yes")
    assert turn(values.pop("phi_bar") - hand.pop("phi_bar") - (math.pi if upright else 0.0)) \
        == pytest.approx(0.0, abs=IDENTITY_TOL)
    scale = max(abs(force), (mass + slider_mass) * G)
    for q, expected in hand.items():
        size = length if q == "q_slide" else scale
        assert values[q] == pytest.approx(expected, abs=IDENTITY_TOL * size), q


def turn(angle: float) -> float:
    """The angle brought into (−π, π]: poses a whole turn apart are the same."""
    return angle - 2.0 * math.pi * math.ceil((angle - math.pi) / (2.0 * math.pi))


@pytest.mark.parametrize("start", ["drawn", *Q1_STARTS])
@pytest.mark.parametrize("name", Q1_SYSTEMS)
@pytest.mark.parametrize("backend", ["mujoco", "pymunk"])
def test_q1_simulators_find_the_equilibrium(backend: str, name: str, start: str) -> None:
    """Damped from the drawn pose (the bar hanging at x = 0) or another start, never the
    equilibrium, each simulator settles at the exam's x, φ and forces, read from its own
    state."""
    case = Q1_SYSTEMS[name]
    if start == "drawn":
        solution = mechcheck.solve(case, backend)
    else:
        x, phi = Q1_STARTS[start]
        if backend == "mujoco":
            solution = settle_free(case, analytic_results(case), {"slide": x, "A": phi})
        else:  # slider translated by x; bar turned by φ about A, then translated by x
            # (coordinates are displacements of the drawing's reference point, S0)
            ax, ay = case.linkage.points["A"]
            c, s = math.cos(phi), math.sin(phi)
            bar = (ax - (c * ax - s * ay) + x, ay - (s * ax + c * ay))
            solution = pymunk_linkage.settle(case, seed=np.array([x, 0.0, 0.0, *bar, phi]))
    assert solution.status == "ok", solution.message
    assert_q1_hand(case, dict(solution.values), backend)


def q2(x: float, velocity: float, acceleration: float, mass: float = 2.0, k1: float = 300.0,
       k2: float = 200.0, mu: float = 0.1, name: str = "q2") -> Case:
    """Exam Q2 as a linkage (SI): a block on a horizontal slide between springs k1 (from
    the left wall) and k2 (to the right wall), both unstretched at x = 0, its coordinate
    driven at (x, ẋ, ẍ); the driver's effort Q_slide is the pushing force F."""
    wall = 0.3
    linkage = Linkage(
        points={"W1": (-wall, 0.0), "W2": (wall, 0.0), "A": (0.0, 0.0)},
        links=(Link("ground", ("W1", "W2")), Link("block", ("A",))),
        joints=(Joint("slide", "prismatic", ("ground", "block"), "A", (1.0, 0.0)),),
        drivers=(Driver("slide", x, velocity, acceleration),),
        masses=(LinkMass("block", mass, (0.0, 0.0), 0.0),),
        springs=(LinearSpring("k1", (("ground", (-wall, 0.0)), ("block", (0.0, 0.0))), k1, wall),
                 LinearSpring("k2", (("block", (0.0, 0.0)), ("ground", (wall, 0.0))), k2, wall)),
        gravity=(0.0, -G),
        friction=JointFriction(mu=mu) if mu else None,
    )
    return Case(name=name, geometry=linkage)


def q2_hand(x: float, velocity: float, acceleration: float, mass: float = 2.0,
            k1: float = 300.0, k2: float = 200.0, mu: float = 0.1) -> float:
    """The exam's Lagrange–d'Alembert drive force."""
    return mass * acceleration + (k1 + k2) * x + mu * mass * G * math.copysign(1.0, velocity)


def test_q2_is_the_exam_equation_in_either_direction() -> None:
    """F = m·ẍ + (k1 + k2)·x ± μ·m·g: reversing ẋ at the same x and ẍ changes F by exactly
    2·μ·m·g, friction opposing the motion."""
    system = {"mass": 2.0, "k1": 150.0, "k2": 250.0, "mu": 0.3}
    forward = mechcheck.solve(q2(0.01, 0.5, -3.0, **system), "analytic").values["Q_slide"]
    backward = mechcheck.solve(q2(0.01, -0.5, -3.0, **system), "analytic").values["Q_slide"]
    assert forward == pytest.approx(2.0 * -3.0 + 400.0 * 0.01 + 0.3 * 2.0 * G, rel=IDENTITY_TOL)
    assert forward - backward == pytest.approx(2.0 * 0.3 * 2.0 * G, rel=IDENTITY_TOL)


def test_q2_force_at_rest_needs_the_sense_friction_opposes() -> None:
    """At ẋ = 0 Coulomb friction is anywhere in ±μ·m·g, so F is not unique: the case is
    refused as written, naming the key (LINKAGES.md: a driver at rest with Coulomb
    friction states the sense of motion it is about to take)."""
    with pytest.raises(CaseError, match=r"drivers\[0\]\.sense"):
        q2(0.01, 0.0, 1.0)


def sine_instants(amplitude: float, omega: float, offset: float,
                  times: np.ndarray) -> list[tuple[float, float, float]]:
    """(x, ẋ, ẍ) of x = offset + X·sin(Ωt) at the times."""
    return [(offset + amplitude * math.sin(omega * t), amplitude * omega * math.cos(omega * t),
             -amplitude * omega**2 * math.sin(omega * t)) for t in times]


#: The exam's motion x = 30 mm·sin(2πt) on its forward stroke, and other systems and
#: motions on both strokes, at least 0.05 s from the reversals: (system, instants).
Q2_CASES = {
    "exam": ({}, sine_instants(0.03, 2.0 * math.pi, 0.0, np.linspace(-0.2, 0.2, 5))),
    "slippery-fast": ({"mass": 0.5, "k1": 20.0, "k2": 80.0, "mu": 0.05},
                      sine_instants(0.05, 10.0, 0.0, np.linspace(-0.14, 0.14, 4))),
    "heavy-rough-offset": ({"mass": 20.0, "k1": 1000.0, "k2": 3000.0, "mu": 0.6},
                           sine_instants(0.02, 3.0, 0.03, np.linspace(-0.5, 0.5, 4))),
    "round-trip": ({}, sine_instants(0.03, 2.0 * math.pi, 0.0, np.array([-0.05, 0.3, 0.55, 0.95]))),
    "no-friction": ({"mu": 0.0}, sine_instants(0.02, 4.0, 0.0, np.linspace(0.0, 0.35, 3))),
}


@pytest.mark.parametrize("name", Q2_CASES)
@pytest.mark.parametrize("backend", ["analytic", "mujoco", "pymunk"])
def test_q2_drive_force_is_the_exam_equation(backend: str, name: str) -> None:
    """At every instant, the driver's effort is the hand F(t), friction sign included,
    within the policy's dynamic (friction) tolerance of the largest |F| along the motion;
    the slide carries N = m·g and the friction −μ·N·sign(ẋ), from each backend's own
    reactions."""
    system, instants = Q2_CASES[name]
    hand = [q2_hand(*xva, **system) for xva in instants]
    scale = max(abs(f) for f in hand)
    mass, mu = system.get("mass", 2.0), system.get("mu", 0.1)
    for (x, v, a), expected in zip(instants, hand, strict=True):
        case = q2(x, v, a, **system, name=f"q2-{name}")
        solution = mechcheck.solve(case, backend)
        assert solution.status == "ok", (x, v, a, solution.message)
        tol = rule(backend, "force", case.kind).rtol
        values = solution.values
        assert values["Q_slide"] == pytest.approx(expected, abs=tol * scale), (x, v, a)
        assert values["F_slide_y"] == pytest.approx(mass * G, abs=tol * scale)
        assert values["F_slide_x"] == pytest.approx(-mu * mass * G * math.copysign(1.0, v),
                                                    abs=tol * scale)


@pytest.mark.parametrize("backend", ["analytic", "superposition", "virtual_work", "mujoco",
                                     "mujoco_solve", "pymunk", "pymunk_solve"])
def test_q2_where_a_spring_s_ends_meet_its_force_has_no_line_of_action(backend: str) -> None:
    """At x = −0.3 m the block reaches the left wall: k1's ends meet, its tension is
    k1·(0 − 0.3 m) = −90 N with no direction, so the reactions are not unique. Every backend
    says `indeterminate`, naming the spring, and gives no force (before, the analytic
    backend said `ok`, quietly dropped the NaN forces, and the run passed on nothing)."""
    solution = mechcheck.solve(q2(-0.3, 0.5, 3.0), backend)
    assert solution.status == "indeterminate", solution.message
    assert "spring k1" in solution.message
    assert not any(q.startswith(("F_", "Q_")) for q in solution.values)


def test_q2_a_spring_without_tension_where_its_ends_meet_adds_nothing() -> None:
    """A k1 of free length 0 whose ends meet carries no tension: the drive force is the
    exam equation with k2 alone, F = m·ẍ + k2·(x − 0) = 2·3 + 200·(−0.3) = −54 N (k2 is
    unstretched at x = 0), plus μ·m·g = 1.962 N for ẋ > 0; an infinitesimal step away
    agrees (the zero-length spring then has tension ≈ 0 along a defined line)."""
    def case(x: float) -> Case:
        base = q2(x, 0.5, 3.0).linkage
        k1 = base.springs[0]
        return Case(name="q2-slack", geometry=dataclasses.replace(
            base, springs=(dataclasses.replace(k1, free_length=0.0), base.springs[1])))
    at = mechcheck.solve(case(-0.3), "analytic")
    assert at.status == "ok", at.message
    assert at.values["S_k1"] == 0.0
    assert at.values["Q_slide"] == pytest.approx(2.0 * 3.0 + 200.0 * -0.3 + 0.1 * 2.0 * G,
                                                 rel=IDENTITY_TOL)
    near = mechcheck.solve(case(-0.3 + 1e-9), "analytic")
    assert near.values["Q_slide"] == pytest.approx(at.values["Q_slide"], rel=1e-6)
