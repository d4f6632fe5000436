"""Identities the analytic force analysis must satisfy, over random assemblable cases.

Expected values here are never outputs of the code under test: each test
states an identity (equilibrium, power balance, linearity, invariance) and
checks it.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from hypothesis import given, settings, strategies as st

from mechcheck.analytic.case import Case
from mechcheck.analytic.kinematics import cross, pose_of
from mechcheck.analytic.presets import redrawn
from mechcheck.analytic.solution import quantity_kind

from .closed_form import forces, superposition, virtual_work
from .strategies import cases

#: Identities that are exact in exact arithmetic hold to rounding, amplified
#: by the condition number (< 1e4 in these strategies): 1e4 × 2.2e-16 ≈ 2e-12,
#: so 1e-9 relative leaves a wide margin and still catches any real error.
IDENTITY_RTOL = 1e-9

SETTINGS = settings(max_examples=60, deadline=None)


def close(a: float, b: float, scale: float) -> bool:
    return abs(a - b) <= IDENTITY_RTOL * max(scale, 1e-9)


def force_scale(values: dict[str, float]) -> float:
    return max((abs(v) for q, v in values.items() if quantity_kind(q) == "force"), default=1.0)


def torque_scale(case: Case, values: dict[str, float]) -> float:
    return max([abs(v) for q, v in values.items() if quantity_kind(q) == "torque"]
               + [force_scale(values) * case.scale])


def link_resultants(case: Case, values: dict[str, float]) -> dict[int, tuple[float, float, float]]:
    """Net force (x, y) and moment about A0 on each moving link: all applied, inertia and joint terms."""
    p = pose_of(case)
    joint = {k: v[0] for k, v in p.joints.items()}

    def f(name: str) -> np.ndarray:
        return np.array([values[f"{name}_x"], values[f"{name}_y"]])

    # (force on link, point of application) for each joint force; F_ij acts on j.
    at_14 = joint["B0"] if case.mechanism == "four_bar" else joint["B"]
    contributions = {
        2: [(f("F12"), joint["A0"]), (-f("F23"), joint["A"])],
        3: [(f("F23"), joint["A"]), (-f("F34"), joint["B"])],
        4: [(f("F34"), joint["B"]), (f("F14"), at_14)],
    }
    net = {}
    for link, parts in contributions.items():
        force = sum((fv for fv, _ in parts), np.zeros(2))
        moment = sum(float(cross(r, fv)) for fv, r in parts)
        for ld in (x for x in case.preset.loads if x.link == link):
            r, _, _ = (v[0] for v in p.point(link, ld.at))
            force = force + np.array(ld.force)
            moment += float(cross(r, np.array(ld.force))) + ld.torque
        m = case.preset.mass_of(link)
        if m is not None:
            r, _, acc = (v[0] for v in p.point(link, m.com))
            applied = m.mass * (np.array(case.gravity) - acc)
            force = force + applied
            moment += float(cross(r, applied)) - m.inertia * float(p.links[link].alpha[0])
        if link == case.preset.drive_link:
            moment += values[f"T1{case.preset.drive_link}"]
        if link == 4 and case.mechanism == "slider_crank":
            moment += values["M14"]
        net[link] = (float(force[0]), float(force[1]), moment)
    return net


@SETTINGS
@given(cases(friction=False))
def test_every_link_is_in_equilibrium(case: Case) -> None:
    """ΣF = 0 and ΣM = 0 (D'Alembert, inertia included) on links 2, 3 and 4."""
    values = dict(forces.solve(case).values)
    fs, ts = force_scale(values), torque_scale(case, values)
    for link, (fx, fy, m) in link_resultants(case, values).items():
        assert close(fx, 0.0, fs) and close(fy, 0.0, fs), (link, fx, fy)
        assert close(m, 0.0, ts), (link, m)


@SETTINGS
@given(cases(friction=False))
def test_virtual_work_torque_equals_matrix_method(case: Case) -> None:
    """The power equation's drive torque equals the matrix method's, inertia included."""
    a = forces.solve(case).values
    b = virtual_work.solve(case)
    q = f"T1{case.preset.drive_link}"
    assert b.status == "ok"
    assert close(b.values[q], a[q], torque_scale(case, dict(a)))


@SETTINGS
@given(cases(friction=False))
def test_superposition_equals_matrix_method(case: Case) -> None:
    """The sum of single-load solutions equals the solution under all loads at once."""
    a = dict(forces.solve(case).values)
    b = superposition.solve(case).values
    for q in a:
        scale = torque_scale(case, a) if quantity_kind(q) == "torque" else force_scale(a)
        assert close(b[q], a[q], scale if quantity_kind(q) != "pose" else 1.0), q


def rotated(case: Case, phi: float) -> Case:
    """The whole problem turned by φ about A0: ground, input, loads and gravity."""
    c, s = math.cos(phi), math.sin(phi)

    def turn(v: tuple[float, float]) -> tuple[float, float]:
        return (c * v[0] - s * v[1], s * v[0] + c * v[1])

    return redrawn(case, theta12=case.preset.theta12 + phi, ground_angle=case.preset.ground_angle + phi,
                   gravity=turn(case.gravity),
                   loads=tuple(replace(ld, force=turn(ld.force)) for ld in case.preset.loads))


@SETTINGS
@given(cases(friction=None), st.floats(-math.pi, math.pi))
def test_rotating_the_problem_rotates_the_answer(case: Case, phi: float) -> None:
    """Turning ground, input, loads and gravity by φ turns every reaction by φ and leaves torques alone."""
    a = dict(forces.solve(case).values)
    b = forces.solve(rotated(case, phi)).values
    c, s = math.cos(phi), math.sin(phi)
    fs, ts = force_scale(a), torque_scale(case, a)
    for j in ("12", "23", "34", "14"):
        x, y = a[f"F{j}_x"], a[f"F{j}_y"]
        assert close(b[f"F{j}_x"], c * x - s * y, fs) and close(b[f"F{j}_y"], s * x + c * y, fs)
    for q in (f"T1{case.preset.drive_link}", "M14"):
        if q in a:
            assert close(b[q], a[q], ts), q
    assert abs(math.remainder(b["theta13"] - a["theta13"] - phi, math.tau)) < 1e-9


@SETTINGS
@given(cases(friction=False, dynamic=False, gravity=False), st.floats(-5.0, 5.0))
def test_results_are_linear_in_the_loads(case: Case, k: float) -> None:
    """Without friction, scaling every load by k scales every reaction and the torque by k."""
    a = dict(forces.solve(case).values)
    scaled = redrawn(case, loads=tuple(replace(ld, force=(k * ld.force[0], k * ld.force[1]),
                                               torque=k * ld.torque) for ld in case.preset.loads))
    b = forces.solve(scaled).values
    for q, v in a.items():
        if quantity_kind(q) == "pose":
            continue
        scale = torque_scale(case, a) if quantity_kind(q) == "torque" else force_scale(a)
        assert close(b[q], k * v, abs(k) * scale + 1e-12), q


@SETTINGS
@given(cases(friction=True, dynamic=None))
def test_friction_never_lowers_the_input_power(case: Case) -> None:
    """With friction the drive supplies at least the frictionless input power (friction only dissipates)."""
    with_f = forces.solve(case)
    without = forces.solve(redrawn(case, friction=None))
    q = f"T1{case.preset.drive_link}"
    speed = float(pose_of(case, omega=float(case.preset.input_sense)).links[case.preset.drive_link].omega[0])
    power_f, power_0 = with_f.values[q] * speed, without.values[q] * speed
    assert power_f >= power_0 - IDENTITY_RTOL * torque_scale(case, dict(without.values))


def test_mm_input_equals_m_input() -> None:
    """A case written in mm and the same case in m give the same SI results."""
    from mechcheck.casefile import parse_cases

    def doc(unit: str, k: float) -> dict[str, object]:
        return {"case": [{
            "name": f"c-{unit}", "mechanism": "slider_crank", "length_unit": unit,
            "theta12": 40.0, "geometry": {"a2": 0.06 * k, "a3": 0.2 * k, "offset": 0.01 * k},
            "loads": [{"link": 3, "at": [0.05 * k, 0.01 * k], "force": {"x": 3.0, "y": -20.0}}],
            "masses": [{"link": 3, "mass": 0.5, "com": [0.1 * k, 0.0], "inertia": 1e-3}],
            "motion": {"omega": 12.0, "alpha": 3.0}, "gravity": [0.0, -9.81],
            "friction": {"mu": 0.1, "pin_radius": {"A": 0.01 * k}, "slide_mu": 0.05},
        }]}

    (m_case, _), = parse_cases(doc("m", 1.0), "m.toml")
    (mm_case, _), = parse_cases(doc("mm", 1000.0), "mm.toml")
    a, b = forces.solve(m_case).values, forces.solve(mm_case).values
    for q in a:
        assert b[q] == np.float64(a[q]) or abs(b[q] - a[q]) <= 1e-12 * max(1.0, abs(a[q])), q

