"""The seed examples' printed answers beside the computed ones.

The seeds print magnitudes and directions rather than components, so a
printed key may name a derived quantity: ``F34`` (magnitude, N),
``F34_angle`` (direction of F34, deg), ``F43_angle`` (of the opposite force),
``N14`` (the slide's normal force, N), ``theta31`` (θ13 measured B→A, deg), or
any CONVENTIONS quantity in table units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from mechcheck.analytic.case import Case, preset_of
from mechcheck.analytic.solution import QUANTITY_UNITS, Solution


def _wrap_deg(angle: float) -> float:
    return (angle + 180.0) % 360.0 - 180.0


def derived_value(case: Case, solution: Solution, key: str) -> float | None:
    """The computed counterpart of a printed key, or None if the solution lacks it."""
    v = solution.values
    if key in QUANTITY_UNITS:
        return v[key] * QUANTITY_UNITS[key][1] if key in v else None
    if key == "theta31" and "theta13" in v:
        return _wrap_deg(math.degrees(v["theta13"]) + 180.0) % 360.0
    if key == "N14" and "F14_x" in v:
        # The slide's normal: the slide direction turned +90°.
        ground = preset_of(case).ground_angle
        return abs(-v["F14_x"] * math.sin(ground) + v["F14_y"] * math.cos(ground))
    if len(key) >= 3 and key[0] == "F" and key[1:3].isdigit():
        i, j = key[1], key[2]
        name = f"F{min(i, j)}{max(i, j)}"
        if f"{name}_x" not in v:
            return None
        x, y = v[f"{name}_x"], v[f"{name}_y"]
        if key.endswith("_angle"):
            angle = math.degrees(math.atan2(y, x)) + (180.0 if i > j else 0.0)
            return _wrap_deg(angle)
        return math.hypot(x, y)
    return None


@dataclass(frozen=True)
class SeedRow:
    case: str
    key: str
    printed: float
    computed: float | None
    source: str
    note: str

    @property
    def unit(self) -> str:
        """The unit of the printed value and of the deviation, as the tables write it."""
        if self.key.endswith("_angle") or self.key == "theta31":
            return "deg"
        if self.key in QUANTITY_UNITS:
            return QUANTITY_UNITS[self.key][0]
        return "N"  # F34, N14: force magnitudes

    @property
    def deviation(self) -> float | None:
        if self.computed is None:
            return None
        d = self.computed - self.printed
        return _wrap_deg(d) if self.key.endswith("_angle") or self.key.startswith("theta") else d
