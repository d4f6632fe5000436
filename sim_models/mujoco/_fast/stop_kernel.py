"""The stop rules (:func:`..settle.first_stops`, the one body) compiled in numba: imported
through :func:`mechcheck.sim_models.compiled.kernel` only where numba is installed.

The same source in the same floating-point operations; the kernel only skips the
interpreter. Its helpers are made callable from compiled code as they are
(``register_jitable``), so the Python run and the compiled one are one text.
"""

from __future__ import annotations

from numba import njit
from numba.extending import register_jitable

from mechcheck.sim_models.mujoco import settle

for _helper in settle.STOP_RULE_HELPERS:
    register_jitable(_helper)

first_stops = njit(nogil=True, cache=True)(settle.first_stops)
