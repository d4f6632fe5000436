"""The ``pymunk`` backend for static cases: hold the mechanism by simulation until it settles.

The drive link is locked to the ground by a GearJoint at its analytic angle,
the loads and weights are applied every step, and the space is stepped with
a constant dt and some damping until it is at rest and its constraint forces
have stopped changing (thresholds in :mod:`mechcheck.sim_models.pymunk.settings`).
The forces are then pymunk's accumulated impulses / dt.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

from mechcheck.analytic.case import Case
from mechcheck.analytic.solution import FORCE_FLOOR_N, Solution
from mechcheck.sim_models.diagnostics import RunDiagnostics
from mechcheck.sim_models.pymunk.loads import apply_loads
from mechcheck.sim_models.pymunk.model import Model, build_model
from mechcheck.sim_models.pymunk.readout import (
    Values,
    crank_angle,
    loop_violation,
    pose_drift,
    pose_values,
    reactions,
    residual_velocity,
)
from mechcheck.sim_models.pymunk.settings import SETTLE, SolverSettings
from mechcheck.sim_models.pymunk.verdict import unsettled_solution

BACKEND = "pymunk"


@dataclass(frozen=True)
class Run:
    """How a run ended: the last reading, the steps taken, and whether it settled."""

    values: Values
    steps: int
    settled: bool
    residual_velocity: float
    force_change: float


def is_four_bar_torque(quantity: str) -> bool:
    """The four-bar's and slider-crank's couples: T12/T14 and M14 (N·m)."""
    return quantity.startswith(("T", "M"))


def force_scale(values: Values, length: float,
                torque: Callable[[str], bool] = is_four_bar_torque,
                floor: float = FORCE_FLOOR_N) -> float:
    """The largest force, or torque / length, in a reading (N), at least ``floor``; the
    unit of 'change'."""
    sizes = [abs(v) / length if torque(q) else abs(v) for q, v in values.items()]
    return max(max(sizes, default=0.0), floor)  # an unloaded case settles too


def relative_change(new: Values, old: Values, length: float,
                    torque: Callable[[str], bool] = is_four_bar_torque,
                    floor: float = FORCE_FLOOR_N) -> float:
    """Largest change between two readings as a fraction of the new reading's force scale."""
    scale = force_scale(new, length, torque, floor)
    diffs = [abs(new[q] - old[q]) / (length if torque(q) else 1.0) for q in new]
    return max(diffs) / scale


#: One step of a run: (the reactions it read, the residual velocity after it, m/s).
Reading = tuple[Values, float]


def run_until_settled(step: Callable[[], Reading], settings: SolverSettings, length: float,
                      torque: Callable[[str], bool] = is_four_bar_torque,
                      floor: float = FORCE_FLOOR_N) -> Run:
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


def step_until_settled(model: Model, settings: SolverSettings | None = None) -> Run:
    """Step the loaded model until it is at rest and its forces stop changing
    (:func:`run_until_settled`)."""
    s = settings or model.settings

    def step() -> Reading:
        apply_loads(model)
        model.space.step(s.dt)
        return reactions(model), residual_velocity(model)

    return run_until_settled(step, s, model.case.geometry.scale)


def diagnostics(model: Model, run: Run, method: str, elapsed: float) -> dict[str, float | str]:
    """The simulator diagnostics every pymunk Solution carries."""
    return RunDiagnostics(
        method, run.steps, elapsed, run.residual_velocity, loop_violation(model),
        pose_drift(model, crank_angle(model)),
    ).as_dict(force_change=run.force_change, dt=model.settings.dt,
              iterations=model.settings.iterations)


def solution_of(model: Model, run: Run, backend: str, method: str, elapsed: float) -> Solution:
    """The Solution of a finished run: forces only if it settled."""
    diag = diagnostics(model, run, method, elapsed)
    if not run.settled:
        return unsettled_solution(model, backend, diag)
    return Solution(model.case.name, backend, pose_values(model) | run.values, diagnostics=diag)


def settle(case: Case, settings: SolverSettings = SETTLE) -> Solution:
    """The ``pymunk`` backend: static equilibrium by simulation (driven motion if dynamic).

    Dynamic and friction cases are dispatched to :func:`mechcheck.sim_models.pymunk.dynamics.drive`.
    """
    if case.kind != "static":
        from mechcheck.sim_models.pymunk.dynamics import drive

        return drive(case)
    start = time.perf_counter()
    model = build_model(case, settings)
    run = step_until_settled(model)
    return solution_of(model, run, BACKEND, "settle", time.perf_counter() - start)
