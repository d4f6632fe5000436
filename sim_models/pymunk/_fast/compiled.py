"""The settling run of a held or free linkage model, compiled when numba is installed
(the ``fast`` extra; ``pip install 'mechcheck[fast]'``).

Why: per step Chipmunk's ``cpSpaceStep`` takes 6.6 µs on seed E1 and the Python around
it (loads, damping, reading the impulses, the stop rule) about as long again, however
lean (:func:`..linkage.python_settle_run`): the settled sweep stayed at 2.1–2.6× the C
floor. The compiled loop (:mod:`.kernel`) does the same work step for step, in the same
floating-point operations, so a run takes the same steps and reads the same forces; only
the Python around each step is gone. ``tests/test_pymunk_compiled.py`` checks that on
whole sweeps.

It runs where the stop rule has no slow window (:func:`..settle.slow_window`: next to a
change point the Python loop keeps the window's readings). Without numba, or with
``MECHCHECK_PURE_PYTHON=1`` in the environment (:mod:`mechcheck.sim_models.compiled`),
every run is the Python loop's.
"""

from __future__ import annotations

import ctypes
from collections.abc import Callable
from functools import cache
from typing import TYPE_CHECKING, NamedTuple, cast

import numpy as np
from pymunk._chipmunk_cffi import ffi, lib

from mechcheck.sim_models.compiled import kernel
from mechcheck.sim_models.pymunk._fast.layout import address, body_address, impulse_cells, pose_doubles

if TYPE_CHECKING:
    from mechcheck.sim_models.pymunk.linkage_model import LinkageModel
    from mechcheck.sim_models.pymunk.settle import StopRule

KERNEL = "mechcheck.sim_models.pymunk._fast.kernel"
#: ``cpSpaceStep(cpSpace *, cpFloat)``; the pointer passed as an integer of its size
#: (the same register on every 64-bit ABI numba runs on).
STEP = ctypes.CFUNCTYPE(None, ctypes.c_ssize_t, ctypes.c_double)
#: How a compiled run ended: steps, settled, residual velocity, relative force change.
Ending = tuple[int, bool, float, float]


def available() -> bool:
    """Whether runs are compiled (:func:`mechcheck.sim_models.compiled.kernel`)."""
    return kernel(KERNEL) is not None


@cache
def space_step() -> Callable[[int, float], None]:
    """Chipmunk's ``cpSpaceStep`` as a function numba can call."""
    return cast(Callable[[int, float], None],
                STEP(int(ffi.cast("uintptr_t", ffi.addressof(lib, "cpSpaceStep")))))


class Plan(NamedTuple):
    """Where a model's loop reads and writes, and how it steps: ``space`` (the struct's
    address), ``dt``, ``keep`` (damping^dt), ``bodies`` (struct addresses, the model's
    order), ``forces`` (n, 2) and ``turning`` (n, 4: has-torque, R, δ, T) of the loads
    (:class:`..loads.LoadTerms`), ``radii``, ``plain`` reading cells (addresses) with their
    ``divisors`` (the couples' and torsional springs' length, else 1), ``held`` slides
    (x cell, y cell, body) with their ``axes`` — the readings of
    :meth:`..readout.Readout.impulses`, in its order."""

    space: int
    dt: float
    keep: float
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
    readout, loads, length, s = model.readout, model.loads, model.scale, model.settings
    turning = np.zeros((len(model.bodies), 4))
    for k, r, phase, couple in loads.turning:
        turning[k] = (1.0, r, phase, couple)
    cells = [(address(c), 1.0) for _, c in readout.forces]
    cells += [(address(c), length) for _, c in readout.couples]
    cells += [(address(impulse_cells(spring)[0]), length if torsional else 1.0)
              for _, spring, torsional in readout.springs]
    held = [(address(slide.cells[0]), address(slide.cells[1]), body_address(slide.body))
            for slide in readout.held]
    return Plan(int(ffi.cast("uintptr_t", model.space._space)), s.dt, s.damping ** s.dt,
                np.array([body_address(b) for b in model.bodies.values()], dtype=np.int64),
                np.asarray(loads.forces, dtype=float).reshape(-1, 2), turning,
                np.asarray(model.radii, dtype=float),
                np.array([a for a, _ in cells], dtype=np.int64),
                np.array([d for _, d in cells], dtype=float),
                np.array(held, dtype=np.int64).reshape(-1, 3),
                np.array([slide.axis for slide in readout.held], dtype=float).reshape(-1, 2))


def run(model: LinkageModel, rule: StopRule, reposed: bool) -> Ending:
    """The compiled loop (:func:`.kernel.settle`) on ``model`` under ``rule``: damped and
    loaded steps, or, ``reposed``, the constraint solve's steps once the bodies are staged
    and re-posed (:meth:`.bulk.Bodies.repose`): every step then starts from the doubles
    that left in each body's struct (position … transform)."""
    loop = kernel(KERNEL)
    assert loop is not None, "compiled runs only where available()"
    saved = pose_doubles(list(model.bodies.values())) if reposed else np.zeros((0, 0))
    steps, settled, speed, change = loop.settle(space_step(), model.plan, rule, saved)
    return int(steps), bool(settled), float(speed), float(change)
