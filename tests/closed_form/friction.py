"""Coulomb friction by the friction circle, solved to convergence.

At a pin (i, j) of radius r the reaction acts on a circle of radius μ·r about
the pin centre (the seed's small-angle friction circle, r·sin φ ≈ r·tan φ =
μ·r): equivalently the force through the centre plus a moment
μ·r·|F_ij| opposing the rotation of j relative to i. On the slide the
friction force μ·|N| opposes sliding, along the axis through pin B.

The moments depend on |F|, which the equations determine, so the system is
nonlinear. Newton's method on K x + b + φ(x) = 0, started from the
frictionless solution, converges quadratically; its Jacobian uses
∂|F|/∂F = F/|F|.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mechcheck.analytic.case import Case
from mechcheck.analytic.kinematics import Pose, cross, pose_of

from .equilibrium import (
    JOINT_LINKS,
    N_UNKNOWNS,
    PIN_COLUMNS,
    Array,
    relative_omega,
    row,
    slide_frame,
)

#: Newton stops when the update is below this fraction of the solution's size.
#: Convergence is quadratic, so the error left after that update is of order
#: its square: far below rounding.
NEWTON_RTOL = 1e-12
NEWTON_MAX_ITERATIONS = 50


@dataclass(frozen=True)
class CoulombTerm:
    """One Coulomb term: a pin (moment arm μ·r) or the slide (coefficient μ)."""

    joint: str
    coefficient: float
    sense: Array  # sign of ω_j − ω_i (pins) or of the slide velocity, per pose


def sense_pose(case: Case, theta12: Array) -> Pose:
    """A pose whose velocities have the signs friction opposes.

    A static case with friction is quasi-static motion in ``direction``: the
    velocity *ratios* follow from a unit input speed in that sense.
    """
    if case.preset.motion.omega != 0.0:
        return pose_of(case, theta12)
    return pose_of(case, theta12, omega=float(case.preset.input_sense), alpha=0.0)


#: Relative speeds below this fraction of the input speed count as zero: at an
#: exact dead centre the closed forms give ±1e-17, and rounding must not decide
#: which way a Coulomb force points (sign(0) = 0: no friction moment there).
ZERO_SPEED = 1e-12


def sense(speed: Array, reference: float) -> Array:
    """sign(speed), with speeds within rounding of zero taken as zero."""
    return np.where(np.abs(speed) <= ZERO_SPEED * abs(reference), 0.0, np.sign(speed))


def coulomb_terms(case: Case, theta12: Array) -> list[CoulombTerm]:
    """The active Coulomb terms with the sense each opposes."""
    f = case.preset.friction
    if f is None or not case.has_coulomb_friction:
        return []
    pose = sense_pose(case, theta12)
    w2 = float(pose.links[2].omega[0])
    terms = []
    for joint in PIN_COLUMNS:
        arm = f.pin_moment_arm(joint)
        if arm > 0.0:
            terms.append(CoulombTerm(joint, arm, sense(relative_omega(pose, joint), w2)))
    if case.mechanism == "slider_crank" and f.slide_coefficient() > 0.0:
        assert pose.s14_dot is not None
        terms.append(CoulombTerm("slide", f.slide_coefficient(),
                                 sense(pose.s14_dot, w2 * case.scale)))
    return terms


def slide_friction_force(term: CoulombTerm, normal: Array) -> Array:
    """Friction force on the slider along u: −μ·|N|·sign(ṡ)."""
    return -term.coefficient * np.abs(normal) * term.sense


def residual_terms(case: Case, pose: Pose, terms: list[CoulombTerm],
                   x: Array) -> tuple[Array, Array]:
    """φ(x) and its Jacobian ∂φ/∂x, shapes (N, 9) and (N, 9, 9)."""
    n = x.shape[0]
    phi = np.zeros((n, N_UNKNOWNS))
    dphi = np.zeros((n, N_UNKNOWNS, N_UNKNOWNS))
    for t in terms:
        if t.joint == "slide":
            u, _ = slide_frame(case)
            lever = cross(pose.joints["B"], np.broadcast_to(u, pose.joints["B"].shape))
            f = slide_friction_force(t, x[:, 6])
            df = -t.coefficient * np.sign(x[:, 6]) * t.sense
            for r, coef in ((6, u[0]), (7, u[1]), (8, lever)):
                phi[:, r] += coef * f
                dphi[:, r, 6] += coef * df
            continue
        i, j = JOINT_LINKS[t.joint]
        c0, c1 = PIN_COLUMNS[t.joint]
        mag = np.hypot(x[:, c0], x[:, c1])
        moment = -t.coefficient * mag * t.sense
        # d|F|/dF = F/|F|; divided componentwise, so that a denormal |F| cannot overflow
        # (1/|F| did, with a RuntimeWarning, in random identities).
        safe = np.where(mag > 0.0, mag, 1.0)
        gain = np.broadcast_to(-t.coefficient * t.sense, mag.shape)
        grad = gain[:, None] * (x[:, [c0, c1]] / safe[:, None])
        for link, sign in ((j, 1.0), (i, -1.0)):
            if link == 1:
                continue
            phi[:, row(link) + 2] += sign * moment
            dphi[:, row(link) + 2, c0] += sign * grad[:, 0]
            dphi[:, row(link) + 2, c1] += sign * grad[:, 1]
    return phi, dphi


def reversing_joints(terms: list[CoulombTerm]) -> list[tuple[str, NDArray[np.bool_]]]:
    """Joints whose Coulomb term reverses (zero relative speed) at each pose."""
    return [(t.joint, t.sense == 0.0) for t in terms if np.any(t.sense == 0.0)]


def solve_with_friction(case: Case, pose: Pose, k: Array, b: Array,
                        x0: Array) -> tuple[Array, NDArray[np.int_], NDArray[np.bool_]]:
    """Newton's method for K x + b + φ(x) = 0.

    Returns (x, iterations, converged) per pose. Poses whose iteration does
    not converge (a self-locking pose has no solution with the assumed
    senses) are reported as not converged, never silently returned.
    """
    terms = coulomb_terms(case, pose.theta12)
    x = x0.copy()
    n = x.shape[0]
    iterations = np.zeros(n, dtype=int)
    converged = np.zeros(n, dtype=bool)
    if not terms:
        return x, iterations, np.ones(n, dtype=bool)
    active = np.all(np.isfinite(x), axis=1)
    for _ in range(NEWTON_MAX_ITERATIONS):
        if not active.any():
            break
        idx = np.flatnonzero(active)
        sub = [CoulombTerm(t.joint, t.coefficient, t.sense[idx]) for t in terms]
        sub_pose = _take(pose, idx)
        phi, dphi = residual_terms(case, sub_pose, sub, x[idx])
        residual = np.einsum("nij,nj->ni", k[idx], x[idx]) + b[idx] + phi
        try:
            step = np.linalg.solve(k[idx] + dphi, residual[..., None])[..., 0]
        except np.linalg.LinAlgError:
            break
        x[idx] -= step
        iterations[idx] += 1
        size = np.abs(x[idx]).max(axis=1) + 1e-300
        done = np.abs(step).max(axis=1) <= NEWTON_RTOL * size
        converged[idx[done]] = True
        active[idx[done]] = False
    return x, iterations, converged


def _take(pose: Pose, idx: NDArray[np.intp]) -> Pose:
    """The sub-pose at indices idx (only joints are needed by the residual)."""
    return Pose(theta12=pose.theta12[idx], joints={k: v[idx] for k, v in pose.joints.items()},
                links=pose.links)
