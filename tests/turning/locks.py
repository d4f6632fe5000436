"""Where a linkage's driver locks, measured by driving it in a simulator (both simulators
share this protocol; each supplies a :class:`.protocol.Turner`).

The driver is let go of its lock and turned from the drawn pose by a bounded-torque
velocity servo, the other drivers held, the passive joints damped, in each sense in turn
(:func:`.protocol.run_leg`): it either turns a full revolution, or jams
at a lock — the servo pushes at its bound and the driver stays still — and the angle it
rests at is the lock measured. The other drivers are held at the drawn pose, as the
analytic range holds them. The analytic side gives the range to compare with
(:func:`mechcheck.analytic.theory.driver_ranges`) and nothing else: the run starts from the
drawn pose, which the case file gives.

A prismatic driver runs the same protocol in units of the linkage's size
(:func:`driver_length`): its travel counts as an angle of travel / size and its force as a
moment of force × size, so the servo's speed, bound, lead, stall and budget keep their
meaning (pymunk has no linear motor; its servo is a pin whose error correction is capped
at the servo speed, :mod:`.pymunk_locks`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

from mechcheck.analytic.case import Case

from .protocol import Ending, Turner, run_leg


@dataclass(frozen=True)
class DriverLocks:
    """What driving one driver showed, in one simulator: where it came to rest in each
    sense (rad, or m for a prismatic driver, from the drawn pose; None where it turned a
    full revolution or the run was undecided), and how each run ended."""

    simulator: str
    joint: str
    low: float | None
    high: float | None
    endings: tuple[Ending, Ending]  # (decreasing, increasing)
    steps: int


def drive_both_ways(simulator: str, case: Case, joint: str,
                    turner: Callable[[Case, str], Turner]) -> DriverLocks:
    """Run ``joint``'s driver of the linkage ``case`` down and then up from the drawn pose
    with the simulator's :class:`Turner` (``turner(case, joint)``)."""
    runner = turner(held_at_drawn(case), joint)
    legs = [run_leg(runner, sense, 1.0) for sense in (-1, 1)]
    length = driver_length(case, joint)
    rests = [leg.rest * length if leg.ending == "jammed" else None for leg in legs]
    return DriverLocks(simulator, joint, rests[0], rests[1],
                       (legs[0].ending, legs[1].ending), sum(len(leg.samples) for leg in legs))


def driver_length(case: Case, joint: str) -> float:
    """What a driver's coordinate is divided by to run the turning protocol: 1 for a
    revolute driver (rad), the linkage's size for a prismatic one (m)."""
    return 1.0 if case.linkage.joint(joint).kind.rotates else case.linkage.scale


def held_at_drawn(case: Case) -> Case:
    """``case`` with every driver at rest at the drawn pose (value 0), as the analytic range
    holds the other drivers (:func:`mechcheck.analytic.theory.driver_ranges`)."""
    linkage = case.linkage
    drivers = tuple(replace(d, value=0.0, velocity=0.0, acceleration=0.0)
                    for d in linkage.drivers)
    return replace(case, geometry=replace(linkage, drivers=drivers))


def degrees(value: float | None) -> float:
    return math.nan if value is None else math.degrees(value)
