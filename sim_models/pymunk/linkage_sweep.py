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
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage_backends import NOTHING_TO_SWEEP, analytic_results, driver_values
from mechcheck.analytic.linkage_forces import LinkageResults
from mechcheck.analytic.linkage_kinematics import Array
from mechcheck.analytic.solution import Solution
from mechcheck.analytic.values import CaseError
from mechcheck.sim_models.convergence import DRIVEN_DRIFT
from mechcheck.sim_models.linkage_motion import (
    at_first_driver,
    driven_sweep,
    has_free_coordinates,
    is_driven,
)
from mechcheck.sim_models.pymunk.linkage import (
    ASSEMBLY_DRIFT,
    Outcome,
    free_start,
    hold_without_correction,
    outcome,
    pose_drifts,
    refusal,
    settle,
    settle_run as held_settle_run,
    solutions,
    solve_run,
    unstable,
)
from mechcheck.sim_models.pymunk.linkage_model import (
    LinkageModel,
    build_linkage_model,
    move_lock,
    place,
)
from mechcheck.sim_models.pymunk.settings import LINKAGE_SETTLE, LINKAGE_SOLVE
from mechcheck.sim_models.pymunk.settle import Run

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
    equilibrium of free coordinates gets its verdict and is not simulated.

    Continuation carries the last pose's impulses (and free coordinates) into the next run,
    and they can push it onto another branch of the linkage. A settled run that came to rest
    off the analytic branch (:func:`off_branch`) is not kept: that pose is run again alone
    from the analytic pose, as ``mechcheck run`` runs it (:func:`restarted`), its
    diagnostics say so (``restart``), and the sweep goes on in a model built anew there."""
    drivers = driver_values(case, values)
    assert drivers is not None
    walk = _HeldWalk(case, backend, results, drivers, backend == BACKENDS[1],
                     has_free_coordinates(case))
    for k, value in enumerate(values):
        walk.step(k, float(value))
    method = "constraint_solve" if walk.solve else "settle"
    given = walk.given
    for built, outcomes in walk.segments:
        given.update(zip((o.index for o in outcomes),
                         solutions(built, backend, method, outcomes, results, values), strict=True))
    return [given[k] if "driver" in given[k].diagnostics else with_driver(given[k], float(v))
            for k, v in enumerate(values)]


@dataclass
class _HeldWalk:
    """A held sweep on its way: the model it continues in (None: build one at the next
    pose), where free coordinates last came to rest, the poses given a Solution directly
    and the runs of each model built."""

    case: Case
    backend: str
    results: LinkageResults
    drivers: Array
    solve: bool
    free: bool
    model: LinkageModel | None = None
    previous: Array | None = None
    given: dict[int, Solution] = field(default_factory=dict)
    segments: list[tuple[LinkageModel, list[Outcome]]] = field(default_factory=list)

    def step(self, k: int, value: float) -> None:
        """Pose k, at the first driver's ``value``: run, or given its verdict."""
        start = time.perf_counter()
        case, solve, free = self.case, self.solve, self.free
        found = None if solve or not free else unstable(case, self.backend, self.results, k)
        if found is not None:
            self.given[k] = found
            return
        q = self.results.pose.q[k]
        seed = q if solve or not free else self.previous if self.previous is not None \
            else free_start(case, self.drivers[k])
        fresh = self.model is None
        if self.model is None:
            self.model = sweep_model(case, solve, seed)
            self.segments.append((self.model, []))
        model = self.model
        move_lock(model, case.linkage.joint(case.linkage.drivers[0].joint), value)
        place(model, seed)
        run = solve_run(model, q) if solve else sweep_settle_run(
            model, q if fresh and not (free or model.members) else None)
        done = outcome(model, run, start, k)
        left = "" if solve or not run.settled else off_branch(model, done.q, q, free)
        if left:
            self.given[k] = restarted(case, self.backend, value, left)
            self.model, self.previous = None, None
            return
        self.segments[-1][1].append(done)
        if free and run.settled:
            self.previous = done.q


def sweep_settle_run(model: LinkageModel, prime_at: Array | None) -> Run:
    """A settling run of the sweep; the first of a model built anew with every coordinate
    held after pymunk's own constraint solve at the pose ``prime_at`` has warmed its
    impulses: from none, the first steps' unresolved load can jolt a held linkage onto its
    other branch (as :func:`~.linkage.primed_settle_run` does for one pose). Elastic
    members are not primed: re-posed unstretched, they would carry nothing."""
    if prime_at is not None:
        solve_run(model, prime_at)
    return held_settle_run(model)


#: A settled run of free coordinates (or of elastic members, which deflect by their strain)
#: that came to rest farther than this × the linkage's size from the analytic pose found
#: another equilibrium: the bound driven runs use for leaving an assembly
#: (:data:`~mechcheck.sim_models.convergence.DRIVEN_DRIFT`). A held rigid linkage is held
#: to :data:`~.linkage.ASSEMBLY_DRIFT`.
FREE_BRANCH_DRIFT = DRIVEN_DRIFT


def off_branch(model: LinkageModel, rest: Array, q: Array, free: bool) -> str:
    """Why a settled run that came to rest at ``rest`` left the analytic branch at pose ``q``
    (both (3n,)), or ``""``: it is farther from ``q`` than :data:`~.linkage.ASSEMBLY_DRIFT` ×
    size (held) or :data:`FREE_BRANCH_DRIFT` × size (free coordinates, or elastic members)."""
    bound = (FREE_BRANCH_DRIFT if free or model.members else ASSEMBLY_DRIFT) * model.scale
    # A body's drift is at most its largest coordinate change × (√2 + its radius): checked
    # first, as one subtraction, since every pose of a sweep is checked and few are off.
    if float(np.abs(rest - q).max()) * (1.5 + float(model.radii.max())) <= bound:
        return ""
    drift = float(pose_drifts(model.radii, rest[None], q[None])[0])
    if drift <= bound:
        return ""
    return (f"continuing from the previous pose, the run came to rest {drift:.3g} m from the "
            f"analytic pose (more than {bound:.3g} m): another branch; restarted from the "
            "analytic pose")


def restarted(case: Case, backend: str, value: float, why: str) -> Solution:
    """The pose at ``value`` of the first driver run alone, as ``mechcheck run`` runs it
    (:func:`~.linkage.settle`), with ``why`` it was restarted as its ``restart`` diagnostic."""
    sol = settle(at_first_driver(case, value))
    return Solution(sol.case, backend, sol.values, sol.status, sol.message,
                    {**sol.diagnostics, "driver": value, "restart": why}, units=sol.units)


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
