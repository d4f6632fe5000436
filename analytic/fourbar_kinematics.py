"""Four-bar kinematics in closed form (the seed's/Söylemez's formulation).

With angles measured from the ground line A0→B0 (φ = θ − ground_angle)::

    C = a1² + a2² + a4² − a3² − 2 a1 a2 cos φ12
    A = −2 a1 a4 + 2 a2 a4 cos φ12,   B = 2 a2 a4 sin φ12,   f = atan2(B, A)
    φ14 = f ∓ acos(C / √(A² + B²))       (open: −, crossed: +)

Velocities and accelerations follow from differentiating the loop
a2 e2 + a3 e3 − a4 e4 − a1 e1 = 0 and projecting on e3 and e4.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mechcheck.analytic.case import FourBarGeometry
from mechcheck.analytic.pose import Array, LinkState, Placement, Pose, perp, stacked


def rocker_angle(g: FourBarGeometry, cos12: Array, sin12: Array, branch: str) -> Array:
    """φ14 (from the ground line) by the seed's closed form, from cos φ12 and sin φ12; NaN
    where it cannot assemble."""
    a = -2.0 * g.a1 * g.a4 + 2.0 * g.a2 * g.a4 * cos12
    b = 2.0 * g.a2 * g.a4 * sin12
    f = np.arctan2(b, a)
    ratio = _cos_ratio(g, cos12, sin12)
    # Rounding can push an exactly-toggling pose to |ratio| = 1 + 1e-16; clip
    # only that, so a truly unassemblable pose still gives NaN.
    ratio = np.where(np.abs(ratio) <= 1.0 + 1e-12, np.clip(ratio, -1.0, 1.0), np.nan)
    sign = -1.0 if branch == "open" else 1.0
    return f + sign * np.arccos(ratio)


def _cos_ratio(g: FourBarGeometry, cos12: Array, sin12: Array) -> Array:
    """cos(φ14 − atan2(b, a)) of the rocker's closed form: a pose assembles where it is
    within [−1, 1] (to rounding)."""
    c = g.a1**2 + g.a2**2 + g.a4**2 - g.a3**2 - 2.0 * g.a1 * g.a2 * cos12
    a = -2.0 * g.a1 * g.a4 + 2.0 * g.a2 * g.a4 * cos12
    b = 2.0 * g.a2 * g.a4 * sin12
    # a2 = a1 at φ12 = 0 (hypot 0), or a hypot near the smallest double: no pose, an
    # infinite or NaN ratio, and no warning.
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        return c / np.hypot(a, b)


def assembles(g: FourBarGeometry, cos12: Array, sin12: Array) -> NDArray[np.bool_]:
    """Where :func:`rocker_angle` has a pose (either branch)."""
    return np.abs(_cos_ratio(g, cos12, sin12)) <= 1.0 + 1e-12


def positions(g: FourBarGeometry, theta12: Array, *, branch: str,
              ground_angle: float) -> Placement:
    """Where the links of a four-bar are at each θ12: the closed form, and nothing that
    statics would throw away."""
    cg, sg = float(np.cos(ground_angle)), float(np.sin(ground_angle))
    c2, s2 = np.cos(theta12), np.sin(theta12)
    theta14 = rocker_angle(g, c2 * cg + s2 * sg, s2 * cg - c2 * sg, branch) + ground_angle
    c4, s4 = np.cos(theta14), np.sin(theta14)
    ax, ay = g.a2 * c2, g.a2 * s2
    b0x, b0y = g.a1 * cg, g.a1 * sg
    bx, by = b0x + g.a4 * c4, b0y + g.a4 * s4
    # The coupler's direction is B − A over its length: no trigonometry needed.
    vx, vy = bx - ax, by - ay
    return Placement(theta12=theta12, angles={2: theta12, 3: np.arctan2(vy, vx), 4: theta14},
                     directions={2: (c2, s2), 3: (vx / g.a3, vy / g.a3), 4: (c4, s4)},
                     joints={"A0": (0.0, 0.0), "A": (ax, ay), "B": (bx, by), "B0": (b0x, b0y)})


def pose(g: FourBarGeometry, theta12: Array, omega: float, alpha: float, *,
         branch: str, ground_angle: float) -> Pose:
    """Positions, velocities and accelerations of a four-bar at each θ12."""
    n = theta12.shape[0]
    place = positions(g, theta12, branch=branch, ground_angle=ground_angle)
    theta13, theta14 = place.angles[3], place.angles[4]
    a0, a, b, b0 = (stacked(place.joints[k], n) for k in ("A0", "A", "B", "B0"))
    e2, e3, e4 = (stacked(place.directions[k], n) for k in (2, 3, 4))

    w2 = np.full(n, float(omega))
    al2 = np.full(n, float(alpha))
    s34 = np.sin(theta13 - theta14)
    w3 = -g.a2 * w2 * np.sin(theta14 - theta12) / (g.a3 * np.sin(theta14 - theta13))
    w4 = g.a2 * w2 * np.sin(theta13 - theta12) / (g.a4 * s34)
    # Known part of the differentiated velocity loop; α3, α4 balance it.
    known = (g.a2 * (al2[:, None] * perp(e2) - (w2**2)[:, None] * e2)
             - g.a3 * (w3**2)[:, None] * e3 + g.a4 * (w4**2)[:, None] * e4)
    al3 = -np.einsum("ij,ij->i", known, e4) / (g.a3 * np.sin(theta14 - theta13))
    al4 = np.einsum("ij,ij->i", known, e3) / (g.a4 * s34)

    zero2 = np.zeros((n, 2))
    v_a = g.a2 * w2[:, None] * perp(e2)
    acc_a = g.a2 * (al2[:, None] * perp(e2) - (w2**2)[:, None] * e2)
    links = {
        2: LinkState(a0, zero2, zero2, theta12.copy(), w2, al2),
        3: LinkState(a, v_a, acc_a, theta13, w3, al3),
        4: LinkState(b0, zero2, zero2, theta14, w4, al4),
    }
    return Pose(theta12=theta12, joints={"A0": a0, "A": a, "B": b, "B0": b0}, links=links)


def assembly_interval(g: FourBarGeometry) -> tuple[float, float] | None:
    """The crank angles φ12 (from the ground line) that assemble, as [lo, hi] in
    [0, π]; the mechanism assembles for |φ12| in that interval (it is symmetric
    about the ground line). None if it never assembles.

    The distance d = |A B0|, d² = a1² + a2² − 2 a1 a2 cos φ12, must lie in
    [|a3 − a4|, a3 + a4].
    """
    def cos_for(d: float) -> float:
        return (g.a1**2 + g.a2**2 - d**2) / (2.0 * g.a1 * g.a2)

    # d grows with φ12 on [0, π]: d(0) = |a1 − a2|, d(π) = a1 + a2.
    lo_d, hi_d = abs(g.a3 - g.a4), g.a3 + g.a4
    if hi_d < abs(g.a1 - g.a2) or lo_d > g.a1 + g.a2:
        return None
    lo = float(np.arccos(np.clip(cos_for(lo_d), -1.0, 1.0))) if lo_d > abs(g.a1 - g.a2) else 0.0
    hi = float(np.arccos(np.clip(cos_for(hi_d), -1.0, 1.0))) if hi_d < g.a1 + g.a2 else float(np.pi)
    return (lo, hi)
