"""The pin in a slot (``kind = "pin_in_slot"``) in the MuJoCo backends: a slide along the slot
and a hinge at the pin in the pin's (or the slot's) body, its reaction read from MuJoCo's
own ``cfrc_int``. Every comparison is with the analytic backend through the harness's own
comparison (:func:`mechcheck.testing.assert_solution_close`, the policy's tolerances), or
with the hand solution of ``tests/test_pin_in_slot.py``."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np
import pytest

from mechcheck.analytic.case import Case
from mechcheck.analytic.joint_kinds import KINDS, PIN_IN_SLOT, PRISMATIC, REVOLUTE
from mechcheck.analytic.linkage import (
    Driver,
    Joint,
    JointFriction,
    Link,
    Linkage,
    LinkMass,
    PointLoad,
    TorsionSpring,
)
from mechcheck.analytic.linkage_backends import analytic_results, solution_from, solve
from mechcheck.analytic.solution import Solution
from mechcheck.sim_models.mujoco import backend as _mujoco
from mechcheck.sim_models.mujoco.joint_kinds import BUILDS, builder_of
from mechcheck.sim_models.mujoco.linkage import sweep_linkage
from mechcheck.sim_models.mujoco.linkage_model import Unbuildable, spanning_tree
from mechcheck.testing import assert_solution_close
from mechcheck.tolerance import rule

from .harness import solver
from .test_pin_in_slot import quick_return, slotted_lever

settle = solver(_mujoco.settle, "mujoco")
solve_at_pose = solver(_mujoco.solve_at_pose, "mujoco_solve")

#: Real masses for the driven runs (kg, m, kg·m²): the crank and the slotted lever.
MASSES = (LinkMass("crank", 2.0, (0.05, 0.3), 0.002), LinkMass("lever", 5.0, (0.1, 0.3), 0.08))


def case_of(name: str, linkage: Linkage) -> Case:
    return Case(name=name, geometry=linkage)


def assert_close(case: Case, sim: Solution, method: str) -> None:
    """Within the policy's tolerance of the analytic backend, every quantity it reports
    reported, by the expected method, and MuJoCo raised no warning."""
    assert sim.diagnostics["method"] == method, sim.diagnostics
    assert_solution_close(case, sim, solve(case), complete=True)
    assert "warnings" not in sim.diagnostics, sim.diagnostics["warnings"]


def moving(*, friction: JointFriction | None = None) -> Linkage:
    """The slotted lever driven at 4 rad/s, with masses and gravity."""
    return replace(slotted_lever(velocity=4.0, friction=friction), masses=MASSES,
                   gravity=(0.0, -9.81))


# -- the kind's builder ------------------------------------------------------------------

def test_every_mujoco_build_reports_its_kinds_quantities() -> None:
    """Each builder reports exactly the reaction quantities its analytic kind reports (M only
    where there is a couple); a kind without one is refused by name (test_sim_kinds.py)."""
    assert set(BUILDS) <= set(KINDS)
    for kind in (KINDS[name] for name in BUILDS):
        joint = Joint("J", kind, ("a", "b"), "P", None if kind == REVOLUTE else (1.0, 0.0))
        assert set(builder_of(joint).reaction_names(joint)) == set(kind.quantities(joint))


@pytest.mark.parametrize(("driver", "sign", "order"), [
    ("O2", -1.0, ("hinge", "slide")),   # the lever hangs from the crank's pin
    ("O4", 1.0, ("slide", "hinge")),    # the crank's pin hangs in the lever's slot
])
def test_the_pin_enters_the_tree_and_the_loop_closes_at_a_revolute_joint(
        driver: str, sign: float, order: tuple[str, ...]) -> None:
    """The pin in a slot is a tree joint either way the tree runs (a slide and a hinge of
    its child body, in the order that keeps the slot's axis fixed in links[0]); the loop
    closes at the undriven revolute joint."""
    linkage = replace(slotted_lever(), drivers=(Driver(driver, 0.0),))
    tree = spanning_tree(linkage)
    (slot,) = [t for t in tree.tree if t.joint.name == "A"]
    assert slot.sign == sign
    assert [j.kind for j in tree.closures] == [REVOLUTE]
    kinds = builder_of(slot.joint).joints(slot.joint, slot.sign)
    assert tuple("hinge" if j.turn else "slide" for j in kinds) == order


# -- the slotted lever ---------------------------------------------------------------------

@pytest.mark.parametrize("backend", [settle, solve_at_pose], ids=["settled", "exact"])
def test_the_slotted_lever_has_the_hand_solution(backend: Callable[..., Solution]) -> None:
    """The hand solution of tests/test_pin_in_slot.py: the slot pushes the crank with
    F_A = (−180, 60) N (normal to the slot, no component along it), O4 carries (−80, 60) N
    and the crank's drive torque is −6 N·m; within the policy's tolerance of each family."""
    case = case_of("slotted-lever", slotted_lever())
    sim = backend(case)
    family = "settled" if sim.diagnostics["method"] == "settle" else "exact_solve"
    rtol = rule("mujoco" if family == "settled" else "mujoco_solve", "force", "static").rtol
    expected = {"F_A_x": -180.0, "F_A_y": 60.0, "F_O4_x": -80.0, "F_O4_y": 60.0,
                "F_O2_x": 180.0, "F_O2_y": -60.0, "Q_O2": -6.0}
    for q, want in expected.items():
        assert sim.values[q] == pytest.approx(want, rel=rtol, abs=rtol * 180.0), q
    assert "M_A" not in sim.values, "a pin turns freely in its slot: no couple"
    assert_close(case, sim, "settle" if family == "settled" else "constraint_solve")


@pytest.mark.parametrize("driver", ["O2", "O4"])
def test_held_statics_settle_to_the_analytic_forces(driver: str) -> None:
    """Settled (family ``settled``, static) with either tree orientation of the slot."""
    case = case_of("slotted-lever", replace(slotted_lever(), drivers=(Driver(driver, 0.3),)))
    assert_close(case, settle(case), "settle")


@pytest.mark.parametrize("rotation", np.radians([-40.0, 0.0, 35.0]))
def test_exact_solve_along_the_turn(rotation: float) -> None:
    """The exact solve (family ``exact_solve``) at poses along the crank's turn, moving with
    masses and gravity: the slot's travel q_A and the lever's rotation are MuJoCo's."""
    case = case_of("slotted-lever", replace(moving(), drivers=(Driver("O2", float(rotation), 4.0),)))
    sim = solve_at_pose(case)
    assert abs(sim.values["q_A"]) > 1e-3 or rotation == 0.0  # the pin has moved in its slot
    assert_close(case, sim, "constraint_solve")


def test_driven_at_four_rad_per_second() -> None:
    """Driven through its prescribed motion (ω = 4 rad/s, masses, gravity): the forces at
    the instant, dynamic tolerance."""
    case = case_of("slotted-lever-driven", moving())
    assert_close(case, settle(case), "driven")


FRICTIONS = {"coulomb": JointFriction(joint_mu={"A": 0.2}),
             "viscous": JointFriction(viscous={"A": 3.0})}


def friction_is_felt(case: Case) -> None:
    """The friction changes the drive torque by ten tolerances or more: the
    comparison is not of the frictionless numbers."""
    bare = solve(replace(case, geometry=replace(case.linkage, friction=None)))
    felt = solve(case)
    change = abs(felt.values["Q_O2"] - bare.values["Q_O2"]) / abs(bare.values["Q_O2"])
    assert change > 10.0 * rule("mujoco", "torque", case.kind).rtol


@pytest.mark.parametrize("friction", sorted(FRICTIONS))
@pytest.mark.parametrize("backend", [settle, solve_at_pose], ids=["driven", "exact"])
def test_friction_in_the_slot(friction: str, backend: Callable[..., Solution]) -> None:
    """Coulomb μ·|N| and a viscous −c·q̇ along the slot, driven at 4 rad/s: both are part
    of the slot's reported force F_A (as a prismatic joint's), read from MuJoCo's own
    reactions and joint rate."""
    case = case_of(f"slotted-lever-{friction}", moving(friction=FRICTIONS[friction]))
    friction_is_felt(case)
    sim = backend(case)
    assert_close(case, sim, "driven" if backend is settle else "constraint_solve")


def test_coulomb_friction_held_static_is_a_quasi_static_motion() -> None:
    """A static case with Coulomb friction in the slot (the crank turning up, sense +1) is
    driven slowly by the settling masses and read at the pose (friction tolerance)."""
    case = case_of("slotted-lever-coulomb-static",
                   slotted_lever(friction=FRICTIONS["coulomb"], sense=1))
    friction_is_felt(case)
    assert_close(case, settle(case), "driven")


# -- a driver on the slot ------------------------------------------------------------------

def driven_in_the_slot(velocity: float = 0.0) -> Linkage:
    """The slotted lever held (or moved) by the pin's travel along the slot: its effort
    Q_A is a force along the slot."""
    return replace(moving(), drivers=(Driver("A", 0.02, velocity),),
                   loads=(PointLoad("lever", (0.2, 0.6), (-100.0, 0.0)),
                          PointLoad("crank", (0.1, 0.3), (0.0, -40.0))))


@pytest.mark.parametrize("backend", [settle, solve_at_pose], ids=["settled", "exact"])
def test_a_driver_on_the_slot_held(backend: Callable[..., Solution]) -> None:
    case = case_of("slot-driven-held", driven_in_the_slot())
    sim = backend(case)
    assert abs(sim.values["Q_A"]) > 1.0
    assert_close(case, sim, "settle" if backend is settle else "constraint_solve")


def test_a_driver_on_the_slot_moving() -> None:
    """The pin pushed along the slot at 0.2 m/s: dynamic tolerance."""
    case = case_of("slot-driven-moving", driven_in_the_slot(0.2))
    assert_close(case, settle(case), "driven")


# -- a larger linkage ----------------------------------------------------------------------

@pytest.mark.parametrize("backend", [settle, solve_at_pose], ids=["settled", "exact"])
def test_a_quick_return_held(backend: Callable[..., Solution]) -> None:
    case = case_of("quick-return", quick_return())
    assert {j.name for j in spanning_tree(case.linkage).closures} == {"O4", "C"}
    assert_close(case, backend(case), "settle" if backend is settle else "constraint_solve")


def test_a_quick_return_driven() -> None:
    case = case_of("quick-return-driven", quick_return(velocity=4.0))
    assert_close(case, settle(case), "driven")


@pytest.mark.parametrize("backend", ["mujoco", "mujoco_solve"])
def test_a_quick_return_sweep(backend: str) -> None:
    """A sweep of the crank over 8 angles with one model: every pose within the policy's
    tolerance of the analytic backend there."""
    case = case_of("quick-return", quick_return())
    first = np.radians(np.linspace(-30.0, 60.0, 8))
    results = analytic_results(case, first)
    sims = sweep_linkage(case, first, backend, results)
    for i, sim in enumerate(sims):
        reference = solution_from(case, "analytic", results, method="analytic", elapsed=0.0,
                                  index=i)
        assert_solution_close(case, sim, reference, complete=True)


def test_free_coordinates_settle_through_the_pin() -> None:
    """No driver: a torsional spring at O2 holds the load; MuJoCo settles the crank, the
    lever and the pin's travel and turn in the slot to the analytic equilibrium."""
    case = case_of("slotted-lever-free",
                   replace(slotted_lever(), drivers=(), springs=(TorsionSpring("k", "O2", 200.0),)))
    assert solve(case).values["q_A"] != 0.0   # the equilibrium is not the drawn pose
    assert_close(case, settle(case), "settle")


# -- refused -------------------------------------------------------------------------------

def scotch_yoke() -> Linkage:
    """A crank whose pin slides in the vertical slot of a yoke that slides along x: the loop
    has one revolute joint, and a driver holds it."""
    points = {"O": (0.0, 0.0), "A": (0.1, 0.0), "Y": (0.1, 0.0)}
    return Linkage(
        points=points,
        links=(Link("ground", ("O",)), Link("crank", ("O", "A")), Link("yoke", ("Y",))),
        joints=(Joint("O", REVOLUTE, ("ground", "crank"), "O"),
                Joint("A", PIN_IN_SLOT, ("yoke", "crank"), "A", (0.0, 1.0)),
                Joint("slide", PRISMATIC, ("ground", "yoke"), "Y", (1.0, 0.0))),
        drivers=(Driver("O", 0.5),),
        loads=(PointLoad("yoke", (0.1, 0.0), (-50.0, 0.0)),))


def test_a_loop_it_cannot_close_is_refused_with_the_reason() -> None:
    """A driven crank in a Scotch yoke: the only joint that could close the loop holds a
    driver, which needs a MuJoCo joint: both backends refuse, saying why, with no numbers."""
    case = case_of("scotch-yoke", scotch_yoke())
    assert solve(case).status == "ok"
    with pytest.raises(Unbuildable, match="pin_in_slot, prismatic and driven joints"):
        spanning_tree(case.linkage)
    for backend in (settle, solve_at_pose):
        sim = backend(case)
        assert sim.status == "not_applicable" and not sim.values
        assert "driver at joint O" in sim.message and "tree joint" in sim.message
