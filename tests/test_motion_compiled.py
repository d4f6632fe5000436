"""The trajectory reference's compiled right-hand side (``analytic/_fast/``, numba) is the
numpy one it replaces: from the same last state, the same positions, rates, accelerations,
efforts and power to rounding, on the built-in trajectory cases and on random linkages with
loads, damped springs and viscous joints; and a whole run of Andrews' squeezer gives the
same trajectory either way. Without numba (or switched off) the numpy path runs alone."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings, strategies as st

import mechcheck
from mechcheck.analytic import _fast, linkage_dynamics as dynamics
from mechcheck.analytic._fast import motion
from mechcheck.analytic.case import Case
from mechcheck.analytic.trajectory import simulate
from mechcheck.analytic.values import CaseError
from mechcheck.casefile import load_cases, parse_cases
from mechcheck.tolerance import rule

from .strategies import linkage_tables
from .test_trajectory_engine import n_four_bar, trajectory_table

pytest.importorskip("numba")

TRAJECTORIES = Path(mechcheck.__file__).parent / "cases" / "trajectories"
#: The same equations in the same operations, only the sums of products added in another
#: order (index order against BLAS's): rounding, amplified by the Jacobian's condition.
RTOL = rule("analytic", "force", "static").rtol


def equations(case: Case, *, compiled: bool) -> tuple[dynamics.Equations, np.ndarray]:
    """The case's equations at its initial state y, with or without the kernel."""
    with pytest.MonkeyPatch.context() as m:
        if not compiled:
            m.setattr(motion, "kernel", lambda name: None)
        found, y = dynamics._start(case, dynamics.model_of(case))
        assert (found.kernel is not None) == compiled
    return found, y


def assert_same(a: dynamics.Evaluation, b: dynamics.Evaluation, what: str) -> None:
    """Two evaluations equal to rounding, each array against its own size."""
    pairs = {"q": (a.kinematics.q, b.kinematics.q), "rates": (a.kinematics.rates, b.kinematics.rates),
             "bias": (a.kinematics.bias, b.kinematics.bias),
             "acceleration": (a.acceleration, b.acceleration), "efforts": (a.efforts, b.efforts),
             "power": (np.array([a.work_rate, a.dissipation_rate]),
                       np.array([b.work_rate, b.dissipation_rate]))}
    for name, (x, y) in pairs.items():
        np.testing.assert_allclose(x, y, rtol=0, atol=RTOL * max(np.abs(y).max(initial=0.0), 1e-300),
                                   err_msg=f"{what}: {name}")


def compare_along(case: Case, steps: int = 4) -> None:
    """From the initial state, a few states along the motion (each closed from the last, as
    the integrator asks them): the kernel's and the numpy path's evaluations agree, and
    the kernel took them."""
    fast, y = equations(case, compiled=True)
    slow, _ = equations(case, compiled=False)
    taken = 0
    for k in range(steps):
        t = 1e-4 * k
        a, b = fast.at(t, y), slow.at(t, y)
        taken += isinstance(a.kinematics.solver, dynamics._Inverted)
        assert_same(a, b, f"{case.name} at step {k}")
        y = y + 1e-4 * fast.rhs(t, y)
    assert taken == steps, "the kernel left states to the numpy path"


@pytest.mark.parametrize("name", ["andrews-squeezer", "seed-fourbar-released",
                                  "seed-slidercrank-released"])
def test_the_kernel_evaluates_the_builtin_trajectories_as_numpy_does(name: str) -> None:
    cases = {c.name: c for c in load_cases(*sorted(TRAJECTORIES.glob("*.toml")))}
    compare_along(cases[name])


@settings(max_examples=10, deadline=None,
          suppress_health_check=[HealthCheck.filter_too_much, HealthCheck.too_slow])
@given(table=linkage_tables(friction=False), torque=st.floats(-5.0, 5.0),
       damping=st.sampled_from([0.0, 3.0]), viscous=st.sampled_from([0.0, 0.2]))
def test_the_kernel_evaluates_random_linkages_as_numpy_does(table: dict[str, Any], torque: float,
                                                            damping: float, viscous: float) -> None:
    """Random four-bars, slider-cranks and six-bars driven by a torque, with and without
    damped springs and a viscous pin (the energy test's linkages, tests/strategies.py)."""
    try:
        case = parse_cases({"case": [trajectory_table(table, torque, damping, viscous)]},
                           "random")[0][0]
        compare_along(case)
    except (CaseError, dynamics.DynamicsError):   # refused, or locked at its start
        assume(False)


def test_a_run_of_andrews_squeezer_is_the_same_either_way() -> None:
    """The whole run to 0.03 s: the same right-hand sides, so the same steps and positions."""
    (case,) = load_cases(TRAJECTORIES / "andrews.toml")
    (fast,) = simulate(case)
    with pytest.MonkeyPatch.context() as m:
        m.setattr(motion, "kernel", lambda name: None)
        (slow,) = simulate(case)
    assert fast.steps == slow.steps
    scale = case.linkage.scale
    np.testing.assert_allclose(fast.coordinates, slow.coordinates, rtol=0, atol=RTOL * scale)


def test_the_kernel_hands_nearly_singular_states_to_the_numpy_path(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Where the Jacobian's smallest singular value may be below the bridge's floor, the
    numpy path takes the state (it interpolates the rates along the branch there,
    analytic/motion_bridge.py): with the floor raised above every state's, the kernel takes
    none of a row of parallelograms' states, and the evaluations are the numpy path's."""
    case = n_four_bar(2, 0.8, 9)
    monkeypatch.setattr(dynamics, "SIGMA", 1e3)
    fast, y = equations(case, compiled=True)
    slow, _ = equations(case, compiled=False)
    for k in range(3):
        a, b = fast.at(1e-4 * k, y), slow.at(1e-4 * k, y)
        assert not isinstance(a.kinematics.solver, dynamics._Inverted)
        assert_same(a, b, f"state {k}")
        y = y + 1e-4 * fast.rhs(1e-4 * k, y)


def test_the_environment_switches_the_kernel_off(monkeypatch: pytest.MonkeyPatch) -> None:
    """``MECHCHECK_PURE_PYTHON=1`` (as without numba): no plan, every state by numpy."""
    (case,) = load_cases(TRAJECTORIES / "andrews.toml")
    _fast.kernel.cache_clear()
    monkeypatch.setenv("MECHCHECK_PURE_PYTHON", "1")
    try:
        found, _ = dynamics._start(case, dynamics.model_of(case))
        assert found.kernel is None
    finally:
        _fast.kernel.cache_clear()
