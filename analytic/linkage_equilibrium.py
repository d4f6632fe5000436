"""Free coordinates: the equilibrium pose of a static linkage with more degrees of freedom
than drivers (LINKAGES.md "Degrees of freedom"; seed 002's exam Q1).

The pose must close every loop and hold every driver, Φ(q) = 0, and the known forces
(loads, weights, springs) must do no virtual work in any motion the constraints allow:
their generalized force Q(q) has no component in the null space of the constraint
Jacobian J, i.e. (I − J⁺J)·Q(q) = 0. The projector I − J⁺J is smooth in q where the rank
is constant, so Gauss–Newton on the stacked residual, from the drawn pose, with a
finite-difference Jacobian, finds the pose. It is **stable** when the potential energy of the
known forces, followed along the constraint manifold, has a positive definite Hessian.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mechcheck.analytic.linkage import Linkage, TorsionSpring
from mechcheck.analytic.linkage_kinematics import (
    Array,
    LinkagePose,
    positions,
    residual_and_jacobian,
    solve_batched,
)
from mechcheck.analytic.linkage_loads import known_vector

#: Gauss–Newton budget and convergence (relative to the linkage's size and force level).
ITERATIONS = 60
RTOL = 1e-12
#: Finite-difference step for the Jacobian of the residual, relative to the linkage's
#: size (translations) or in radians (rotations).
STEP = 1e-7
#: Step of the potential's second differences: rounding eps·V/h² stays ~1e-8 of V.
HESSIAN_STEP = 1e-4


@dataclass(frozen=True)
class Equilibrium:
    q: Array            # (3n,) coordinates at equilibrium
    converged: bool
    stable: bool
    residual: float


def generalized_forces(pose: LinkagePose, b: Array) -> Array:
    """Q (N, 3n): the known forces b (N, 3n: F, M about the origin per link) as generalized
    forces of the coordinates (t, φ): F, and M − t × F for the rotation."""
    q = np.zeros_like(b)
    for k in range(0, b.shape[1], 3):
        t = pose.q[:, k:k + 2]
        q[:, k:k + 2] = b[:, k:k + 2]
        q[:, k + 2] = b[:, k + 2] - (t[:, 0] * b[:, k + 1] - t[:, 1] * b[:, k])
    return q


def _static_pose(linkage: Linkage, q: Array, values: Array) -> LinkagePose:
    zeros = np.zeros_like(q)
    return LinkagePose(linkage, values, q, zeros, zeros, np.full(q.shape[0], np.nan))


def _generalized(linkage: Linkage, q: Array, values: Array) -> Array:
    """Q(q) (3n,): the known forces as generalized forces at one pose."""
    pose = _static_pose(linkage, q[None, :], values[None, :])
    return generalized_forces(pose, known_vector(pose))[0]


def _residual(linkage: Linkage, q: Array, values: Array, scale: float) -> Array:
    """[Φ(q); (I − J⁺J)·Q(q) / scale] for one pose (q: (3n,)). ``scale`` is fixed for the
    whole search: divided by a Q-dependent size, the largest component would be ±1
    wherever it is and its derivative 0 (a 5 m exam-Q1 bar stalled at the drawn pose)."""
    phi, jac = residual_and_jacobian(linkage, q[None, :], values[None, :])
    projector = np.eye(q.shape[0]) - np.linalg.pinv(jac[0]) @ jac[0]
    return np.concatenate([phi[0] / max(1.0, linkage.scale),
                           projector @ _generalized(linkage, q, values) / scale])


def _steps(linkage: Linkage, size: int) -> Array:
    h = np.full(size, STEP * max(1.0, linkage.scale))
    h[2::3] = STEP
    return h


def equilibrium(linkage: Linkage, values: Array) -> Equilibrium:
    """The equilibrium pose reached from the drawn pose (drivers first brought to their
    values with the free coordinates carried along), and whether it is stable."""
    start, _ = positions(linkage, values[None, :])
    q = np.nan_to_num(start[0])
    h = _steps(linkage, q.shape[0])
    scale = max(float(np.abs(_generalized(linkage, q, values)).max()), 1e-300)
    r = _residual(linkage, q, values, scale)
    for _ in range(ITERATIONS):
        jac = np.stack([(_residual(linkage, q + e, values, scale)
                         - _residual(linkage, q - e, values, scale))
                        / (2 * e.max()) for e in np.diag(h)], axis=1)
        step = np.linalg.lstsq(jac, -r, rcond=None)[0]
        # Halve the step until the residual falls: Gauss–Newton may overshoot far from it.
        for _ in range(30):
            trial = _residual(linkage, q + step, values, scale)
            if np.linalg.norm(trial) < np.linalg.norm(r) or np.linalg.norm(step) < 1e-15:
                break
            step = step / 2
        q, r = q + step, trial
        if np.linalg.norm(r) <= RTOL:
            break
    converged = bool(np.linalg.norm(r) <= 1e3 * RTOL)
    return Equilibrium(q, converged, converged and _stable(linkage, q, values),
                       float(np.linalg.norm(r)))


def potential(linkage: Linkage, q: Array) -> float:
    """The potential energy of the known static forces at coordinates q (3n,): constant
    forces and couples (−F·p, −τ·φ), weights (−m·g·p), springs (½·k·stretch²)."""
    pose = _static_pose(linkage, q[None, :], np.zeros((1, len(linkage.drivers))))
    energy = 0.0
    for load in linkage.loads:
        energy -= float(np.dot(load.force, pose.point(load.link, load.at)[0][0]))
        energy -= load.torque * float(pose.angle(load.link)[0][0])
    g = np.array(linkage.gravity)
    for m in linkage.masses:
        energy -= m.mass * float(np.dot(g, pose.point(m.link, m.com)[0][0]))
    for spring in linkage.springs:
        if isinstance(spring, TorsionSpring):
            stretch = float(pose.joint_coordinate(linkage.joint(spring.joint))[0][0]) \
                - spring.free_rotation
        else:
            (la, pa), (lb, pb) = spring.ends
            stretch = float(np.linalg.norm(pose.point(lb, pb)[0][0] - pose.point(la, pa)[0][0])) \
                - spring.free_length
        energy += 0.5 * spring.stiffness * stretch**2
    return energy


def _stable(linkage: Linkage, q: Array, values: Array) -> bool:
    """The potential's Hessian along the constraint manifold is positive definite.

    The manifold is followed, not its tangent: a step along the free directions N (the
    null space of J) is brought back onto the constraints, so the curvature of the
    manifold, through which the constraint forces contribute stiffness, is included. At
    an equilibrium the Hessian does not depend on how the manifold is parametrized.
    """
    _, jac = residual_and_jacobian(linkage, q[None, :], values[None, :])
    _, s, vt = np.linalg.svd(jac[0])
    rank = int((s > 1e-9 * s[0]).sum()) if s.size else 0
    free = vt[rank:].T                               # (3n, f)
    h = HESSIAN_STEP * max(1.0, linkage.scale)

    def energy_at(shift: Array) -> float:
        qq = q + free @ shift
        for _ in range(30):  # back onto the constraints
            phi, jj = residual_and_jacobian(linkage, qq[None, :], values[None, :])
            qq = qq - solve_batched(jj, phi)[0]
        return potential(linkage, qq)

    f = free.shape[1]
    eye = np.eye(f) * h
    base = energy_at(np.zeros(f))
    hessian = np.empty((f, f))
    for i in range(f):
        for j in range(i, f):
            hessian[i, j] = hessian[j, i] = (
                energy_at(eye[i] + eye[j]) - energy_at(eye[i] - eye[j])
                - energy_at(eye[j] - eye[i]) + energy_at(-eye[i] - eye[j])) / (4 * h * h) \
                if i != j else (energy_at(eye[i]) - 2 * base + energy_at(-eye[i])) / (h * h)
    return bool(np.all(np.linalg.eigvalsh(hessian) > 0.0))


def equilibrium_poses(linkage: Linkage, values: Array | None) -> tuple[LinkagePose, Array]:
    """The equilibrium pose of the free coordinates at each row of driver values (static
    cases only), and its stability per pose: 1 stable, 0 unstable, NaN not found."""
    d = len(linkage.drivers)
    rows = (np.array([[drv.value for drv in linkage.drivers]]) if values is None
            else np.atleast_2d(np.asarray(values, dtype=float)).reshape(-1, d))
    found = [equilibrium(linkage, row) for row in rows]
    q = np.array([e.q if e.converged else np.full(e.q.shape, np.nan) for e in found])
    stable = np.array([float(e.stable) if e.converged else np.nan for e in found])
    zeros = np.zeros_like(q)
    return LinkagePose(linkage, rows, q, zeros, zeros, np.full(rows.shape[0], np.nan)), stable
