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
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage_backends import NOTHING_TO_SWEEP, analytic_results, driver_values
from mechcheck.analytic.linkage_forces import LinkageResults
from mechcheck.analytic.linkage_kinematics import Array
from mechcheck.analytic.solution import Solution
from mechcheck.analytic.values import CaseError
from mechcheck.sim_models.linkage_motion import driven_sweep, is_driven
from mechcheck.sim_models.pymunk.linkage import (
    Outcome,
    free_start,
    has_free_coordinates,
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
    along,
    build_linkage_model,
    coordinates,
    place,
)
from mechcheck.sim_models.pymunk.settings import LINKAGE_SETTLE, LINKAGE_SOLVE

BACKENDS = ("pymunk", "pymunk_solve")


def hold_first_driver(model: LinkageModel, value: float) -> None:
    """Move the first driver's lock to ``value`` (rad or m from the drawn pose)."""
    linkage = model.linkage
    joint = linkage.joint(linkage.drivers[0].joint)
    if joint.kind.rotates:
        model.drives[joint.name].phase = value
    else:
        model.held[joint.name].anchor_a = along(joint, linkage.points[joint.at], value)


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
        from mechcheck.sim_models.pymunk.linkage_dynamics import drive_linkage

        return driven_sweep(case, values, lambda at: drive_linkage(at, analytic_results(at)))
    refused = refusal(case, backend)
    if refused is not None:
        return [refused] * len(values)
    return held_sweep(case, values, backend,
                      results if results is not None else analytic_results(case, values))


def held_sweep(case: Case, values: Array, backend: str, results: LinkageResults) -> list[Solution]:
    """The sweep of a held linkage, pose after pose in one model (:class:`Continuation`);
    an unstable equilibrium of free coordinates gets its verdict and is not simulated."""
    drivers = driver_values(case, values)
    assert drivers is not None
    walk = Continuation(case, backend, results, drivers, has_free_coordinates(case))
    verdicts: dict[int, Solution] = {}
    outcomes: list[Outcome] = []
    for k, value in enumerate(values):
        start = time.perf_counter()
        found = unstable(case, backend, results, k) if walk.free and backend == "pymunk" else None
        if found is not None:
            verdicts[k] = found
        else:
            outcomes.append(walk.run(k, float(value), start))
    method = "settle" if backend == "pymunk" else "constraint_solve"
    simulated = dict(zip((o.index for o in outcomes),
                         solutions(walk.model, backend, method, outcomes, results, values)
                         if walk.model else [], strict=True))
    return [simulated[k] if k in simulated else with_driver(verdicts[k], float(value))
            for k, value in enumerate(values)]


@dataclass
class Continuation:
    """A held sweep from pose to pose (``drivers``: every driver's value per pose; ``free``:
    the linkage has free coordinates): one ``model``, built at the first pose simulated,
    and the pose the last settled run of free coordinates came to rest in, where the next
    run starts."""

    case: Case
    backend: str
    results: LinkageResults
    drivers: Array
    free: bool
    model: LinkageModel | None = None
    previous: Array | None = None

    def seed(self, k: int) -> Array:
        """Where pose ``k``'s run starts: the analytic pose when every coordinate is held
        (and for the constraint solve), else where the last settled run came to rest, the
        first from the drawn pose."""
        if not self.free or self.backend == "pymunk_solve":
            return np.asarray(self.results.pose.q[k])
        return self.previous if self.previous is not None else free_start(self.case, self.drivers[k])

    def built(self, seed: Array) -> LinkageModel:
        """The sweep's model, built at ``seed`` the first time."""
        if self.model is None:
            solve = self.backend == "pymunk_solve"
            self.model = build_linkage_model(self.case, LINKAGE_SOLVE if solve else LINKAGE_SETTLE, seed)
            if solve:
                hold_without_correction(self.model)
        return self.model

    def run(self, k: int, value: float, start: float) -> Outcome:
        """Pose ``k`` at the first driver's ``value``, run from its seed."""
        seed = self.seed(k)
        model = self.built(seed)
        hold_first_driver(model, value)
        place(model, seed)
        q = self.results.pose.q[k]
        run = settle_run(model) if self.backend == "pymunk" else solve_run(model, q)
        done = outcome(model, run, start, k)
        if self.free and run.settled:
            self.previous = coordinates(model)
        return done


def with_driver(sol: Solution, value: float) -> Solution:
    """``sol`` with the sweep's driver ``value`` among its diagnostics."""
    return Solution(sol.case, sol.backend, sol.values, sol.status, sol.message,
                    {**sol.diagnostics, "driver": value}, units=sol.units)
