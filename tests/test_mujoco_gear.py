"""The gear mesh (``kind = "gear"``) in the MuJoCo backends: a tendon on the line of action
held at constant length by a tendon equality, its force read from MuJoCo's own constraint
force and site positions, the bearings' reactions from MuJoCo's ``cfrc_int``. Every
comparison is with the analytic backend through the harness's own comparison
(:func:`mechcheck.testing.assert_solution_close`, the policy's tolerances), or with the hand
solution of ``tests/test_gear.py``."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np
import pytest

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage import Driver, Link, Linkage, LinkMass
from mechcheck.analytic.linkage_backends import analytic_results, solution_from, solve
from mechcheck.analytic.solution import Solution
from mechcheck.sim_models.mujoco import backend as _mujoco
from mechcheck.sim_models.mujoco.linkage import sweep_linkage
from mechcheck.sim_models.mujoco.linkage_model import Unbuildable, spanning_tree
from mechcheck.testing import assert_solution_close
from mechcheck.tolerance import rule

from .harness import solver
from .test_gear import pair, pair_by_hand, planetary

settle = solver(_mujoco.settle, "mujoco")
solve_at_pose = solver(_mujoco.solve_at_pose, "mujoco_solve")
BACKENDS = [settle, solve_at_pose]
IDS = ["settled", "exact"]

#: Real masses for the pair (kg, m, kg·m²): centres of mass off the bearings, so that the
#: weights load the bearings and the mesh.
MASSES = (LinkMass("pinion", 1.5, (0.01, 0.0), 0.002), LinkMass("wheel", 6.0, (0.15, 0.02), 0.03))


def case_of(name: str, linkage: Linkage) -> Case:
    return Case(name=name, geometry=linkage)


def method_of(backend: Callable[..., Solution]) -> str:
    return "settle" if backend is settle else "constraint_solve"


def assert_close(case: Case, sim: Solution, method: str) -> None:
    """Within the policy's tolerance of the analytic backend, every quantity it reports
    reported, by the expected method, and MuJoCo raised no warning."""
    assert sim.status == "ok", sim.message
    assert sim.diagnostics["method"] == method, sim.diagnostics
    assert_solution_close(case, sim, solve(case), complete=True)
    assert "warnings" not in sim.diagnostics, sim.diagnostics["warnings"]


# -- the model ---------------------------------------------------------------------------

def test_a_mesh_closes_its_loop_through_the_bearings() -> None:
    """The mesh is never a tree joint: the gears hang on their bearings, the mesh closes
    the loop; a gear held by meshes alone is refused, saying why."""
    tree = spanning_tree(pair(10.0))
    assert [j.name for j in tree.meshes] == ["mesh"]
    assert {t.joint.name for t in tree.tree} == {"Pa", "Pb"} and not tree.closures
    with pytest.raises(Unbuildable, match="link wheel is held by gear meshes alone"):
        spanning_tree(loose_wheel())


def loose_wheel() -> Linkage:
    """The pair with the wheel's bearing taken away: the wheel is held by the mesh alone."""
    linkage = pair(10.0)
    return replace(linkage, points={"Pa": (0.0, 0.0), "Pb": (0.15, 0.0)},
                   links=(Link("ground", ("Pa",)), *linkage.links[1:]),
                   joints=linkage.joints[::2])


# -- hand solutions -------------------------------------------------------------------------

@pytest.mark.parametrize("torque", [10.0, -10.0])
@pytest.mark.parametrize("backend", BACKENDS, ids=IDS)
def test_the_external_pair_has_the_hand_solution(backend: Callable[..., Solution],
                                                  torque: float) -> None:
    """tests/test_gear.py's hand solution: F_t = T/rb, the radial part tan20°·|F_t| pushes
    the wheel along +x whichever way the torque goes, each bearing carries the tooth force
    back and the pinion needs Q = T·ra/rb; within the policy's tolerance of each family."""
    sim = backend(case_of("gear-pair", pair(torque)))
    family = "mujoco" if sim.diagnostics["method"] == "settle" else "mujoco_solve"
    rtol = rule(family, "force", "static").rtol
    for q, want in pair_by_hand(torque).items():
        assert sim.values[q] == pytest.approx(want, rel=rtol, abs=rtol * 100.0), q
    assert sim.values["phi_wheel"] == pytest.approx(-0.25, rel=rtol)


# -- against the analytic backend -----------------------------------------------------------

@pytest.mark.parametrize("torque", [10.0, -10.0])
@pytest.mark.parametrize("internal", [False, True], ids=["external", "internal"])
@pytest.mark.parametrize("backend", BACKENDS, ids=IDS)
def test_a_pair_agrees_with_the_analytic_backend(backend: Callable[..., Solution],
                                                 internal: bool, torque: float) -> None:
    case = case_of("gear-pair", pair(torque, internal=internal))
    assert_close(case, backend(case), method_of(backend))


@pytest.mark.parametrize("carrier_deg", [0.0, 100.0, 200.0, 370.0, 725.0])
@pytest.mark.parametrize("backend", BACKENDS, ids=IDS)
def test_a_planetary_train_agrees_with_the_analytic_backend(backend: Callable[..., Solution],
                                                            carrier_deg: float) -> None:
    """Sun, planet on the carrier and a fixed ring, the carrier held past whole turns: the
    sun's angle, both meshes' tooth forces and every bearing's reaction."""
    case = case_of("planetary", planetary(math.radians(carrier_deg), velocity=0.0))
    sim = backend(case)
    ratio = 1.0 + 0.09 / 0.03
    rtol = rule("mujoco" if backend is settle else "mujoco_solve", "force", "static").rtol
    assert sim.values["phi_sun"] == pytest.approx(math.radians(carrier_deg) * ratio, rel=rtol)
    assert_close(case, sim, method_of(backend))


def test_a_planetary_train_driven() -> None:
    """The carrier driven at 1 rad/s (massless links: the massless limit of two runs)."""
    case = case_of("planetary-driven", planetary(math.radians(100.0)))
    assert_close(case, settle(case), "driven")


@pytest.mark.parametrize("backend", BACKENDS, ids=IDS)
def test_a_pair_with_masses_and_gravity(backend: Callable[..., Solution]) -> None:
    case = case_of("gear-pair-heavy", replace(pair(10.0), masses=MASSES, gravity=(0.0, -9.81)))
    assert_close(case, backend(case), method_of(backend))


@pytest.mark.parametrize("torque", [10.0, -10.0])
def test_a_driven_pair(torque: float) -> None:
    """The pinion driven at 4 rad/s, masses and gravity: the forces at the instant
    (dynamic tolerance), the tendon put back on the line of action at every step."""
    case = case_of("gear-pair-driven", replace(pair(torque), masses=MASSES, gravity=(0.0, -9.81),
                                               drivers=(Driver("Pa", 0.5, 4.0),)))
    assert_close(case, settle(case), "driven")


@pytest.mark.parametrize("backend", ["mujoco", "mujoco_solve"])
def test_a_planetary_sweep(backend: str) -> None:
    """A sweep of the carrier with one model, pose by pose. (At a line of centres turned by
    exactly ±180° the rolled arc q is on either branch of Δθ: the analytic coordinate wraps
    there, so the sweep stays short of it.)"""
    case = case_of("planetary", planetary(0.0, velocity=0.0))
    first = np.radians(np.linspace(0.0, 150.0, 4))
    results = analytic_results(case, first)
    for i, sim in enumerate(sweep_linkage(case, first, backend, results)):
        reference = solution_from(case, "analytic", results, method="analytic", elapsed=0.0,
                                  index=i)
        assert_solution_close(case, sim, reference, complete=True)


def test_a_gear_on_no_bearing_is_refused_with_the_reason() -> None:
    """A wheel held by the mesh alone: both backends refuse, saying why, with no numbers."""
    case = case_of("loose-wheel", loose_wheel())
    for backend in BACKENDS:
        sim = backend(case)
        assert sim.status == "not_applicable" and not sim.values
        assert "held by gear meshes alone" in sim.message
