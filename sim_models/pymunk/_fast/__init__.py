"""The fence: what the pymunk backends do for speed or past pymunk's public API
(:mod:`.layout` C-struct offsets and impulse cells, :mod:`.bulk` bodies in bulk,
:mod:`.compiled` and :mod:`.kernel` the numba loop; ../README.md). The physics modules
use this package's names below, never its modules.
"""

from mechcheck.sim_models.pymunk._fast.bulk import Bodies
from mechcheck.sim_models.pymunk._fast.compiled import Plan, available, plan, run
from mechcheck.sim_models.pymunk._fast.layout import Cell, direction_cells, impulse_cells, read, write

__all__ = ["Bodies", "Cell", "Plan", "available", "direction_cells", "impulse_cells", "plan", "read",
           "run", "write"]
