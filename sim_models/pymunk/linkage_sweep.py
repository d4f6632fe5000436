"""A linkage's sweep over its first driver in one pymunk Space, with continuation.

The model is built once. At each value of the first driver (rad or m from the drawn
pose; the other drivers stay at the case's values) its lock is moved — a gear's phase,
or a held slide's anchor — and the run settles (``pymunk``) or iterates at the fixed
analytic pose (``pymunk_solve``), starting from the previous pose's accumulated
impulses: pymunk's warm start carries them over, which is what makes a neighbouring
pose cheap. With every coordinate driven the bodies are re-posed on the analytic pose
(a seed); free coordinates start from the pose the previous run settled to (the first
from the drawn pose), never from their equilibrium.

Poses get the analytic backends' verdicts (no_solution, singular, indeterminate) and are
then not simulated.
"""

from __future__ import annotations

import time

import numpy as np
from numpy.typing import ArrayLike

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage_backends import NOTHING_TO_SWEEP, analytic_results, driver_values
from mechcheck.analytic.linkage_forces import LinkageResults
from mechcheck.analytic.linkage_kinematics import Array
from mechcheck.analytic.solution import Solution
from mechcheck.analytic.values import CaseError
from mechcheck.sim_models.linkage_motion import driven_sweep, has_free_coordinates, is_driven
from mechcheck.sim_models.pymunk.linkage import (
    Outcome,
    free_start,
    hold_without_correction,
    outcome,
    refusal,
    settle_run,
    solutions,
    solve_run,
    unstable,
)
from mechcheck.sim_models.pymunk.linkage_model import (
    LinkageModel,
    build_linkage_model,
    coordinates,
    move_lock,
    place,
)
from mechcheck.sim_models.pymunk.settings import LINKAGE_SETTLE, LINKAGE_SOLVE

BACKENDS = ("pymunk", "pymunk_solve")


def sweep(case: Case, first: ArrayLike, backend: str = "pymunk",
          results: LinkageResults | None = None) -> list[Solution]:
    """One Solution per value of the first driver, in order (``pymunk`` or ``pymunk_solve``);
    ``results``: the analytic pose analysis of those values, if already made."""
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
    if not case.linkage.drivers:
        raise CaseError(NOTHING_TO_SWEEP, key="drivers", case=case.name)
    values = np.atleast_1d(np.asarray(first, dtype=float))
    if backend == "pymunk" and is_driven(case):
        from mechcheck.sim_models.pymunk.linkage_dynamics import drive_linkage, drive_stretch

        return driven_sweep(case, values, lambda at: drive_linkage(at, analytic_results(at)),
                            drive_stretch, results)
    refused = refusal(case, backend)
    if refused is not None:
        return [refused] * len(values)
    return held_sweep(case, values, backend,
                      results if results is not None else analytic_results(case, values))


def held_sweep(case: Case, values: Array, backend: str, results: LinkageResults) -> list[Solution]:
    """The sweep of a held linkage in one model (built at the first pose simulated): every
    coordinate held, or the constraint solve, from the analytic pose; free coordinates from
    where the last settled run came to rest (the first from the drawn pose). An unstable
    equilibrium of free coordinates gets its verdict and is not simulated."""
    drivers, free, solve = driver_values(case, values), has_free_coordinates(case), backend == BACKENDS[1]
    assert drivers is not None
    first = case.linkage.joint(case.linkage.drivers[0].joint)
    model: LinkageModel | None = None
    previous: Array | None = None
    verdicts: dict[int, Solution] = {}
    outcomes: list[Outcome] = []
    for k, value in enumerate(values):
        start = time.perf_counter()
        found = None if solve or not free else unstable(case, backend, results, k)
        if found is not None:
            verdicts[k] = found
            continue
        q = results.pose.q[k]
        seed = q if solve or not free else previous if previous is not None else free_start(case, drivers[k])
        model = model or sweep_model(case, solve, seed)
        move_lock(model, first, float(value))
        place(model, seed)
        run = solve_run(model, q) if solve else settle_run(model)
        outcomes.append(outcome(model, run, start, k))
        if free and run.settled:
            previous = coordinates(model)
    method = "constraint_solve" if solve else "settle"
    simulated = dict(zip((o.index for o in outcomes),
                         solutions(model, backend, method, outcomes, results, values) if model else [],
                         strict=True))
    return [simulated[k] if k in simulated else with_driver(verdicts[k], float(value))
            for k, value in enumerate(values)]


def sweep_model(case: Case, solve: bool, seed: Array) -> LinkageModel:
    """The sweep's model at its first seed; the constraint solve's (``solve``) without
    joint-error correction."""
    model = build_linkage_model(case, LINKAGE_SOLVE if solve else LINKAGE_SETTLE, seed)
    if solve:
        hold_without_correction(model)
    return model


def with_driver(sol: Solution, value: float) -> Solution:
    """``sol`` with the sweep's driver ``value`` among its diagnostics."""
    return Solution(sol.case, sol.backend, sol.values, sol.status, sol.message,
                    {**sol.diagnostics, "driver": value}, units=sol.units)
