"""The pymunk (Munk2D / Chipmunk 7) backends, on any linkage.

- :func:`settle` — backend ``pymunk``: statics held by simulation until settled
  (:mod:`.linkage`); moving and Coulomb-friction cases driven along their motion
  (:mod:`.linkage_dynamics`).
- :func:`solve_at_pose` — backend ``pymunk_solve``: pymunk's constraint solver at the
  fixed analytic pose (statics).
- :func:`sweep` — either backend over the first driver (:mod:`.linkage_sweep`).
- :func:`simulate` — backend ``pymunk`` on a trajectory case: the linkage moving freely,
  on a ladder of time steps and iterations (:mod:`.trajectory`).

The modules, one line each, and the fence around the speed code (``_fast/``): README.md.
"""

import numpy as np
from numpy.typing import ArrayLike

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage_backends import analytic_results, quantity_units
from mechcheck.analytic.solution import Solution
from mechcheck.analytic.trajectory import Trajectory
from mechcheck.sim_models.linkage_motion import gated_sweep, is_driven, unmodelled
from mechcheck.sim_models.pymunk import linkage, linkage_dynamics, linkage_sweep, trajectory
from mechcheck.sim_models.pymunk.joint_kinds import BUILDERS, builder
from mechcheck.sim_models.pymunk.members import modelled, sliding_ends
from mechcheck.sim_models.pymunk.settings import LINKAGE_SETTLE, LINKAGE_SOLVE, SolverSettings

__all__ = ["settle", "simulate", "solve_at_pose", "sweep"]


def refused(case: Case, backend: str, stretches: bool = False) -> Solution | None:
    """``not_applicable`` for what the pymunk model has no counterpart for
    (:func:`~mechcheck.sim_models.linkage_motion.unmodelled`), else None. ``stretches``: the
    run models elastic members (a held structure settled by simulation), if each has an
    end to slide (:func:`.members.sliding_ends`)."""
    why = (unmodelled(case.linkage, BUILDERS, "pymunk", stretches) or built_inexactly(case)
           or (unstretched(case) if stretches else None))
    if why is None:
        return None
    return Solution(case.name, backend, {}, status="not_applicable", message=why,
                    units=quantity_units(case.linkage))


def unstretched(case: Case) -> str | None:
    """Why the elastic members of this redundant linkage cannot stretch in the model, or
    None."""
    if not modelled(case.linkage):
        return None
    ends = sliding_ends(case.linkage)
    return ends if isinstance(ends, str) else None


def built_inexactly(case: Case) -> str | None:
    """Why a joint's build would not be exact in this linkage (its builder's refusal), or
    None."""
    for joint in case.linkage.joints:
        why = builder(joint).refusal(case.linkage, joint)
        if why is not None:
            return why
    return None


def settle(case: Case, settings: SolverSettings | None = None) -> Solution:
    """The ``pymunk`` backend: a linkage held until settled
    (:func:`mechcheck.sim_models.pymunk.linkage.settle`), or driven along its prescribed motion
    when it moves or has Coulomb friction
    (:func:`mechcheck.sim_models.pymunk.linkage_dynamics.drive_linkage`)."""
    no = refused(case, "pymunk", stretches=not is_driven(case))
    if no is not None:
        return no
    if is_driven(case):
        return linkage_dynamics.drive_linkage(case, analytic_results(case))
    return linkage.settle(case, settings or LINKAGE_SETTLE)


def solve_at_pose(case: Case, settings: SolverSettings | None = None) -> Solution:
    """The ``pymunk_solve`` backend: pymunk's constraint solver at the analytic pose
    (:func:`mechcheck.sim_models.pymunk.linkage.solve_at_pose`)."""
    no = refused(case, "pymunk_solve")
    return no if no is not None else linkage.solve_at_pose(case, settings or LINKAGE_SOLVE)


def sweep(case: Case, grid: ArrayLike, backend: str = "pymunk") -> list[Solution]:
    """``pymunk`` or ``pymunk_solve`` over a sweep of a linkage's first driver (rad or m from
    the drawn pose, :func:`mechcheck.sim_models.pymunk.linkage_sweep.sweep`), behind the
    pose gate (:func:`~mechcheck.sim_models.linkage_motion.gated_sweep`)."""
    if backend not in linkage_sweep.BACKENDS:
        raise ValueError(f"backend must be one of {linkage_sweep.BACKENDS}, got {backend!r}")
    no = refused(case, backend)
    if no is not None:
        return [no for _ in np.atleast_1d(np.asarray(grid, dtype=float))]
    return gated_sweep(case, np.asarray(grid, dtype=float), backend,
                       lambda values, results: linkage_sweep.sweep(case, values, backend, results))


def simulate(case: Case) -> tuple[Trajectory, ...]:
    """The ``pymunk`` backend on a trajectory case: one run per rung of its ladder, the
    last the finest (:func:`mechcheck.sim_models.pymunk.trajectory.simulate`); one
    ``not_applicable`` run for what the model has no counterpart for."""
    no = refused(case, "pymunk")
    if no is not None:
        return (trajectory.refused(case, no.message),)
    return trajectory.simulate(case)
