"""What a simulator has no model of is refused by name, never guessed: a kind of joint it
does not build (a kind the engine knows and no simulator has an entry for: how a new kind
lands in the engine first), and, in a fixed-pose solve, a redundant linkage whose forces its
members' stretch decides (its bodies are rigid). Each backend says ``not_applicable`` with the
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


@pytest.mark.parametrize("backend", ["mujoco_solve", "pymunk_solve"])
def test_a_fixed_pose_solve_does_not_compare_a_redundant_elastic_structure(backend: str) -> None:
    """Three elastic bars to one node (E·A ~ 10⁷ N, strain about 3·10⁻⁵): the analytic backend
    decides the forces from the stretches; a fixed-pose solve holds the drawn, unstretched
    pose, where no member carries anything: it says so and does not compare. (The held
    simulators compare it within the small-displacement bound: tests/test_mujoco_elastic.py,
    tests/test_pymunk_elastic.py.)"""
    case = Case("bars", bars({"A": 2.0e7, "B": 1.0e7, "C": 3.0e7}))
    assert math.isfinite(mechcheck.solve(case).values["N_barA"])
    solution = mechcheck.solve(case, backend)
    assert solution.status == "not_applicable" and "axial_stiffness" in solution.message
