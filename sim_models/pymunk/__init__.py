"""pymunk (Munk2D / Chipmunk 7) backends (:mod:`.backend`).

- ``pymunk``: static equilibrium held by simulation until settled; dynamic and friction
  cases driven through their prescribed motion;
- ``pymunk_solve``: pymunk's constraint solver at the fixed analytic pose (statics).

Nothing here imports pymunk, so that listing the backends stays light: the functions
(``settle``, ``solve_at_pose``, ``sweep``) are in :mod:`.backend`.
"""

from __future__ import annotations

from mechcheck.analytic.contract import Backend
from mechcheck.sim_models.protocol import Simulator

_HERE = "mechcheck.sim_models.pymunk.backend"

BACKENDS = (
    Backend("pymunk", f"{_HERE}:settle", "settled",
            "pymunk, held until settled (statics) or driven (dynamics, friction)",
            sweep=f"{_HERE}:sweep", requires="pymunk"),
    Backend("pymunk_solve", f"{_HERE}:solve_at_pose", "exact_solve",
            "pymunk's constraint solver at the fixed analytic pose",
            sweep=f"{_HERE}:sweep", requires="pymunk"),
)

SIMULATOR = Simulator("pymunk", BACKENDS, "mechcheck.sim_models.pymunk.stiffness:stiffness_study",
                      requires="pymunk")
