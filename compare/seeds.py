"""The seed examples' printed answers beside the computed ones.

The seeds print magnitudes and directions rather than components, so a
printed key may name a derived quantity: ``F34`` (magnitude, N),
``F34_angle`` (direction of F34, deg), ``F43_angle`` (of the opposite force),
``N14`` (the slide's normal force, N), ``theta31`` (θ13 measured B→A, deg), or
any CONVENTIONS quantity in table units. A linkage's printed key is one of its own
quantities (LINKAGES.md: ``Q_A0``, ``phi_bar`` …), in the unit its joint, link or spring
gives it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from mechcheck.analytic.case import Case, preset_of
from mechcheck.analytic.linkage_backends import quantity_units
from mechcheck.analytic.solution import QUANTITY_UNITS, Solution, table_value, wraps


def _wrap_deg(angle: float) -> float:
    return (angle + 180.0) % 360.0 - 180.0


def derived_value(case: Case, solution: Solution, key: str) -> float | None:
    """The computed counterpart of a printed key, or None if the solution lacks it."""
    v = solution.values
    if key in QUANTITY_UNITS:
        return v[key] * QUANTITY_UNITS[key][1] if key in v else None
    if not case.is_preset:
        return table_value(key, v[key], seed_unit(case, key)) if key in v else None
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


def _preset_unit(key: str) -> str:
    """The unit of a four-bar's or slider-crank's printed key."""
    if key.endswith("_angle") or key == "theta31":
        return "deg"
    if key in QUANTITY_UNITS:
        return QUANTITY_UNITS[key][0]
    return "N"  # F34, N14: force magnitudes


def seed_unit(case: Case, key: str) -> str:
    """The unit of a printed key as the tables write it: a linkage's from the kind of the
    joint, link or spring it names (a revolute driver's effort N*m, a prismatic one's N)."""
    if case.is_preset:
        return _preset_unit(key)
    return quantity_units(case.linkage).get(key, "")


@dataclass(frozen=True)
class SeedRow:
    case: str
    key: str
    printed: float
    computed: float | None
    source: str
    note: str
    #: The unit of a linkage's key (:func:`seed_unit`); a preset's follows from the key.
    quantity_unit: str = ""

    @property
    def unit(self) -> str:
        """The unit of the printed value and of the deviation, as the tables write it."""
        return self.quantity_unit or _preset_unit(self.key)

    @property
    def deviation(self) -> float | None:
        if self.computed is None:
            return None
        d = self.computed - self.printed
        direction = (self.key.endswith("_angle") or self.key.startswith("theta")
                     or wraps(self.key, self.unit))
        return _wrap_deg(d) if direction else d


def seed_row(case: Case, solution: Solution, key: str, printed: float, source: str,
             note: str) -> SeedRow:
    """A printed answer of ``case`` beside ``solution``'s value, in the key's unit."""
    return SeedRow(case.name, key, printed, derived_value(case, solution, key), source, note,
                   "" if case.is_preset else seed_unit(case, key))
