"""Redundant structures with elastic members (``axial_stiffness``) settled in MuJoCo: each
member is two bodies on a slide held by a soft tendon equality of E·A/L
(sim_models/mujoco/linkage_members.py). Its reactions and each member's N (the equality's
force, MuJoCo's own) against the analytic backend, and against the displacement method
written in tests/test_elastic.py; where the members stretch more, within the policy's
small-displacement bound (MuJoCo settles to the exact equilibrium on the stretched members,
the analytic answer is the linear one)."""

from __future__ import annotations

from dataclasses import replace

import mujoco
import numpy as np
import pytest

import mechcheck
from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage import LinkMass
from mechcheck.sim_models.linkage_motion import STRAIN_LIMIT
from mechcheck.sim_models.mujoco.linkage_rig import LinkageRig
from mechcheck.tables import comparison_rows
from mechcheck.testing import assert_solution_close
from mechcheck.tolerance import STRAIN_FACTOR, rule
from tests.test_elastic import along_bar, bars, displacement_method, loaded_bar_method

RTOL = rule("mujoco", "force", "static").rtol

#: Steel-like members stiff enough that the analytic backend's max_strain is ≤ 1e-8.
STIFF = [
    {"A": 2.0e11, "B": 1.0e11, "C": 3.0e11},
    {"A": 1.0e11, "B": 5.0e10, "C": 1.0e11, "E": 2.0e10},
]


@pytest.mark.parametrize("stiffness", STIFF, ids=["three-bars", "four-bars"])
def test_mujoco_settles_redundant_bars_as_the_analytic_backend(stiffness: dict[str, float]) -> None:
    """Every quantity the analytic backend reports, N_<bar> among them, within the policy's
    settled tolerance; MuJoCo's own largest strain is the analytic one."""
    case = Case("bars", bars(dict(stiffness)))
    reference = mechcheck.solve(case)
    assert reference.diagnostics["max_strain"] <= STRAIN_LIMIT
    sim = mechcheck.solve(case, "mujoco")
    assert_solution_close(case, sim, reference, complete=True)
    assert sim.diagnostics["max_strain"] == pytest.approx(reference.diagnostics["max_strain"],
                                                          rel=1e-4)


def test_mujoco_bars_carry_the_displacement_methods_forces() -> None:
    """Three bars of E·A 2e11, 1e11, 3e11 N: each bar's N_<bar> is the displacement method's
    (K_node·u = P, N = (E·A/L)·e·u) within the settled tolerance of the load (1000 N)."""
    stiffness = STIFF[0]
    sim = mechcheck.solve(Case("bars", bars(dict(stiffness))), "mujoco")
    assert sim.status == "ok", sim.message
    for w, tension in displacement_method(stiffness).items():
        assert sim.values[f"N_bar{w}"] == pytest.approx(tension, rel=RTOL, abs=RTOL * 1000.0), w


@pytest.mark.parametrize("t", [0.5, 0.25])
def test_a_member_with_its_own_weight_shares_the_load_as_the_displacement_method_says(
        t: float) -> None:
    """Bar B of 20 kg, its centre of mass at its middle or a quarter of the way from the wall:
    each N_<bar> MuJoCo reads (its equality's force, less the weight's share off the middle)
    is the displacement method's with the weight's lever-rule share at the node; every
    reaction the analytic backend's."""
    stiffness = STIFF[0]
    heavy = replace(bars(dict(stiffness)), gravity=(0.0, -9.81),
                    masses=(LinkMass("barB", 20.0, along_bar("B", t), 0.0),))
    case = Case("heavy-bars", heavy)
    sim = mechcheck.solve(case, "mujoco")
    assert sim.status == "ok", sim.message
    for w, tension in loaded_bar_method(stiffness, "B", t, (0.0, -9.81 * 20.0)).items():
        assert sim.values[f"N_bar{w}"] == pytest.approx(tension, rel=RTOL, abs=RTOL * 1000.0), w
    assert_solution_close(case, sim, complete=True)


def test_a_member_is_a_spring_of_its_stiffness() -> None:
    """The member's equality, after settling, holds a force of E·A/L per metre of its own
    stretch (efc_pos): MuJoCo's soft constraint is the member's spring, not a fitted one."""
    stiffness = STIFF[0]
    case = Case("bars", bars(dict(stiffness)))
    rig = LinkageRig(case)
    m, d = rig.model, rig.data
    for _ in range(2000):
        mujoco.mj_kinematics(m, d)
        rig.apply_loads()
        mujoco.mj_forward(m, d)
        mujoco.mj_Euler(m, d)
    mujoco.mj_forward(m, d)
    rows = rig.member_rows
    measured = d.efc_force[rows] / d.efc_pos[rows]
    lengths = [float(np.hypot(*np.subtract((1.2, 0.9), p))) for p in ((0.0, 0.0), (0.0, 0.8),
                                                                        (0.0, 2.0))]
    expected = [-stiffness[w] / length for w, length in zip("ABC", lengths, strict=True)]
    assert measured == pytest.approx(expected, rel=1e-4)


def test_members_that_stretch_more_are_compared_within_the_small_displacement_bound() -> None:
    """E·A of 1e7–3e7 N (strain 3.3e-5): MuJoCo's exact equilibrium is off the linear answer
    by more than the settled tolerance, and within it plus the policy's small-displacement
    bound (STRAIN_FACTOR × max_strain), which the comparison rows say."""
    case = Case("bars", bars({"A": 2.0e7, "B": 1.0e7, "C": 3.0e7}))
    reference, sim = mechcheck.solve(case), mechcheck.solve(case, "mujoco")
    assert sim.status == "ok", sim.message
    assert float(sim.diagnostics["max_strain"]) > 1e-5
    rows = comparison_rows(case, reference, sim)
    assert max(float(str(r["rel_err"])) for r in rows) > RTOL
    assert_solution_close(case, sim, complete=True)
    widened = [r for r in rows if "small-displacement bound" in str(r["reason"])]
    assert len(widened) == len(rows)
    expected = RTOL + STRAIN_FACTOR * float(reference.diagnostics["max_strain"])
    assert float(str(widened[0]["tolerance"])) == pytest.approx(expected, rel=1e-12)


def test_the_exact_solve_still_refuses_elastic_redundancy() -> None:
    """``mujoco_solve`` gives rigid constraint forces: it keeps its refusal."""
    sim = mechcheck.solve(Case("bars", bars(dict(STIFF[0]))), "mujoco_solve")
    assert sim.status == "not_applicable" and "axial_stiffness" in sim.message
