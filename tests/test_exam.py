"""Exam Q1 and Q2 of seed 002 (SEEDS.md): analytic models, and MuJoCo and pymunk against them.

Expected values come from :mod:`mechcheck.analytic.exam` only. The simulators never see
them: Q1 settles from a pose chosen here (never the equilibrium) and Q2 gets
only the prescribed path x(t).
"""

from __future__ import annotations

import math
from types import ModuleType

import mujoco
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from mechcheck.analytic.exam import (
    EXAM_Q1_PHI_DEG,
    EXAM_Q1_TAN_PHI,
    Q1Equilibrium,
    Q1Result,
    Q1System,
    Q2Result,
    Q2System,
    SineMotion,
    bar_end,
    exam_q1,
    exam_q2,
    q1_equilibrium,
    q1_generalized_forces,
    q2_drive_force,
    q2_force,
)
from mechcheck.sim_models.mujoco import exam as mujoco_exam
from mechcheck.sim_models.pymunk import exam as pymunk_exam

#: The exam prints φ to one decimal (34,2°) and tan φ to two (0,68): half a unit.
PRINTED_DEG_HALF = 0.05
PRINTED_TAN_HALF = 0.005
#: Analytic identities hold to rounding; the quantities are O(1…100) in SI.
IDENTITY_TOL = 1e-9
#: Target of the simulated Q1 angle, rad (issue 6, item 4).
ANGLE_TOL = 1e-4
#: The same target carried to lengths at the bar's scale: |Δx| ≤ ANGLE_TOL·l.
#: (k·x is the spring force, so this is also ≤ 1e-3 of it for any x ≳ 0.1·l.)
POSITION_TOL_PER_LENGTH = 1e-4
#: Target of every simulated force, relative (issue 6, item 4). Q1: relative to
#: the force itself, floored at the largest force of the case (a force that is
#: zero has no relative error). Q2: relative to F(t) itself where F keeps its
#: sign, else to the largest |F| along the readings.
FORCE_RTOL = 1e-3

BACKENDS: dict[str, ModuleType] = {"mujoco": mujoco_exam, "pymunk": pymunk_exam}

#: Q1 systems: the exam's data with our k, l; then other springs, bars, masses and signs of F.
Q1_SYSTEMS = {
    "exam-k200-l0.5": exam_q1(),
    "exam-k1000-l0.2": exam_q1(stiffness=1000.0, length=0.2),
    "stiff-short-F-negative": Q1System(force=-25.0, mass=1.2, length=0.2, stiffness=1500.0,
                                       slider_mass=0.1),
    "heavy-long-soft": Q1System(force=4.0, mass=8.0, length=1.5, stiffness=50.0, slider_mass=2.0),
    "large-angle": Q1System(force=60.0, mass=2.0, length=0.8, stiffness=300.0, gravity=9.81),
}
#: Start poses (x, φ) the simulators settle from; none is an equilibrium of any system above.
Q1_STARTS = {"hanging-at-rest-length": (0.0, 0.0), "far-left-swung-back": (-0.3, -1.2),
             "nearly-upright": (0.2, 2.8)}


def q1_errors(system: Q1System, sim: Q1Equilibrium) -> dict[str, float]:
    """Error per quantity in the units of its tolerance: rad, lengths of l, relative forces."""
    ref = q1_equilibrium(system).as_dict()
    got = sim.as_dict()
    forces = ("spring_force", "pin_x", "pin_y", "normal")
    scale = max(abs(ref[q]) for q in forces)
    # A bar that swung over the top rests at φ + 2π·n: the same pose.
    dphi = (got["phi"] - ref["phi"] + math.pi) % (2.0 * math.pi) - math.pi
    out = {"phi": abs(dphi), "x": abs(got["x"] - ref["x"]) / system.length}
    out |= {q: abs(got[q] - ref[q]) / max(abs(ref[q]), scale) for q in forces}
    return out


def assert_q1_close(name: str, system: Q1System, result: Q1Result) -> None:
    """``result`` settled, and every quantity is within its target of the analytic value."""
    assert result.status == "ok", f"{name} [{result.backend}]: {result.message}"
    assert result.values is not None
    limits = {"phi": ANGLE_TOL, "x": POSITION_TOL_PER_LENGTH} | dict.fromkeys(
        ("spring_force", "pin_x", "pin_y", "normal"), FORCE_RTOL)
    ref = q1_equilibrium(system).as_dict()
    got = result.values.as_dict()
    bad = [f"{q}: {got[q]:.10g} vs analytic {ref[q]:.10g}, error {e:.2e} > {limits[q]:.0e}"
           for q, e in q1_errors(system, result.values).items() if not e <= limits[q]]
    assert not bad, f"{name} [{result.backend}]: " + "; ".join(bad)


# ------------------------------------------------------------------ Q1 analytic


def test_q1_reproduces_the_printed_angle() -> None:
    """With F = 10 N, m = 3 kg and g = 9.81, tan φ = 2F/(m·g) = 0.68 and φ ≈ 34.2°, as the exam prints."""
    eq = q1_equilibrium(exam_q1())
    assert abs(math.tan(eq.phi) - EXAM_Q1_TAN_PHI) <= PRINTED_TAN_HALF
    assert abs(math.degrees(eq.phi) - EXAM_Q1_PHI_DEG) <= PRINTED_DEG_HALF


@pytest.mark.parametrize("length", [0.1, 0.5, 2.0])
@pytest.mark.parametrize("stiffness", [50.0, 200.0, 5000.0])
def test_q1_angle_does_not_depend_on_k_or_l(stiffness: float, length: float) -> None:
    """φ depends only on F/(m·g), so the exam could leave k and l open; x = F/k depends on k alone."""
    eq = q1_equilibrium(exam_q1(stiffness=stiffness, length=length))
    assert eq.phi == pytest.approx(math.atan(0.2 * 10.0 / 2.943), abs=IDENTITY_TOL)
    assert eq.x == pytest.approx(10.0 / stiffness, rel=IDENTITY_TOL)


@settings(max_examples=50, deadline=None)
@given(force=st.floats(-100.0, 100.0), mass=st.floats(0.1, 50.0), length=st.floats(0.05, 5.0),
       stiffness=st.floats(1.0, 1e4), slider_mass=st.floats(0.01, 10.0))
def test_q1_equilibrium_balances_every_body(force: float, mass: float, length: float, stiffness: float,
                                            slider_mass: float) -> None:
    """At the analytic equilibrium the virtual work vanishes and bar and slider each have ΣF = 0, ΣM_A = 0."""
    s = Q1System(force=force, mass=mass, length=length, stiffness=stiffness, slider_mass=slider_mass)
    eq = q1_equilibrium(s)
    q_x, q_phi = q1_generalized_forces(s, eq.x, eq.phi)
    weight = mass * s.gravity
    assert abs(q_x) <= IDENTITY_TOL * (abs(force) + 1.0)
    assert abs(q_phi) <= IDENTITY_TOL * length * (abs(force) + weight)
    # Bar: pin force R + F + weight = 0, and the moments about A of F and the weight cancel.
    assert eq.pin_x + force == pytest.approx(0.0, abs=IDENTITY_TOL * (abs(force) + 1.0))
    assert eq.pin_y - weight == pytest.approx(0.0, abs=IDENTITY_TOL * weight)
    bx, by = bar_end(s, eq.x, eq.phi)
    moment = -(by - 0.0) * force + 0.5 * (bx - eq.x) * (-weight)
    assert abs(moment) <= IDENTITY_TOL * length * (abs(force) + weight)
    # Slider: spring − R (the bar pushes back) = 0 along x; normal − weights − R_y = 0 along y.
    assert eq.spring_force - eq.pin_x == pytest.approx(0.0, abs=IDENTITY_TOL * (abs(force) + 1.0))
    assert eq.normal - slider_mass * s.gravity - eq.pin_y == pytest.approx(0.0, abs=IDENTITY_TOL * weight)
    assert abs(eq.phi) < 0.5 * math.pi  # the hanging (stable) branch


def test_q1_system_refuses_nonsense() -> None:
    """A bar without mass, a spring without stiffness or a non-finite force is refused when built."""
    with pytest.raises(ValueError, match="mass"):
        Q1System(mass=0.0)
    with pytest.raises(ValueError, match="stiffness"):
        Q1System(stiffness=-1.0)
    with pytest.raises(ValueError, match="force"):
        Q1System(force=math.nan)


# ---------------------------------------------------------------- Q1 simulators


@pytest.mark.parametrize("backend", BACKENDS)
def test_q1_simulators_reproduce_the_printed_angle(backend: str) -> None:
    """Settled from the bar hanging straight down, each simulator's bar comes to rest at φ ≈ 34.2°."""
    result = BACKENDS[backend].settle_q1(exam_q1())
    assert result.status == "ok", result.message
    assert result.values is not None
    assert abs(math.degrees(result.values.phi) - EXAM_Q1_PHI_DEG) <= PRINTED_DEG_HALF
    assert abs(math.tan(result.values.phi) - EXAM_Q1_TAN_PHI) <= PRINTED_TAN_HALF


@pytest.mark.parametrize("start", Q1_STARTS)
@pytest.mark.parametrize("name", Q1_SYSTEMS)
@pytest.mark.parametrize("backend", BACKENDS)
def test_q1_simulators_find_the_equilibrium(backend: str, name: str, start: str) -> None:
    """Damped from a pose that is not the equilibrium, each simulator settles at x = F/k, tan φ = 2F/(m·g)
    with the spring, pin and normal forces of the analytic model, read from its own state."""
    module = BACKENDS[backend]
    x0, phi0 = Q1_STARTS[start]
    system = Q1_SYSTEMS[name]
    result = module.settle_q1(system, module.Q1Settings(start_x=x0, start_phi=phi0))
    assert_q1_close(f"{name} from {start}", system, result)
    assert result.residual_velocity <= module.VELOCITY_TOL


@pytest.mark.parametrize("backend", BACKENDS)
def test_q1_unsettled_run_withholds_forces(backend: str) -> None:
    """A run stopped by its step budget is reported not_settled, with no forces, not as an equilibrium."""
    module = BACKENDS[backend]
    result = module.settle_q1(exam_q1(), module.Q1Settings(max_steps=20))
    assert result.status == "not_settled"
    assert result.values is None
    assert "20 steps" in result.message


def test_q1_mujoco_model_is_planar_with_explicit_gravity() -> None:
    """The MJCF has gravity along −y (not MuJoCo's default −z), contacts off, and compiles as written."""
    xml = mujoco_exam.q1_xml(exam_q1())
    model = mujoco.MjModel.from_xml_string(xml)
    assert np.allclose(model.opt.gravity, [0.0, -9.81, 0.0])
    assert model.opt.disableflags & mujoco.mjtDisableBit.mjDSBL_CONTACT
    assert model.neq == 2 and model.njnt == 5


def test_q2_mujoco_model_round_trips_through_xml() -> None:
    """The Q2 MJCF compiles to the same masses, springs and gravity as the spec it was written from."""
    s = Q2System()
    from_xml = mujoco.MjModel.from_xml_string(mujoco_exam.q2_xml(s))
    from_spec = mujoco_exam.q2_spec(s).compile()
    for field in ("body_mass", "tendon_stiffness", "eq_type", "eq_obj1id", "eq_obj2id"):
        assert np.array_equal(getattr(from_xml, field), getattr(from_spec, field)), field
    # A joint equality uses its 5 polynomial coefficients; the rest of eq_data is other types' defaults.
    assert np.array_equal(from_xml.eq_data[:, :5], from_spec.eq_data[:, :5])
    assert np.allclose(from_xml.opt.gravity, [0.0, -s.gravity, 0.0])


# ------------------------------------------------------------------ Q2 analytic


def test_q2_is_the_exam_equation_when_moving_forward() -> None:
    """For ẋ > 0, F = m·ẍ + (k1 + k2)·x + μ·m·g, the exam's Lagrange–d'Alembert result."""
    s = Q2System(mass=2.0, k1=150.0, k2=250.0, mu=0.3)
    f = q2_force(s, x=0.01, velocity=0.5, acceleration=-3.0)
    assert float(f) == pytest.approx(2.0 * -3.0 + 400.0 * 0.01 + 0.3 * 2.0 * 9.81, rel=IDENTITY_TOL)


def test_q2_friction_opposes_the_velocity() -> None:
    """Reversing ẋ at the same x and ẍ changes F by exactly 2·μ·m·g: friction always opposes the motion."""
    s = Q2System()
    forward = q2_force(s, 0.01, 0.5, -3.0)
    backward = q2_force(s, 0.01, -0.5, -3.0)
    assert float(forward - backward) == pytest.approx(2.0 * s.mu * s.normal_force, rel=IDENTITY_TOL)


def test_q2_force_is_indeterminate_at_rest() -> None:
    """At ẋ = 0 Coulomb friction is anywhere in ±μ·m·g, so no unique F exists and none is returned."""
    with pytest.raises(ValueError, match="indeterminate"):
        q2_force(Q2System(), 0.0, 0.0, 1.0)


def test_q2_exam_motion_keeps_the_force_positive() -> None:
    """Along the chosen exam motion (ẋ > 0 for |t| < 0.25 s) F stays between 2.6 and 9.2 N."""
    s, motion = exam_q2()
    lo, hi = motion.forward_interval()
    t = np.linspace(lo, hi, 1001)[1:-1]
    assert np.all(motion.velocity(t) > 0.0)
    f = q2_drive_force(s, motion, t)
    assert 2.6 < f.min() and f.max() < 9.2


# ---------------------------------------------------------------- Q2 simulators

#: Readings of the exam motion: nine instants across its forward stroke.
EXAM_TIMES = np.linspace(-0.2, 0.2, 9)

#: Other systems and motions: (system, motion, reading times). "round-trip" reads
#: on both strokes, at least 0.05 s from the reversals, where friction changes sign.
Q2_CASES = {
    "slippery-fast": (Q2System(mass=0.5, k1=20.0, k2=80.0, mu=0.05),
                      SineMotion(amplitude=0.05, omega=10.0), np.linspace(-0.14, 0.14, 7)),
    "heavy-rough-offset": (Q2System(mass=20.0, k1=1000.0, k2=3000.0, mu=0.6),
                           SineMotion(amplitude=0.02, omega=3.0, offset=0.03), np.linspace(-0.5, 0.5, 6)),
    "round-trip": (Q2System(), SineMotion(amplitude=0.03, omega=2.0 * math.pi),
                   np.array([-0.2, -0.05, 0.1, 0.3, 0.4, 0.55, 0.7, 0.95])),
    "no-friction": (Q2System(mu=0.0), SineMotion(amplitude=0.02, omega=4.0), np.linspace(0.0, 0.35, 5)),
}


def q2_errors(result: Q2Result, reference: np.ndarray, *, pointwise: bool) -> np.ndarray:
    """|F_sim − F| relative to F itself (pointwise), or to the largest |F| along the readings."""
    scale = np.abs(reference) if pointwise else np.full_like(reference, np.abs(reference).max())
    return np.abs(result.force - reference) / scale


@pytest.mark.parametrize("backend", BACKENDS)
def test_q2_simulators_need_the_exam_force(backend: str) -> None:
    """Driven along x = X·sin(Ωt) while ẋ > 0, each simulator's drive force is m·ẍ + (k1 + k2)·x + μ·m·g
    at every reading, within 1e-3 of F itself."""
    s, motion = exam_q2()
    result = BACKENDS[backend].drive_q2(s, motion, EXAM_TIMES)
    assert result.status == "ok", result.message
    assert np.allclose(result.times, EXAM_TIMES, rtol=0.0, atol=1e-9)
    reference = q2_drive_force(s, motion, result.times)
    errors = q2_errors(result, reference, pointwise=True)
    assert errors.max() <= FORCE_RTOL, f"[{backend}] F errors {errors}"


@pytest.mark.parametrize("backend", BACKENDS)
def test_q2_simulators_carry_mu_times_their_own_normal_force(backend: str) -> None:
    """The simulators' surface carries N = m·g and their friction is −μ·N while the mass slides forward."""
    s, motion = exam_q2()
    result = BACKENDS[backend].drive_q2(s, motion, EXAM_TIMES)
    assert np.allclose(result.normal, s.normal_force, rtol=FORCE_RTOL, atol=0.0)
    assert np.allclose(result.friction, -s.mu * result.normal, rtol=FORCE_RTOL, atol=0.0)


@pytest.mark.parametrize("name", Q2_CASES)
@pytest.mark.parametrize("backend", BACKENDS)
def test_q2_simulators_follow_other_systems(backend: str, name: str) -> None:
    """For other masses, springs, friction and motions (both strokes included) the simulators' drive
    force is the Lagrange–d'Alembert F(t), friction sign included, within 1e-3 of its largest value."""
    system, motion, times = Q2_CASES[name]
    result = BACKENDS[backend].drive_q2(system, motion, times)
    assert result.status == "ok", result.message
    reference = q2_drive_force(system, motion, result.times)
    errors = q2_errors(result, reference, pointwise=False)
    assert errors.max() <= FORCE_RTOL, f"{name} [{backend}] F errors {errors}"


@pytest.mark.parametrize("backend", BACKENDS)
def test_q2_reading_before_the_start_up_transient_is_refused(backend: str) -> None:
    """With no lead-in the first step has no steady normal force, so the run is not_settled with no F."""
    module = BACKENDS[backend]
    s, motion = exam_q2()
    result = module.drive_q2(s, motion, EXAM_TIMES[:2], module.Q2Settings(lead_in=0.0, max_lead_in=0.0))
    assert result.status == "not_settled"
    assert np.isnan(result.force[0])
