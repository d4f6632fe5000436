"""The fence: everything in the pymunk backends that is there for speed, or that reaches
past pymunk's public API.

- :mod:`.layout` — offsets into Chipmunk's private C structs (bodies, constraints),
  checked once per process against public values; the impulse :data:`~.layout.Cell`\\ s
  and the only Python code that reads or writes one.
- :mod:`.bulk` — :class:`~.bulk.Bodies`: every body read and written in one C call
  (pymunk's batch iterators on preallocated arrays) and ``cpSpaceStep`` called directly.
- :mod:`.compiled` — the :class:`~.compiled.Plan` of a model (addresses and load terms as
  arrays) and the compiled run; :mod:`.kernel` — its numba loop (imported only with numba).

The physics modules import this package, never its modules: what they may use is below.
"""

from mechcheck.sim_models.pymunk._fast.bulk import Bodies
from mechcheck.sim_models.pymunk._fast.compiled import Plan, available, plan, run
from mechcheck.sim_models.pymunk._fast.layout import Cell, impulse_cells, read, write

__all__ = ["Bodies", "Cell", "Plan", "available", "impulse_cells", "plan", "read", "run", "write"]
