"""A batch's settling passes stepped in numba (:class:`.batch_settle.BatchSettler`; imported
through :func:`mechcheck.sim_models.compiled.kernel` only where numba is installed).

Pose for pose, step for step, it does what a batch's rollouts do (MuJoCo's
``_unsafe_rollout``: each rollout sets the pose's state, zeroes the solver's warm start
and the warning counters, sets the controls, then steps; a warning ends the stepping of
that rollout, the rest of its readings repeating the last), with the rollouts cut where
the batch cuts them (:data:`.batch_settle.CHUNK` steps, a refinement pass's first
:data:`.batch_settle.REFINE_CHUNK`), and it applies the same stop rules
(:func:`.stop_kernel.first_stops`) to the same readings. What it leaves out is what the
batch throws away: the steps past a pass's stop, and a return to Python every chunk.
MuJoCo's functions are called through their C pointers (:mod:`.exact_compiled`) with
Python's lock released, so a thread per core steps its own poses.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

from mechcheck.sim_models.mujoco.settle import FLOOR_WINDOW
from mechcheck.sim_models.mujoco.stop_kernel import first_stops

Array = np.ndarray


@njit(nogil=True, cache=True)
def passes(step: Any, set_state: Any, get_state: Any, m: int, d: int, full: int,
           controls_spec: int, eq_data: Array, driver_eqs: Array, eq_active: Array,
           eq_active0: Array, warnings: Array, warmstart: Array, sensordata: Array,
           qvel: Array, targets: Array, starts: Array, controls: Array, first_chunk: int,
           chunk: int, readings_left: Array, earliest: Array, columns: Array,
           column_scale: Array, weight: Array, rounding: float, ended_at: Array, rules: Array,
           ended_state: Array) -> None:
    """One settling pass of each pose i: its drivers at ``targets[i]``, from ``starts[i]``
    (a FULLPHYSICS state), its loads ``controls[i]`` held, its first rollout ``first_chunk``
    steps long and the others ``chunk``. Writes the pass's last reading
    (``ended_at[i]``, counted from the pass's start), the rule that fired there (−1: none,
    the pass ran out of budget or read a number that is not finite) and the state it was
    read at (``ended_state[i]``). ``rounding``: the floor rule's absolute allowance (N)."""
    back = FLOOR_WINDOW - 1
    m_read = columns.size
    history = np.empty((1, back, m_read))
    reading = np.empty((1, 1, m_read))
    speed = np.empty((1, 1))
    before = np.empty(starts.shape[1])
    for i in range(starts.shape[0]):
        for j in range(driver_eqs.size):
            eq_data[driver_eqs[j], 0] = targets[i, j]
        before[:] = starts[i]
        history[:] = math.nan
        offset, length, done = 0, first_chunk, False
        while not done:
            # A rollout begins: the state set, warm start and warnings cleared, loads set.
            set_state(m, d, before.ctypes.data, full)
            eq_active[:] = eq_active0
            warmstart[:] = 0.0
            warnings[:] = 0
            set_state(m, d, controls[i].ctypes.data, controls_spec)
            left = readings_left[i] - offset
            early = earliest[i] - offset
            finite = True
            for t in range(length):
                if t > 0:
                    get_state(m, d, before.ctypes.data, full)
                fast = 0.0
                for k in range(qvel.size):
                    v = abs(qvel[k] * weight[k])
                    fast = math.nan if (fast != fast or v != v) else max(fast, v)
                speed[0, 0] = math.inf if (t >= left or t < early) else fast
                warned = False
                for k in range(warnings.size):
                    warned = warned or warnings[k] != 0
                if not warned:
                    step(m, d)
                for k in range(m_read):
                    reading[0, 0, k] = sensordata[columns[k]] * column_scale[k]
                    finite = finite and math.isfinite(reading[0, 0, k])
                first, rule = first_stops(history, reading, speed, rounding)
                history[0, :back - 1] = history[0, 1:]
                history[0, back - 1] = reading[0, 0]
                if first[0] >= 0:
                    ended_at[i], rules[i], done = offset + t, rule[0], True
                    break
                if t == left - 1:  # out of budget: no rule fires past here
                    break
            if done:
                break
            if left <= length or not finite:  # the state of that reading is ``before``
                ended_at[i], rules[i], done = offset + min(left, length) - 1, -1, True
                break
            get_state(m, d, before.ctypes.data, full)  # the next rollout's start
            offset += length
            length = chunk
        ended_state[i] = before
