"""The loops of :func:`..linkage.settle_run` and :func:`..linkage.solve_run` in numba
(imported by :mod:`.compiled` only with numba). Step for step the Python loop's
floating-point operations (:func:`..linkage.damped_and_loaded` or :meth:`.bulk.Bodies.repose`,
:meth:`..readout.Readout.impulses`, and :func:`..settle.run_until_settled`'s decision,
compiled from its own functions), on the C structs at offsets :func:`.layout.check_layout`
verified; Chipmunk's ``cpSpaceStep`` called through its pointer. Kernels take the
model's :class:`.compiled.Plan` whole.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, cast

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

from mechcheck.sim_models.pymunk import settle as rule
from mechcheck.sim_models.pymunk._fast.compiled import Plan
from mechcheck.sim_models.pymunk._fast.layout import BODY_FIELDS
from mechcheck.sim_models.pymunk.settle import StopRule

Array = np.ndarray
#: Byte offsets of a body's position, velocity, force, angle, angular velocity and torque.
P, V, F, A, W, T = (BODY_FIELDS[name] for name in ("p", "v", "f", "a", "w", "t"))


@intrinsic
def _load(typingctx: Any, address: Any) -> tuple[Any, Callable[..., Any]]:
    """The double at ``address``."""
    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        return builder.load(builder.inttoptr(args[0], ir.DoubleType().as_pointer()))
    return types.float64(types.int64), codegen


@intrinsic
def _store(typingctx: Any, address: Any, value: Any) -> tuple[Any, Callable[..., Any]]:
    """Write the double ``value`` at ``address``."""
    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        builder.store(args[1], builder.inttoptr(args[0], ir.DoubleType().as_pointer()))
        return context.get_dummy_value()
    return types.void(types.int64, types.float64), codegen


# The intrinsics as what they do, for the type checker (numba calls the same objects).
load = cast(Callable[[int], float], _load)
store = cast(Callable[[int, float], None], _store)
# The stop rule's decision, compiled from the functions the Python loop runs.
forces_calm = njit(cache=True)(rule.forces_calm)
at_rest = njit(cache=True)(rule.at_rest)
patient = njit(cache=True)(rule.patient)


@njit(cache=True)
def push(plan: Plan) -> None:
    """Velocities × ``keep`` (damping^dt), the loads' force and their torque at the body's
    angle (:class:`..loads.LoadTerms`: columns has-torque, R, δ, T), body after body."""
    bodies, keep, forces, turning = plan.bodies, plan.keep, plan.forces, plan.turning
    for b in range(bodies.size):
        base = bodies[b]
        store(base + V, load(base + V) * keep)
        store(base + V + 8, load(base + V + 8) * keep)
        store(base + W, load(base + W) * keep)
        store(base + F, forces[b, 0])
        store(base + F + 8, forces[b, 1])
        torque = 0.0
        if turning[b, 0] != 0.0:
            torque = turning[b, 1] * math.cos(load(base + A) + turning[b, 2]) + turning[b, 3]
        store(base + T, torque)


@njit(cache=True)
def repose(plan: Plan, saved: Array) -> None:
    """Every body back to the pose, rest and loads a re-posed step starts from: its
    position … transform as :meth:`.bulk.Bodies.repose` left them (``saved``, a row per
    body of the doubles from :data:`.layout.POSE_FIELDS`)."""
    bodies = plan.bodies
    for b in range(bodies.size):
        base = bodies[b] + P
        for k in range(saved.shape[1]):
            store(base + 8 * k, saved[b, k])


@njit(cache=True)
def read(plan: Plan, out: Array) -> None:
    """The stop rule's reading into ``out``: each plain cell ÷ its divisor, then each held
    slide's impulse split along and across its axis turned with its body."""
    plain, divisors, held, axes = plan.plain, plan.divisors, plan.held, plan.axes
    m = plain.size
    for i in range(m):
        out[i] = load(plain[i]) / divisors[i]
    for j in range(held.shape[0]):
        x, y, phi = load(held[j, 0]), load(held[j, 1]), load(held[j, 2] + A)
        c, s = math.cos(phi), math.sin(phi)
        ux, uy = c * axes[j, 0] - s * axes[j, 1], s * axes[j, 0] + c * axes[j, 1]
        along = x * ux + y * uy
        out[m + 3 * j] = along
        out[m + 3 * j + 1] = x - along * ux
        out[m + 3 * j + 2] = y - along * uy


@njit(cache=True)
def residual(plan: Plan, reposed: bool) -> float:
    """The residual velocity the stop rule reads: none in a re-posed step, else the largest
    point speed |v| + |ω|·radius of any body, m/s; NaN if any is."""
    if reposed:
        return 0.0
    bodies, radii = plan.bodies, plan.radii
    fastest = -math.inf
    for b in range(bodies.size):
        base = bodies[b]
        point = math.hypot(load(base + V), load(base + V + 8)) + abs(load(base + W)) * radii[b]
        if point > fastest or point != point:
            fastest = point
    return fastest


@njit(cache=True)
def size(reading: Array, floor: float) -> float:
    """The reading's largest entry in size, at least ``floor``; NaN if any entry is."""
    largest = floor
    for x in reading:
        if abs(x) > largest or x != x:
            largest = abs(x)
    return largest


@njit(cache=True)
def largest_change(new: Array, old: Array) -> float:
    """The largest change of any entry; NaN if any entry is (a NaN never settles)."""
    largest = 0.0
    for k in range(new.size):
        change = abs(new[k] - old[k])
        if change > largest or change != change:
            largest = change
    return largest


@njit(cache=True)
def settle(step: Callable[[int, float], None], plan: Plan, stop: StopRule,
           saved: Array) -> tuple[int, bool, float, float]:
    """Step until settled or ``max_steps``: (steps, settled, residual velocity, relative
    force change), as :func:`..settle.run_until_settled` decides them. Each step starts
    damped and loaded (:func:`push`), or, given ``saved`` rows, re-posed (:func:`repose`,
    the constraint solve: residual velocity 0)."""
    new = np.empty(plan.plain.size + 3 * plan.held.shape[0])
    old = np.empty_like(new)
    reposed = saved.shape[0] > 0
    calm = 0
    for n in range(1, stop.max_steps + 1):
        if reposed:
            repose(plan, saved)
        else:
            push(plan)
        step(plan.space, plan.dt)
        read(plan, new)
        if n > 1:
            scale = size(new, stop.floor)
            change = largest_change(new, old)
            if forces_calm(change, scale, stop) and at_rest(residual(plan, reposed), stop):
                calm += 1
                if patient(calm, stop):
                    return n, True, residual(plan, reposed), change / scale
            else:
                calm = 0
        old, new = new, old
    change = largest_change(old, new) / size(old, stop.floor) if stop.max_steps > 1 else math.inf
    return stop.max_steps, False, residual(plan, reposed), change
