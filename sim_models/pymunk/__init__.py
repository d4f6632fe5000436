"""The pymunk (Munk2D / Chipmunk 7) backends.

- :func:`settle` — backend ``pymunk``: static equilibrium held by simulation
  until settled; dynamic and friction cases are driven through θ12.
- :func:`solve_at_pose` — backend ``pymunk_solve``: pymunk's constraint
  solver at the fixed analytic pose (statics).
- :func:`sweep` — a θ12 sweep with continuation in one Space.

Modules: ``model`` (Case → Space), ``forces`` (reading force vectors),
``loads``, ``readout``, ``settle``, ``solve``, ``dynamics``, ``friction``,
``sweep``, ``study`` (solver-setting study), ``settings``.
"""

from mechcheck.sim_models.pymunk.settle import settle
from mechcheck.sim_models.pymunk.solve import solve_at_pose
from mechcheck.sim_models.pymunk.sweep import sweep

__all__ = ["settle", "solve_at_pose", "sweep"]
