"""Lock positions of any linkage measured in both simulators (issue 12: the turning checks
generalised): each revolute driver, let go of its lock, is turned by a bounded-torque servo
from the drawn pose both ways, the other drivers held, and where it jams is its lock. The
expected values are the analytic driver ranges (:func:`mechcheck.analytic.theory.driver_ranges`,
continuation of the closed-form dyads), a different method from the simulators' forward
dynamics."""

from __future__ import annotations

import math

import pytest

from mechcheck.analytic.theory import driver_ranges
from mechcheck.sim_models.mujoco import locks as mujoco_locks
from mechcheck.sim_models.pymunk import locks as pymunk_locks

from .builtin import builtin_cases

SIMULATORS = {"mujoco": mujoco_locks.driver_locks, "pymunk": pymunk_locks.driver_locks}

#: The issue's target: lock positions within 0.01° of the analytic ones. (Measured: ≤ 3.5e-4°
#: in MuJoCo and ≤ 2e-10° in pymunk on the four-bar, six-bar and five-bar; 7e-4° on the
#: bonnet, where both simulators agree to 1e-5° with each other and the analytic lock
#: search is the coarser one.)
LOCK_TOL_DEG = 0.01

#: The built-in linkages whose revolute drivers lock both ways, with those drivers.
LOCKING = [("locking-fourbar", "O2"), ("bonnet-hold", "G1"), ("watt-ii-demo", "O2"),
           ("five-bar-two-drivers", "O1"), ("five-bar-two-drivers", "O5")]


@pytest.mark.parametrize("simulator", SIMULATORS)
@pytest.mark.parametrize(("name", "joint"), LOCKING)
def test_lock_positions_agree_with_the_analytic_range(simulator: str, name: str,
                                                      joint: str) -> None:
    case = builtin_cases()[name]
    expected = next(r for r in driver_ranges(case.linkage) if r.joint == joint)
    assert expected.low is not None and expected.high is not None
    measured = SIMULATORS[simulator](case, joint)
    assert measured.endings == ("jammed", "jammed")
    assert measured.low is not None and measured.high is not None
    assert math.degrees(measured.low) == pytest.approx(math.degrees(expected.low), abs=LOCK_TOL_DEG)
    assert math.degrees(measured.high) == pytest.approx(math.degrees(expected.high),
                                                        abs=LOCK_TOL_DEG)


@pytest.mark.parametrize("simulator", SIMULATORS)
def test_a_crank_that_turns_fully_does_not_lock(simulator: str) -> None:
    """The crank shaper's crank has no lock (analytic: none within a turn either way)."""
    case = builtin_cases()["crank-shaper"]
    assert all(r.low is None and r.high is None for r in driver_ranges(case.linkage))
    measured = SIMULATORS[simulator](case, "O2")
    assert measured.endings == ("turned", "turned") and measured.low is None is measured.high


@pytest.mark.parametrize("simulator", SIMULATORS)
def test_a_change_point_is_not_a_lock(simulator: str) -> None:
    """Seed E1 as a linkage (a2 + a3 = a1 + a4, SEEDS.md): its analytic range ends at the
    change point, θ12 = 180° (120° from the drawn 60°), where the open and crossed branches
    meet and continuation cannot say which one follows. The linkage does not lock there:
    in both simulators the crank turns through it, both ways."""
    case = builtin_cases()["e1-linkage"]
    expected = driver_ranges(case.linkage)[0]
    assert expected.high is not None and math.degrees(expected.high) == pytest.approx(120.0, abs=0.01)
    measured = SIMULATORS[simulator](case, "A0")
    assert measured.endings == ("turned", "turned")


def test_a_prismatic_driver_is_refused_with_the_reason() -> None:
    case = builtin_cases()["boom-hold-drawn"]
    with pytest.raises(ValueError, match="revolute drivers only"):
        mujoco_locks.driver_locks(case, "cyl")
