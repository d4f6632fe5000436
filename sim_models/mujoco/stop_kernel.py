""":func:`.batch_settle.first_stops` in numba (imported through
:func:`mechcheck.sim_models.compiled.kernel` only where numba is installed).

The same rules in the same floating-point operations, reading by reading instead of array
by array: a maximum that meets a NaN is NaN, as numpy's is, and every comparison with it is
false, so a window reaching back past a pass's first reading (NaN) fires no rule here
either. ``tests/test_mujoco.py`` checks the two agree exactly, on the rules' own cases and
on random readings with NaNs, infinities and zeros.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

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


@njit(cache=True)
def larger(a: float, b: float) -> float:
    """max(a, b), NaN if either is (numpy's maximum)."""
    if a != a or b != b:
        return math.nan
    return a if a >= b else b


@njit(cache=True)
def largest_entry(x: Array) -> float:
    """The largest |entry| of a reading, NaN if any is NaN."""
    out = 0.0
    for v in x:
        out = larger(out, abs(v))
    return out


@njit(cache=True)
def largest_step(new: Array, old: Array) -> float:
    """The largest |change| between two readings, NaN if any is NaN."""
    out = 0.0
    for j in range(new.size):
        out = larger(out, abs(new[j] - old[j]))
    return out


@njit(cache=True)
def first_stops(history: Array, readings: Array, speed: Array,
                rounding: float = 0.0) -> tuple[Array, Array]:
    """:func:`.batch_settle.first_stops`: per pose, the first reading at which a rule fires
    with the joints slower than VELOCITY_TOL (−1 if none), and the rule (the last reading's
    where none fires, as numpy's indexing gives); ``rounding``, the floor rule's absolute
    allowance (N)."""
    poses, back, m = history.shape
    chunk = readings.shape[1]
    first = np.full(poses, -1, dtype=np.int64)
    rules = np.full(poses, -1, dtype=np.int64)
    recent = np.empty((STOP_WINDOW + chunk, m))
    size = np.empty(STOP_WINDOW + chunk)
    change = np.empty(STOP_WINDOW + chunk - 1)
    jumps = np.empty(back + chunk - 1)
    whole = np.empty((back + chunk, m))
    for p in range(poses):
        recent[:STOP_WINDOW] = history[p, back - STOP_WINDOW:]
        recent[STOP_WINDOW:] = readings[p]
        for i in range(STOP_WINDOW + chunk):
            size[i] = larger(largest_entry(recent[i]), FORCE_FLOOR_N)
        for i in range(STOP_WINDOW + chunk - 1):
            change[i] = largest_step(recent[i + 1], recent[i]) / size[i + 1]
        jumps_known = False
        for t in range(chunk):
            # The window of STOP_WINDOW changes ending at reading t of the chunk.
            largest = change[t]
            for k in range(1, STOP_WINDOW):
                largest = larger(largest, change[t + k])
            ratio = -math.inf
            for k in range(STOP_WINDOW - 1):
                step = change[t + k + 1] / change[t + k] if change[t + k] > 0 else math.inf
                ratio = larger(ratio, step)
            left = largest * ratio / (1.0 - ratio) if ratio < 1.0 else math.inf
            here = size[STOP_WINDOW + t]
            wobble = larger(WOBBLE_RTOL, rounding / here)  # :func:`.settle.wobble_allowed`
            rule = -1
            if largest == 0.0 or left <= SETTLE_RTOL:
                rule = 0
            elif largest <= QUIET_RTOL:
                rule = 1
            elif largest <= wobble and speed[p, t] <= VELOCITY_TOL:
                if not jumps_known:
                    whole[:back] = history[p]
                    whole[back:] = readings[p]
                    for i in range(back + chunk - 1):
                        jumps[i] = largest_step(whole[i + 1], whole[i])
                    jumps_known = True
                widest = jumps[t]
                for i in range(t + 1, t + back):
                    widest = larger(widest, jumps[i])
                if widest <= wobble * here:
                    start = back + t + 1 - FLOOR_WINDOW  # the floor window's first reading
                    spread = 0.0
                    for j in range(m):
                        low, high = whole[start, j], whole[start, j]
                        for i in range(start + 1, start + FLOOR_WINDOW):
                            low = -larger(-low, -whole[i, j])
                            high = larger(high, whole[i, j])
                        spread = larger(spread, high - low)
                    if spread / here <= wobble:
                        rule = 2
            rules[p] = rule
            if rule >= 0 and speed[p, t] <= VELOCITY_TOL:
                first[p] = t
                break
    return first, rules
