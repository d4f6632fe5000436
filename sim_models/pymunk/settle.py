"""The stop rule of a held pymunk model (:mod:`.linkage`): step until it is at rest and
its constraint forces have stopped changing (thresholds in
:mod:`mechcheck.sim_models.pymunk.settings`), never for a fixed number of steps. The
forces are then pymunk's accumulated impulses / dt.
"""

from __future__ import annotations

import math
from array import array
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from operator import sub
from typing import NamedTuple

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


class StopRule(NamedTuple):
    """The stop rule's thresholds as a step reads them: residual velocity (m/s), relative
    force change, the impulses' floor (force floor × dt), calm steps in a row, budget."""

    still: float
    calm_change: float
    floor: float
    patience: int
    max_steps: int


def stop_rule(settings: SolverSettings, length: float, floor: float = FORCE_FLOOR_N) -> StopRule:
    """The :class:`StopRule` of ``settings`` for a model of size ``length``, force floor
    ``floor`` (N)."""
    s = settings
    return StopRule(s.settle_speed * length, s.settle_force_change, floor * s.dt,
                    s.settle_patience, s.max_steps)


# The stop rule's decision, written once: the Python loop runs it, the compiled loop
# compiles it (:mod:`._fast.kernel`).

def forces_calm(change: float, scale: float, rule: StopRule) -> bool:
    """Whether a step's largest change is within ``calm_change`` of the reading's size."""
    return change <= rule.calm_change * scale


def at_rest(speed: float, rule: StopRule) -> bool:
    """Whether the residual velocity is within ``still``."""
    return speed <= rule.still


def patient(calm: int, rule: StopRule) -> bool:
    """Whether ``calm`` steps in a row are enough to call the run settled."""
    return calm >= rule.patience


def relative_change(new: list[float], old: list[float], floor: float) -> float:
    """Largest change between two readings as a fraction of the new reading's largest
    entry, at least ``floor`` (an unloaded case settles too). The readings are impulses
    (N·s), a couple's divided by the length (:meth:`~.readout.Readout.impulses`): the
    fraction is that of the forces they are over one step."""
    return largest_change(new, old) / size(new, floor)


#: The slowest convergence per step that ``settle_force_change`` is sized for: warm-started
#: Gauss–Seidel leaves about change × ρ/(1 − ρ) still to come, ≤ 10× the threshold at
#: ρ ≤ 0.9 (:class:`~.settings.SolverSettings`). A run whose slow mode is slower
#: (:mod:`.slow_mode`, next to a change point) is judged over a window as well
#: (:func:`slow_window`).
ASSUMED_CONTRACTION = 0.9
#: Next to a change point a slow mode with 1 − ρ ≈ 1e-5 shrinks by 1e-5 of itself a step:
#: to leave no more than 10 × ``settle_force_change`` still to come, a step's change would
#: have to be below 1e-14 of the forces, under the rounding of the positions (2e-13 of the
#: reactions, seed E1 at condition number 1e4 with 1e5 kg bodies), so a per-step rule
#: would never end. Over a window of W steps with W·(1 − ρ) = this fraction, the slow mode
#: moves by that fraction of what is left, while the rounding stays the size of one step's.
#: So the run is settled only when, besides the per-step rule, the net change over the
#: window is at most this fraction of 10 × ``settle_force_change``: 1e-11 of the forces,
#: 50× above that rounding.
WINDOW_SHARE = 1.0e-2


#: Next to a change point the settling run has a slow mode of its own, slower than the
#: constraint solve's (seed E1 at condition number 880: 1/(1 − ρ) = 15 000 steps settling,
#: 4 000 solving): a run still moving by more than :data:`WINDOW_SHARE` over its window
#: is settled if it decays over two windows with at most this fraction of the forces left
#: to come: 100× below the 1e-6 static target (MuJoCo's ``SETTLE_RTOL``).
SLOW_REMAINING = 1.0e-8


def slow_window(contraction: float) -> int:
    """The steps over which a slow mode shrinking by ``contraction`` a step moves by
    :data:`WINDOW_SHARE` of itself (0: no window, for ρ ≤ :data:`ASSUMED_CONTRACTION`)."""
    if contraction <= ASSUMED_CONTRACTION:
        return 0
    return math.ceil(WINDOW_SHARE / (1.0 - contraction))


def largest_change(new: Sequence[float], old: Sequence[float]) -> float:
    """The largest change of any entry between two readings."""
    return max(map(abs, map(sub, new, old)), default=0.0)


def size(reading: list[float], floor: float) -> float:
    """A reading's largest entry in size, at least ``floor``."""
    return max(max(reading, default=0.0), -min(reading, default=0.0), floor)


#: One step of a run: (the impulses it read, :meth:`~.readout.Readout.impulses`, and how
#: to get the residual velocity after it, m/s: computed only when the rule needs it).
Reading = tuple[list[float], Callable[[], float]]


def run_until_settled(step: Callable[[], Reading], settings: SolverSettings, length: float,
                      report: Callable[[], Values], floor: float = FORCE_FLOOR_N,
                      slowest: Callable[[], float] | None = None) -> Run:
    """Call ``step`` until the model is at rest and its forces stop changing.

    Settled means: residual velocity below ``settle_speed`` × ``length`` *and*
    relative force change below ``settle_force_change`` for ``settle_patience``
    consecutive steps. Never a fixed step count; ``max_steps`` is only a budget.
    A step that re-poses the model (the constraint solve) reports velocity 0. The
    velocity is computed only where the force change passes (and for the last step).
    The force change is that of every reported force, and couple / ``length``, as a
    fraction of the largest of them, at least ``floor`` (N); it is measured on the
    impulses a step reads, which are those forces × dt. Every step compares the largest
    change with that fraction of the size (:func:`largest_change`, :func:`size`); the
    fraction itself (:func:`relative_change`) is computed once, for the report.
    ``report`` reads the named reactions once, when the run ends.

    ``slowest``, if given, is the contraction per step of the run's slowest mode as
    measured so far (:class:`~.slow_mode.SlowMode`). Slower than
    :data:`ASSUMED_CONTRACTION`, the run must also have changed by no more than
    :data:`WINDOW_SHARE` × 10 × ``settle_force_change`` of the forces over the last
    :func:`slow_window` steps, or be decaying over the last two such windows with no more
    than :data:`SLOW_REMAINING` of them left to come (:func:`settled_over_window`).
    """
    rule = stop_rule(settings, length, floor)
    window_change = WINDOW_SHARE * 10.0 * rule.calm_change
    readings = Recent()
    previous: list[float] | None = None
    earlier: list[float] | None = None
    calm = 0
    speed: Callable[[], float] = lambda: float("inf")  # noqa: E731 (no step taken yet)
    for n in range(1, rule.max_steps + 1):
        impulses, speed = step()
        scale = size(impulses, rule.floor)
        if previous is not None and forces_calm(largest_change(impulses, previous), scale, rule) \
                and at_rest(speed(), rule):
            calm += 1
            if patient(calm, rule) and (slowest is None or settled_over_window(
                    impulses, readings, slow_window(slowest()), window_change * scale,
                    SLOW_REMAINING * scale)):
                return Run(report(), n, True, speed(),
                           relative_change(impulses, previous, rule.floor))
        else:
            calm = 0
        if slowest is not None:
            readings.add(impulses, 2 * slow_window(slowest()))
        earlier, previous = previous, impulses
    change = relative_change(previous, earlier, rule.floor) \
        if previous is not None and earlier is not None else float("inf")
    return Run(report(), rule.max_steps, False, speed(), change)


class Recent(deque[Sequence[float]]):
    """A run's readings as far back as its window rule looks (:func:`settled_over_window`:
    two windows), each compact (8 bytes an impulse, where a list of Python floats takes 32).
    Every step's impulses kept for the whole run made a 64-loop chain of four-bars, 50 144
    steps of 387 impulses, peak at 946 MB; now 168 MB, the same steps and verdict."""

    def add(self, reading: list[float], keep: int) -> None:
        """Append ``reading``, keeping the last ``keep`` readings; all of them while there is
        no window yet (``keep`` 0: the window, once measured, may look back that far)."""
        self.append(array("d", reading))
        while keep and len(self) > keep:
            self.popleft()


def settled_over_window(reading: list[float], before: Sequence[Sequence[float]], window: int,
                        allowed: float, remaining: float) -> bool:
    """Whether a slow run has settled over its last two windows of ``window`` steps (True
    without a window; False until the run is two windows long): the net change over the
    last window is at most ``allowed``, or it shrinks geometrically from the window
    before and what it leaves to come (change × q/(1 − q), q the ratio of the two
    windows' changes) is at most ``remaining``."""
    if window == 0:
        return True
    if len(before) < 2 * window:
        return False
    last = largest_change(reading, before[-window])
    if last <= allowed:
        return True
    first = largest_change(before[-window], before[-2 * window])
    return last < first and last * last / (first - last) <= remaining
