"""The settling run of a held or free linkage model, compiled when numba is installed
(the ``fast`` extra; ``pip install 'mechcheck[fast]'``).

Why: per step Chipmunk's ``cpSpaceStep`` takes 6.6 µs on seed E1 and the Python around
it (loads, damping, reading the impulses, the stop rule) about as long again, however
lean (:func:`.linkage.settle_run`): the settled sweep stayed at 2.1–2.6× the C floor.
The compiled loop (:mod:`.kernel`) does the same work step for step, in the same
floating-point operations, so a run takes the same steps and reads the same forces; only
the Python around each step is gone. ``tests/test_pymunk_compiled.py`` checks that on
whole sweeps.

It runs where the stop rule has no slow window (:func:`~.settle.slow_window`: next to a
change point the Python loop keeps the window's readings). Without numba, or with
``MECHCHECK_PURE_PYTHON=1`` in the environment (:mod:`mechcheck.sim_models.compiled`),
every run is the Python loop's.
"""

from __future__ import annotations

import ctypes
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from typing import cast

import numpy as np
from pymunk._chipmunk_cffi import ffi, lib

from mechcheck.sim_models.compiled import kernel
from mechcheck.sim_models.pymunk.forces import (
    POSE_FIELDS,
    address,
    body_address,
    impulse_cells,
)
from mechcheck.sim_models.pymunk.linkage_model import LinkageModel
from mechcheck.sim_models.pymunk.settle import Run

KERNEL = "mechcheck.sim_models.pymunk.kernel"
#: ``cpSpaceStep(cpSpace *, cpFloat)``; the pointer passed as an integer of its size
#: (the same register on every 64-bit ABI numba runs on).
STEP = ctypes.CFUNCTYPE(None, ctypes.c_ssize_t, ctypes.c_double)


def available() -> bool:
    """Whether runs are compiled (:func:`mechcheck.sim_models.compiled.kernel`)."""
    return kernel(KERNEL) is not None


@cache
def space_step() -> Callable[[int, float], None]:
    """Chipmunk's ``cpSpaceStep`` as a function numba can call."""
    return cast(Callable[[int, float], None],
                STEP(int(ffi.cast("uintptr_t", ffi.addressof(lib, "cpSpaceStep")))))


@dataclass(frozen=True)
class Plan:
    """Where a model's loop reads and writes: ``bodies`` (struct addresses, the model's
    order), ``forces`` (n, 2) and ``turning`` (n, 4: has-torque, R, δ, T) of the loads
    (:class:`~.loads.LoadTerms`), ``plain`` reading cells (addresses) with their
    ``divisors`` (the couples' and torsional springs' length, else 1), ``held`` slides
    (x cell, y cell, body) with their ``axes`` — the readings of
    :meth:`~.readout.Readout.impulses`, in its order."""

    space: int
    bodies: np.ndarray
    forces: np.ndarray
    turning: np.ndarray
    radii: np.ndarray
    plain: np.ndarray
    divisors: np.ndarray
    held: np.ndarray
    axes: np.ndarray


def plan(model: LinkageModel) -> Plan:
    """The :class:`Plan` of a built model (its objects stay alive with the model)."""
    readout, loads, length = model.readout, model.loads, model.scale
    turning = np.zeros((len(model.bodies), 4))
    for k, r, phase, couple in loads.turning:
        turning[k] = (1.0, r, phase, couple)
    cells = [(address(c), 1.0) for _, c in readout.forces]
    cells += [(address(c), length) for _, c in readout.couples]
    cells += [(address(impulse_cells(spring)[0]), length if torsional else 1.0)
              for _, spring, torsional in readout.springs]
    held = [(address(slide.cells[0]), address(slide.cells[1]), body_address(slide.body))
            for slide in readout.held]
    return Plan(int(ffi.cast("uintptr_t", model.space._space)),
                np.array([body_address(b) for b in model.bodies.values()], dtype=np.int64),
                np.asarray(loads.forces, dtype=float).reshape(-1, 2), turning,
                np.asarray(model.radii, dtype=float),
                np.array([a for a, _ in cells], dtype=np.int64),
                np.array([d for _, d in cells], dtype=float),
                np.array(held, dtype=np.int64).reshape(-1, 3),
                np.array([slide.axis for slide in readout.held], dtype=float).reshape(-1, 2))


def settle_run(model: LinkageModel, impulse_floor: float) -> Run:
    """:func:`.linkage.settle_run` without a slow window, compiled: the same steps, the
    same readings (``impulse_floor``: the rounding floor × dt)."""
    return run(model, impulse_floor, np.zeros((0, 0)))


def solve_run(model: LinkageModel, impulse_floor: float) -> Run:
    """:func:`.linkage.solve_run` without a slow mode watched, compiled, once the bodies are
    staged and re-posed (:meth:`~.bulk.Bodies.repose`): every step starts from the doubles
    that left in each body's struct (position … transform), the same steps and readings."""
    start, end = POSE_FIELDS
    saved = np.array([np.frombuffer(ffi.buffer(ffi.cast("char *", b._body) + start, end - start))
                      for b in model.bodies.values()])
    return run(model, impulse_floor, saved)


def run(model: LinkageModel, impulse_floor: float, saved: np.ndarray) -> Run:
    """The compiled loop (:func:`.kernel.settle`) on ``model``; re-posed from ``saved``
    rows, if any."""
    loop = kernel(KERNEL)
    assert loop is not None, "compiled runs only where available()"
    s, p = model.settings, model.plan
    steps, settled, speed, change = loop.settle(
        space_step(), p.space, s.dt, p.bodies, s.damping ** s.dt, p.forces, p.turning, p.radii,
        saved, p.plain, p.divisors, p.held, p.axes, s.settle_speed * model.scale,
        s.settle_force_change, impulse_floor, s.settle_patience, s.max_steps)
    return Run(model.readout.values(), int(steps), bool(settled), float(speed), float(change))
