"""Elastic members (``axial_stiffness``) of redundant structures in the ``pymunk`` backend:
each member stretches on a spring along a groove (:mod:`mechcheck.sim_models.pymunk.members`),
and the reactions and ``N_<link>`` pymunk settles to, read from its own constraints, agree
with the analytic backend's (stiff members: max_strain ≤ 1e-7, so the first-order analytic
answer and pymunk's exact equilibrium differ by less than the policy's tolerance), and with
the displacement method written in tests/test_elastic.py."""

from __future__ import annotations

from dataclasses import replace

import pytest

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage import LinkMass
from mechcheck.sim_models.pymunk import backend as pm
from mechcheck.testing import assert_solution_close
from mechcheck.tolerance import rule

from .test_elastic import LOAD, bars, displacement_method

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


def test_a_member_with_its_own_weight_is_refused_with_the_reason() -> None:
    """A member's weight makes its tension vary along it: pymunk's spring carries the end's,
    the analytic stretch the mean's; not_applicable, saying so."""
    linkage = bars(dict(THREE))
    heavy = replace(linkage, masses=(LinkMass("barB", 2.0, (0.6, 0.85), 0.0),),
                    gravity=(0.0, -9.81))
    solution = pm.settle(Case("heavy-bars", heavy))
    assert solution.status == "not_applicable" and "barB" in solution.message
