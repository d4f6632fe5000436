"""Identities of the generic linkage engine over random assemblable linkages (hypothesis):
four-bars, slider-cranks, Watt and Stephenson six-bars, with loads, masses, gravity,
springs, motion and friction."""

from __future__ import annotations

import copy
import math
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings, strategies as st

from mechcheck import load_cases
from mechcheck.analytic.case import Case, CaseError
from mechcheck.analytic.linkage_backends import solve, superposition, virtual_work
from mechcheck.analytic.solution import FORCE_FLOOR_N
from mechcheck.casefile import linkage_case
from mechcheck.linkage_file import LinkageCaseSpec

from .strategies import MAX_CONDITION, linkage_tables
from .test_linkage_against_reference import LINKAGES, assert_agree

SETTINGS = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])


def case_of(table: dict[str, Any]) -> Case:
    """The table as a Case; tables the contract refuses, or poses near a toggle, are skipped."""
    try:
        case = linkage_case(LinkageCaseSpec.model_validate(table))
    except CaseError:
        assume(False)
        raise
    solution = solve(case)
    assume(solution.status == "ok")
    assume(float(solution.diagnostics["condition_number"]) < MAX_CONDITION)
    return case


@SETTINGS
@given(linkage_tables(friction=False))
def test_random_linkages_equal_the_independent_reference(table: dict[str, Any]) -> None:
    """The engine and the Lagrange-multiplier reference agree (1e-9) on random linkages."""
    assert_agree(case_of(table), table)


@SETTINGS
@given(linkage_tables(friction=True))
def test_random_linkages_with_friction_equal_the_independent_reference(table: dict[str, Any]) -> None:
    """With friction circles at random pins, the Coulomb iteration agrees with the reference."""
    assert_agree(case_of(table), table)


@SETTINGS
@given(linkage_tables(friction=False))
def test_virtual_work_and_superposition_equal_the_matrix_method(table: dict[str, Any]) -> None:
    """The power equation and the sum of single-load solutions give the matrix method's
    driver effort (and superposition every reaction), to rounding."""
    case = case_of(table)
    matrix = solve(case)
    scale = max(abs(v) for q, v in matrix.values.items() if q[:2] in ("F_", "Q_", "S_")) or 1.0
    for other in (virtual_work(case), superposition(case)):
        assert other.status == "ok"
        for q, v in other.values.items():
            assert abs(v - matrix.values[q]) <= 1e-9 * max(scale, 1.0) * max(1.0, case.linkage.scale)


def transformed(table: dict[str, Any], angle: float, shift: tuple[float, float],
                factor: float = 1.0) -> dict[str, Any]:
    """The same linkage drawn rotated by ``angle``, moved by ``shift`` and its lengths
    written ``factor`` times larger (with ``length_unit`` saying so)."""
    c, s = math.cos(angle), math.sin(angle)

    def point(p: list[float]) -> list[float]:
        return [factor * (c * p[0] - s * p[1] + shift[0]), factor * (s * p[0] + c * p[1] + shift[1])]

    def vector(v: list[float]) -> list[float]:
        return [c * v[0] - s * v[1], s * v[0] + c * v[1]]

    out = copy.deepcopy(table)
    out["points"] = {n: point(p) for n, p in table["points"].items()}
    for joint in out["joints"]:
        if "axis" in joint:
            joint["axis"] = vector(joint["axis"])
    for load in out["loads"]:
        load["at"] = point(load["at"])
        fx, fy = vector([load["force"]["x"], load["force"]["y"]])
        load["force"] = {"x": fx, "y": fy}
    for mass in out.get("masses", []):
        mass["com"] = point(mass["com"])
    out["gravity"] = vector(table["gravity"])
    for spring in out.get("springs", []):
        if "ends" in spring:
            spring["ends"] = [[link, p if isinstance(p, str) else point(p)] for link, p in spring["ends"]]
            spring["free_length"] = factor * spring["free_length"]
    if factor != 1.0:
        out["length_unit"] = "mm"
    return out


@SETTINGS
@given(linkage_tables(friction=False), st.floats(-3.0, 3.0))
def test_rotating_and_moving_the_drawing_rotates_the_answer(table: dict[str, Any],
                                                            angle: float) -> None:
    """Drawn rotated by α and moved: every reaction turns by α, efforts and spring forces
    stay, and every link's rotation from the drawn pose stays."""
    case = case_of(table)
    base = solve(case)
    turned = solve(case_of(transformed(table, angle, (0.7, -0.4))))
    c, s = math.cos(angle), math.sin(angle)
    # Measured against the policy's force floor where every force is zero (a README test
    # command draw: springs at their free length, no load; the moved drawing's spring read
    # 4.7e-16 N of rounding against an exact 0).
    scale = max(max(abs(v) for q, v in base.values.items() if q[:2] in ("F_", "Q_", "S_", "M_")),
                FORCE_FLOOR_N)
    for q, v in base.values.items():
        got = turned.values[q]
        if q.startswith("F_") and q.endswith("_x"):
            fx, fy = v, base.values[q[:-1] + "y"]
            assert got == pytest.approx(c * fx - s * fy, abs=1e-9 * scale)
            assert turned.values[q[:-1] + "y"] == pytest.approx(s * fx + c * fy, abs=1e-9 * scale)
        elif q[:2] in ("Q_", "S_", "M_"):
            assert got == pytest.approx(v, abs=1e-9 * scale * max(1.0, case.linkage.scale))
        elif base.unit(q) == "deg":
            assert math.remainder(got - v, math.tau) == pytest.approx(0.0, abs=1e-9)


@SETTINGS
@given(linkage_tables(friction=False))
def test_millimetres_are_metres(table: dict[str, Any]) -> None:
    """The same linkage written in mm gives the same SI numbers."""
    case = case_of(table)
    base = solve(case).values
    in_mm = solve(case_of(transformed(table, 0.0, (0.0, 0.0), factor=1000.0))).values
    scale = max(abs(v) for v in base.values()) or 1.0
    for q, v in base.items():
        assert in_mm[q] == pytest.approx(v, abs=1e-9 * scale)


@SETTINGS
@given(linkage_tables(friction=False, moving=False, springs=False))
def test_forces_are_linear_in_the_loads(table: dict[str, Any]) -> None:
    """Without masses, gravity or springs, doubling every load doubles every reaction and
    effort."""
    table = {**table, "masses": [], "gravity": [0.0, 0.0]}
    doubled = copy.deepcopy(table)
    for load in doubled["loads"]:
        load["force"] = {k: 2 * v for k, v in load["force"].items()}
        load["torque"] = 2 * load["torque"]
    base = solve(case_of(table)).values
    twice = solve(case_of(doubled)).values
    scale = max(abs(v) for q, v in base.items() if q[:2] in ("F_", "Q_")) or 1.0
    for q, v in base.items():
        if q[:2] in ("F_", "Q_", "M_"):
            assert twice[q] == pytest.approx(2 * v, abs=1e-9 * scale)


def test_at_the_equilibrium_pose_the_springs_balance_the_loads() -> None:
    """The released bonnet's equilibrium pose, held there by a driver, needs no effort: its
    strut and hinge spring balance its weight there (1e-9 of the holding torque scale)."""
    cases = {c.name: c for c in load_cases(LINKAGES / "bonnet_counterbalanced.toml")}
    free = solve(cases["bonnet-free"])
    assert free.diagnostics["stable"] == "yes"
    hold = cases["bonnet-hold"]
    held = hold.linkage.drivers[0]
    rotation = free.values[f"q_{held.joint}"]
    from dataclasses import replace

    at_rest = replace(hold, geometry=replace(hold.linkage, drivers=(replace(held, value=rotation),)))
    effort = solve(at_rest).values[f"Q_{held.joint}"]
    assert abs(effort) <= 1e-9 * abs(solve(hold).values[f"Q_{held.joint}"])
    assert np.isfinite(effort)
