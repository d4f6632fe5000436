"""Forward dynamics of a linkage that moves freely: the analytic reference of a trajectory
case (:func:`.trajectory.simulate`).

The equations of motion are the linkage engine's own, written in **independent
coordinates** x: every driver's joint (an effort, or a prescribed motion) and as many free
joints as the linkage has degrees of freedom beyond its drivers (:func:`independent_joints`).
With each of them written as a driver row, the joints' rows (evaluated over all joints at
once, :mod:`.motion_rows`) give

- positions q(x): Newton's method on the constraints from the last pose, through a
  second-order predictor q + S·Δx + ½·q̈₀·τ², first with the last pose's factorisation (a
  chord iteration), so the motion stays on the branch it started on and passes a change
  point (a parallelogram lying flat) on its smooth branch; the positions are on the
  constraints at every evaluation (the "re-projection");
- velocities q̇ = S ẋ with J S = [0, I], and the accelerations' bias q̈₀ with
  J q̈₀ = −J̇ q̇, so that q̈ = S ẍ + q̈₀. Both are solved as corrections of the last state's:
  where the Jacobian is nearly singular (a change point, condition number above
  1/:data:`RCOND`) the part the constraints no longer decide stays the last state's
  (:class:`Solver`: the inverse or sparse LU factors, else the SVD). On a linkage of one
  coordinate, S and q̈₀ = B·ẋ² are taken where the Jacobian's smallest singular value is
  below :data:`.motion_bridge.SIGMA` from the polynomial along the branch through poses on
  either side (:class:`.motion_bridge.Bridge`): solved there, their rounding would grow
  like 1/σ³ and stall the integrator.

With 𝕄 the links' block-diagonal mass matrix and F the forces on them in the links' own
coordinates (:mod:`.motion_terms`), the efforts the coordinates need are
Q = Sᵀ(𝕄 q̈ − F): the constraints' reactions do no work on S, redundant ones included, so
the equations hold where the reactions are indeterminate (the redundant poses of a
parallelogram chain). So M = Sᵀ𝕄S, h = Sᵀ(𝕄 q̈₀ − F) and M ẍ = Q_applied − h.

Coulomb friction depends on the reactions, hence on ẍ: on a linkage of one degree of
freedom the member-equilibrium solve with friction
(:func:`.linkage_forces.solve_with_friction`) gives Q(ẍ), the friction forces being one
more term of the same equations, and the secant method solves Q(ẍ) = Q_applied from the
frictionless ẍ; the coordinate's rate reaching zero and a frictional joint's relative rate
reversing are events, at which the motion sticks or slips (:func:`integrate`). This term
goes through the engine's general per-joint code (one coordinate, a few unknowns).

scipy's ``solve_ivp`` integrates x, ẋ and the energy's work and dissipated terms at tight
tolerances (:data:`RTOL`); the kinetic and potential energies at the output times come from
the links' own motion through the engine's general code (:func:`kinetic_energy`,
:func:`potential_energy`, not :mod:`.motion_terms`), so T + V − W + D − E₀ = 0 is an
identity the run must satisfy to the integrator's tolerance (its ``energy_residual``).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from mechcheck.analytic._fast import motion as fast
from mechcheck.analytic.case import Case
from mechcheck.analytic.linalg import DENSE_COLUMNS
from mechcheck.analytic.linkage import Driver, LinearSpring, Linkage, TorsionSpring
from mechcheck.analytic.linkage_forces import (
    CoulombTerm,
    coefficient_entries,
    friction_residual,
    solve_with_friction,
)
from mechcheck.analytic.linkage_kinematics import (
    CLOSURE_RTOL,
    NEWTON_ITERATIONS,
    LinkagePose,
    constraint_system,
    positions,
    unit_scales,
)
from mechcheck.analytic.linkage_loads import known_vector, spring_axis
from mechcheck.analytic.motion_bridge import SIGMA, Bridge
from mechcheck.analytic.motion_rows import Rows, RowState, joint_rows
from mechcheck.analytic.motion_terms import terms
from mechcheck.analytic.rigid import Array, force_layout

#: The integrator and its relative tolerance. DOP853 (an explicit Runge–Kutta method of
#: order 8): on exam Q2 (0.5 s) it takes 515 right-hand sides where Radau takes 8 955 for the
#: same accuracy; no built-in case is stiff enough for an implicit method to pay.
METHOD = "DOP853"
RTOL = 1e-12
#: Singular values of the scaled constraint Jacobian below this fraction of the largest are
#: taken as zero: within 1e-10 of a change point the predicted rates keep the component
#: the constraints no longer decide (the smooth branch's), elsewhere the solves are exact.
RCOND = 1e-10
#: Rates S that change by more than this share of their size between two states closed one
#: from the other mean another branch (:meth:`Tracker.solve`): the state is then reached
#: through half-way states, at most :data:`HALVINGS` deep.
JUMP = 0.5
HALVINGS = 30
#: Newton steps with the last state's factorisation before a state's own Jacobian is
#: factorised: the predictor's error is of order Δx², and each step multiplies it by the
#: Jacobian's change over Δx, so two or three close it.
CHORD_ITERATIONS = 6
#: A joint named in ``rates`` becomes an independent coordinate where the scaled constraint
#: Jacobian with its row added keeps its smallest singular value above this (dimensionless:
#: rows and columns in lengths of the linkage's size).
INDEPENDENT = 1e-6
#: Switches of stick and slip (and of friction's sense at a joint) before a run gives up: a
#: linkage chattering between them would otherwise never reach its end time.
MAX_PHASES = 10_000
#: The secant iteration on Q(ẍ) = Q_applied with Coulomb friction: converged when the step
#: is below this fraction of the acceleration's size.
SECANT_RTOL = 1e-14
SECANT_ITERATIONS = 50
#: Rounds of inverse iteration for a Jacobian's smallest singular value: three give it
#: within a few per cent, enough to tell a nearly singular pose (motion_bridge.SIGMA).
INVERSE_ITERATIONS = 3
#: Every this many right-hand sides a run checks its pace, and ends, saying why, where at
#: that pace it would need more than MAX_EVALUATIONS more to reach its end time: the
#: integrator's step has collapsed (scipy stops only below 10 ulp of t, ~1e-300 s near
#: t = 0) and the run would go on for hours, keeping every state of its phase. The longest
#: built-in run takes 3 900 right-hand sides for all of its 10 s.
STALL_EVALUATIONS = 20_000
MAX_EVALUATIONS = 1_000_000


class DynamicsError(Exception):
    """The motion cannot be continued (the constraints no longer close, the friction
    equations have no solution): the run stops with this message."""


# -- the independent coordinates ----------------------------------------------------------

def independent_joints(linkage: Linkage, rates: tuple[str, ...] = ()) -> tuple[str, ...]:
    """The joints whose coordinates are the independent ones: the drivers' joints, then the
    free joints the linkage needs beyond them (its dof): those named in ``rates`` first
    (their rates at time 0 are then the state's own), each where it leaves the constraint
    Jacobian regular, then each chosen so that the Jacobian with its row added is best
    conditioned at the drawn pose."""
    chosen = [d.joint for d in linkage.drivers]
    free = linkage.dof - len(chosen)
    candidates = [j.name for j in linkage.joints if j.kind.drivable and j.name not in chosen]
    for name in [n for n in rates if n in candidates]:
        if len(chosen) < len(linkage.drivers) + free and \
                _smallest_singular_value(linkage, [*chosen, name]) > INDEPENDENT:
            chosen.append(name)
            candidates.remove(name)
    while len(chosen) < len(linkage.drivers) + free:
        best = max(candidates, key=lambda name: _smallest_singular_value(linkage, [*chosen, name]))
        chosen.append(best)
        candidates.remove(best)
    return tuple(chosen)


def _smallest_singular_value(linkage: Linkage, joints: list[str]) -> float:
    """σ_min of the scaled Jacobian of the joints' rows plus a driver row on each of
    ``joints`` at the drawn pose (in lengths, :func:`.unit_scales`); rows in the order
    given, so a named rate's joint wins a tie."""
    trial = coordinates_linkage(linkage, tuple(joints))
    jac = _scaled_jacobian(trial, np.zeros(3 * len(linkage.moving_links)),
                           np.zeros(len(joints)))[1]
    return float(np.linalg.svd(jac, compute_uv=False)[-1])


def coordinates_linkage(linkage: Linkage, joints: tuple[str, ...]) -> Linkage:
    """The linkage with a driver on each of ``joints`` and nothing else driving it: its
    constraint rows are the joints' plus one row per independent coordinate."""
    return replace(linkage, drivers=tuple(Driver(name, 0.0) for name in joints),
                   free_motion=True)


def _scaled_jacobian(linkage: Linkage, q: Array, x: Array) -> tuple[Array, Array]:
    """The constraint residual and Jacobian at one pose, in lengths (:func:`.unit_scales`)."""
    rows, cols = unit_scales(linkage)
    phi, jac = constraint_system(linkage, q[None, :], x[None, :])
    return phi[0] * rows, jac.dense()[0] * rows[:, None] * cols[None, :]


# -- positions, velocities and the accelerations' bias ---------------------------------------

@dataclass(frozen=True)
class Kinematics:
    """The linkage at one state: positions q (3n,), the rates S (3n, d) of every link per
    unit rate of each independent coordinate, the velocities q̇ = S ẋ and the bias q̈₀ of
    the accelerations (q̈ = S ẍ + q̈₀); ``solver``: its scaled Jacobian's, with which the
    next state's positions are closed (a chord Newton), ``turns``: cos and sin of each
    link's φ (the ground's last)."""

    x: Array
    xdot: Array
    q: Array
    rates: Array
    qdot: Array
    bias: Array
    solver: Solver | None = field(default=None, compare=False, repr=False)
    turns: tuple[Array, Array] | None = field(default=None, compare=False, repr=False)


@dataclass
class Tracker:
    """Positions followed continuously along a motion: each state is closed by Newton's
    method from the last one through the second-order predictor, and its rates are solved
    as corrections of the last ones (the part the constraints do not decide at a change
    point stays the last one's), or, near a change point of a linkage of one coordinate,
    interpolated along the branch (:class:`.motion_bridge.Bridge`). Every state it solves is
    kept (``visited``) without its factors (a long phase would otherwise hold one Jacobian's
    per evaluation), so that the output times start from a pose close to them."""

    linkage: Linkage
    last: Kinematics
    visited: list[Kinematics] = field(default_factory=list)
    #: The visited states' coordinates, by the list's identity and length (outputs ask
    #: for the nearest many times between two visits).
    _visited_x: tuple[tuple[int, int], Array] | None = None

    def __post_init__(self) -> None:
        self.rows: Rows = joint_rows(self.linkage)
        self.row_scales, self.col_scales = unit_scales(self.linkage)
        # One coordinate: its rates interpolated along the branch where the Jacobian is
        # nearly singular (motion_bridge.py); while its nodes are solved, never.
        self.bridge = Bridge(self._node_rates, float(coordinate_units(self.linkage)[0])) \
            if len(self.linkage.drivers) == 1 else None
        self._on_nodes = False

    def solve(self, x: Array, xdot: Array, start: Kinematics | None = None, *,
              keep: bool = True) -> Kinematics:
        """The state at coordinates x and rates ẋ, closed from ``start`` (default: the last
        state); ``keep`` False: an output's, which the motion does not continue from."""
        near = self.last if start is None else start
        found = self._reach(near, x, xdot, HALVINGS)
        if keep:
            self.last = found
            self.visited.append(replace(found, solver=None))
        return found

    def _reach(self, near: Kinematics, x: Array, xdot: Array, depth: int) -> Kinematics:
        """x closed from ``near``; where Newton does not close it, or closes it on another
        branch (the rates jump: near a change point the predictor's error can exceed the
        branches' distance), through the half-way state first."""
        found = self.close(near, x, xdot)
        if found is not None and not _jumps(near.rates, found.rates, self.col_scales):
            return found
        if depth == 0:
            raise DynamicsError("the joints' constraints no longer close on the branch the "
                                f"motion follows: the linkage locks at "
                                f"{_coordinates_text(self.linkage, x)}")
        half = self._reach(near, 0.5 * (near.x + x), xdot, depth - 1)
        return self._reach(half, x, xdot, depth - 1)

    def close(self, near: Kinematics, x: Array, xdot: Array) -> Kinematics | None:
        """Newton's method from the predictor near.q + S·Δx (None: it did not close): first
        with ``near``'s factorisation (a chord iteration, no Jacobian to factorise), then,
        if that does not close, with the Jacobian at each iterate."""
        predicted = _predicted(near, x)
        rows, cols = self.row_scales, self.col_scales
        tol = CLOSURE_RTOL * self.linkage.scale
        q = self._chord(near, predicted, x, tol) if near.solver is not None else None
        for _ in range(NEWTON_ITERATIONS + 1):
            q = predicted if q is None else q
            state = self.rows.at(q)
            phi = self._residual(state, x)
            solver = Solver(self.rows.dense(state) * rows[:, None] * cols[None, :])
            if np.abs(phi).max(initial=0.0) <= tol:
                break
            q = q - cols * solver.solve(phi)
        else:
            return None
        # One more step, through the factorisation the rates need anyway: near a change
        # point a residual within the closure leaves the position uncertain by
        # closure / σ_min along the direction the constraints hardly hold, which would be
        # noise in the right-hand side; after it, by rounding / σ_min.
        q = q - cols * solver.solve(phi)
        bridged = self._bridged(q, x, xdot, solver, state)
        if bridged is not None:
            return bridged
        return self._rates(q, x, xdot, solver, state, near, cols)

    def _bridged(self, q: Array, x: Array, xdot: Array, solver: Solver,
                 state: RowState) -> Kinematics | None:
        """The state with its rates S and bias B·ẋ² from the branch's interpolation
        (:class:`.motion_bridge.Bridge`), where the Jacobian is nearly singular; else None."""
        if self.bridge is None or self._on_nodes or not solver.below(SIGMA):
            return None
        found = self.bridge.rates(float(x[0]))
        if found is None:
            return None
        rates, unit_bias = found
        return Kinematics(x.copy(), xdot.copy(), q, rates[:, None], rates * xdot[0],
                          unit_bias * (xdot[0] * xdot[0]), solver, (state.cos, state.sin))

    def _node_rates(self, x: float) -> tuple[Array, Array] | None:
        """S and the bias at unit rate B, solved at coordinate x (closed from the nearest
        visited state); None where the Jacobian is nearly singular there too, or the
        positions do not close."""
        at = np.array([x])
        self._on_nodes = True
        try:
            kin = self._reach(self.nearest(at), at, np.ones(1), HALVINGS)
        except DynamicsError:
            return None
        finally:
            self._on_nodes = False
        assert kin.solver is not None
        if kin.solver.below(SIGMA):
            return None
        return kin.rates[:, 0], kin.bias

    def _chord(self, near: Kinematics, q: Array, x: Array, tol: float) -> Array | None:
        """Newton's iteration with ``near``'s Jacobian: the closed q, or None where it does
        not close within :data:`CHORD_ITERATIONS` (or stops contracting)."""
        assert near.solver is not None
        cols = self.col_scales
        size = math.inf
        for _ in range(CHORD_ITERATIONS):
            phi = self._residual(self.rows.at(q, jacobian=False), x)
            worst = float(np.abs(phi).max(initial=0.0))
            if worst <= tol:
                return q
            if worst >= size:
                return None
            size = worst
            q = q - cols * near.solver.solve(phi)
        return None

    def _residual(self, state: RowState, x: Array) -> Array:
        """Φ in lengths at ``state``, the drivers' rows at coordinates x."""
        phi = state.phi.copy()
        phi[phi.size - x.size:] -= x
        return phi * self.row_scales

    def _rates(self, q: Array, x: Array, xdot: Array, solver: Solver, state: RowState,
               near: Kinematics, cols: Array) -> Kinematics:
        """S and q̈₀ at the closed pose q (``solver``: its scaled Jacobian's), each the
        correction of ``near``'s that J demands."""
        rows = self.row_scales
        d = x.size
        m = rows.size
        unit = np.zeros((m, d))
        unit[m - d:] = np.eye(d)
        rates = cols[:, None] * solver.corrected(near.rates / cols[:, None], unit * rows[:, None])
        qdot = rates @ xdot
        bias_rhs = -self.rows.quadratic(state, qdot) * rows
        bias = cols * solver.corrected(near.bias / cols, bias_rhs)
        return Kinematics(x.copy(), xdot.copy(), q, rates, qdot, bias, solver,
                          (state.cos, state.sin))

    def nearest(self, x: Array) -> Kinematics:
        """The visited state whose coordinates are closest to x (in lengths)."""
        size = self.linkage.scale
        lengths = np.array([self.linkage.joint(d.joint).kind.length(size)
                            for d in self.linkage.drivers])
        if not self.visited:
            return self.last
        key = (id(self.visited), len(self.visited))
        if self._visited_x is None or self._visited_x[0] != key:
            self._visited_x = (key, np.array([k.x for k in self.visited]))
        found = self._visited_x[1]
        return self.visited[int(np.argmin(np.abs((found - x) * lengths).max(axis=1)))]


def _predicted(near: Kinematics, x: Array) -> Array:
    """q at coordinates x from ``near`` to second order along its motion: q + S·Δx +
    ½·q̈₀·τ², τ the time at ``near``'s rates that comes closest to Δx (q̈₀ = Ṡ·ẋ, the
    path's curvature at those rates); first order where it is at rest."""
    step = x - near.x
    q = near.q + near.rates @ step
    speed = float(near.xdot @ near.xdot)
    if speed > 0.0:
        tau = float(near.xdot @ step) / speed
        q = q + (0.5 * tau * tau) * near.bias
    return q


def _jumps(before: Array, after: Array, cols: Array) -> bool:
    """The rates S changed by more than :data:`JUMP` of their size (in lengths): another
    branch, not the one followed (along it S changes smoothly with x)."""
    a, b = before / cols[:, None], after / cols[:, None]
    size = max(np.abs(a).max(initial=0.0), np.abs(b).max(initial=0.0))
    return bool(size > 0.0 and np.abs(b - a).max() > JUMP * size)


class Solver:
    """Solutions of J·y = rhs for one scaled Jacobian: through its inverse (small) or its
    sparse LU factors (large, :data:`.linalg.DENSE_COLUMNS`) where it is square and its
    condition number below 1/:data:`RCOND`; else through its SVD, singular values below
    :data:`RCOND` of the largest dropped (a change point, or redundant rows)."""

    def __init__(self, jac: Array) -> None:
        self.jac = jac
        self.factors: _Factors | None = None
        if jac.shape[0] == jac.shape[1] and jac.size:
            self.factors = _dense_inverse(jac) if jac.shape[0] <= DENSE_COLUMNS \
                else _sparse_lu(jac)
        self.apply = None if self.factors is None else self.factors.apply
        self.pseudo = _PseudoInverse(jac) if self.apply is None else None
        self._smallest: float | None = None

    def below(self, limit: float) -> bool:
        """Whether the Jacobian's smallest singular value is below ``limit``: no where a
        cheap lower bound (1/‖J⁻¹‖_F, from the inverse) is above it, else by
        :meth:`smallest_singular_value`."""
        if self.factors is not None and self.factors.floor >= limit:
            return False
        return self.smallest_singular_value() < limit

    def smallest_singular_value(self) -> float:
        """σ_min of the Jacobian: by inverse iteration on JᵀJ through the factors (from a
        fixed start, :data:`INVERSE_ITERATIONS` rounds: its order of magnitude is what is
        asked), or the SVD's."""
        if self._smallest is None:
            if self.factors is None:
                assert self.pseudo is not None
                self._smallest = self.pseudo.smallest
            else:
                v = np.ones(self.jac.shape[0])
                for _ in range(INVERSE_ITERATIONS):
                    v = self.factors.transposed(self.factors.apply(v / np.linalg.norm(v)))
                self._smallest = float(1.0 / math.sqrt(np.linalg.norm(v)))
        return self._smallest

    def solve(self, rhs: Array) -> Array:
        """The solution nearest zero."""
        if self.apply is not None:
            return self.apply(rhs)
        return self.corrected(np.zeros(self.jac.shape[1:] + rhs.shape[1:]), rhs)

    def corrected(self, guess: Array, rhs: Array) -> Array:
        """guess + J⁺(rhs − J·guess): the solution of J·y = rhs nearest ``guess`` (J
        regular: the solution)."""
        if self.apply is not None:
            return self.apply(rhs)
        assert self.pseudo is not None
        return self.pseudo.corrected(guess, rhs)


class _Factors(NamedTuple):
    """J⁻¹·rhs and J⁻ᵀ·rhs of a regular Jacobian, and a lower bound on its smallest
    singular value (0 where none comes cheap)."""

    apply: Callable[[Array], Array]
    transposed: Callable[[Array], Array]
    floor: float


def _dense_inverse(jac: Array) -> _Factors | None:
    """y = J⁻¹·rhs and y = J⁻ᵀ·rhs by J's inverse, where its 1-norm condition number
    (exact, from the inverse) is below 1/RCOND; else None."""
    try:
        inverse = np.linalg.inv(jac)
    except np.linalg.LinAlgError:
        return None
    condition = np.abs(jac).sum(axis=0).max() * np.abs(inverse).sum(axis=0).max()
    if not condition * RCOND < 1.0:
        return None
    return _inverse_factors(np.asarray(inverse, dtype=np.float64))


def _inverse_factors(inverse: Array) -> _Factors:
    """J⁻¹·rhs and J⁻ᵀ·rhs through J's inverse, and 1/‖J⁻¹‖_F, a lower bound on σ_min."""
    return _Factors(lambda rhs: np.asarray(inverse @ rhs, dtype=np.float64),
                    lambda rhs: np.asarray(inverse.T @ rhs, dtype=np.float64),
                    float(1.0 / np.linalg.norm(inverse)))


def _sparse_lu(jac: Array) -> _Factors | None:
    """y = J⁻¹·rhs and J⁻ᵀ·rhs by SuperLU, where the factor U's pivots span less than 1/RCOND (a
    cheap bound on the condition number's order); else None."""
    from scipy import sparse
    from scipy.sparse.linalg import splu

    try:
        lu = splu(sparse.csc_matrix(jac))
    except RuntimeError:     # exactly singular
        return None
    pivots = np.abs(lu.U.diagonal())
    if not pivots.min() > RCOND * pivots.max():
        return None
    return _Factors(lambda rhs: np.asarray(lu.solve(rhs), dtype=np.float64),
                    lambda rhs: np.asarray(lu.solve(rhs, trans="T"), dtype=np.float64), 0.0)


class _PseudoInverse:
    """J⁺ of one scaled Jacobian, singular values below :data:`RCOND` of the largest
    dropped."""

    def __init__(self, jac: Array) -> None:
        u, sigma, vt = np.linalg.svd(jac, full_matrices=False)
        kept = sigma > RCOND * sigma[0] if sigma.size else sigma > 0.0
        self.smallest = float(sigma[-1]) if sigma.size and jac.shape[0] == jac.shape[1] else 0.0
        self.u, self.vt = u[:, kept], vt[kept]
        self.inverse_sigma = 1.0 / sigma[kept]
        self.jac = jac

    def corrected(self, guess: Array, rhs: Array) -> Array:
        """guess + J⁺(rhs − J·guess): the solution of J·y = rhs nearest ``guess``."""
        residual = rhs - self.jac @ guess
        inner = self.u.T @ residual
        inner = inner * (self.inverse_sigma[:, None] if inner.ndim == 2 else self.inverse_sigma)
        return np.asarray(guess + self.vt.T @ inner, dtype=np.float64)


def _coordinates_text(linkage: Linkage, x: Array) -> str:
    return ", ".join(f"{linkage.joint(d.joint).kind.describe(float(v))} of {d.joint}"
                     for d, v in zip(linkage.drivers, x, strict=True))


# -- the equations of motion -----------------------------------------------------------------

@dataclass(frozen=True)
class Model:
    """A trajectory case's equations of motion: the linkage with a driver row on each
    independent coordinate (the original drivers first, in order, then the free joints),
    which of them move by the equations of motion (``moving``: effort drivers and free
    joints) and which are prescribed, and the joints with Coulomb friction."""

    linkage: Linkage
    drivers: tuple[Driver, ...]
    moving: NDArray[np.intp]
    prescribed: NDArray[np.intp]
    frictional: tuple[tuple[str, float], ...]

    @property
    def size(self) -> int:
        return len(self.linkage.drivers)

    def applied(self, t: float) -> Array:
        """The efforts applied on the moving coordinates at t (a free joint's is 0)."""
        out = np.zeros(self.moving.size)
        for k, times, values in self._effort_tables:
            out[k] = np.interp(t, times, values)      # Effort.at, its rows made arrays once
        return out

    @cached_property
    def _effort_tables(self) -> tuple[tuple[int, Array, Array], ...]:
        """Each moving coordinate with an effort: its place, the effort's times and values."""
        drivers = [self.drivers[i] if i < len(self.drivers) else None for i in self.moving]
        return tuple((k, np.array(d.effort.times), np.array(d.effort.values))
                     for k, d in enumerate(drivers) if d is not None and d.effort is not None)

    def coordinates(self, t: float, x: Array, v: Array) -> tuple[Array, Array, Array]:
        """Every independent coordinate, its rate and its known acceleration at t (moving
        ones from the state x, v; prescribed ones from their drivers; the moving ones'
        accelerations 0)."""
        d = self.size
        xs, vs, acc = np.zeros(d), np.zeros(d), np.zeros(d)
        xs[self.moving], vs[self.moving] = x, v
        for i in self.prescribed:
            drv = self.drivers[i]
            xs[i] = drv.value + drv.velocity * t + 0.5 * drv.acceleration * t * t
            vs[i] = drv.velocity + drv.acceleration * t
            acc[i] = drv.acceleration
        return xs, vs, acc

    def units(self) -> Array:
        """Each coordinate's unit (:func:`coordinate_units`); the coordinates' absolute
        tolerances are RTOL times these."""
        return coordinate_units(self.linkage)


def coordinate_units(linkage: Linkage) -> Array:
    """Each driver's coordinate's unit as a length's share: 1 for an angle (rad), the
    linkage's size for a slide (m)."""
    size = linkage.scale
    return np.array([size / linkage.joint(d.joint).kind.length(size) for d in linkage.drivers])


def model_of(case: Case) -> Model:
    """The independent coordinates of a trajectory case and what moves them."""
    linkage = case.linkage
    rates = tuple(case.simulation.rates) if case.simulation is not None else ()
    joints = independent_joints(linkage, rates)
    chosen = coordinates_linkage(linkage, joints)
    own = len(linkage.drivers)
    moving = [i for i in range(len(joints)) if i >= own or linkage.drivers[i].effort is not None]
    friction = linkage.friction
    frictional = tuple((j.name, j.kind.coulomb_coefficient(friction, j)) for j in linkage.joints
                       if friction is not None and j.kind.coulomb_coefficient(friction, j) > 0.0)
    return Model(chosen, linkage.drivers, np.array(moving, dtype=np.intp),
                 np.array([i for i in range(own) if i not in moving], dtype=np.intp), frictional)


def refusal(case: Case) -> str | None:
    """Why the reference does not integrate a case (None: it does)."""
    linkage = case.linkage
    if not linkage.masses and linkage.dof > len(linkage.drivers) - len(linkage.efforts):
        return ("the linkage has no mass: its free coordinates have no equations of motion "
                "(give its links [[case.masses]])")
    if linkage.elastic_links:
        return ("the reference integrates rigid links: members with axial_stiffness would "
                "need their stretch as coordinates of their own")
    if not linkage.has_coulomb_friction:
        return None
    if linkage.redundant:
        return ("Coulomb friction on a linkage with redundant joints: friction follows the "
                "reactions, which are not unique there; members with axial_stiffness or "
                "fewer joints would decide them")
    free = linkage.dof - len(linkage.drivers) + len(linkage.efforts)
    if free != 1 or len(linkage.drivers) > len(linkage.efforts):
        return (f"Coulomb friction is integrated on a linkage of one degree of freedom moved "
                f"by its own effort or released (this one moves {free} coordinate(s) by "
                f"the equations of motion, {len(linkage.drivers) - len(linkage.efforts)} by a "
                "prescribed motion): stick and slip of several coordinates at once would need "
                "a complementarity problem solved at each switch")
    return None


def origin_velocities(q: Array, rates: Array) -> Array:
    """(3n, k): for each column of link rates (ṫ, ω per link), each link's velocity of the
    point at the global origin and its ω, the motion a link's known forces reduced to the
    origin (Fx, Fy, M) do power on (:func:`.linkage_backends.virtual_work_results`):
    v_O = ṫ − ω·perp(t)."""
    out = rates.copy()
    omega = rates[2::3]
    out[0::3] += omega * q[1::3, None]
    out[1::3] -= omega * q[0::3, None]
    return out


@dataclass(frozen=True)
class Evaluation:
    """The equations of motion at one state: every coordinate's acceleration and effort
    (applied on the moving ones, needed by the prescribed ones), and the rates of the work
    done on the linkage and of what it dissipates."""

    kinematics: Kinematics
    acceleration: Array
    efforts: Array
    work_rate: float
    dissipation_rate: float


@dataclass
class Equations:
    """The right-hand side of a run: the model, the tracker that follows its positions, the
    senses of Coulomb friction in the current phase and the count of evaluations."""

    model: Model
    tracker: Tracker
    #: The run's length (s): what :meth:`_check_progress` measures its advance against.
    span: float = 1.0
    senses: dict[str, float] = field(default_factory=dict)
    direction: float = 0.0
    evaluations: int = 0
    _kept: tuple[float, bytes, Evaluation] | None = None
    #: The time and the count of evaluations when progress was last checked.
    _mark: tuple[float, int] = (0.0, 0)

    def at(self, t: float, y: Array) -> Evaluation:
        """The evaluation at (t, y), kept for the event functions at the same state."""
        key = y.tobytes()
        if self._kept is not None and self._kept[0] == t and self._kept[1] == key:
            return self._kept[2]
        self._check_progress(t)
        m = self.model.moving.size
        x, v, known = self.model.coordinates(t, y[:m], y[m:2 * m])
        found = self._compiled(t, x, v, known)
        if found is None:
            kin = self.tracker.solve(x, v)
            found = self.evaluate(t, kin, known)
        self.evaluations += 1
        self._kept = (t, key, found)
        return found

    def _check_progress(self, t: float) -> None:
        """Every :data:`STALL_EVALUATIONS` evaluations: a run that at the pace of the last
        ones would need more than :data:`MAX_EVALUATIONS` more to reach its end ends here."""
        since, count = self._mark
        done = self.evaluations - count
        if done < STALL_EVALUATIONS:
            return
        advanced = t - since
        if advanced * MAX_EVALUATIONS < (self.span - t) * done:
            raise DynamicsError(
                f"the integrator's steps have shrunk to {advanced / done:.3g} s at {t:.9g} s: "
                f"at this pace it needs more than {MAX_EVALUATIONS:,} more right-hand sides "
                f"to reach {self.span:g} s. The equations of motion are too stiff to "
                "integrate here, as where a moving coordinate carries almost no mass or "
                "inertia (give its links [[case.masses]] away from their pivots); a long, "
                "smooth run stops here too (shorten its end)")
        self._mark = (t, self.evaluations)

    def rhs(self, t: float, y: Array) -> Array:
        found = self.at(t, y)
        m = self.model.moving.size
        out = np.empty(y.size)
        out[:m] = y[m:2 * m]
        out[m:2 * m] = found.acceleration[self.model.moving]
        out[2 * m] = found.work_rate
        out[2 * m + 1] = found.dissipation_rate
        return out

    @cached_property
    def kernel(self) -> fast.Kernel | None:
        """These equations as the compiled kernel takes them, and the kernel (None: the
        numpy path runs every state)."""
        tracker = self.tracker
        settings = fast.Settings(CLOSURE_RTOL * tracker.linkage.scale, RCOND, JUMP,
                                 CHORD_ITERATIONS, NEWTON_ITERATIONS,
                                 0.0 if tracker.bridge is None else SIGMA)
        return fast.motion_plan(tracker.rows, terms(tracker.linkage),
                                (tracker.row_scales, tracker.col_scales), self.model.moving,
                                settings)

    def _compiled(self, t: float, x: Array, v: Array, known: Array) -> Evaluation | None:
        """The state at x, v closed from the last one and its equations of motion, as
        :meth:`Tracker.solve` and :meth:`evaluate` give them, by the compiled kernel
        (:mod:`._fast`); None where the numpy path takes them: no kernel, Coulomb friction
        in this phase, a last state solved by its SVD, or a state off the kernel's plain
        road (a branch to pass through half-way states, an ill-conditioned Jacobian)."""
        near = self.tracker.last
        solver = near.solver
        if self.kernel is None or self.senses or solver is None or solver.apply is None:
            return None
        inverse = solver.inverse if isinstance(solver, _Inverted) else solver.solve(np.eye(near.q.size))
        found = fast.step(self.kernel, (near.x, near.xdot, near.q, near.rates, near.bias, inverse),
                          x, v, known, self.model.applied(t))
        if found is None:
            return None
        kin = Kinematics(x, v, found.q, found.rates, found.qdot, found.bias,
                         _Inverted(found.jacobian, found.inverse), (found.cos, found.sin))
        self.tracker.last = kin
        self.tracker.visited.append(replace(kin, solver=None))   # kept without its factors
        return Evaluation(kin, found.acceleration, found.efforts, found.work, found.dissipated)

    def evaluate(self, t: float, kin: Kinematics, known: Array) -> Evaluation:
        """The equations of motion at one state: M = Sᵀ𝕄S, and the efforts the
        coordinates need, Q = Sᵀ(𝕄·q̈ − F) with q̈ = S·ẍ + q̈₀ (the constraints' reactions
        do no work on S, redundant ones included)."""
        model = self.model
        moving = model.moving
        base = kin.bias + kin.rates @ known
        cos, sin = kin.turns if kin.turns is not None else _turns(kin.q)
        own = terms(model.linkage)
        forces = own.forces(kin.q, kin.qdot, cos, sin)
        weighted = own.mass_times(cos, sin, np.column_stack([kin.rates, base]))
        mass_all = kin.rates.T @ weighted[:, :-1]
        h = kin.rates.T @ (weighted[:, -1] - forces.total)
        mass = mass_all[moving][:, moving]
        applied = model.applied(t)
        acceleration = known.copy()
        acceleration[moving] = _accelerations(mass, applied - h[moving])
        friction = np.zeros(kin.q.size)
        if self.senses:
            acceleration[0], friction = self._with_friction(
                kin, known, float(mass[0, 0]), float(acceleration[0]), float(applied[0]))
        efforts = h + acceleration[moving] @ mass_all[moving]
        efforts[moving] = applied
        work = float(efforts @ kin.xdot) + float(forces.loads @ kin.qdot)
        dissipated = -float(forces.dissipative @ kin.qdot)
        if self.senses:
            dissipated -= float(friction @ (origin_velocities(kin.q, kin.rates) @ kin.xdot))
        return Evaluation(kin, acceleration, efforts, work, dissipated)

    def _with_friction(self, kin: Kinematics, known: Array, mass: float, first: float,
                       applied: float) -> tuple[float, Array]:
        """The moving coordinate's acceleration with Coulomb friction in this phase's senses
        (one coordinate, no prescribed ones): the secant method on Q(ẍ) = Q_applied from
        the frictionless ẍ (``first``), its first step along the frictionless mass;
        returns (ẍ, the friction forces on the links (3n,))."""
        a0 = first
        effort, forces = self._effort_with_friction(kin, known, a0)
        f0 = effort - applied
        a1 = a0 - f0 / mass
        size = abs(first) + abs(f0 / mass)
        for _ in range(SECANT_ITERATIONS):
            effort, forces = self._effort_with_friction(kin, known, a1)
            f1 = effort - applied
            if f1 == 0.0 or f1 == f0 or abs(a1 - a0) <= SECANT_RTOL * max(size, abs(a1)):
                return a1, forces
            a0, a1, f0 = a1, a1 - f1 * (a1 - a0) / (f1 - f0), f1
        raise DynamicsError("the friction equations do not converge: Q(ẍ) with Coulomb "
                            "friction has no root near the frictionless acceleration")

    def _effort_with_friction(self, kin: Kinematics, known: Array,
                              acceleration: float) -> tuple[float, Array]:
        """Q(ẍ) with Coulomb friction in the phase's senses (one moving coordinate), from
        the member-equilibrium solve, and the friction forces on the links (3n,)."""
        linkage = self.model.linkage
        pose = _pose(linkage, kin, (kin.bias + kin.rates[:, 0] * acceleration
                                    + kin.rates @ known)[None, :])
        return effort_with_friction(pose, self.model.frictional, self.senses)


class _Inverted(Solver):
    """The :class:`Solver` of a state the compiled kernel closed: its scaled Jacobian's
    inverse, found there and its condition checked as :func:`_dense_inverse` does."""

    def __init__(self, jac: Array, inverse: Array) -> None:
        self.jac, self.inverse, self.pseudo, self._smallest = jac, inverse, None, None
        self.factors = _inverse_factors(inverse)
        self.apply = self.factors.apply


def effort_with_friction(pose: LinkagePose, frictional: tuple[tuple[str, float], ...],
                         senses: dict[str, float]) -> tuple[float, Array]:
    """The first driver's effort at one pose of a linkage of one driver, with Coulomb
    friction at ``frictional`` joints in ``senses`` (+1, −1; 0: none), from the
    member-equilibrium solve (:func:`.linkage_forces.solve_with_friction`); and the
    friction forces on the links (3n,)."""
    linkage = pose.linkage
    entries = coefficient_entries(pose)
    k = entries.dense()
    b = known_vector(pose)
    n = 1
    terms = [CoulombTerm(j, j.kind.nonlinear_coefficient(j), np.ones(n), friction=False)
             for j in linkage.joints if j.kind.nonlinear_coefficient(j) > 0.0]
    friction = [CoulombTerm(linkage.joint(name), c, np.full(n, senses[name]))
                for name, c in frictional]
    x = np.asarray(np.linalg.solve(k, -b[:, :, None])[:, :, 0], dtype=np.float64)
    x, converged = solve_with_friction(pose, entries, b, x, terms + friction)
    if not converged.all():
        raise DynamicsError("the friction equations have no solution in the senses of "
                            "motion (the linkage self-locks)")
    column = force_layout(linkage).driver_column(0)
    return float(x[0, column]), friction_residual(pose, friction, x)[0][0]


def _turns(q: Array) -> tuple[Array, Array]:
    """cos and sin of each link's φ, the ground's (0) last."""
    angles = np.append(q[2::3], 0.0)
    return np.cos(angles), np.sin(angles)


def _accelerations(mass: Array, net: Array) -> Array:
    """M ẍ = Q_applied − h; a singular M (a coordinate that moves no mass) stops the run."""
    try:
        found = np.linalg.solve(mass, net) if net.size else np.zeros(0)
    except np.linalg.LinAlgError:
        found = np.full(net.size, np.nan)
    if not np.all(np.isfinite(found)):
        raise DynamicsError("the reduced mass matrix is singular here: a free coordinate "
                            "moves no mass or inertia (give its links [[case.masses]])")
    return np.asarray(found, dtype=np.float64)


def _pose(linkage: Linkage, kin: Kinematics, accelerations: Array) -> LinkagePose:
    """The linkage at kin's positions and velocities with each row of ``accelerations``."""
    n = accelerations.shape[0]
    return LinkagePose(linkage, np.tile(kin.x, (n, 1)), np.tile(kin.q, (n, 1)),
                       np.tile(kin.qdot, (n, 1)), accelerations, np.full(n, np.nan))


# -- energy ------------------------------------------------------------------------------------

def kinetic_energy(pose: LinkagePose) -> Array:
    """T = Σ ½ m v_com² + ½ I ω² at each pose (N,), J."""
    out = np.zeros(pose.q.shape[0])
    for m in pose.linkage.masses:
        v = pose.point(m.link, m.com)[1]
        omega = pose.angle(m.link)[1]
        out += 0.5 * m.mass * (v * v).sum(axis=1) + 0.5 * m.inertia * omega**2
    return out


def potential_energy(pose: LinkagePose) -> Array:
    """V = −Σ m g·r_com + Σ ½ k (L − L0)² + Σ ½ k (q − q0)² at each pose (N,), J."""
    linkage = pose.linkage
    g = np.array(linkage.gravity)
    out = np.zeros(pose.q.shape[0])
    for m in linkage.masses:
        out -= m.mass * (pose.point(m.link, m.com)[0] @ g)
    for spring in linkage.springs:
        if isinstance(spring, TorsionSpring):
            q = pose.joint_coordinate(linkage.joint(spring.joint))[0]
            out += 0.5 * spring.stiffness * (q - spring.free_rotation) ** 2
        else:
            (la, pa), (lb, pb) = spring.ends
            length = spring_axis(linkage, pose.point(lb, pb)[0] - pose.point(la, pa)[0])[0]
            out += 0.5 * spring.stiffness * (length - spring.free_length) ** 2
    return out


# -- the run -------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Run:
    """The reference's run at the output times: every moving link's displacement (T, 3n),
    the energy terms (J), the switches of stick and slip, the right-hand-side evaluations,
    the coordinates' absolute tolerance (m) and, if the run stopped early, why."""

    times: Array
    coordinates: Array
    kinetic: Array
    potential: Array
    work: Array
    dissipated: Array
    events: tuple[tuple[float, str], ...]
    evaluations: int
    atol: float
    message: str = ""


@dataclass
class _Outputs:
    """The output rows being filled, in time order."""

    times: Array
    size: int
    filled: int = 0

    def __post_init__(self) -> None:
        n = self.times.size
        self.coordinates = np.full((n, self.size), np.nan)
        self.energy = np.full((4, n), np.nan)

    def within(self, start: float, stop: float, *, last: bool) -> tuple[list[int], Array]:
        """The rows not yet filled at times within start … stop (the ``last`` phase: every
        row left, one a rounding past the end read at the end), and the phase's t_eval:
        their times, then ``stop``."""
        times = self.times[self.filled:]
        count = times.size if last else int(np.searchsorted(times, stop, side="right"))
        rows = list(range(self.filled, self.filled + count))
        t_eval = np.clip(times[:count], start, stop)
        if not t_eval.size or t_eval[-1] < stop:
            t_eval = np.append(t_eval, stop)
        return rows, t_eval

    def pending(self, until: float) -> list[int]:
        """The rows not yet filled at times up to ``until``."""
        stop = int(np.searchsorted(self.times, until, side="right"))
        rows = list(range(self.filled, max(stop, self.filled)))
        self.filled = max(stop, self.filled)
        return rows


def integrate(case: Case) -> Run:
    """The case's motion from its initial state to its end time, read at its output times.
    Raises nothing for a motion that cannot continue: the run then ends there, its message
    saying why (:attr:`Run.message`), the later rows NaN."""
    assert case.simulation is not None
    sim = case.simulation
    model = model_of(case)
    linkage = model.linkage
    outputs = _Outputs(np.array(sim.outputs), 3 * len(linkage.moving_links))
    units = model.units()
    atol_units = np.concatenate([units[model.moving], units[model.moving]])
    events: list[tuple[float, str]] = []
    equations: Equations | None = None
    message = ""
    try:
        equations, y = _start(case, model)
        energy_atol = RTOL * _energy_size(linkage, equations.tracker.last)
        atol = np.concatenate([RTOL * atol_units, [energy_atol, energy_atol]])
        _phases(case, equations, y, atol, outputs, events)
    except DynamicsError as error:
        message = str(error)
    kinetic, potential, work, dissipated = outputs.energy
    return Run(outputs.times, outputs.coordinates, kinetic, potential, work, dissipated,
               tuple(events), 0 if equations is None else equations.evaluations,
               RTOL * linkage.scale, message)


def _start(case: Case, model: Model) -> tuple[Equations, Array]:
    """The equations and the initial state y = (x, ẋ, W = 0, D = 0) of the moving
    coordinates: effort drivers at their values and velocities, free joints at the drawn
    pose with the rates the case gives."""
    assert case.simulation is not None
    rates = case.simulation.rates
    x0, v0 = np.zeros(model.moving.size), np.zeros(model.moving.size)
    for k, i in enumerate(model.moving):
        joint = model.linkage.drivers[i].joint
        if i < len(model.drivers):
            x0[k], v0[k] = model.drivers[i].value, model.drivers[i].velocity
        else:
            v0[k] = rates.get(joint, 0.0)
    x, v, _ = model.coordinates(0.0, x0, v0)
    q, _ = positions(model.linkage, x[None, :])
    if not np.all(np.isfinite(q)):
        raise DynamicsError("the linkage does not assemble at its drivers' values at time 0: "
                            + _coordinates_text(model.linkage, x))
    n, d = q.shape[1], x.size
    still = Kinematics(x, v, q[0], np.zeros((n, d)), np.zeros(n), np.zeros(n))
    tracker = Tracker(model.linkage, still)
    first = tracker.close(still, x, v)     # no rates before it to keep to
    if first is None:
        raise DynamicsError("the linkage does not close at its drivers' values at time 0: "
                            + _coordinates_text(model.linkage, x))
    tracker.last = first
    return Equations(model, tracker, case.simulation.end), np.concatenate([x0, v0, [0.0, 0.0]])


def _energy_size(linkage: Linkage, kin: Kinematics) -> float:
    """An energy the work and dissipated terms are measured against (J): the initial
    kinetic energy, the weights, springs, loads and efforts across the linkage's size."""
    size = linkage.scale
    pose = _pose(linkage, kin, np.zeros((1, kin.q.size)))
    out = float(kinetic_energy(pose)[0])
    out += sum(m.mass for m in linkage.masses) * math.hypot(*linkage.gravity) * size
    out += sum(s.stiffness * (size**2 if isinstance(s, LinearSpring) else 1.0)
               for s in linkage.springs)
    out += sum(math.hypot(*ld.force) * size + abs(ld.torque) for ld in linkage.loads)
    out += sum(max(map(abs, d.effort.values)) * size for d in linkage.drivers if d.effort)
    return max(out, 1e-300)


def _phases(case: Case, equations: Equations, y: Array, atol: Array, outputs: _Outputs,
            events: list[tuple[float, str]]) -> None:
    """Integrate phase by phase: a phase ends at an effort's table row (where the effort
    bends), at the end time, or at an event of Coulomb friction (the coordinate's rate
    reaching zero, a frictional joint's relative rate reversing)."""
    from scipy.integrate import solve_ivp

    assert case.simulation is not None
    end = case.simulation.end
    model = equations.model
    breaks = sorted({t for d in model.drivers if d.effort for t in d.effort.times if 0.0 < t < end})
    t = 0.0
    for _ in range(MAX_PHASES):
        if t >= end:
            return
        stop = min([b for b in breaks if b > t], default=end)
        switches: list[Callable[[float, Array], float]] = []
        if model.frictional:
            decided = _stick_or_slip(equations, t, y, end, outputs, events)
            if decided is not None:
                t = decided
                continue
            switches = _switches(equations)
        # The outputs of the phase as t_eval (and its end): the dense output (three more
        # right-hand sides per step with DOP853) is formed only on the steps that hold one.
        rows, t_eval = outputs.within(t, stop, last=stop >= end)
        solved = solve_ivp(equations.rhs, (t, stop), y, method=METHOD, rtol=RTOL, atol=atol,
                           events=switches or None, t_eval=t_eval)
        if solved.status == -1:
            raise DynamicsError(f"the integrator stopped at {t:.9g} s: {solved.message}")
        reached = solved.t.size
        _fill(equations, outputs, rows[:reached], solved.y[:, :min(reached, len(rows))])
        t, y = _end_of_phase(solved, stop)
        if solved.status == 1:
            _switched(equations, solved.t_events, t, y, events)
        equations.tracker.visited = [equations.tracker.last]
    raise DynamicsError(f"more than {MAX_PHASES} switches of stick and slip before "
                        f"{end:g} s: the motion chatters")


def _end_of_phase(solved: Any, stop: float) -> tuple[float, Array]:
    """Where a phase ended: at its terminal event, or at ``stop`` (its last t_eval)."""
    if solved.status == 1:
        for times, states in zip(solved.t_events, solved.y_events, strict=True):
            if times.size:
                return float(times[0]), np.asarray(states[0], dtype=np.float64).copy()
    return stop, np.asarray(solved.y[:, -1], dtype=np.float64).copy()


def _fill(equations: Equations, outputs: _Outputs, rows: list[int], states: Array) -> None:
    """The output ``rows`` from their states: positions closed from the nearest state the
    phase visited."""
    model = equations.model
    m = model.moving.size
    tracker = equations.tracker
    for row, y in zip(rows, states.T, strict=True):
        t = float(outputs.times[row])
        outputs.filled = row + 1
        x, v, _ = model.coordinates(t, y[:m], y[m:2 * m])
        kin = tracker.solve(x, v, tracker.nearest(x), keep=False)
        _write(outputs, row, kin, model.linkage, y[2 * m], y[2 * m + 1])


def _write(outputs: _Outputs, row: int, kin: Kinematics, linkage: Linkage, work: float,
           dissipated: float) -> None:
    pose = _pose(linkage, kin, np.zeros((1, kin.q.size)))
    outputs.coordinates[row] = kin.q
    outputs.energy[:, row] = (kinetic_energy(pose)[0], potential_energy(pose)[0], work, dissipated)


# -- Coulomb friction: stick, slip and the switches between them ---------------------------------

def joint_rates(model: Model, kin: Kinematics) -> dict[str, float]:
    """Each frictional joint's relative rate per unit rate of the (one) moving coordinate."""
    n = kin.q.size
    pose = LinkagePose(model.linkage, kin.x[None, :], kin.q[None, :], kin.rates[:, 0][None, :],
                       np.zeros((1, n)), np.full(1, np.nan))
    return {name: float(pose.joint_coordinate(model.linkage.joint(name))[1][0])
            for name, _ in model.frictional}


def _stick_or_slip(equations: Equations, t: float, y: Array, end: float, outputs: _Outputs,
                   events: list[tuple[float, str]]) -> float | None:
    """At rest (ẋ = 0): stick while the applied effort stays within the efforts that hold
    the linkage against friction either way (returns when it leaves them, the rows until
    then filled at rest), else slip toward the net effort's side (returns None, the phase's
    senses set). Moving: the senses of the current direction."""
    model = equations.model
    if y[1] != 0.0:
        _set_senses(equations, float(np.sign(y[1])), y)
        return None
    x, v, _ = model.coordinates(t, y[:1], np.zeros(1))
    kin = equations.tracker.solve(x, v)
    rates = joint_rates(model, kin)
    rest = _pose(model.linkage, kin, np.zeros((1, kin.q.size)))
    holds = [effort_with_friction(rest, model.frictional,
                                  {j: side * float(np.sign(r)) for j, r in rates.items()})[0]
             for side in (1.0, -1.0)]
    low, high = min(holds), max(holds)
    applied = float(model.applied(t)[0])
    if low <= applied <= high:
        leaves = _effort_leaves(model, low, high, t, end)
        if not events or not events[-1][1].startswith("stick"):
            events.append((t, "stick at joint " + ", ".join(name for name, _ in model.frictional)))
        # the outputs at rest until the effort leaves the bracket
        for row in outputs.pending(leaves if leaves < end else math.inf):
            _write(outputs, row, kin, model.linkage, y[2], y[3])
        return leaves
    side = 1.0 if applied > high else -1.0
    events.append((t, f"slip toward {'+' if side > 0 else '-'}"))
    _set_senses(equations, side, y)
    return None


def _set_senses(equations: Equations, side: float, y: Array) -> None:
    """The senses of friction at every frictional joint for a motion toward ``side``: from
    the joints' rates a little way along it (a joint at its dead point, its rate zero, takes
    the sense it has just after)."""
    model = equations.model
    kin = equations.tracker.last
    probe = kin.x + side * 1e-7 * model.units()
    near = equations.tracker.solve(probe, kin.xdot, keep=False)
    equations.direction = side
    equations.senses = {j: side * float(np.sign(r)) for j, r in joint_rates(model, near).items()}
    del y


def _switches(equations: Equations) -> list[Callable[[float, Array], float]]:
    """The phase's events: the coordinate's rate reaching zero, and each frictional joint's
    relative rate reaching zero (its friction turns); each positive while the phase's senses
    hold, terminal where it falls through zero."""
    side = equations.direction

    def rest(t: float, y: Array) -> float:
        return float(side * y[1])

    found: list[Callable[[float, Array], float]] = [rest]
    for name, sense in equations.senses.items():
        if sense == 0.0:
            continue

        def turn(t: float, y: Array, name: str = name, sense: float = sense) -> float:
            kin = equations.at(t, y).kinematics
            return sense * side * joint_rates(equations.model, kin)[name]

        found.append(turn)
    for event in found:
        event.terminal = True    # type: ignore[attr-defined]
        event.direction = -1.0   # type: ignore[attr-defined]
    return found


def _switched(equations: Equations, found: list[Array], t: float, y: Array,
              events: list[tuple[float, str]]) -> None:
    """After a terminal event: the coordinate at rest exactly (ẋ = 0), or a joint's
    friction turned (recorded; the next phase takes its new sense)."""
    if found[0].size:
        y[1] = 0.0
        return
    names = [name for name, sense in equations.senses.items() if sense != 0.0]
    for name, times in zip(names, found[1:], strict=True):
        if times.size:
            events.append((t, f"friction turns at joint {name}"))


def _effort_leaves(model: Model, low: float, high: float, t: float, end: float) -> float:
    """The first time after t at which the applied effort (linear between its rows) leaves
    [low, high]; ``end`` if it never does."""
    effort = model.drivers[int(model.moving[0])].effort if model.moving[0] < len(model.drivers) \
        else None
    if effort is None:
        return end
    knots = [t, *[k for k in effort.times if t < k < end], end]
    for a, b in itertools.pairwise(knots):
        fa, fb = float(effort.at(a)), float(effort.at(b))
        for bound in (low, high):
            if (fa - bound) * (fb - bound) < 0.0:   # a linear piece crosses the bound
                return a + (b - a) * (bound - fa) / (fb - fa)
        if not low <= fb <= high:
            return b
    return end
