"""The pin in a slot (``kind = "pin_in_slot"``) in pymunk: a groove alone, free to turn
(:mod:`mechcheck.sim_models.pymunk.joint_kinds`), read from its own accumulated impulse.
The slotted lever and a quick-return mechanism held (settled and by the exact constraint
solve), driven, with Coulomb and viscous friction on the slot, swept, and with a driver on
the slot itself: against the hand solution where there is one, else against the analytic
backend through the harness's own comparison, at the policy's tolerances."""

from __future__ import annotations

import ast
import math
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from mechcheck import backends
from mechcheck.analytic.case import Case
from mechcheck.analytic.joint_kinds import KINDS, PIN_IN_SLOT
from mechcheck.analytic.linkage import (
    Driver,
    JointFriction,
    LinearSpring,
    Linkage,
    TorsionSpring,
)
from mechcheck.analytic.linkage_backends import solve
from mechcheck.analytic.solution import Solution
from mechcheck.sim_models.pymunk import _fast, backend as pm, linkage as pl
from mechcheck.sim_models.pymunk.joint_kinds import BUILDERS
from mechcheck.testing import assert_solution_close
from mechcheck.tolerance import rule

from .test_pin_in_slot import quick_return, slotted_lever

BACKENDS = {"pymunk": pm.settle, "pymunk_solve": pm.solve_at_pose}
#: The tolerance family each is judged by (held statics settled, the exact solve).
FAMILY = {"pymunk": "settled", "pymunk_solve": "exact_solve"}
#: Where the crank is turned to in the held and driven cases: away from the drawn pose, so
#: the lever and the slot are not at their drawn angles.
ROTATION = 0.4
OMEGA = 4.0


def case_of(name: str, linkage: Linkage) -> Case:
    return Case(name=name, geometry=linkage)


def slot_driven(value: float = 0.0, velocity: float = 0.0) -> Linkage:
    """The slotted lever moved by a driver on its pin in the slot (the travel of A along the
    slot) instead of on the crank, which now turns freely about O2."""
    return replace(slotted_lever(), drivers=(Driver("A", value, velocity),))


# -- held -------------------------------------------------------------------------------

@pytest.mark.parametrize("backend", BACKENDS)
def test_the_slotted_lever_held_has_the_hand_solution(backend: str) -> None:
    """At the drawn pose (test_pin_in_slot's hand solution): the slot pushes the crank with
    N·n = (−180, 60) N, O4 carries (−80, 60) N, O2 (180, −60) N and the crank's drive
    torque is −6 N·m, within the policy's tolerance of the backend's family; no couple."""
    sim = BACKENDS[backend](case_of("slotted-lever", slotted_lever()))
    assert sim.status == "ok", sim.message
    tol = rule(backend, "force", "static").rtol
    expected = {"F_A_x": -180.0, "F_A_y": 60.0, "F_O4_x": -80.0, "F_O4_y": 60.0,
                "F_O2_x": 180.0, "F_O2_y": -60.0, "Q_O2": -6.0}
    for q, want in expected.items():
        assert sim.values[q] == pytest.approx(want, rel=tol, abs=tol * 180.0), q
    assert "M_A" not in sim.values


@pytest.mark.parametrize("backend", BACKENDS)
def test_the_slotted_lever_held_turned_agrees_with_analytic(backend: str) -> None:
    """The crank turned 0.4 rad: every analytic quantity (settled: tolerance family
    ``settled``; the constraint solve: ``exact_solve``)."""
    case = case_of("slotted-lever-turned", slotted_lever(rotation=ROTATION))
    sim = BACKENDS[backend](case)
    assert backends.REGISTRY[backend].family == FAMILY[backend]
    assert_solution_close(case, sim, complete=True)
    assert sim.diagnostics["method"] == ("settle" if backend == "pymunk" else "constraint_solve")


@pytest.mark.parametrize("backend", BACKENDS)
def test_every_quantity_of_the_slot_is_reported(backend: str) -> None:
    """The pin in a slot's quantities are the analytic side's: F_A_x, F_A_y and its travel
    q_A, and no couple M_A (a prismatic joint's), under the same units."""
    case = case_of("slotted-lever-turned", slotted_lever(rotation=ROTATION))
    sim, ref = BACKENDS[backend](case), solve(case)
    joint = case.linkage.joint("A")
    declared = {*joint.kind.quantities(joint), f"q_{joint.name}"}
    assert declared == {"F_A_x", "F_A_y", "q_A"}
    assert declared <= set(ref.values) and declared <= set(sim.values)
    assert "M_A" not in sim.values
    assert all(sim.unit(q) == ref.unit(q) for q in declared)


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_quick_return_closed_by_the_slot_agrees_with_analytic(backend: str) -> None:
    """The quick-return (masses, gravity, a cutting force on the ram, a prismatic slide): the
    pin in the slot closes its loop; every analytic quantity."""
    case = case_of("quick-return", quick_return())
    assert_solution_close(case, BACKENDS[backend](case), complete=True)


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_quick_return_with_a_spring_agrees_with_analytic(backend: str) -> None:
    """A linear spring (1000 N/m, stretched 5 cm) from the ground to the ram: its S and
    every reaction."""
    spring = LinearSpring("return", (("ground", (0.9, 0.65)), ("ram", (0.5, 0.65))), 1000.0, 0.35)
    case = case_of("quick-return-spring", quick_return(springs=(spring,)))
    assert_solution_close(case, BACKENDS[backend](case), complete=True)


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_free_crank_settles_against_its_spring(backend: str) -> None:
    """No driver: a torsion spring (200 N·m/rad) at O2 holds the crank against the load, and
    the settling finds the equilibrium from the drawn pose (the pin sliding and turning in
    the slot); every analytic quantity."""
    linkage = replace(slotted_lever(), drivers=(), springs=(TorsionSpring("k", "O2", 200.0),))
    case = case_of("slotted-lever-free", linkage)
    assert_solution_close(case, BACKENDS[backend](case), complete=True)


# -- a driver on the slot -----------------------------------------------------------------

@pytest.mark.parametrize("backend", BACKENDS)
def test_a_driver_on_the_slot_has_the_hand_solution(backend: str) -> None:
    """The slotted lever held by a driver on A's travel in the slot (the crank free about
    O2). The slot passes through O4, so the driver's force Q·u has no moment about O4 and
    the slot's normal force is the hand solution's N·n = (−180, 60) N; the free crank takes
    no moment about O2, so the force on it at A, N·n + Q·u with u = (1, 3)/√10, is
    horizontal: 60 + 3Q/√10 = 0, Q = −20√10 N; then O2 carries −(N·n + Q·u) = (200, 0) N and
    O4 −((200, 0) + (−100, 0)) = (−100, 0) N."""
    sim = BACKENDS[backend](case_of("slot-driven", slot_driven()))
    assert sim.status == "ok", sim.message
    tol = rule(backend, "force", "static").rtol
    expected = {"Q_A": -20.0 * math.sqrt(10.0), "F_A_x": -180.0, "F_A_y": 60.0,
                "F_O2_x": 200.0, "F_O2_y": 0.0, "F_O4_x": -100.0, "F_O4_y": 0.0}
    for q, want in expected.items():
        assert sim.values[q] == pytest.approx(want, rel=tol, abs=tol * 200.0), q


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_driver_on_the_slot_moved_agrees_with_analytic(backend: str) -> None:
    """The driver holds A 3 cm along the slot: every analytic quantity, its effort Q_A a
    force along the slot."""
    case = case_of("slot-driven-moved", slot_driven(0.03))
    sim = BACKENDS[backend](case)
    assert_solution_close(case, sim, complete=True)
    assert sim.unit("Q_A") == "N"


def test_a_driver_on_the_slot_moving_agrees_with_analytic() -> None:
    """The slot's driver moving at 0.2 m/s: driven (dynamic tolerance)."""
    case = case_of("slot-driven-moving", slot_driven(0.03, 0.2))
    sim = pm.settle(case)
    assert_solution_close(case, sim, complete=True)
    assert sim.diagnostics["method"] == "driven"


# -- driven, and friction on the slot -----------------------------------------------------

def test_the_slotted_lever_driven_agrees_with_analytic() -> None:
    """The crank turning at 4 rad/s: driven through its motion, every analytic quantity
    within the policy's dynamic tolerance."""
    case = case_of("slotted-lever-driven", slotted_lever(rotation=ROTATION, velocity=OMEGA))
    sim = pm.settle(case)
    assert case.kind == "dynamic"
    assert_solution_close(case, sim, complete=True)
    assert sim.diagnostics["method"] == "driven"


def test_a_quick_return_driven_agrees_with_analytic() -> None:
    """The quick-return at 4 rad/s, its links' inertia in the reactions: every analytic
    quantity within the dynamic tolerance."""
    case = case_of("quick-return-driven", quick_return(velocity=OMEGA))
    sim = pm.settle(case)
    assert_solution_close(case, sim, complete=True)
    assert sim.diagnostics["method"] == "driven"


FRICTION = {"coulomb": JointFriction(mu=0.0, joint_mu={"A": 0.2}),
            "viscous": JointFriction(mu=0.0, viscous={"A": 30.0})}


@pytest.mark.parametrize("kind", FRICTION)
def test_friction_on_the_slot_agrees_with_analytic(kind: str) -> None:
    """μ = 0.2 (μ·|N| along the slot) or c = 30 N·s/m on the pin in the slot, the crank at
    4 rad/s: every analytic quantity within the friction tolerance, the slot's force F_A
    including its friction; and the friction is felt (the drive torque moves by more than
    ten tolerances from the frictionless one)."""
    case = case_of(f"slotted-lever-{kind}",
                   slotted_lever(rotation=ROTATION, velocity=OMEGA, friction=FRICTION[kind]))
    sim = pm.settle(case)
    assert case.kind == "friction"
    assert_solution_close(case, sim, complete=True)
    bare = solve(case_of("bare", slotted_lever(rotation=ROTATION, velocity=OMEGA)))
    tol = rule("pymunk", "torque", "friction").rtol
    assert abs(sim.values["Q_O2"] - bare.values["Q_O2"]) > 10.0 * tol * abs(bare.values["Q_O2"])


def test_coulomb_friction_on_the_slot_at_rest_is_driven_slowly() -> None:
    """A static case with Coulomb friction on the slot (the crank about to turn in +θ): the
    quasi-static drive, every analytic quantity within the friction tolerance."""
    case = case_of("slotted-lever-coulomb-static",
                   slotted_lever(rotation=ROTATION, sense=1, friction=FRICTION["coulomb"]))
    sim = pm.settle(case)
    assert_solution_close(case, sim, complete=True)
    assert sim.diagnostics["method"] == "driven"


# -- sweeps, and the compiled loop ----------------------------------------------------------

@pytest.mark.parametrize("backend", BACKENDS)
def test_a_sweep_of_the_slotted_lever_agrees_pose_by_pose(backend: str) -> None:
    """The crank swept from −40° to 80° in one Space (warm-started from pose to pose): each
    pose as its own case through the analytic backend."""
    case = case_of("slotted-lever-sweep", slotted_lever())
    values = np.radians([-40.0, 0.0, 40.0, 80.0])
    driver = case.linkage.drivers[0]
    for value, sim in zip(values, pm.sweep(case, values, backend), strict=True):
        at = case.with_(geometry=replace(case.linkage, drivers=(replace(driver, value=value),)))
        assert sim.diagnostics["driver"] == value
        assert_solution_close(at, sim, complete=True)


@pytest.mark.parametrize("linkage", [slotted_lever(rotation=ROTATION), quick_return(), slot_driven(0.03)],
                         ids=["slotted-lever", "quick-return", "slot-driven"])
@pytest.mark.parametrize("backend", ["settle", "solve_at_pose"])
def test_the_compiled_loop_reads_the_slot_as_python_does(linkage: Linkage, backend: str,
                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    """The compiled loop reads the groove's (and a held slot's) impulse cells the Python
    loop reads: the same steps and the same forces, bit for bit."""
    assert_compiled_is_python(getattr(pl, backend), case_of("compiled", linkage), monkeypatch)


def assert_compiled_is_python(run: Callable[[Case], Solution], case: Case,
                              monkeypatch: pytest.MonkeyPatch) -> None:
    """``run`` (a pymunk backend) gives the same steps and values, bit for bit, with the
    compiled loop and with the Python loop."""
    pytest.importorskip("numba")
    assert _fast.available()
    fast = run(case)
    monkeypatch.setattr(_fast, "available", lambda: False)
    slow = run(case)
    assert fast.status == slow.status == "ok"
    assert fast.diagnostics["steps"] == slow.diagnostics["steps"]
    assert fast.values == slow.values


# -- the one place ----------------------------------------------------------------------------

def test_every_builder_is_of_a_kind_the_engine_knows() -> None:
    """Each pymunk builder builds a kind a case file may name; a kind without one is refused
    by name (tests/test_sim_kinds.py)."""
    assert set(BUILDERS) <= set(KINDS) and {"revolute", "prismatic", "pin_in_slot"} <= set(BUILDERS)


def test_only_the_builders_ask_what_kind_a_joint_is() -> None:
    """No pymunk module but joint_kinds.py tests ``kind.pins``, ``kind.rotates`` or a kind's
    name: build and read-out decisions are the builders'."""
    folder = Path(pl.__file__).parent
    for path in folder.rglob("*.py"):
        if path.name == "joint_kinds.py":
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.Attribute) and node.attr in ("pins", "rotates", "freedoms"):
                assert not (isinstance(node.value, ast.Attribute) and node.value.attr == "kind"), \
                    f"{path.name}:{node.lineno}"
        assert "PIN_IN_SLOT" not in path.read_text(encoding="utf-8"), path.name
    assert PIN_IN_SLOT.name in BUILDERS
