"""Pose, velocity and acceleration of every link of a four-bar or slider-crank, vectorised
over θ12: the closed forms of :mod:`mechcheck.analytic.fourbar_kinematics` and
:mod:`mechcheck.analytic.slidercrank_kinematics`, which fill in a
:class:`~mechcheck.analytic.pose.Pose`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mechcheck.analytic import fourbar_kinematics, slidercrank_kinematics
from mechcheck.analytic.case import Case, FourBarGeometry, Preset, preset_of
from mechcheck.analytic.pose import Array, LinkState, Placement, Pose, cross, perp, unit

__all__ = [
    "Array",
    "LinkState",
    "Placement",
    "Pose",
    "as_angles",
    "assembles",
    "cross",
    "perp",
    "placement_of",
    "pose_of",
    "unit",
]


def as_angles(theta12: ArrayLike) -> Array:
    """θ12 as a 1-D float array (a scalar becomes length 1)."""
    return np.atleast_1d(np.asarray(theta12, dtype=float))


def pose_of(case: Case | Preset, theta12_rad: ArrayLike | None = None, *,
            omega: float | None = None, alpha: float | None = None) -> Pose:
    """The pose of ``case`` at its own θ12, or at an array of them.

    ``omega``/``alpha`` override the case's motion (the static force analysis
    with friction needs velocity *ratios*, computed with a unit ω).
    """
    # A pose that does not assemble is NaN by design (its verdict is no_solution):
    # the arithmetic on it must not warn.
    p = preset_of(case)
    with np.errstate(invalid="ignore", divide="ignore"):
        angles = as_angles(p.theta12 if theta12_rad is None else theta12_rad)
        w = p.motion.omega if omega is None else omega
        a = p.motion.alpha if alpha is None else alpha
        g = p.geometry
        if isinstance(g, FourBarGeometry):
            return fourbar_kinematics.pose(g, angles, w, a, branch=p.branch,
                                           ground_angle=p.ground_angle)
        return slidercrank_kinematics.pose(g, angles, w, a, branch=p.branch,
                                           ground_angle=p.ground_angle)


def placement_of(case: Case | Preset, theta12: Array) -> Placement:
    """Where the links of ``case`` are at each θ12 (rad): positions only, for statics."""
    p = preset_of(case)
    module = fourbar_kinematics if isinstance(p.geometry, FourBarGeometry) else slidercrank_kinematics
    return module.positions(p.geometry, theta12, branch=p.branch, ground_angle=p.ground_angle)


def assembles(case: Case | Preset, theta12: ArrayLike) -> NDArray[np.bool_]:
    """Where the closed form places ``case`` at each θ12 (rad): a few operations per pose,
    without placing it."""
    p = preset_of(case)
    angles = as_angles(theta12) - p.ground_angle
    g = p.geometry
    if isinstance(g, FourBarGeometry):
        return fourbar_kinematics.assembles(g, np.cos(angles), np.sin(angles))
    return slidercrank_kinematics.assembles(g, np.sin(angles))
