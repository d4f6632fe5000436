"""Free coordinates: the equilibrium pose of a static linkage with more degrees of freedom
than drivers (LINKAGES.md "Degrees of freedom"; seed 002's exam Q1).

The pose must close every loop and hold every driver, Φ(q) = 0, and the known forces
(loads, weights, springs) must do no virtual work in any motion the constraints allow:
their generalized force Q(q) = −∇V has no component in the null space of the constraint
Jacobian J. It is **stable** where the potential energy V, followed along the constraint
manifold, has a positive definite Hessian.

The search first **descends** the potential along the manifold from the drawn pose, so
that it ends on a minimum, a stable equilibrium, wherever one is reachable: projected
Newton steps on V, with the Hessian's eigenvalues made positive (a direction of negative
curvature is followed downhill, so a maximum or a saddle is left), a step bound that grows
while the quadratic model holds, and a line search that requires V to fall. The end is
polished by Gauss–Newton on [Φ(q); (I − J⁺J)·Q(q)]. Where descent finds no minimum (the
potential keeps falling as a slide runs off, or no direction lowers it), Gauss–Newton from
the drawn pose finds the nearest stationary point, maxima included, and the reason is kept.

Everything is in units of the linkage's size L (:func:`~.linkage_kinematics.unit_scales`):
coordinates z = (t/L, φ), constraint rows Φ/L or angles, energies relative to the force
level of the pose (its generalized forces and reduced curvature). Every tolerance is
relative, so a drawing scaled by any factor, with forces scaled consistently, gives the
same pose, verdict and stability.
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
    unit_scales,
)
from mechcheck.analytic.linkage_loads import known_vector

#: Gauss–Newton budget and convergence (the residual is dimensionless, see the module).
ITERATIONS = 60
RTOL = 1e-12
#: Finite-difference step of the Gauss–Newton Jacobian, in z (a size fraction or radians).
STEP = 1e-7
#: Step of the Lagrangian gradient's central differences (the reduced Hessian): near
#: eps^(1/3), where truncation and rounding errors (~1e-10 of the force level) balance.
HESSIAN_STEP = 1e-5
#: Descent budget, first step bound (a quarter of the size, or 0.25 rad) and the largest
#: rotation of one step: a link turning further might skip a minimum on its way.
DESCENT_ITERATIONS = 200
FIRST_STEP = 0.25
LARGEST_TURN = 1.0
#: Backtracking halvings of one step, and the fraction of the model's decrease it must
#: achieve (Armijo).
BACKTRACKS = 40
ARMIJO = 1e-4
#: A slide that descent carries this many sizes from the drawn pose runs off: the
#: potential falls without bound, or toward a bound it never reaches, along it.
RUNAWAY = 1e4
#: Descent has reached a minimum where the reduced gradient is below this fraction of the
#: force level; curvatures below STABLE_RTOL of it count as zero (neither sign is trusted
#: beyond the difference quotients' ~1e-10).
GRADIENT_RTOL = 1e-9
STABLE_RTOL = 1e-8
#: Closure of the constraints (dimensionless rows) after a step along the manifold.
CLOSURE_RTOL = 1e-13
CLOSURE_ITERATIONS = 30
#: Singular values of the scaled Jacobian below this fraction of the largest count as 0.
RANK_RTOL = 1e-9


@dataclass(frozen=True)
class Equilibrium:
    q: Array            # (3n,) coordinates at equilibrium
    converged: bool
    stable: bool
    residual: float
    #: Why only an unstable equilibrium was found ("" where stable or none was found).
    reason: str = ""


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


# -- the problem in units of the linkage's size -----------------------------------------

@dataclass(frozen=True)
class _Model:
    """The potential near one pose, in the free directions N of the manifold there."""

    free: Array          # N (3n, f): orthonormal in z
    gradient: Array      # Nᵀ∇V (f,)
    hessian: Array       # the reduced Hessian (f, f), constraint stiffness included
    level: float         # the force level: largest |∂V/∂z| or reduced curvature


@dataclass(frozen=True)
class _Units:
    """The linkage at fixed driver values, in coordinates z with q = cols·z."""

    linkage: Linkage
    values: Array
    cols: Array          # L for translations, 1 for rotations
    rows: Array          # 1/L for rows that are lengths, 1 for angle rows

    @classmethod
    def of(cls, linkage: Linkage, values: Array) -> _Units:
        rows, cols = unit_scales(linkage)   # a system in lengths: t and L·φ
        size = linkage.scale
        return cls(linkage, values, cols * size, rows / size)

    def constraints(self, q: Array) -> tuple[Array, Array]:
        """(Φ̂ (m,), ∂Φ̂/∂z (m, 3n)), dimensionless."""
        phi, jac = residual_and_jacobian(self.linkage, q[None, :], self.values[None, :])
        return self.rows * phi[0], self.rows[:, None] * jac[0] * self.cols[None, :]

    def gradient(self, q: Array) -> Array:
        """∂V/∂z = −cols·Q(q)."""
        return -self.cols * _generalized(self.linkage, q, self.values)

    def close(self, q: Array) -> Array | None:
        """The pose on the constraints nearest q (least-norm Newton steps in z), or None
        where they do not close (the linkage locks on the way)."""
        q = q.copy()
        with np.errstate(all="ignore"):
            for _ in range(CLOSURE_ITERATIONS):
                phi, jac = self.constraints(q)
                if not np.all(np.isfinite(phi)):
                    return None
                size = max(1.0, float(np.abs(q / self.cols).max()))
                if float(np.abs(phi).max(initial=0.0)) <= CLOSURE_RTOL * size:
                    return q
                q = q - self.cols * np.linalg.lstsq(jac, phi, rcond=None)[0]
        return None

    def model(self, q: Array) -> _Model:
        """The reduced gradient and Hessian at q. The Hessian is that of the Lagrangian
        V − μ·Φ̂ (μ the least-squares multipliers) along N, by central differences of its
        gradient: the constraint forces' stiffness through the manifold's curvature is in
        it, and it is the Hessian of V followed along the manifold."""
        _, jac = self.constraints(q)
        free = _null_space(jac)
        grad = self.gradient(q)
        mu = np.linalg.lstsq(jac.T, grad, rcond=None)[0] if jac.size else np.zeros(0)

        def lagrangian_gradient(shift: Array) -> Array:
            qq = q + self.cols * shift
            return self.gradient(qq) - self.constraints(qq)[1].T @ mu

        h = HESSIAN_STEP
        columns = [(lagrangian_gradient(h * n) - lagrangian_gradient(-h * n)) / (2 * h)
                   for n in free.T]
        hessian = free.T @ np.array(columns).T if columns else np.zeros((0, 0))
        hessian = 0.5 * (hessian + hessian.T)
        eig = np.abs(np.linalg.eigvalsh(hessian)) if hessian.size else np.zeros(0)
        level = max(float(np.abs(grad).max(initial=0.0)), float(eig.max(initial=0.0)))
        return _Model(free, free.T @ grad, hessian, level)


def _null_space(jac: Array) -> Array:
    """An orthonormal basis (3n, f) of the null space of the scaled Jacobian."""
    _, s, vt = np.linalg.svd(jac)
    rank = int((s > RANK_RTOL * s[0]).sum()) if s.size and s[0] > 0.0 else 0
    return np.asarray(vt[rank:].T, dtype=np.float64)


def _is_minimum(model: _Model) -> bool:
    """Positive curvature in every free direction, relative to the force level."""
    if not model.hessian.size:
        return False
    return bool(np.linalg.eigvalsh(model.hessian).min() > STABLE_RTOL * model.level)


# -- descent ----------------------------------------------------------------------------

@dataclass(frozen=True)
class _Descent:
    q: Array
    minimum: bool        # ended where the gradient vanishes and the curvature is positive
    runaway: bool        # a slide ran off with the potential still falling
    reason: str          # why no minimum was reached ("" if one was)


def _direction(model: _Model, bound: float) -> Array:
    """A descent direction in N, per eigenvector of the reduced Hessian: Newton's where the
    curvature is positive, else ``bound`` downhill (the quadratic model has no minimum
    there). A maximum or saddle, where the gradient vanishes, is so left along its falling
    direction, and a slope that flattens out is followed at the bound, not crept along."""
    lam, vec = np.linalg.eigh(model.hessian)
    comp = vec.T @ model.gradient
    floor = STABLE_RTOL * model.level
    step = np.empty_like(comp)
    for i, (c, curvature) in enumerate(zip(comp, lam, strict=True)):
        if curvature > floor:
            step[i] = -c / curvature
        elif c != 0.0 or curvature < -floor:
            step[i] = -bound if c >= 0.0 else bound
        else:
            step[i] = 0.0
    return np.asarray(vec @ step, dtype=np.float64)


def _bounded(model: _Model, direction: Array, bound: float) -> tuple[Array, bool]:
    """The direction shortened to at most ``bound`` in z and LARGEST_TURN of any rotation;
    whether it reaches the bound (where a good step widens it)."""
    dz = model.free @ direction
    length = float(np.linalg.norm(dz))
    turn = float(np.abs(dz[2::3]).max(initial=0.0))
    factor = min(1.0, bound / max(length, 1e-300), LARGEST_TURN / max(turn, 1e-300))
    return direction * factor, factor * length >= (1.0 - 1e-9) * bound


def _runaway(units: _Units, q: Array) -> str:
    """The slide carried furthest from the drawn pose if beyond RUNAWAY sizes, else ""."""
    linkage = units.linkage
    pose = _static_pose(linkage, q[None, :], units.values[None, :])
    travel = {joint.name: abs(float(pose.joint_coordinate(joint)[0][0]))
              for joint in linkage.joints if not joint.kind.rotates}
    far = max(travel, key=lambda name: travel[name], default="")
    return far if far and not travel[far] <= RUNAWAY * linkage.scale else ""


def _descend(units: _Units, q: Array) -> _Descent:
    """Descent of the potential along the manifold from q (see the module)."""
    start = units.close(q)
    if start is None:
        return _Descent(q, False, False, "the drawn pose does not close, so no descent starts "
                        "from it")
    q, bound = start, FIRST_STEP
    for _ in range(DESCENT_ITERATIONS):
        model = units.model(q)
        if _is_minimum(model) and float(np.linalg.norm(model.gradient)) \
                <= GRADIENT_RTOL * model.level:
            return _Descent(q, True, False, "")
        direction, at_bound = _bounded(model, _direction(model, bound), bound)
        accepted = _line_search(units, model, q, direction)
        if accepted is None:
            return _Descent(q, False, False, _stall_reason(units, model, q, direction))
        q, alpha = accepted
        length = alpha * float(np.linalg.norm(model.free @ direction))
        if alpha == 1.0 and at_bound:  # the step held over the whole bound: widen it
            bound = min(2.0 * bound, RUNAWAY)
        elif alpha < 1.0:
            bound = max(length, 1e-3 * FIRST_STEP)
        slide = _runaway(units, q)
        if slide:
            return _Descent(q, False, True, (
                f"descending the potential from the drawn pose carries joint {slide} more than "
                f"{RUNAWAY:g} times the linkage's size away with the potential still falling, so "
                f"no minimum is reachable: the potential falls without bound (or toward a bound "
                f"it never reaches) along {slide}"))
    return _Descent(q, False, False, f"descending the potential from the drawn pose reached no "
                    f"minimum within {DESCENT_ITERATIONS} steps")


def _line_search(units: _Units, model: _Model, q: Array,
                 direction: Array) -> tuple[Array, float] | None:
    """(pose, fraction α of the step) where V falls by at least ARMIJO of the model's
    decrease α·g·d + ½α²·min(dᵀHd, 0), halving α; None where no fraction does."""
    v0 = potential(units.linkage, q)
    slope = float(model.gradient @ direction)
    curvature = min(float(direction @ model.hessian @ direction), 0.0)
    alpha = 1.0
    for _ in range(BACKTRACKS):
        trial = units.close(q + units.cols * (model.free @ (alpha * direction)))
        if trial is not None:
            drop = v0 - potential(units.linkage, trial)
            if drop > 0.0 and drop >= -ARMIJO * (alpha * slope + 0.5 * alpha**2 * curvature):
                return trial, alpha
        alpha /= 2.0
    return None


def _stall_reason(units: _Units, model: _Model, q: Array, direction: Array) -> str:
    """Why descent stopped short of a minimum."""
    if units.close(q + units.cols * (model.free @ (1e-6 * direction))) is None:
        return ("descending the potential from the drawn pose stops where the linkage locks: "
                "the constraints do not close beyond that pose")
    return ("descending the potential from the drawn pose stops at a pose where no motion the "
            "constraints allow lowers it, and the potential's curvature there is not positive "
            "in every free direction")


# -- stationarity (polish) --------------------------------------------------------------

def _residual(units: _Units, q: Array, scale: float) -> Array:
    """[Φ̂(q); (I − Ĵ⁺Ĵ)·∂V/∂z / scale] for one pose. ``scale`` is fixed for the whole
    search: divided by a size that changes with q, the largest component would be ±1
    wherever it is and its derivative 0 (a 5 m exam-Q1 bar stalled at the drawn pose)."""
    phi, jac = units.constraints(q)
    projector = np.eye(q.shape[0]) - np.linalg.pinv(jac) @ jac
    return np.concatenate([phi, projector @ units.gradient(q) / scale])


def _polish(units: _Units, q: Array) -> tuple[Array, float]:
    """Gauss–Newton on the stationarity residual from q: (pose, residual norm)."""
    scale = max(units.model(q).level, 1e-300)
    r = _residual(units, q, scale)
    trial = r
    for _ in range(ITERATIONS):
        jac = np.stack([(_residual(units, q + units.cols * e, scale)
                         - _residual(units, q - units.cols * e, scale)) / (2 * STEP)
                        for e in np.eye(q.shape[0]) * STEP], axis=1)
        step = units.cols * np.linalg.lstsq(jac, -r, rcond=None)[0]
        # Halve the step until the residual falls: Gauss–Newton may overshoot far from it.
        for _ in range(30):
            trial = _residual(units, q + step, scale)
            if np.linalg.norm(trial) < np.linalg.norm(r) \
                    or np.linalg.norm(step / units.cols) < 1e-15:
                break
            step = step / 2
        q, r = q + step, trial
        if np.linalg.norm(r) <= RTOL:
            break
    return q, float(np.linalg.norm(r))


def _stable(units: _Units, q: Array) -> bool:
    """The potential's Hessian along the constraint manifold is positive definite."""
    return _is_minimum(units.model(q))


def equilibrium(linkage: Linkage, values: Array) -> Equilibrium:
    """The equilibrium pose reached from the drawn pose (drivers first brought to their
    values with the free coordinates carried along), and whether it is stable: a stable
    one wherever descent of the potential reaches it, else the stationary point nearest
    the drawn pose, with the reason no stable one was found."""
    with np.errstate(all="ignore"):
        start, _ = positions(linkage, values[None, :])
        drawn = np.nan_to_num(start[0])
        units = _Units.of(linkage, values)
        descent = _descend(units, drawn)
        unstable: list[tuple[Array, float]] = []
        origins = [drawn] if descent.runaway else [descent.q, drawn]
        q, residual = drawn, np.inf
        for origin in origins:
            q, residual = _polish(units, origin)
            if not residual <= 1e3 * RTOL:
                continue
            if _stable(units, q):
                return Equilibrium(q, True, True, residual)
            unstable.append((q, residual))
    if not unstable:
        return Equilibrium(q, False, False, residual)
    q, residual = unstable[0]
    reason = descent.reason or ("descending the potential from the drawn pose ends at a "
                                "stationary point whose curvature is not positive in every "
                                "free direction")
    return Equilibrium(q, True, False, residual, reason)


def unstable_reason(linkage: Linkage, values: Array) -> str:
    """The message of a pose whose free coordinates' equilibrium is unstable: that only an
    unstable one was found from the drawn pose, and why (the search is repeated; it is
    deterministic)."""
    found = equilibrium(linkage, np.asarray(values, dtype=float))
    return ("only an unstable equilibrium of the free coordinates was found from the drawn "
            f"pose: {found.reason or 'the potential has no minimum where the search ended'}")


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
