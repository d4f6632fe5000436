"""Singular poses: the condition number, the withheld forces and the 1/δ growth near a toggle."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings

from mechcheck.analytic.case import Case
from mechcheck.analytic.kinematics import pose_of
from mechcheck.analytic.presets import redrawn

from .builtin import builtin
from .closed_form import forces, superposition, virtual_work
from .closed_form.equilibrium import SINGULAR_CONDITION, coefficient_matrix, eliminate, known_vector
from .strategies import cases

#: Two routes to the same linear solve differ by rounding amplified by the
#: condition number (< 1e4 here): 1e4 × 2.2e-16 ≈ 2e-12 ≪ 1e-9.
ROUTE_RTOL = 1e-9


@settings(max_examples=60, deadline=None)
@given(cases(friction=False))
def test_block_elimination_equals_the_full_matrix_solve(case: Case) -> None:
    """Solving the nine member equations whole (np.linalg.solve) gives the block elimination's answer."""
    pose = pose_of(case)
    b = known_vector(case, pose)
    whole = np.linalg.solve(coefficient_matrix(case, pose), -b[..., None])[..., 0]
    fast = eliminate(case, pose, b)
    scale = np.abs(whole).max() * max(1.0, case.scale)
    assert np.allclose(fast, whole, rtol=0, atol=ROUTE_RTOL * scale)


def test_change_point_is_singular_in_every_backend() -> None:
    """At the seed four-bar's change point (θ12 = 180°) no backend prints forces."""
    case = builtin("fourbar-change-point")
    for backend in (forces, superposition, virtual_work):
        s = backend.solve(case)
        assert s.status == "singular", backend.__name__
        assert not any(q.startswith(("F", "T")) for q in s.values)
    assert forces.solve(case).diagnostics["condition_number"] > SINGULAR_CONDITION


@pytest.mark.parametrize("delta_deg", [0.1, 0.01, 0.001])
def test_forces_grow_like_one_over_delta_near_the_change_point(delta_deg: float) -> None:
    """Approaching θ12 = 180° by δ, the condition number and the coupler force grow like 1/δ.

    For this change point the coupler and rocker straighten with an angle
    γ ≈ k·δ between them, so cond ≈ 2/γ and |F34| ∝ 1/γ: the products
    cond·δ and |F34|·δ tend to constants. Each δ is compared with a ten
    times larger one; the ratio of the products must be 1 within 5 % (the
    next term of the expansion is O(δ): 3.4 % between δ = 1° and 0.1°, hence
    δ ≤ 0.1° here). The drive torque stays bounded: the crank is not in line
    with the coupler, so the huge F23 passes close to A0.
    """
    case = builtin("fourbar-change-point")
    d = math.radians(delta_deg)
    near, far = (forces.solve(redrawn(case, theta12=math.pi - x)) for x in (d, 10 * d))
    c_near = float(near.diagnostics["condition_number"]) * d
    c_far = float(far.diagnostics["condition_number"]) * 10 * d
    assert c_near / c_far == pytest.approx(1.0, rel=0.05)
    f_near = math.hypot(near.values["F34_x"], near.values["F34_y"]) * d
    f_far = math.hypot(far.values["F34_x"], far.values["F34_y"]) * 10 * d
    assert f_near / f_far == pytest.approx(1.0, rel=0.05)
