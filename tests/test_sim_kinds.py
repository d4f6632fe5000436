"""What a simulator has no model of is refused by name, never guessed: a kind of joint it
does not build (the gear mesh, where it has no build), and a redundant linkage whose forces
its members' stretch decides (the simulators' bodies are rigid). Each backend says
``not_applicable`` with the reason, at one pose and along a sweep, and the run passes."""

from __future__ import annotations

import math

import numpy as np
import pytest

import mechcheck
from mechcheck.analytic.case import Case
from mechcheck.analytic.joint_kinds import GEAR

from .test_elastic import bars
from .test_gear import pair

SIMULATORS = ["mujoco", "mujoco_solve", "pymunk", "pymunk_solve"]


def builds_gears(backend: str) -> bool:
    """Whether the backend's simulator has a build for the gear mesh."""
    if backend.startswith("mujoco"):
        from mechcheck.sim_models.mujoco.joint_kinds import BUILDS
        return GEAR.name in BUILDS
    from mechcheck.sim_models.pymunk.joint_kinds import BUILDERS
    return GEAR.name in BUILDERS


@pytest.mark.parametrize("backend", SIMULATORS)
def test_a_kind_without_a_build_is_refused_by_name(backend: str) -> None:
    """A gear pair where the simulator builds no gear: not_applicable naming the joint."""
    if builds_gears(backend):
        pytest.skip(f"{backend} builds gear meshes (tests/test_*_gear.py)")
    case = Case("pair", pair(10.0))
    solution = mechcheck.solve(case, backend)
    assert solution.status == "not_applicable"
    assert "joint mesh is a gear" in solution.message and "analytic" in solution.message
    swept = mechcheck.backends.get(backend).sweeper()(case, np.radians([0.0, 20.0]), backend)
    assert [s.status for s in swept] == ["not_applicable", "not_applicable"]


@pytest.mark.parametrize("backend", SIMULATORS)
def test_a_redundant_elastic_structure_is_refused_by_every_simulator(backend: str) -> None:
    """Three elastic bars to one node: the analytic backend decides the forces from the
    stretches; a rigid simulator cannot, and says so."""
    case = Case("bars", bars({"A": 2.0e7, "B": 1.0e7, "C": 3.0e7}))
    assert math.isfinite(mechcheck.solve(case).values["N_barA"])
    solution = mechcheck.solve(case, backend)
    assert solution.status == "not_applicable" and "axial_stiffness" in solution.message
