"""Can a Case be assembled at its θ12?  If not, say which θ12 can.

A pose that cannot be assembled is unusable input, so the message must tell
the user what would be usable: the θ12 range for that geometry and branch.
"""

from __future__ import annotations

import math

import numpy as np

from mechcheck.analytic import fourbar_kinematics, slidercrank_kinematics
from mechcheck.analytic.case import Case, CaseError, FourBarGeometry


def _deg(rad: float) -> str:
    return f"{math.degrees(rad):.4g}°"


def assembly_range_text(case: Case) -> str:
    """Human description of the θ12 values (global, degrees) that assemble."""
    g = case.geometry
    gd = case.ground_angle
    if isinstance(g, FourBarGeometry):
        interval = fourbar_kinematics.assembly_interval(g)
        if interval is None:
            return "no θ12 assembles this geometry (a link is longer than the other three together)"
        lo, hi = interval
        if lo == 0.0 and hi == math.pi:
            return "every θ12 assembles (the crank turns fully)"
        if lo == 0.0:
            return f"θ12 must lie in [{_deg(gd - hi)}, {_deg(gd + hi)}]"
        if hi == math.pi:
            return (f"θ12 must lie in [{_deg(gd + lo)}, {_deg(gd + 2 * math.pi - lo)}]")
        return (f"θ12 must lie in [{_deg(gd + lo)}, {_deg(gd + hi)}] or "
                f"[{_deg(gd - hi)}, {_deg(gd - lo)}]")
    interval = slidercrank_kinematics.assembly_interval(g)
    if interval is None:
        return "no θ12 assembles this geometry (the offset exceeds crank plus rod)"
    lo, hi = interval
    if lo <= -1.0 and hi >= 1.0:
        return "every θ12 assembles (the crank turns fully)"
    # sin φ in [lo, hi]: describe in φ, then shift by the ground angle.
    a_lo, a_hi = math.asin(lo), math.asin(hi)
    if lo <= -1.0:
        return f"θ12 must lie in [{_deg(gd + math.pi - a_hi)}, {_deg(gd + 2 * math.pi + a_hi)}]"
    if hi >= 1.0:
        return f"θ12 must lie in [{_deg(gd + a_lo)}, {_deg(gd + math.pi - a_lo)}]"
    return (f"θ12 must lie in [{_deg(gd + a_lo)}, {_deg(gd + a_hi)}] or "
            f"[{_deg(gd + math.pi - a_hi)}, {_deg(gd + math.pi - a_lo)}]")


def check_assembly(case: Case) -> None:
    """Raise :class:`CaseError` (key ``theta12``) if the case's pose cannot be assembled."""
    from mechcheck.analytic.kinematics import pose_of

    p = pose_of(case, omega=0.0, alpha=0.0)
    if not np.all(np.isfinite(p.theta14)) or not np.all(np.isfinite(p.theta13)):
        raise CaseError(
            f"the {case.mechanism} cannot be assembled at θ12 = {_deg(case.theta12)} "
            f"({case.branch} branch): {assembly_range_text(case)}", key="theta12")
