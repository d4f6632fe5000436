"""The trajectory reference's right-hand side compiled (numba; imported through
:func:`.compiled.kernel` only where numba is installed): one state closed from the last by
the chord Newton, its rates S and bias q̈₀, and the equations of motion there, in one call
(:func:`step`, handed a :class:`.plans.MotionPlan`).

Each function does what the numpy path does (:class:`.motion_rows.Rows`,
:class:`.motion_terms.Terms`, :class:`.linkage_dynamics.Tracker`,
:meth:`.linkage_dynamics.Equations.evaluate`) in the same floating-point operations, element
by element; only the sums of products add in index order, where BLAS may add them in
another (rounding). Where the numpy path would leave its plain road (the chord and Newton
do not close, a Jacobian too ill-conditioned for its inverse, rates that jump to another
branch, a singular mass matrix), the kernel says so (ok False, or LinAlgError) and the
numpy path takes the state from the start.

Few functions, each called from few places: numba compiles every call site, and the
kernel's first compilation is paid once per installation (``cache=True``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numba import njit, typeof, types

# -- products, summed in index order --------------------------------------------------------


@njit(cache=True)
def times(a, v):  # type: ignore[no-untyped-def]
    """a·v, a a matrix (rows × columns; its transpose aᵀ as ``a.T``), v a vector."""
    out = np.zeros(a.shape[0])
    for i in range(a.shape[0]):
        for k in range(a.shape[1]):
            out[i] += a[i, k] * v[k]
    return out


# -- the rows (motion_rows.Rows) -------------------------------------------------------------

@njit(cache=True)
def rows_at(rows, q):  # type: ignore[no-untyped-def]
    """The rows at q (:meth:`.Rows.at`): Φ without the drivers' targets; and what it was
    read from: cos and sin of each link's φ (the ground's last), each plan point's offset r
    from its link's origin and its place p, each ``along`` row's direction w."""
    n = q.size // 3
    angles = np.zeros(n + 1)
    qe = np.zeros(3 * n + 3)    # the ground's coordinates (0) last
    qe[:3 * n] = q
    for k in range(n):
        angles[k] = q[3 * k + 2]
    cos, sin = np.cos(angles), np.sin(angles)
    count = rows.point_links.size
    rx, ry, px, py = np.empty(count), np.empty(count), np.empty(count), np.empty(count)
    for p in range(count):
        k = rows.point_links[p]
        rx[p] = cos[k] * rows.drawn_x[p] - sin[k] * rows.drawn_y[p]
        ry[p] = sin[k] * rows.drawn_x[p] + cos[k] * rows.drawn_y[p]
        px[p] = qe[3 * k] + rx[p]
        py[p] = qe[3 * k + 1] + ry[p]
    along, w0 = rows.along, rows.along_w
    wx, wy = np.empty(along.shape[0]), np.empty(along.shape[0])
    phi = np.zeros(rows.row_count)
    for c in range(rows.coincide.shape[0]):
        r, a, b = rows.coincide[c, 0], rows.coincide[c, 1], rows.coincide[c, 2]
        phi[r] = px[a] - px[b]
        phi[r + 1] = py[a] - py[b]
    for c in range(rows.lock.shape[0]):
        phi[rows.lock[c, 0]] = angles[rows.lock[c, 2]] - angles[rows.lock[c, 1]]
    for c in range(along.shape[0]):
        r, i, j, k = along[c, 0], along[c, 1], along[c, 2], along[c, 3]
        wx[c] = cos[k] * w0[c, 0] - sin[k] * w0[c, 1]
        wy[c] = sin[k] * w0[c, 0] + cos[k] * w0[c, 1]
        phi[r] = wx[c] * (px[j] - px[i]) + wy[c] * (py[j] - py[i])
    return phi, cos, sin, rx, ry, px, py, wx, wy


@njit(cache=True)
def jacobian(rows, rx, ry, px, py, wx, wy):  # type: ignore[no-untyped-def]
    """J = ∂Φ/∂q (rows × 3n) (:meth:`.Rows.dense`): written over the ground's columns too,
    which are then cut off."""
    jac = np.zeros((rows.row_count, rows.size + 3))
    at = 3 * rows.point_links
    for c in range(rows.coincide.shape[0]):
        r, a, b = rows.coincide[c, 0], rows.coincide[c, 1], rows.coincide[c, 2]
        jac[r, at[a]], jac[r + 1, at[a] + 1] = 1.0, 1.0
        jac[r, at[b]], jac[r + 1, at[b] + 1] = -1.0, -1.0
        jac[r, at[a] + 2], jac[r + 1, at[a] + 2] = -ry[a], rx[a]
        jac[r, at[b] + 2], jac[r + 1, at[b] + 2] = ry[b], -rx[b]
    for c in range(rows.lock.shape[0]):
        r = rows.lock[c, 0]
        jac[r, 3 * rows.lock[c, 2] + 2] = 1.0
        jac[r, 3 * rows.lock[c, 1] + 2] = -1.0
    for c in range(rows.along.shape[0]):
        r, i, j = rows.along[c, 0], rows.along[c, 1], rows.along[c, 2]
        dx, dy = px[j] - px[i], py[j] - py[i]
        jac[r, at[j]], jac[r, at[j] + 1] = wx[c], wy[c]
        jac[r, at[j] + 2] = wy[c] * rx[j] - wx[c] * ry[j]
        jac[r, at[i]], jac[r, at[i] + 1] = -wx[c], -wy[c]
        jac[r, at[i] + 2] = (wx[c] * dy - wy[c] * dx) - (wy[c] * rx[i] - wx[c] * ry[i])
    return np.ascontiguousarray(jac[:, :rows.size])


@njit(cache=True)
def quadratic(rows, qdot, rx, ry, px, py, wx, wy):  # type: ignore[no-untyped-def]
    """J̇·q̇ (:meth:`.Rows.quadratic`)."""
    qde = np.zeros(qdot.size + 3)
    qde[:qdot.size] = qdot
    count = rows.point_links.size
    spin, vx, vy = np.empty(count), np.empty(count), np.empty(count)
    for p in range(count):
        k = rows.point_links[p]
        spin[p] = qde[3 * k + 2]
        vx[p] = qde[3 * k] - spin[p] * ry[p]
        vy[p] = qde[3 * k + 1] + spin[p] * rx[p]
    square = spin * spin
    out = np.zeros(rows.row_count)
    for c in range(rows.coincide.shape[0]):
        r, a, b = rows.coincide[c, 0], rows.coincide[c, 1], rows.coincide[c, 2]
        out[r] = square[b] * rx[b] - square[a] * rx[a]
        out[r + 1] = square[b] * ry[b] - square[a] * ry[a]
    for c in range(rows.along.shape[0]):
        r, i, j = rows.along[c, 0], rows.along[c, 1], rows.along[c, 2]
        dx, dy = px[j] - px[i], py[j] - py[i]
        ddx, ddy = vx[j] - vx[i], vy[j] - vy[i]
        wi = spin[i]
        out[r] = (-(wi * wi) * (wx[c] * dx + wy[c] * dy) + 2.0 * wi * (wx[c] * ddy - wy[c] * ddx)
                  + wx[c] * (square[i] * rx[i] - square[j] * rx[j])
                  + wy[c] * (square[i] * ry[i] - square[j] * ry[j]))
    return out


# -- the tracker (linkage_dynamics.Tracker, its inverse path) ---------------------------------

@njit(cache=True)
def closure(plan, q, x):  # type: ignore[no-untyped-def]
    """Φ in lengths at q, the drivers' rows at coordinates x (:meth:`.Tracker._residual`),
    its largest size, and what it was read from (:func:`rows_at`)."""
    phi, cos, sin, rx, ry, px, py, wx, wy = rows_at(plan.rows, q)
    first = phi.size - x.size
    worst = 0.0
    for r in range(phi.size):
        target = x[r - first] if r >= first else 0.0
        phi[r] = (phi[r] - target) * plan.row_scales[r]
        # NaN counts as the worst: numpy's max carries it, and it never closes
        worst = math.inf if math.isnan(phi[r]) else max(worst, abs(phi[r]))
    return phi, worst, cos, sin, rx, ry, px, py, wx, wy


@njit(cache=True)
def chord(plan, near_inverse, q, x):  # type: ignore[no-untyped-def]
    """Newton's iteration with the last state's inverse (:meth:`.Tracker._chord`): the
    closed q and whether it closed."""
    size = math.inf
    for _ in range(plan.settings.chord_iterations):
        phi, worst = closure(plan, q, x)[:2]
        if worst <= plan.settings.tolerance:
            return q, True
        if worst >= size:
            return q, False
        size = worst
        q = q - plan.col_scales * times(near_inverse, phi)
    return q, False


@njit(cache=True)
def inverse(jac, rcond):  # type: ignore[no-untyped-def]
    """J⁻¹, and whether its 1-norm condition number is below 1/rcond
    (:func:`.linkage_dynamics._dense_inverse`; where it is not, the numpy path takes the
    SVD). A singular J raises LinAlgError, which the seam takes as the same answer."""
    inv = np.ascontiguousarray(np.linalg.inv(jac))   # C order, as the numpy path hands it
    condition = np.abs(jac).sum(axis=0).max() * np.abs(inv).sum(axis=0).max()
    return inv, condition * rcond < 1.0


@njit(cache=True)
def close(plan, near_x, near_xdot, near_q, near_rates, near_bias, near_inverse, x, xdot):  # type: ignore[no-untyped-def]
    """The state at x, ẋ closed from the last one (:meth:`.Tracker.close`): q, the scaled
    Jacobian and its inverse, S, q̇, q̈₀, cos and sin of the links' φ, and ok."""
    rows, cols, scales = plan.rows, plan.col_scales, plan.row_scales
    step = x - near_x      # the predictor (linkage_dynamics._predicted)
    start = near_q + times(near_rates, step)
    speed = near_xdot @ near_xdot
    if speed > 0.0:
        tau = (near_xdot @ step) / speed
        start = start + (0.5 * tau * tau) * near_bias
    q, closed = chord(plan, near_inverse, start, x)
    if not closed:
        q = start
    for _ in range(plan.settings.newton_iterations + 1):
        phi, worst, cos, sin, rx, ry, px, py, wx, wy = closure(plan, q, x)
        jac = jacobian(rows, rx, ry, px, py, wx, wy)
        for r in range(rows.row_count):
            for k in range(rows.size):
                jac[r, k] = jac[r, k] * scales[r] * cols[k]
        inv, regular = inverse(jac, plan.settings.rcond)
        closed = worst <= plan.settings.tolerance
        if closed or not regular:
            break
        q = q - cols * times(inv, phi)
    if not (closed and regular):
        return q, jac, inv, near_rates, near_q, near_bias, cos, sin, False
    if plan.settings.sigma_floor > 0.0 and 1.0 / np.sqrt((inv * inv).sum()) < plan.settings.sigma_floor:
        # nearly singular: the numpy path decides, and may take the rates from the bridge
        return q, jac, inv, near_rates, near_q, near_bias, cos, sin, False
    # one more step (Tracker.close: the position to rounding / σ_min, not closure / σ_min)
    q = q - cols * times(inv, phi)
    m, d = rows.row_count, x.size
    rates = np.empty((rows.size, d))
    for i in range(rows.size):
        for k in range(d):
            rates[i, k] = cols[i] * (inv[i, m - d + k] * scales[m - d + k])
    qdot = times(rates, xdot)
    bias = cols * times(inv, -quadratic(rows, qdot, rx, ry, px, py, wx, wy) * scales)
    # the rates changed by more than JUMP of their size: another branch (linkage_dynamics._jumps)
    size, change = 0.0, 0.0
    for i in range(rows.size):
        for k in range(d):
            a, b = near_rates[i, k] / cols[i], rates[i, k] / cols[i]
            size = max(size, abs(a), abs(b))
            change = max(change, abs(b - a))
    return q, jac, inv, rates, qdot, bias, cos, sin, not (size > 0.0 and change > plan.settings.jump * size)


# -- the equations of motion (motion_terms.Terms, Equations.evaluate) --------------------------

@njit(cache=True)
def summed(index, values, size):  # type: ignore[no-untyped-def]
    """Values added into the coordinates at ``index`` in order, the ground's dropped
    (:meth:`.Terms._summed`)."""
    out = np.zeros(size + 3)
    for k in range(index.size):
        out[index[k]] += values[k]
    return out[:size]


@njit(cache=True)
def loads(terms, cos, sin, size):  # type: ignore[no-untyped-def]
    """The point loads' generalised forces (:meth:`.Terms._loads`)."""
    count = terms.load_links.size
    values = np.empty(3 * count)
    for p in range(count):
        k = terms.load_links[p]
        rx = cos[k] * terms.load_x[p] - sin[k] * terms.load_y[p]
        ry = sin[k] * terms.load_x[p] + cos[k] * terms.load_y[p]
        fx, fy = terms.load_force[p, 0], terms.load_force[p, 1]
        values[p], values[count + p] = fx, fy
        values[2 * count + p] = rx * fy - ry * fx + terms.load_torque[p]
    return summed(terms.load_index, values, size)


@njit(cache=True)
def springs(terms, q, qdot, cos, sin):  # type: ignore[no-untyped-def]
    """The linear springs' elastic and damping forces, summed together (:meth:`.Terms._springs`):
    (2, 3n)."""
    k = terms.spring_stiffness.size
    qe, qde = np.zeros(q.size + 3), np.zeros(q.size + 3)
    qe[:q.size], qde[:q.size] = q, qdot
    rx, ry = np.empty(2 * k), np.empty(2 * k)
    tx, ty, vx, vy = np.empty(2 * k), np.empty(2 * k), np.empty(2 * k), np.empty(2 * k)
    for e in range(2 * k):       # every a end, then every b end
        at = 3 * terms.spring_ends[e]
        c, s = cos[terms.spring_ends[e]], sin[terms.spring_ends[e]]
        rx[e] = c * terms.spring_drawn[e, 0] - s * terms.spring_drawn[e, 1]
        ry[e] = s * terms.spring_drawn[e, 0] + c * terms.spring_drawn[e, 1]
        tx[e], ty[e] = qe[at] + rx[e], qe[at + 1] + ry[e]
        vx[e], vy[e] = qde[at] - qde[at + 2] * ry[e], qde[at + 1] + qde[at + 2] * rx[e]
    values = np.empty((2, 6 * k))     # elastic, damping: every x component, every y, every moment
    for s in range(k):
        dx, dy = tx[k + s] - tx[s], ty[k + s] - ty[s]
        length = math.hypot(dx, dy)
        meets = length <= terms.meeting
        ux, uy = (0.0, 0.0) if meets else (dx / length, dy / length)
        both = (terms.spring_stiffness[s] * (length - terms.spring_length[s]),
                terms.spring_damping[s] * (ux * (vx[k + s] - vx[s]) + uy * (vy[k + s] - vy[s])))
        for part in range(2):
            fx, fy = both[part] * ux, both[part] * uy
            for end, sign in ((s, 1.0), (k + s, -1.0)):   # on end a; the reverse on end b
                values[part, end], values[part, 2 * k + end] = fx * sign, fy * sign
                values[part, 4 * k + end] = rx[end] * (fy * sign) - ry[end] * (fx * sign)
    out = np.empty((2, q.size))
    for part in range(2):
        out[part] = summed(terms.spring_index, values[part], q.size)
    return out


@njit(cache=True)
def coordinate_forces(terms, q, qdot):  # type: ignore[no-untyped-def]
    """Torsion springs, their dampers and viscous joints (:meth:`.Terms._add_coordinates`):
    (k(q − q0))·D and c·q̇·D, (2, 3n)."""
    rows = terms.coordinates
    phi, _, _, rx, ry, px, py, wx, wy = rows_at(rows, q)
    gradient = jacobian(rows, rx, ry, px, py, wx, wy)
    table = terms.coordinate_terms
    out = np.empty((2, q.size))
    out[0] = times(gradient.T, table[:, 0] * phi - table[:, 1])
    out[1] = times(gradient.T, table[:, 2] * times(gradient, qdot))
    return out


@njit(cache=True)
def forces(terms, q, qdot, cos, sin):  # type: ignore[no-untyped-def]
    """The generalised forces (:meth:`.Terms.forces`): their total, the loads' and the
    dissipative ones; and each moving link's centre of mass from its origin, now."""
    size = q.size
    n = size // 3
    rx = cos[:n] * terms.com_x - sin[:n] * terms.com_y
    ry = sin[:n] * terms.com_x + cos[:n] * terms.com_y
    conservative, inertial = np.empty(size), np.zeros(size)
    for k in range(n):
        m = terms.mass[k]
        wx, wy = m * terms.gravity[0], m * terms.gravity[1]
        conservative[3 * k], conservative[3 * k + 1] = wx, wy
        conservative[3 * k + 2] = rx[k] * wy - ry[k] * wx
        spin = m * qdot[3 * k + 2] * qdot[3 * k + 2]
        inertial[3 * k], inertial[3 * k + 1] = spin * rx[k], spin * ry[k]
    applied = loads(terms, cos, sin, size) if terms.load_links.size else np.zeros(size)
    dissipative = np.zeros(size)
    if terms.spring_stiffness.size:
        both = springs(terms, q, qdot, cos, sin)
        conservative += both[0]
        dissipative += both[1]
    if terms.coordinates.row_count:
        both = coordinate_forces(terms, q, qdot)
        conservative = conservative - both[0]
        dissipative = dissipative - both[1]
    return conservative + applied + dissipative + inertial, applied, dissipative, rx, ry


@njit(cache=True)
def evaluate(plan, q, rates, qdot, bias, cos, sin, xdot, known, applied):  # type: ignore[no-untyped-def]
    """The equations of motion at one state (:meth:`.Equations.evaluate` without Coulomb
    friction): every coordinate's acceleration, the efforts, the work and dissipation
    rates, and ok (False: the accelerations are not finite). M = Sᵀ𝕄S and
    h = Sᵀ(𝕄q̈₀ − F), 𝕄 each link's 3 × 3 block (:meth:`.Terms.mass_times`)."""
    terms, moving = plan.terms, plan.moving
    d = rates.shape[1]
    total, on_loads, dissipative, rx, ry = forces(terms, q, qdot, cos, sin)
    columns = np.empty((rates.shape[0], d + 1))
    columns[:, :d] = rates
    columns[:, d] = bias + times(rates, known)
    weighted = np.empty_like(columns)
    for k in range(terms.mass.size):
        m = terms.mass[k]
        mx, my = m * rx[k], m * ry[k]
        turning = terms.inertia[k] + m * (rx[k] * rx[k] + ry[k] * ry[k])
        for c in range(d + 1):
            v0, v1, v2 = columns[3 * k, c], columns[3 * k + 1, c], columns[3 * k + 2, c]
            weighted[3 * k, c] = m * v0 - my * v2
            weighted[3 * k + 1, c] = m * v1 + mx * v2
            weighted[3 * k + 2, c] = (-my * v0 + mx * v1) + turning * v2
    mass_all = np.empty((d, d))
    for k in range(d):
        mass_all[:, k] = times(rates.T, np.ascontiguousarray(weighted[:, k]))
    h = times(rates.T, weighted[:, d] - total)
    m = moving.size
    mass, net, held = np.empty((m, m)), np.empty(m), np.empty((m, d))
    for a in range(m):
        net[a] = applied[a] - h[moving[a]]
        held[a] = mass_all[moving[a]]
        for b in range(m):
            mass[a, b] = mass_all[moving[a], moving[b]]
    # a singular mass matrix raises LinAlgError: the seam's "not here"
    found = np.linalg.solve(mass, net) if m else np.zeros(0)
    acceleration = known.copy()
    efforts = h + times(held.T, found)
    for a in range(m):
        acceleration[moving[a]] = found[a]
        efforts[moving[a]] = applied[a]
    work = efforts @ xdot + on_loads @ qdot
    return acceleration, efforts, work, -(dissipative @ qdot), bool(np.all(np.isfinite(found)))


@njit(cache=True)
def step(plan, near_x, near_xdot, near_q, near_rates, near_bias, near_inverse, x, xdot,  # type: ignore[no-untyped-def]
         known, applied):
    """One right-hand side: the state at x, ẋ closed from the last, and its equations of
    motion (the tuple :class:`.motion.Step` names), and ok."""
    q, jac, inv, rates, qdot, bias, cos, sin, ok = close(
        plan, near_x, near_xdot, near_q, near_rates, near_bias, near_inverse, x, xdot)
    if not ok:
        return q, jac, inv, rates, qdot, bias, cos, sin, known, known, 0.0, 0.0, False
    acceleration, efforts, work, dissipated, ok = evaluate(
        plan, q, rates, qdot, bias, cos, sin, xdot, known, applied)
    return q, jac, inv, rates, qdot, bias, cos, sin, acceleration, efforts, work, dissipated, ok


def compiled_step(plan: Any) -> Callable[..., Any]:
    """:func:`step` compiled (or loaded from the cache) for ``plan``'s types and C-ordered
    float arrays, to be called without numba's dispatch, which types every array of a plan
    at each call (10 µs a call, a third of Andrews' right-hand side): the caller hands
    arrays of exactly these types (:func:`.motion.step`)."""
    vector, matrix = types.float64[::1], types.float64[:, ::1]
    signature = (typeof(plan), vector, vector, vector, matrix, vector, matrix, vector, vector,
                 vector, vector)
    return step.compile(signature)
