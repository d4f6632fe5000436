"""What a simulator has no model of is refused by name, never guessed: a kind of joint it
does not build (a kind the engine knows and no simulator has an entry for: how a new kind
lands in the engine first), and a redundant linkage whose forces its members' stretch
decides (the simulators' bodies are rigid). Each backend says ``not_applicable`` with the
reason, at one pose and along a sweep."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

import mechcheck
from mechcheck.analytic.case import Case
from mechcheck.analytic.joint_kinds import PIN_IN_SLOT
from mechcheck.analytic.joint_kinds.pin_in_slot import PinInSlot

from .test_elastic import bars
from .test_pin_in_slot import slotted_lever

SIMULATORS = ["mujoco", "mujoco_solve", "pymunk", "pymunk_solve"]


class Unbuilt(PinInSlot):
    """A kind the engine solves (a pin in a slot's equations) under a name no simulator
    has an entry for."""

    name = "unbuilt_slot"


@pytest.mark.parametrize("backend", SIMULATORS)
def test_a_kind_without_a_build_is_refused_by_name(backend: str) -> None:
    """A kind without a simulator entry: not_applicable naming the joint and the kind, and
    the analytic backend still solves it."""
    lever = slotted_lever()
    joints = tuple(replace(j, kind=Unbuilt()) if j.kind == PIN_IN_SLOT else j
                   for j in lever.joints)
    case = Case("lever", replace(lever, joints=joints))
    assert mechcheck.solve(case).status == "ok"
    solution = mechcheck.solve(case, backend)
    assert solution.status == "not_applicable"
    assert "joint A is a unbuilt_slot" in solution.message and "analytic" in solution.message
    swept = mechcheck.backends.get(backend).sweeper()(case, np.radians([0.0, 20.0]), backend)
    assert [s.status for s in swept] == ["not_applicable", "not_applicable"]


@pytest.mark.parametrize("backend", SIMULATORS)
def test_a_soft_redundant_structure_is_not_compared_by_any_simulator(backend: str) -> None:
    """Three elastic bars to one node, soft enough (E·A ~ 10⁷ N) that they stretch by about
    10⁻⁴: the analytic backend decides the forces from the stretches to first order; the
    fixed-pose solves cannot stretch them, and the held simulators' exact equilibrium differs
    from the first-order one by more than the policy allows: each says so, none compares.
    (Stiff members are compared: tests/test_mujoco_elastic.py, tests/test_pymunk_elastic.py.)"""
    case = Case("bars", bars({"A": 2.0e7, "B": 1.0e7, "C": 3.0e7}))
    assert math.isfinite(mechcheck.solve(case).values["N_barA"])
    solution = mechcheck.solve(case, backend)
    assert solution.status == "not_applicable" and "axial_stiffness" in solution.message
