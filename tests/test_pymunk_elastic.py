"""Elastic members (``axial_stiffness``) of redundant structures in the ``pymunk`` backend:
each member stretches on a spring along a groove (:mod:`mechcheck.sim_models.pymunk.members`),
and the reactions and ``N_<link>`` pymunk settles to, read from its own constraints, agree
with the analytic backend's (stiff members: max_strain ≤ 1e-7, so the first-order analytic
answer and pymunk's exact equilibrium differ by less than the settled tolerance), and with
the displacement method written in tests/test_elastic.py, a member's own weight included.
The catalogue's steel bracket, within the small-displacement bound:
tests/test_catalogue_gears.py."""

from __future__ import annotations

from dataclasses import replace

import pytest

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage import LinkMass
from mechcheck.sim_models.linkage_motion import STRAIN_LIMIT
from mechcheck.sim_models.pymunk import backend as pm
from mechcheck.testing import assert_solution_close
from mechcheck.tolerance import rule

from .test_elastic import LOAD, along_bar, bars, displacement_method, loaded_bar_method

THREE = {"A": 2.0e10, "B": 1.0e10, "C": 3.0e10}
FOUR = {"A": 1.0e10, "B": 5.0e10, "C": 1.0e10, "E": 2.0e10}


@pytest.mark.parametrize("stiffness", [THREE, FOUR], ids=["three-bars", "four-bars"])
def test_held_redundant_bars_settle_to_the_analytic_forces(stiffness: dict[str, float]) -> None:
    """Every reaction and member force the analytic backend reports, within the policy."""
    case = Case("bars", bars(dict(stiffness)))
    solution = pm.settle(case)
    assert solution.status == "ok", solution.message
    assert_solution_close(case, solution, complete=True)


def test_three_bars_share_the_load_as_the_displacement_method_says() -> None:
    """N_<bar> from pymunk's springs against the displacement method's hand solution."""
    solution = pm.settle(Case("bars", bars(dict(THREE))))
    assert solution.status == "ok", solution.message
    tol = rule("pymunk", "force", "static")
    size = max(abs(f) for f in LOAD)
    for w, tension in displacement_method(THREE).items():
        assert solution.values[f"N_bar{w}"] == pytest.approx(
            tension, rel=tol.rtol, abs=tol.atol + tol.rtol * size), w


def test_the_constraint_solve_at_the_pose_still_refuses_elastic_members() -> None:
    """Re-posed on the unstretched pose, no member could carry anything: not_applicable."""
    solution = pm.solve_at_pose(Case("bars", bars(dict(THREE))))
    assert solution.status == "not_applicable" and "axial_stiffness" in solution.message


@pytest.mark.parametrize("t", [0.5, 0.25])
def test_a_member_with_its_own_weight_shares_the_load_as_the_displacement_method_says(
        t: float) -> None:
    """Bar B of 20 kg (196 N, a fifth of the load), its centre of mass at its middle or a
    quarter of the way from the wall: the node bears t of its weight, and the bar stretches
    by its whole tension (∫N dx/(E·A)). Each N_<bar> of pymunk's (its spring's tension and
    the weight's share) is the displacement method's (tests/test_elastic.py) within the
    settled tolerance; every reaction the analytic backend's."""
    weight = (0.0, -9.81 * 20.0)
    heavy = replace(bars(dict(THREE)), gravity=(0.0, -9.81),
                    masses=(LinkMass("barB", 20.0, along_bar("B", t), 0.0),))
    case = Case("heavy-bars", heavy)
    solution = pm.settle(case)
    assert solution.status == "ok", solution.message
    tol = rule("pymunk", "force", "static")
    size = max(abs(f) for f in LOAD)
    expected = loaded_bar_method(THREE, "B", t, weight)
    unweighted = displacement_method(THREE)
    assert abs(expected["B"] - unweighted["B"]) > 1e3 * tol.rtol * size  # the weight matters
    for w, tension in expected.items():
        assert solution.values[f"N_bar{w}"] == pytest.approx(
            tension, rel=tol.rtol, abs=tol.atol + tol.rtol * size), w
    assert_solution_close(case, solution, complete=True)


def test_members_that_stretch_past_the_limit_are_not_compared() -> None:
    """E·A of 3e5–9e5 N (strain 1.1e-3, past STRAIN_LIMIT): the displacements are not small,
    and pymunk answers not_applicable, naming the members and its own strain."""
    solution = pm.settle(Case("bars", bars({"A": 6.0e5, "B": 3.0e5, "C": 9.0e5})))
    assert solution.status == "not_applicable", solution.message
    assert "axial_stiffness of barA, barB, barC" in solution.message
    assert float(solution.diagnostics["max_strain"]) > STRAIN_LIMIT
