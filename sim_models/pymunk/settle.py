"""The stop rule of a held pymunk model (:mod:`.linkage`): step until it is at rest and
its constraint forces have stopped changing (thresholds in
:mod:`mechcheck.sim_models.pymunk.settings`), never for a fixed number of steps. The
forces are then pymunk's accumulated impulses / dt.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from mechcheck.analytic.solution import FORCE_FLOOR_N
from mechcheck.sim_models.pymunk.readout import Values
from mechcheck.sim_models.pymunk.settings import SolverSettings


@dataclass(frozen=True)
class Run:
    """How a run ended: the last reading, the steps taken, and whether it settled."""

    values: Values
    steps: int
    settled: bool
    residual_velocity: float
    force_change: float


def force_scale(values: Values, length: float, torque: Callable[[str], bool],
                floor: float = FORCE_FLOOR_N) -> float:
    """The largest force, or torque / length, in a reading (N), at least ``floor``; the
    unit of 'change'."""
    sizes = [abs(v) / length if torque(q) else abs(v) for q, v in values.items()]
    return max(max(sizes, default=0.0), floor)  # an unloaded case settles too


def relative_change(new: Values, old: Values, length: float, torque: Callable[[str], bool],
                    floor: float = FORCE_FLOOR_N) -> float:
    """Largest change between two readings as a fraction of the new reading's force scale."""
    scale = force_scale(new, length, torque, floor)
    diffs = [abs(new[q] - old[q]) / (length if torque(q) else 1.0) for q in new]
    return max(diffs) / scale


#: One step of a run: (the reactions it read, the residual velocity after it, m/s).
Reading = tuple[Values, float]


def run_until_settled(step: Callable[[], Reading], settings: SolverSettings, length: float,
                      torque: Callable[[str], bool], floor: float = FORCE_FLOOR_N) -> Run:
    """Call ``step`` until the model is at rest and its forces stop changing.

    Settled means: residual velocity below ``settle_speed`` × ``length`` *and*
    relative force change below ``settle_force_change`` for ``settle_patience``
    consecutive steps. Never a fixed step count; ``max_steps`` is only a budget.
    A step that re-poses the model (the constraint solve) reports velocity 0.
    ``torque`` says which quantities are couples (compared as couple / ``length``),
    ``floor`` is the smallest force scale a change is measured against (N).
    """
    s = settings
    previous: Values | None = None
    calm = 0
    values: Values = {}
    velocity = change = float("inf")
    for n in range(1, s.max_steps + 1):
        values, velocity = step()
        change = relative_change(values, previous, length, torque, floor) if previous else float("inf")
        previous = values
        calm = calm + 1 if velocity <= s.settle_speed * length and change <= s.settle_force_change else 0
        if calm >= s.settle_patience:
            return Run(values, n, True, velocity, change)
    return Run(values, s.max_steps, False, velocity, change)
