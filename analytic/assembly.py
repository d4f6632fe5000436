"""Can a Case be assembled at its θ12?  If not, say which θ12 can.

A geometry that assembles at no θ12 is unusable input (the geometry refuses itself).
A θ12 outside the range that assembles is a property of the pose, like a toggle:
every backend gives it the verdict ``no_solution``, naming the range that does
assemble; a θ12 inside the range where the pose is still undefined is a change
point (``singular``) (:func:`unassembled_verdict`).
"""

from __future__ import annotations

import math

from mechcheck.analytic import fourbar_kinematics, slidercrank_kinematics
from mechcheck.analytic.case import Case, FourBarGeometry, Preset, preset_of
from mechcheck.analytic.solution import Status

#: Decimal places of the degrees in printed ranges (rounded inward, so that every
#: printed value, an endpoint included, assembles).
RANGE_DECIMALS = 4


def _deg_range(lo: float, hi: float) -> str:
    """[lo, hi] in degrees, rounded inward."""
    scale = 10.0**RANGE_DECIMALS
    a = math.ceil(round(math.degrees(lo) * scale, 6)) / scale
    b = math.floor(round(math.degrees(hi) * scale, 6)) / scale
    return f"[{a:.{RANGE_DECIMALS}f}°, {b:.{RANGE_DECIMALS}f}°]"


def assembly_range_text(case: Case | Preset) -> str:
    """Human description of the θ12 values (global, degrees) that assemble."""
    g = preset_of(case).geometry
    gd = preset_of(case).ground_angle
    why = g.never_assembles()
    if why is not None:
        return f"no θ12 assembles this geometry ({why})"
    if isinstance(g, FourBarGeometry):
        interval = fourbar_kinematics.assembly_interval(g)
        assert interval is not None
        lo, hi = interval
        if lo == 0.0 and hi == math.pi:
            return "every θ12 assembles (the crank turns fully)"
        if lo == 0.0:
            return f"θ12 must lie in {_deg_range(gd - hi, gd + hi)}"
        if hi == math.pi:
            return f"θ12 must lie in {_deg_range(gd + lo, gd + 2 * math.pi - lo)}"
        return (f"θ12 must lie in {_deg_range(gd + lo, gd + hi)} or "
                f"{_deg_range(gd - hi, gd - lo)}")
    sin_range = slidercrank_kinematics.assembly_interval(g)
    assert sin_range is not None
    lo, hi = sin_range
    if lo <= -1.0 and hi >= 1.0:
        return "every θ12 assembles (the crank turns fully)"
    # sin φ in [lo, hi]: describe in φ, then shift by the ground angle.
    a_lo, a_hi = math.asin(lo), math.asin(hi)
    if lo <= -1.0:
        return f"θ12 must lie in {_deg_range(gd + math.pi - a_hi, gd + 2 * math.pi + a_hi)}"
    if hi >= 1.0:
        return f"θ12 must lie in {_deg_range(gd + a_lo, gd + math.pi - a_lo)}"
    return (f"θ12 must lie in {_deg_range(gd + a_lo, gd + a_hi)} or "
            f"{_deg_range(gd + math.pi - a_hi, gd + math.pi - a_lo)}")


def in_assembly_range(case: Case | Preset, theta12: float) -> bool:
    """Whether θ12 (rad) lies in the range that assembles (endpoints included, to rounding)."""
    g = preset_of(case).geometry
    phi = math.remainder(theta12 - preset_of(case).ground_angle, math.tau)
    slack = 1e-12
    if isinstance(g, FourBarGeometry):
        interval = fourbar_kinematics.assembly_interval(g)
        return interval is not None and interval[0] - slack <= abs(phi) <= interval[1] + slack
    sin_range = slidercrank_kinematics.assembly_interval(g)
    return sin_range is not None and sin_range[0] - slack <= math.sin(phi) <= sin_range[1] + slack


def unassembled_verdict(case: Case | Preset, theta12: float) -> tuple[Status, str]:
    """The verdict at a θ12 (rad) where the pose has no unique position: ``no_solution``
    outside the range that assembles, ``singular`` at a change point inside it."""
    at = f"θ12 = {math.degrees(theta12):.6g}°"
    if in_assembly_range(case, theta12):
        return ("singular", change_point_message(case, theta12))
    return ("no_solution", f"the {preset_of(case).mechanism} cannot be assembled at {at} "
                           f"({preset_of(case).branch} branch): {assembly_range_text(case)}")


def change_point_message(case: Case | Preset, theta12: float) -> str:
    """Why a preset has no unique forces at a change point θ12 (rad)."""
    return (f"θ12 = {math.degrees(theta12):.6g}° is a change point of this {preset_of(case).mechanism}: "
            "the links fold onto one line, where the branches meet and the position of the "
            "coupler is not determined; statics is singular there")
