"""The pymunk (Munk2D / Chipmunk 7) backends.

- :func:`settle` — backend ``pymunk``: static equilibrium held by simulation
  until settled; dynamic and friction cases are driven through θ12.
- :func:`solve_at_pose` — backend ``pymunk_solve``: pymunk's constraint
  solver at the fixed analytic pose (statics).
- :func:`sweep` — a θ12 sweep with continuation in one Space.

Linkage cases (``mechanism = "linkage"``) go to :mod:`~mechcheck.sim_models.pymunk.linkage`,
moving ones to :mod:`~mechcheck.sim_models.pymunk.linkage_dynamics` (model:
:mod:`~mechcheck.sim_models.pymunk.linkage_model`).

Modules: ``model`` (Case → Space), ``forces`` (reading force vectors),
``loads``, ``readout``, ``settle``, ``solve``, ``dynamics``, ``friction``,
``sweep``, ``study`` (solver-setting study), ``settings``.
"""

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage_backends import analytic_results
from mechcheck.analytic.solution import Solution
from mechcheck.sim_models.linkage_motion import is_driven
from mechcheck.sim_models.pymunk import linkage, linkage_dynamics, settle as settling, solve as solving
from mechcheck.sim_models.pymunk.settings import (
    LINKAGE_SETTLE,
    LINKAGE_SOLVE,
    SETTLE,
    SOLVE,
    SolverSettings,
)
from mechcheck.sim_models.pymunk.sweep import sweep

__all__ = ["settle", "solve_at_pose", "sweep"]


def settle(case: Case, settings: SolverSettings | None = None) -> Solution:
    """The ``pymunk`` backend (:func:`mechcheck.sim_models.pymunk.settle.settle`; linkages:
    :func:`mechcheck.sim_models.pymunk.linkage.settle`, moving ones and Coulomb friction
    :func:`mechcheck.sim_models.pymunk.linkage_dynamics.drive_linkage`), with its own
    settings by default."""
    if case.mechanism == "linkage" and is_driven(case):
        return linkage_dynamics.drive_linkage(case, analytic_results(case))
    if case.mechanism == "linkage":
        return linkage.settle(case, settings or LINKAGE_SETTLE)
    return settling.settle(case, settings or SETTLE)


def solve_at_pose(case: Case, settings: SolverSettings | None = None) -> Solution:
    """The ``pymunk_solve`` backend (:func:`mechcheck.sim_models.pymunk.solve.solve_at_pose`;
    linkages: :func:`mechcheck.sim_models.pymunk.linkage.solve_at_pose`)."""
    if case.mechanism == "linkage":
        return linkage.solve_at_pose(case, settings or LINKAGE_SOLVE)
    return solving.solve_at_pose(case, settings or SOLVE)
