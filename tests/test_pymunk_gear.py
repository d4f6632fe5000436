"""The gear mesh (``kind = "gear"``) in pymunk: the tooth contact, a pin joint along the line
of action laid through the pitch point before every solve
(:mod:`mechcheck.sim_models.pymunk.gear_mesh`), read from its own impulse. The external and
the internal pair of tests/test_gear.py under both torque senses, held (settled and by the
exact constraint solve); a planetary train held at carrier angles past a whole turn, swept
in one Space and driven; a pair with masses under gravity, held and driven at 4 rad/s:
against the analytic backend through the harness's own comparison at the policy's
tolerances, and the hand solution of tests/test_gear.py for the external pair."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from mechcheck.analytic.case import Case
from mechcheck.analytic.joint_kinds import GEAR, PRISMATIC, REVOLUTE, GearMesh
from mechcheck.analytic.linkage import Driver, Joint, Link, Linkage, LinkMass, PointLoad
from mechcheck.sim_models.pymunk import backend as pm, linkage as pl
from mechcheck.sim_models.pymunk.joint_kinds import BUILDERS
from mechcheck.testing import assert_solution_close
from mechcheck.tolerance import rule

from .test_gear import TAN20, pair, planetary
from .test_pymunk_pin_in_slot import assert_compiled_is_python

BACKENDS = {"pymunk": pm.settle, "pymunk_solve": pm.solve_at_pose}
OMEGA = 4.0


def case_of(name: str, linkage: Linkage) -> Case:
    return Case(name=name, geometry=linkage)


def heavy_pair(velocity: float = 0.0) -> Linkage:
    """tests/test_gear.py's external pair (the wheel carrying 10 N·m) with a 2 kg pinion and
    a 5 kg wheel whose centres of mass lie off their axes, under gravity, the pinion turned
    0.5 rad (and turning at ``velocity``): the weights' moments change the tooth force."""
    base = pair(10.0)
    return replace(base, drivers=(Driver("Pa", 0.5, velocity),),
                   masses=(LinkMass("pinion", 2.0, (0.01, 0.02), 2e-3),
                           LinkMass("wheel", 5.0, (0.17, -0.03), 2e-2)),
                   gravity=(0.0, -9.81))


def static_planetary(carrier: float) -> Linkage:
    """tests/test_gear.py's planetary train held at ``carrier`` (rad)."""
    return planetary(carrier, velocity=0.0)


# -- held pairs -----------------------------------------------------------------------------

@pytest.mark.parametrize("backend", BACKENDS)
def test_the_external_pair_has_the_hand_solution(backend: str) -> None:
    """tests/test_gear.py's hand solution (T = 10 N·m on the wheel, rb = 100 mm): F_t =
    T/rb = 100 N along t = +y, the radial part tan 20°·100 N pushing the wheel along +x,
    each bearing carrying the tooth force back, Q = T·ra/rb = 5 N·m; within the policy's
    tolerance of the backend's family."""
    sim = BACKENDS[backend](case_of("gear-pair", pair(10.0)))
    assert sim.status == "ok", sim.message
    tol = rule(backend, "force", "static").rtol
    radial = TAN20 * 100.0
    expected = {"F_mesh_t": 100.0, "F_mesh_r": radial, "F_mesh_x": radial, "F_mesh_y": 100.0,
                "F_Pb_x": -radial, "F_Pb_y": -100.0, "F_Pa_x": radial, "F_Pa_y": 100.0}
    for q, want in expected.items():
        assert sim.values[q] == pytest.approx(want, rel=tol, abs=tol * 100.0), q
    assert sim.values["Q_Pa"] == pytest.approx(5.0, rel=rule(backend, "torque", "static").rtol)


@pytest.mark.parametrize("torque", [10.0, -10.0])
@pytest.mark.parametrize("internal", [False, True], ids=["external", "internal"])
@pytest.mark.parametrize("backend", BACKENDS)
def test_a_held_pair_agrees_with_analytic(backend: str, internal: bool, torque: float) -> None:
    """Either pair under either torque sense: every analytic quantity, the radial part
    pushing the gears apart whichever way the torque goes (so the flank in contact is
    the one the torque's sign picks)."""
    case = case_of("pair", pair(torque, internal=internal))
    sim = BACKENDS[backend](case)
    assert_solution_close(case, sim, complete=True)
    assert sim.values["F_mesh_r"] > 0.0
    assert math.copysign(1.0, sim.values["F_mesh_t"]) == math.copysign(1.0, torque)


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_pair_with_masses_under_gravity_agrees_with_analytic(backend: str) -> None:
    """Weights off both axes: every analytic quantity."""
    case = case_of("heavy-pair", heavy_pair())
    assert_solution_close(case, BACKENDS[backend](case), complete=True)


# -- a planetary train --------------------------------------------------------------------

@pytest.mark.parametrize("carrier_deg", [0.0, 100.0, 200.0, 370.0])
@pytest.mark.parametrize("backend", BACKENDS)
def test_a_held_planetary_train_agrees_with_analytic(backend: str, carrier_deg: float) -> None:
    """The line of centres turns with the carrier, past a whole turn: the sun's and the
    ring's tooth forces, the carrier's drive torque (−8 N·m, Willis) and every bearing."""
    case = case_of("planetary", static_planetary(math.radians(carrier_deg)))
    sim = BACKENDS[backend](case)
    assert_solution_close(case, sim, complete=True)
    tol = rule(backend, "torque", "static").rtol
    assert sim.values["Q_O_arm"] == pytest.approx(-8.0, rel=tol)


def test_a_sweep_of_the_planetary_train_agrees_pose_by_pose() -> None:
    """The carrier swept over more than a turn in one Space (the pin re-laid at each pose,
    warm-started from the last): each pose as its own case through the analytic backend."""
    case = case_of("planetary-sweep", static_planetary(0.0))
    values = np.radians([-30.0, 60.0, 150.0, 240.0, 400.0])
    driver = case.linkage.drivers[0]
    for value, sim in zip(values, pm.sweep(case, values, "pymunk_solve"), strict=True):
        at = case.with_(geometry=replace(case.linkage, drivers=(replace(driver, value=value),)))
        assert_solution_close(at, sim, complete=True)


def test_a_driven_planetary_train_agrees_with_analytic() -> None:
    """The carrier turning at 1 rad/s (the sun at 4): driven, every analytic quantity within
    the policy's dynamic tolerance."""
    case = case_of("planetary-driven", planetary(math.radians(100.0), velocity=1.0))
    sim = pm.settle(case)
    assert case.kind == "dynamic"
    assert_solution_close(case, sim, complete=True)
    assert sim.diagnostics["method"] == "driven"


# -- driven pairs ---------------------------------------------------------------------------

@pytest.mark.parametrize("internal", [False, True], ids=["external", "internal"])
def test_a_driven_pair_agrees_with_analytic(internal: bool) -> None:
    """The pinion at 4 rad/s against the wheel's 10 N·m: driven, every analytic quantity."""
    linkage = pair(10.0, internal=internal)
    case = case_of("pair-driven", replace(linkage, drivers=(Driver("Pa", 0.5, OMEGA),)))
    sim = pm.settle(case)
    assert_solution_close(case, sim, complete=True)
    assert sim.diagnostics["method"] == "driven"


def test_a_driven_pair_with_masses_agrees_with_analytic() -> None:
    """The heavy pair at 4 rad/s: the links' inertia and weights in the tooth force, which
    changes along the motion; every analytic quantity within the dynamic tolerance."""
    case = case_of("heavy-pair-driven", heavy_pair(OMEGA))
    sim = pm.settle(case)
    assert case.kind == "dynamic"
    assert_solution_close(case, sim, complete=True)


# -- the compiled loop, the refusal, the registry -----------------------------------------

@pytest.mark.parametrize("linkage", [pair(-10.0, internal=True), heavy_pair(),
                                     static_planetary(math.radians(200.0))],
                         ids=["internal-pair", "heavy-pair", "planetary"])
@pytest.mark.parametrize("backend", ["settle", "solve_at_pose"])
def test_the_compiled_loop_reads_the_mesh_as_python_does(linkage: Linkage, backend: str,
                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    """The pin is re-laid by a callback inside Chipmunk's step, which both loops call, and
    its impulse is read from the same cell: the same steps and forces, bit for bit."""
    assert_compiled_is_python(getattr(pl, backend), case_of("compiled", linkage), monkeypatch)


def sliding_wheel() -> Linkage:
    """The external pair with the wheel on a carriage that slides along the line of
    centres: nothing holds the centre distance, which the analytic mesh takes as drawn."""
    base = pair(10.0)
    return Linkage(
        points=base.points,
        links=(Link("ground", ("Pa",)), Link("pinion", ("Pa",)), Link("carriage", ("Pb",)),
               Link("wheel", ("Pb",))),
        joints=(Joint("Pa", REVOLUTE, ("ground", "pinion"), "Pa"),
                Joint("slide", PRISMATIC, ("ground", "carriage"), "Pb", (1.0, 0.0)),
                Joint("Pb", REVOLUTE, ("carriage", "wheel"), "Pb"),
                Joint("mesh", GEAR, ("pinion", "wheel"), "Pa",
                      mesh=GearMesh(("Pa", "Pb"), (0.05, 0.10)))),
        drivers=(Driver("Pa", 0.5), Driver("slide", 0.0)),
        loads=(PointLoad("wheel", (0.15, 0.0), (0.0, 0.0), 10.0),))


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_mesh_whose_centre_distance_nothing_holds_is_refused_by_name(backend: str) -> None:
    """The tooth contact is the rolling constraint only where the centres are held apart:
    elsewhere not_applicable, naming the joint and why."""
    sim = BACKENDS[backend](case_of("sliding-wheel", sliding_wheel()))
    assert sim.status == "not_applicable"
    assert "joint mesh is a gear whose centre distance" in sim.message
    assert "analytic" in sim.message


def test_pymunk_builds_the_gear_mesh() -> None:
    assert GEAR.name in BUILDERS
