"""The pymunk (Munk2D / Chipmunk 7) backends.

- :func:`settle` — backend ``pymunk``: static equilibrium held by simulation
  until settled; dynamic and friction cases are driven through θ12.
- :func:`solve_at_pose` — backend ``pymunk_solve``: pymunk's constraint
  solver at the fixed analytic pose (statics).
- :func:`sweep` — a θ12 sweep with continuation in one Space.

Linkage cases (``mechanism = "linkage"``) go to :mod:`~mechcheck.sim_models.pymunk.linkage`
(model: :mod:`~mechcheck.sim_models.pymunk.linkage_model`).

Modules: ``model`` (Case → Space), ``forces`` (reading force vectors),
``loads``, ``readout``, ``settle``, ``solve``, ``dynamics``, ``friction``,
``sweep``, ``study`` (solver-setting study), ``settings``.
"""

from mechcheck.analytic.case import Case
from mechcheck.analytic.solution import Solution
from mechcheck.sim_models.pymunk import linkage, settle as settling, solve as solving
from mechcheck.sim_models.pymunk.settings import SETTLE, SOLVE, SolverSettings
from mechcheck.sim_models.pymunk.sweep import sweep

__all__ = ["settle", "solve_at_pose", "sweep"]


def settle(case: Case, settings: SolverSettings = SETTLE) -> Solution:
    """The ``pymunk`` backend (:func:`mechcheck.sim_models.pymunk.settle.settle`)."""
    if case.mechanism == "linkage":
        return linkage.settle(case, settings)
    return settling.settle(case, settings)


def solve_at_pose(case: Case, settings: SolverSettings = SOLVE) -> Solution:
    """The ``pymunk_solve`` backend (:func:`mechcheck.sim_models.pymunk.solve.solve_at_pose`)."""
    if case.mechanism == "linkage":
        return linkage.solve_at_pose(case, settings)
    return solving.solve_at_pose(case, settings)
