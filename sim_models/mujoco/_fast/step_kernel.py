"""A batch's settling passes stepped in numba (:class:`..batch_settle.BatchSettler`;
imported through :func:`mechcheck.sim_models.compiled.kernel` only where numba is installed).

Pose for pose, step for step, it does what a batch's rollouts do (MuJoCo's
``_unsafe_rollout``: each rollout sets the pose's state, zeroes the solver's warm start
and the warning counters, sets the controls, then steps; a warning ends the stepping of
that rollout, the rest of its readings repeating the last), with the rollouts cut where
the batch cuts them (:data:`..batch_settle.CHUNK` steps, a refinement pass's first
:data:`..batch_settle.REFINE_CHUNK`), and it applies the same stop rules
(:func:`..settle.first_stops`, compiled by :mod:`.stop_kernel`) to the same readings. What
it leaves out is what the batch throws away: the steps past a pass's stop, and a return to
Python every chunk. MuJoCo's functions are called through their C pointers
(:mod:`.pointers`) with Python's lock released, so a thread per core steps its own poses.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from mechcheck.sim_models.mujoco._fast.plans import MjCalls, PassData, PassPlan
from mechcheck.sim_models.mujoco._fast.stop_kernel import first_stops
from mechcheck.sim_models.mujoco.settle import FLOOR_WINDOW

Array = np.ndarray


@njit(nogil=True, cache=True)
def rollout_begins(mj: MjCalls, v: PassData, state: Array, controls: Array) -> None:
    """A rollout begins: the state set, warm start and warnings cleared, loads set."""
    mj.set_state(mj.m, mj.d, state.ctypes.data, v.full)
    v.eq_active[:] = v.eq_active0
    v.warmstart[:] = 0.0
    v.warnings[:] = 0
    mj.set_state(mj.m, mj.d, controls.ctypes.data, v.controls_spec)


@njit(nogil=True, cache=True)
def joint_speed(v: PassData, weight: Array) -> float:
    """The largest weighted joint speed, NaN if any is."""
    fast = 0.0
    for k in range(v.qvel.size):
        s = abs(v.qvel[k] * weight[k])
        fast = math.nan if (fast != fast or s != s) else max(fast, s)
    return fast


@njit(nogil=True, cache=True)
def step_and_read(mj: MjCalls, v: PassData, p: PassPlan, reading: Array) -> bool:
    """One step (none once MuJoCo has warned), its reading; whether it is finite."""
    warned = False
    for k in range(v.warnings.size):
        warned = warned or v.warnings[k] != 0
    if not warned:
        mj.step(mj.m, mj.d)
    finite = True
    for k in range(p.columns.size):
        reading[0, 0, k] = v.sensordata[p.columns[k]] * p.column_scale[k]
        finite = finite and math.isfinite(reading[0, 0, k])
    return finite


@njit(nogil=True, cache=True)
def one_rollout(mj: MjCalls, v: PassData, p: PassPlan, i: int, offset: int, length: int,
                before: Array, history: Array) -> tuple[int, int, bool]:
    """One rollout of pose ``i``'s pass, ``length`` steps from reading ``offset`` on:
    (the reading it ended at, the rule, −1: none) once the pass ends, else (−1, −1);
    whether every reading was finite. ``before`` holds the state of the last reading."""
    back = history.shape[1]
    reading = np.empty((1, 1, p.columns.size))
    speed = np.empty((1, 1))
    rollout_begins(mj, v, before, p.controls[i])
    left = p.readings_left[i] - offset
    early = p.earliest[i] - offset
    finite = True
    for t in range(length):
        if t > 0:
            mj.get_state(mj.m, mj.d, before.ctypes.data, v.full)
        fast = joint_speed(v, p.weight)
        speed[0, 0] = math.inf if (t >= left or t < early) else fast
        finite = step_and_read(mj, v, p, reading) and finite
        first, rule = first_stops(history, reading, speed, p.rounding)
        history[0, :back - 1] = history[0, 1:]
        history[0, back - 1] = reading[0, 0]
        if first[0] >= 0:
            return offset + t, rule[0], finite
        if t == left - 1:  # out of budget: no rule fires past here
            break
    return -1, -1, finite


@njit(nogil=True, cache=True)
def passes(mj: MjCalls, v: PassData, p: PassPlan) -> None:
    """One settling pass of each pose i: its drivers at ``p.targets[i]``, from
    ``p.starts[i]`` (a FULLPHYSICS state), its loads ``p.controls[i]`` held, its first
    rollout ``p.first_chunk`` steps long and the others ``p.chunk``. Writes the pass's last
    reading (``p.ended_at[i]``, counted from the pass's start), the rule that fired there
    (−1: none, the pass ran out of budget or read a number that is not finite) and the
    state it was read at (``p.ended_state[i]``)."""
    history = np.empty((1, FLOOR_WINDOW - 1, p.columns.size))
    before = np.empty(p.starts.shape[1])
    for i in range(p.starts.shape[0]):
        for j in range(v.driver_eqs.size):
            v.eq_data[v.driver_eqs[j], 0] = p.targets[i, j]
        before[:] = p.starts[i]
        history[:] = math.nan
        offset, length = 0, p.first_chunk
        while True:
            at, rule, finite = one_rollout(mj, v, p, i, offset, length, before, history)
            if at >= 0:
                p.ended_at[i], p.rules[i] = at, rule
                break
            left = p.readings_left[i] - offset
            if left <= length or not finite:  # the state of that reading is ``before``
                p.ended_at[i], p.rules[i] = offset + min(left, length) - 1, -1
                break
            mj.get_state(mj.m, mj.d, before.ctypes.data, v.full)  # the next rollout's start
            offset += length
            length = p.chunk
        p.ended_state[i] = before
