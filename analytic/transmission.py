"""Transmission angle μ over θ12, vectorised (seed 001).

Four-bar: the angle between coupler and rocker, μ = |θ13 − θ14| folded into
[0°, 180°]; ideal 90°. Slider-crank: the angle between the connecting rod and
the normal to the slide, so that for a centric slider-crank with the crank at
90°, cos μ = a2/a3 (the seed's μmin).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from mechcheck.analytic.case import Case, Preset, preset_of
from mechcheck.analytic.kinematics import Array, pose_of


def transmission_angle(case: Case | Preset, theta12: ArrayLike | None = None) -> Array:
    """μ (rad) at each θ12; NaN where the pose cannot be assembled."""
    pose = pose_of(case, theta12, omega=0.0, alpha=0.0)
    if pose.s14 is None:
        diff = np.abs(np.remainder(pose.theta13 - pose.theta14 + np.pi, 2 * np.pi) - np.pi)
        return diff
    # Angle between the rod and the slide normal: 90° minus the rod's angle to the slide.
    rod_to_slide = np.abs(np.remainder(pose.theta13 - preset_of(case).ground_angle + np.pi / 2, np.pi)
                          - np.pi / 2)
    return np.pi / 2 - rod_to_slide
