"""Independent twins of MuJoCo's stop rules, kept only to prove the one production body
(:func:`mechcheck.sim_models.mujoco.settle.first_stops`, run as Python or compiled) right:
the rules read one step at a time in plain Python (:class:`StepWatch`), and vectorised
over poses and readings in numpy (:func:`vectorised_stops`). Each is written from the
rules' definitions, not from the body they check; the tests ask all three for the same
stop, reading and rule."""

from __future__ import annotations

import itertools
from collections import deque
from collections.abc import Iterable

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from mechcheck.analytic.solution import FORCE_FLOOR_N
from mechcheck.sim_models.mujoco.settle import (
    FLOOR_WINDOW,
    QUIET_RTOL,
    SETTLE_RTOL,
    STOP_WINDOW,
    VELOCITY_TOL,
    WOBBLE_RTOL,
)

Array = np.ndarray


class StepWatch:
    """The stop rules on a sequence of force vectors, one reading at a time, in plain
    Python: settled when the change still to come of a decay is below SETTLE_RTOL, when the
    last changes are all below QUIET_RTOL, or when the forces sit on their rounding floor
    (spread over FLOOR_WINDOW readings by at most the wobble allowed). ``rule`` names the
    one that fired."""

    def __init__(self, rounding: float = 0.0) -> None:
        self.readings: deque[list[float]] = deque(maxlen=FLOOR_WINDOW)
        self.changes: list[float] = []
        self.rule = ""
        self.rounding = rounding

    def settled(self, current: np.ndarray) -> bool:
        """Record ``current``; True when the forces have settled."""
        values = current.tolist()
        size = max(max(map(abs, values)), FORCE_FLOOR_N)
        if self.readings:
            previous = self.readings[-1]
            self.changes.append(max(abs(a - b) for a, b in zip(values, previous, strict=True))
                                / size)
        self.readings.append(values)
        wobble = max(WOBBLE_RTOL, self.rounding / size)  # or the rounding floor where larger
        if remaining_change(self.changes) <= SETTLE_RTOL:
            self.rule = "decay"
        elif len(self.changes) >= STOP_WINDOW and max(self.changes[-STOP_WINDOW:]) <= QUIET_RTOL:
            self.rule = "quiet"
        elif (len(self.readings) == FLOOR_WINDOW
              and max(self.changes[-STOP_WINDOW:]) <= wobble
              and floor_spread(self.readings) / size <= wobble):
            self.rule = "floor"
        else:
            return False
        return True


def remaining_change(changes: list[float]) -> float:
    """Estimated change still to come after the last of ``changes`` (relative per-step
    changes), from the last STOP_WINDOW of them: Δ·r/(1 − r) while they decay
    geometrically, ∞ when they do not (or before a window is known). Δ is the window's
    largest change and r its largest step ratio."""
    if len(changes) < STOP_WINDOW:
        return np.inf
    window = changes[-STOP_WINDOW:]
    size = max(window)
    if size == 0.0:
        return 0.0
    ratio = max(b / a if a else np.inf for a, b in itertools.pairwise(window))
    if ratio < 1.0:
        return size * ratio / (1.0 - ratio)
    return np.inf


def floor_spread(readings: Iterable[Iterable[float]]) -> float:
    """Largest spread (max − min) of any force component over ``readings``."""
    stack = np.array(list(readings))
    return float((stack.max(axis=0) - stack.min(axis=0)).max())


def vectorised_stops(history: Array, readings: Array, speed: Array,
                     rounding: float = 0.0) -> tuple[Array, Array]:
    """For each pose of a wave, the first of its ``readings`` (P, T, m) at which
    the stop rules would say settled with the joints slower than
    VELOCITY_TOL (``speed`` (P, T) at each reading): its index (−1 if
    none) and the rule that fired (an index into :data:`RULES`).

    ``history`` (P, FLOOR_WINDOW − 1, m) holds each pose's earlier readings of the pass,
    NaN where the pass has fewer: a window reaching back past the pass's first reading
    holds a NaN, and no rule fires on it, as no rule fires before its window is known.
    ``rounding``: the model's rounding floor (N, :func:`.settle.rounding_floor`), the floor
    rule's allowance where it is more than :data:`.settle.WOBBLE_RTOL` of a reading.
    """
    back = history.shape[1]
    # Each reading's change from the last (largest over the forces) and size, from the
    # first reading the chunk's windows reach back to on.
    recent = np.concatenate([history[:, back - STOP_WINDOW:], readings], axis=1)
    size = np.maximum(np.abs(recent).max(axis=2), FORCE_FLOOR_N)
    step = np.abs(np.diff(recent, axis=1)).max(axis=2)
    # The windows of changes ending at each reading of the chunk.
    windows = sliding_window_view(step / size[:, 1:], STOP_WINDOW, axis=1)
    largest = windows.max(axis=2)
    with np.errstate(divide="ignore", invalid="ignore"):
        steps = windows[:, :, 1:] / windows[:, :, :-1]
        ratio = np.where(windows[:, :, :-1] > 0, steps, np.inf).max(axis=2)
        left = np.where(ratio < 1.0, largest * ratio / (1.0 - ratio), np.inf)
    decay = (largest == 0.0) | (left <= SETTLE_RTOL)
    quiet = largest <= QUIET_RTOL
    here = size[:, STOP_WINDOW:]  # the size at each reading of the chunk
    with np.errstate(invalid="ignore"):
        wobble = np.maximum(WOBBLE_RTOL, rounding / here)  # or the rounding floor where larger
    # The floor's spread only where the rest of its rule holds and no single step in its
    # window is larger than the spread allowed (a spread is at least every step within
    # it): a window of 32 readings at every reading costs more than the rollout.
    floor = np.zeros_like(decay)
    candidate = (largest <= wobble) & ~decay & ~quiet & (speed <= VELOCITY_TOL)
    if candidate.any():
        x = np.concatenate([history, readings], axis=1)
        jumps = np.abs(np.diff(x, axis=1)).max(axis=2)
        widest = sliding_window_view(jumps, FLOOR_WINDOW - 1, axis=1)[:, -readings.shape[1]:]
        candidate &= widest.max(axis=2) <= wobble * here
        p, t = np.nonzero(candidate)
        rows = (back + t + 1 - FLOOR_WINDOW)[:, None] + np.arange(FLOOR_WINDOW)
        window = x[p[:, None], rows]  # (candidates, FLOOR_WINDOW, m)
        spread = (window.max(axis=1) - window.min(axis=1)).max(axis=1)
        floor[p, t] = spread / here[p, t] <= wobble[p, t]
    rule = np.where(decay, 0, np.where(quiet, 1, np.where(floor, 2, -1)))
    fired = (rule >= 0) & (speed <= VELOCITY_TOL)
    first = np.where(fired.any(axis=1), fired.argmax(axis=1), -1)
    return first, rule[np.arange(len(first)), first]

