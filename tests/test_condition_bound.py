"""The general solve's singular verdict from a bound of the condition number.

A linkage without an Assur plan decides each pose's ``singular`` verdict (condition number of
the scaled equilibrium matrix S above 10⁸) from ‖S‖_F·‖S⁻¹‖_F where that bound is below the
threshold, and from the SVD elsewhere. Both norm inequalities, σ_max ≤ ‖S‖_F and
1/σ_min ≤ ‖S⁻¹‖_F, make it an upper bound, so it can only send a pose to the SVD, never give
another verdict: checked here against the SVD's number at every pose of whole sweeps.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import mechcheck
from mechcheck.analytic.linkage_forces import (
    SINGULAR_CONDITION,
    LinkageResults,
    coefficient_entries,
    condition_bound,
    solve_linkage,
)

#: Built-in linkages without an Assur plan: a four-bar drawn on its change point (singular
#: there, with a condition number of about 4.6e16), a cylinder boom, a scissor lift (ten
#: joints) and a Whitworth quick-return (two slides).
NEWTON_CASES = ("fourbar-change-point", "boom-hold-drawn", "scissor-lift-hold", "whitworth-static")


def sweep(name: str) -> LinkageResults:
    """The case's analysis over a whole turn of its driver (±180°), or ±0.4 of the linkage's
    size of travel, in 0.5° or 1 mm-per-metre steps."""
    case = next(c for c in mechcheck.load_cases() if c.name == name)
    linkage = case.linkage
    assert linkage.assur_plan is None
    turns = linkage.joint(linkage.drivers[0].joint).kind.rotates
    grid = np.linspace(-math.pi, math.pi, 721) if turns else np.linspace(-0.4, 0.4, 801) * linkage.scale
    values = np.tile([d.value for d in linkage.drivers], (grid.size, 1))
    values[:, 0] = grid
    return solve_linkage(linkage, values)


@pytest.mark.parametrize("name", NEWTON_CASES)
def test_the_bound_is_above_the_condition_number_where_it_decides(name: str) -> None:
    """At every assembled pose below the threshold by the SVD, ‖S‖_F·‖S⁻¹‖_F ≥ σ_max/σ_min."""
    results = sweep(name)
    pose = results.pose
    bound = condition_bound(pose, coefficient_entries(pose))
    exact = results.condition
    decided = pose.assembled & (exact <= SINGULAR_CONDITION)
    assert decided.sum() > 100
    assert (bound[decided] >= exact[decided]).all()


@pytest.mark.parametrize("name", NEWTON_CASES)
def test_the_verdicts_are_those_of_the_exact_condition_number(name: str) -> None:
    """The singular poses are exactly the assembled ones whose SVD condition number is above
    10⁸ (the change-point four-bar has one: its drawing)."""
    results = sweep(name)
    by_svd = results.pose.assembled & ~(results.condition <= SINGULAR_CONDITION)
    np.testing.assert_array_equal(results.singular, by_svd)
    assert by_svd.any() == (name == "fourbar-change-point")
