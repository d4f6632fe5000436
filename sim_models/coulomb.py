"""Where a driven run cannot measure Coulomb friction: its relative motion reverses or stops.

A simulator takes the sense of each Coulomb force from its own relative
motion. Where the prescribed motion makes that motion stop at the reading
(ω(t*) = 0 with α ≠ 0: the whole mechanism reverses there) the sense is not
a property of the motion at all; the case's ``direction`` settles it by
convention, which no simulated motion can show. For pymunk, whose readings
are judged smooth over a stretch of steps before t*, a reversal anywhere in
that stretch already makes the reading unjudgeable (see
:func:`mechcheck.sim_models.pymunk.dynamics.coulomb_reversal`). Shared by both
simulators; kinematics of the prescribed motion only, no force enters.
"""

from __future__ import annotations

import numpy as np

from mechcheck.analytic.case import Case
from mechcheck.analytic.equilibrium import relative_omega
from mechcheck.analytic.kinematics import pose_of

#: Relative speeds within this fraction of the largest one over the stretch
#: judged count as zero (closed forms give ±1e-17 where a speed vanishes).
ZERO_SPEED = 1e-12

#: rad/s: a crank slower than this is at rest for a simulator. In 1 s it
#: turns 1e-9 rad, below what a driven run tracks its clock to (~1e-7 rad
#: per reading); measured: MuJoCo read T12 7.8e-3 off at ω = −3e-232 rad/s,
#: α = 0, where only the sign of ω sets the Coulomb senses.
REST_OMEGA = 1e-9


def coulomb_speeds(case: Case, omega: float, alpha: float, tau: np.ndarray) -> dict[str, np.ndarray]:
    """Relative speed of every Coulomb term at the times ``tau`` from the reading along the
    prescribed crank motion θ12 + ω·τ + ½·α·τ² (ω_j − ω_i at a pin, ṡ on the slide)."""
    f = case.friction
    if f is None:
        return {}
    theta = case.theta12 + omega * tau + 0.5 * alpha * tau * tau
    pose = pose_of(case, np.atleast_1d(theta), omega=1.0, alpha=0.0)
    crank = omega + alpha * tau
    out = {joint: relative_omega(pose, joint) * crank
           for joint in ("A0", "A", "B", "B0") if f.pin_moment_arm(joint) > 0.0}
    if pose.s14_dot is not None and f.slide_coefficient() > 0.0:
        out["slide"] = pose.s14_dot * crank
    return out


def coulomb_reversal(case: Case, omega: float, alpha: float, tau: np.ndarray,
                     at: int) -> tuple[str, str]:
    """(joint, what) of the first Coulomb term whose relative motion stops at ``tau[at]``
    (the reading) or changes sense anywhere over ``tau``; ("", "") when none does."""
    resting = np.abs(omega + alpha * tau) <= REST_OMEGA
    for joint, speed in coulomb_speeds(case, omega, alpha, tau).items():
        scale = float(np.abs(speed).max())
        sense = np.where((np.abs(speed) <= ZERO_SPEED * scale) | resting, 0.0, np.sign(speed))
        if scale == 0.0 or sense[at] == 0.0:
            return joint, "is at rest at the reading"
        if np.any(sense != sense[at]):
            return joint, "reverses next to the reading"
    return "", ""


def at_rest_reason(case: Case, omega: float, alpha: float) -> str:
    """Why a simulator cannot give the friction forces: a Coulomb term is at rest at the reading."""
    joint, what = coulomb_reversal(case, omega, alpha, np.zeros(1), 0)
    if not joint:
        return ""
    return (f"the relative motion of the Coulomb friction at {joint} {what} (prescribed motion "
            f"ω = {omega:g} rad/s, α = {alpha:g} rad/s²): the sense its friction opposes is "
            "not a property of the motion there (the case's direction settles it by "
            "convention), so a simulator cannot measure it")
