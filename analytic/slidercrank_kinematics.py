"""Slider-crank kinematics in closed form, with offset and tilted slide.

With u the slide direction (ground_angle g), n = u turned +90° and φ = θ − g,
pin B = a2 e2 + a3 e3 = s14 u + e n. Projecting on n fixes the rod angle,
sin φ13 = (e − a2 sin φ12)/a3; ``right`` takes cos φ13 ≥ 0 (larger s14),
``left`` cos φ13 ≤ 0.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mechcheck.analytic.case import SliderCrankGeometry
from mechcheck.analytic.pose import Array, LinkState, Placement, Pose, stacked


def rod_angle(g: SliderCrankGeometry, sin12: Array, branch: str) -> tuple[Array, Array]:
    """(cos φ13, sin φ13) of the rod (from the slide axis), from sin φ12; NaN where the
    pose cannot assemble."""
    s = (g.offset - g.a2 * sin12) / g.a3
    s = np.where(assembles(g, sin12), np.clip(s, -1.0, 1.0), np.nan)
    c = np.sqrt(1.0 - s**2) * (1.0 if branch == "right" else -1.0)
    return c, s


def assembles(g: SliderCrankGeometry, sin12: Array) -> NDArray[np.bool_]:
    """Where :func:`rod_angle` has a pose (either branch): |sin φ13| ≤ 1, to rounding."""
    return np.abs((g.offset - g.a2 * sin12) / g.a3) <= 1.0 + 1e-12


def positions(g: SliderCrankGeometry, theta12: Array, *, branch: str,
              ground_angle: float) -> Placement:
    """Where the links of a slider-crank are at each θ12: the closed form, and nothing that
    statics would throw away."""
    cg, sg = float(np.cos(ground_angle)), float(np.sin(ground_angle))  # u; n = (−sg, cg)
    c2, s2 = np.cos(theta12), np.sin(theta12)
    cos2 = c2 * cg + s2 * sg
    c3, s3 = rod_angle(g, s2 * cg - c2 * sg, branch)
    s14 = g.a2 * cos2 + g.a3 * c3
    return Placement(theta12=theta12, angles={2: theta12, 3: np.arctan2(s3, c3) + ground_angle},
                     directions={2: (c2, s2), 3: (c3 * cg - s3 * sg, s3 * cg + c3 * sg),
                                 4: (cg, sg)},
                     joints={"A0": (0.0, 0.0), "A": (g.a2 * c2, g.a2 * s2),
                             "B": (s14 * cg - g.offset * sg, s14 * sg + g.offset * cg)},
                     s14=s14)


def pose(g: SliderCrankGeometry, theta12: Array, omega: float, alpha: float, *,
         branch: str, ground_angle: float) -> Pose:
    """Positions, velocities and accelerations of a slider-crank at each θ12."""
    n = theta12.shape[0]
    place = positions(g, theta12, branch=branch, ground_angle=ground_angle)
    assert place.s14 is not None
    phi2 = theta12 - ground_angle
    phi3 = place.angles[3] - ground_angle
    u = np.array(place.directions[4])
    a0, a, b = (stacked(place.joints[k], n) for k in ("A0", "A", "B"))

    w2 = np.full(n, float(omega))
    al2 = np.full(n, float(alpha))
    w3 = -g.a2 * w2 * np.cos(phi2) / (g.a3 * np.cos(phi3))
    s_dot = -g.a2 * w2 * np.sin(phi2) - g.a3 * w3 * np.sin(phi3)
    al3 = (-g.a2 * (al2 * np.cos(phi2) - w2**2 * np.sin(phi2))
           + g.a3 * w3**2 * np.sin(phi3)) / (g.a3 * np.cos(phi3))
    s_ddot = (g.a2 * (-al2 * np.sin(phi2) - w2**2 * np.cos(phi2))
              + g.a3 * (-al3 * np.sin(phi3) - w3**2 * np.cos(phi3)))

    e2 = stacked(place.directions[2], n)
    zero2 = np.zeros((n, 2))
    perp_e2 = np.stack([-e2[:, 1], e2[:, 0]], axis=-1)
    v_a = g.a2 * w2[:, None] * perp_e2
    acc_a = g.a2 * (al2[:, None] * perp_e2 - (w2**2)[:, None] * e2)
    zeros = np.zeros(n)
    links = {
        2: LinkState(a0, zero2, zero2, theta12.copy(), w2, al2),
        3: LinkState(a, v_a, acc_a, place.angles[3], w3, al3),
        4: LinkState(b, s_dot[:, None] * u, s_ddot[:, None] * u,
                     np.full(n, float(ground_angle)), zeros, zeros.copy()),
    }
    return Pose(theta12=theta12, joints={"A0": a0, "A": a, "B": b}, links=links,
                s14=place.s14, s14_dot=s_dot, s14_ddot=s_ddot)


def assembly_interval(g: SliderCrankGeometry) -> tuple[float, float] | None:
    """Range of sin φ12 that assembles, as (lo, hi) ⊂ [−1, 1]; None if none.

    |e − a2 sin φ12| ≤ a3  ⇔  (e − a3)/a2 ≤ sin φ12 ≤ (e + a3)/a2.
    """
    lo = (g.offset - g.a3) / g.a2
    hi = (g.offset + g.a3) / g.a2
    if lo > 1.0 or hi < -1.0:
        return None
    return (max(lo, -1.0), min(hi, 1.0))
