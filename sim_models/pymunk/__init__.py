"""pymunk (Munk2D / Chipmunk 7) backends (:mod:`.backend`).

- ``pymunk``: static equilibrium held by simulation until settled; dynamic and friction
  cases driven through their prescribed motion;
- ``pymunk_solve``: pymunk's constraint solver at the fixed analytic pose (statics).

Nothing here imports pymunk, so that listing the backends stays light: the functions
(``settle``, ``solve_at_pose``, ``sweep``) are in :mod:`.backend`.
"""

from __future__ import annotations

from mechcheck.sim_models.protocol import held_and_exact

SIMULATOR = held_and_exact("pymunk", "mechcheck.sim_models.pymunk.backend",
                           "pymunk, held until settled (statics) or driven (dynamics, friction)",
                           "pymunk's constraint solver at the fixed analytic pose",
                           "mechcheck.sim_models.pymunk.stiffness:stiffness_study")
BACKENDS = SIMULATOR.backends
