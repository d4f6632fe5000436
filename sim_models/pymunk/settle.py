"""The stop rule of a held pymunk model (:mod:`.linkage`): step until it is at rest and
its constraint forces have stopped changing (thresholds in
:mod:`mechcheck.sim_models.pymunk.settings`), never for a fixed number of steps. The
forces are then pymunk's accumulated impulses / dt.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from operator import sub

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


def relative_change(new: list[float], old: list[float], floor: float) -> float:
    """Largest change between two readings as a fraction of the new reading's largest
    entry, at least ``floor`` (an unloaded case settles too). The readings are impulses
    (N·s), a couple's divided by the length (:meth:`~.readout.Readout.impulses`): the
    fraction is that of the forces they are over one step."""
    scale = max(max(map(abs, new), default=0.0), floor)
    return max(map(abs, map(sub, new, old)), default=0.0) / scale


#: One step of a run: (the impulses it read, :meth:`~.readout.Readout.impulses`, and how
#: to get the residual velocity after it, m/s: computed only when the rule needs it).
Reading = tuple[list[float], Callable[[], float]]


def run_until_settled(step: Callable[[], Reading], settings: SolverSettings, length: float,
                      report: Callable[[], Values], floor: float = FORCE_FLOOR_N) -> Run:
    """Call ``step`` until the model is at rest and its forces stop changing.

    Settled means: residual velocity below ``settle_speed`` × ``length`` *and*
    relative force change below ``settle_force_change`` for ``settle_patience``
    consecutive steps. Never a fixed step count; ``max_steps`` is only a budget.
    A step that re-poses the model (the constraint solve) reports velocity 0. The
    velocity is computed only where the force change passes (and for the last step).
    The force change is that of every reported force, and couple / ``length``, as a
    fraction of the largest of them, at least ``floor`` (N); it is measured on the
    impulses a step reads, which are those forces × dt. ``report`` reads the named
    reactions once, when the run ends.
    """
    s = settings
    impulse_floor, still, calm_change = floor * s.dt, s.settle_speed * length, s.settle_force_change
    previous: list[float] | None = None
    calm = 0
    change = float("inf")
    speed: Callable[[], float] = lambda: float("inf")  # noqa: E731 (no step taken yet)
    for n in range(1, s.max_steps + 1):
        impulses, speed = step()
        change = relative_change(impulses, previous, impulse_floor) if previous is not None \
            else float("inf")
        previous = impulses
        calm = calm + 1 if change <= calm_change and speed() <= still else 0
        if calm >= s.settle_patience:
            return Run(report(), n, True, speed(), change)
    return Run(report(), s.max_steps, False, speed(), change)
