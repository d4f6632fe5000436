"""An independent reference force analysis in maximal (Cartesian) coordinates.

This module is test code. It shares nothing with :mod:`analytic` except the
input dataclasses of :mod:`mechcheck.analytic.case`; the method is deliberately
different from the backend's member-equilibrium matrix method:

* Every moving link i carries q_i = (x_i, y_i, φ_i), the position of its
  link-frame origin (CONVENTIONS.md) and the angle of its x axis, so
  q = (q_2, q_3, q_4) has nine entries (Nikravesh, *Computer-Aided Analysis of
  Mechanical Systems*).
* Joints are algebraic constraints Φ(q, t) = 0. A body-fixed point is
  p = r + A(φ) s. A pin joining i and j (F_ij is the force by i on j) is
  Φ = p_i − p_j, with a ground point a constant. The slide of a slider-crank
  is Φ = (e − n·r_4, g − φ_4), the slider origin being pin B. The driver is
  Φ = θ(t) − φ_k.
* Positions: Newton–Raphson on Φ(q) = 0 from a guess whose point B is a
  circle–circle (four-bar) or circle–line (slider) intersection picked by the
  branch *definition*, never by the backend's closed form.
  Velocities: Φ_q q̇ = −Φ_t. Accelerations: Φ_q q̈ = γ.
* Forces: the Newton–Euler equations of each link at its frame origin,
  E(q̈) = Q + Q_c, with the constraint forces Q_c = −Φ_qᵀ λ. Because every
  constraint is written "ground/previous link minus this link", each
  multiplier *is* the reaction in CONVENTIONS terms: λ_pin = F_ij, the slide's
  λ = (N, M14), the driver's λ = T12 (or T14). The system Φ_qᵀ λ = Q − E is
  square, so links may be massless.
* Coulomb friction makes Q depend on |λ|; Newton's method on
  R(λ) = Φ_qᵀ λ − Q(λ) + E (Jacobian from ∂|F|/∂F = F/|F|), started from the
  frictionless λ, runs until a step is below 1e-12 of |λ| and then takes one
  more step, which leaves an error at the rounding floor (< 1e-14).

Friction semantics (from the contract): a pin (i, j) of radius r puts the
moment −μ·r·|F_ij|·sign(ω_j − ω_i) on j and the opposite on i; the slide puts
−μ_s·|N|·sign(ṡ) along u on the slider at pin B; viscous terms are
−c·(ω_j − ω_i) and −c·ṡ. With motion.omega = 0 the Coulomb senses come from a
quasi-static motion with unit input speed in friction.direction; viscous
terms use the actual velocities (zero then).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from mechcheck.analytic.case import Case, FourBarGeometry, SliderCrankGeometry

Vector = NDArray[np.float64]
Matrix = NDArray[np.float64]

#: Newton is converged once a step is below this fraction of the unknowns' size;
#: it then takes one more (polishing) step. Convergence is quadratic, so after
#: that step the error is of order (1e-12)², i.e. at the rounding floor (a fixed
#: 1e-15 threshold cannot always be met: rounding alone makes steps of
#: cond·eps ≈ 1e-14 in a moderately conditioned pose).
NEWTON_RTOL = 1e-12
#: Near a toggle the Jacobian's condition number c makes Newton's steps stall at about
#: c·eps (2e-12 at c = 1e4, the test's limit) instead of shrinking below NEWTON_RTOL; a
#: step below this that no longer halves is that rounding floor, i.e. converged.
ROUNDING_FLOOR = 1e-9
#: A Newton iteration that has not converged after this many steps has failed.
NEWTON_MAX_ITERATIONS = 60

#: Column offset of each moving link's (x, y, φ) in q.
COL = {2: 0, 3: 3, 4: 6}
#: (i, j) of each pin: its multiplier is F_ij, the force by i on j.
PIN_LINKS = {"A0": (1, 2), "A": (2, 3), "B": (3, 4), "B0": (1, 4)}


class ReferenceError(RuntimeError):
    """The reference could not assemble the pose or solve the friction equations."""


def rot(phi: float) -> Matrix:
    """The rotation matrix A(φ)."""
    c, s = math.cos(phi), math.sin(phi)
    return np.array([[c, -s], [s, c]])


def perp(v: Vector) -> Vector:
    """v turned +90° (k × v)."""
    return np.array([-v[1], v[0]])


def cross2(r: Vector, f: Vector) -> float:
    """z-component of r × f."""
    return float(r[0] * f[1] - r[1] * f[0])


@dataclass(frozen=True)
class Pin:
    """A revolute joint: body-fixed point s_i on link i coincides with s_j on link j.

    For the ground (link 1) s is the point's fixed global position.
    """

    name: str
    i: int
    s_i: Vector
    j: int
    s_j: Vector


@dataclass
class Model:
    """The constraint model of one Case: pins, slide and driver rows."""

    case: Case
    pins: list[Pin]
    slide: tuple[Vector, Vector, float, float] | None  # (u, n, e, g)

    # -- points and their derivatives ---------------------------------------------
    @staticmethod
    def point(q: Vector, link: int, s: Vector) -> Vector:
        if link == 1:
            return s
        c = COL[link]
        return np.asarray(q[c:c + 2] + rot(q[c + 2]) @ s)

    # -- Φ, Φ_q, γ ---------------------------------------------------------------
    def phi(self, q: Vector, theta: float, driver: int) -> Vector:
        out = np.zeros(9)
        for k, p in enumerate(self.pins):
            out[2 * k:2 * k + 2] = self.point(q, p.i, p.s_i) - self.point(q, p.j, p.s_j)
        if self.slide is not None:
            _, n, e, g = self.slide
            out[6] = e - n @ q[6:8]
            out[7] = g - q[8]
        out[8] = theta - q[COL[driver] + 2]
        return out

    def jacobian(self, q: Vector, driver: int) -> Matrix:
        jac = np.zeros((9, 9))
        for k, p in enumerate(self.pins):
            for link, s, sign in ((p.i, p.s_i, 1.0), (p.j, p.s_j, -1.0)):
                if link == 1:
                    continue
                c = COL[link]
                jac[2 * k:2 * k + 2, c:c + 2] += sign * np.eye(2)
                jac[2 * k:2 * k + 2, c + 2] += sign * perp(rot(q[c + 2]) @ s)
        if self.slide is not None:
            _, n, _, _ = self.slide
            jac[6, 6:8] = -n
            jac[7, 8] = -1.0
        jac[8, COL[driver] + 2] = -1.0
        return jac

    def gamma(self, q: Vector, qd: Vector, alpha: float) -> Vector:
        """Right side of Φ_q q̈ = γ: A_i s_i φ̇_i² − A_j s_j φ̇_j² for pins, −α for the driver."""
        out = np.zeros(9)
        for k, p in enumerate(self.pins):
            for link, s, sign in ((p.i, p.s_i, 1.0), (p.j, p.s_j, -1.0)):
                if link == 1:
                    continue
                c = COL[link]
                out[2 * k:2 * k + 2] += sign * (rot(q[c + 2]) @ s) * qd[c + 2] ** 2
        out[8] = -alpha
        return out


def build_model(case: Case) -> Model:
    """Pins (and the slide) of the case's mechanism, in link frames."""
    g = case.preset.geometry
    zero = np.zeros(2)
    if isinstance(g, FourBarGeometry):
        b0 = g.a1 * np.array([math.cos(case.preset.ground_angle), math.sin(case.preset.ground_angle)])
        pins = [
            Pin("A0", 1, zero, 2, zero),
            Pin("A", 2, np.array([g.a2, 0.0]), 3, zero),
            Pin("B", 3, np.array([g.a3, 0.0]), 4, np.array([g.a4, 0.0])),
            Pin("B0", 1, b0, 4, zero),
        ]
        return Model(case, pins, None)
    assert isinstance(g, SliderCrankGeometry)
    u = np.array([math.cos(case.preset.ground_angle), math.sin(case.preset.ground_angle)])
    pins = [
        Pin("A0", 1, zero, 2, zero),
        Pin("A", 2, np.array([g.a2, 0.0]), 3, zero),
        Pin("B", 3, np.array([g.a3, 0.0]), 4, zero),
    ]
    return Model(case, pins, (u, perp(u), g.offset, case.preset.ground_angle))


def initial_guess(case: Case) -> Vector:
    """q with point B placed by the branch definition (CONVENTIONS.md).

    Four-bar: B is an intersection of the circles (A, a3) and (B0, a4). The
    contract's closed form φ14 = f ∓ acos(·), f the direction of B0→A, turns
    B0→A clockwise (open) or counter-clockwise (crossed) to reach B, so
    open ⇔ (A − B0) × (B − B0) < 0. Slider-crank: B = s u + e n on the circle
    (A, a3), s = A·u ± √(a3² − (e − A·n)²); right is the larger root.
    """
    g = case.preset.geometry
    t2 = case.preset.theta12
    a = g.a2 * np.array([math.cos(t2), math.sin(t2)])
    q = np.zeros(9)
    q[2] = t2
    q[3:5] = a
    if isinstance(g, FourBarGeometry):
        b0 = g.a1 * np.array([math.cos(case.preset.ground_angle), math.sin(case.preset.ground_angle)])
        d_vec = a - b0
        d = float(np.hypot(*d_vec))
        along = (g.a4**2 - g.a3**2 + d**2) / (2.0 * d)
        h2 = g.a4**2 - along**2
        if h2 < -1e-9 * g.scale**2:
            raise ReferenceError("the four-bar does not assemble at this θ12")
        h = math.sqrt(max(h2, 0.0))
        e_d = d_vec / d
        side = -1.0 if case.preset.branch == "open" else 1.0
        b = b0 + along * e_d + side * h * perp(e_d)
        q[6:8] = b0
        q[8] = math.atan2(b[1] - b0[1], b[0] - b0[0])
    else:
        assert isinstance(g, SliderCrankGeometry)
        u = np.array([math.cos(case.preset.ground_angle), math.sin(case.preset.ground_angle)])
        n = perp(u)
        disc = g.a3**2 - (g.offset - a @ n) ** 2
        if disc < -1e-9 * g.scale**2:
            raise ReferenceError("the slider-crank does not assemble at this θ12")
        root = math.sqrt(max(disc, 0.0)) * (1.0 if case.preset.branch == "right" else -1.0)
        b = (a @ u + root) * u + g.offset * n
        q[6:8] = b
        q[8] = case.preset.ground_angle
    q[5] = math.atan2(b[1] - a[1], b[0] - a[0])
    return q


def solve_positions(model: Model, q0: Vector) -> tuple[Vector, int]:
    """Newton–Raphson on Φ(q) = 0 (driver on link 2); returns q and the iterations."""
    q = q0.copy()
    scale = model.case.scale
    size = np.array([scale, scale, 1.0] * 3)
    previous = math.inf
    for it in range(1, NEWTON_MAX_ITERATIONS + 1):
        step = np.linalg.solve(model.jacobian(q, 2), model.phi(q, model.case.preset.theta12, 2))
        q -= step
        size_of_step = float(np.max(np.abs(step) / size))
        if size_of_step <= NEWTON_RTOL:
            q -= np.linalg.solve(model.jacobian(q, 2), model.phi(q, model.case.preset.theta12, 2))
            return q, it + 1
        if size_of_step <= ROUNDING_FLOOR and size_of_step > 0.5 * previous:
            return q, it  # stalled at the rounding floor of a near-toggle pose
        previous = size_of_step
    raise ReferenceError("position Newton–Raphson did not converge")


def velocities(model: Model, q: Vector, omega: float) -> Vector:
    """q̇ from Φ_q q̇ = −Φ_t, where only the driver depends on t (Φ_t = ω)."""
    rhs = np.zeros(9)
    rhs[8] = -omega
    return np.asarray(np.linalg.solve(model.jacobian(q, 2), rhs))


def accelerations(model: Model, q: Vector, qd: Vector, alpha: float) -> Vector:
    """q̈ from Φ_q q̈ = γ."""
    return np.asarray(np.linalg.solve(model.jacobian(q, 2), model.gamma(q, qd, alpha)))


def generalized_force(q: Vector, link: int, local: Vector, force: Vector,
                      torque: float = 0.0) -> Vector:
    """The 9-vector of a force at a body-fixed point (moment about the link origin)."""
    out = np.zeros(9)
    c = COL[link]
    out[c:c + 2] = force
    out[c + 2] = cross2(rot(q[c + 2]) @ local, force) + torque
    return out


def inertia_terms(case: Case, q: Vector, qd: Vector, qdd: Vector) -> Vector:
    """E: m·a_G and I_G·φ̈ + (r_G − r_O) × m·a_G per link (Newton–Euler at the origin)."""
    out = np.zeros(9)
    for m in case.preset.masses:
        c = COL[m.link]
        rc = rot(q[c + 2]) @ np.asarray(m.com)
        a_g = qdd[c:c + 2] + perp(rc) * qdd[c + 2] - rc * qd[c + 2] ** 2
        out[c:c + 2] += m.mass * a_g
        out[c + 2] += m.inertia * qdd[c + 2] + cross2(rc, m.mass * a_g)
    return out


def applied_forces(case: Case, q: Vector) -> Vector:
    """Q of the external loads and the weights."""
    out = np.zeros(9)
    for ld in case.preset.loads:
        out += generalized_force(q, ld.link, np.asarray(ld.at), np.asarray(ld.force), ld.torque)
    g = np.asarray(case.gravity)
    for m in case.preset.masses:
        out += generalized_force(q, m.link, np.asarray(m.com), m.mass * g)
    return out


def link_omega(qd: Vector, link: int) -> float:
    return 0.0 if link == 1 else float(qd[COL[link] + 2])


def sign(x: float) -> float:
    return float((x > 0.0) - (x < 0.0))


#: A relative speed this small compared with the input's (|ω2|, or |ω2|·L for the
#: slide) is rounding noise around an exact zero (e.g. a dead centre, where the
#: closed form gives ṡ = a2·ω·sin 0 = 0 but a linear solve gives ±1e-19): the
#: contract's sign(0) = 0 applies.
ZERO_SPEED_RTOL = 1e-12


def sense(x: float, scale: float) -> float:
    """sign(x), with |x| ≤ ZERO_SPEED_RTOL·scale counted as 0."""
    return 0.0 if abs(x) <= ZERO_SPEED_RTOL * scale else sign(x)


@dataclass
class Friction:
    """Friction terms ready to evaluate: viscous (known) and Coulomb (|λ|-dependent)."""

    viscous: Vector
    slide_viscous: float  # the viscous force on the slider along u
    pins: list[tuple[int, int, int, float]]  # (row of λ, link i, link j, μ·r·sign(ω_j − ω_i))
    slide: float  # μ_s·sign(ṡ) (0 when absent)
    #: The smallest |relative speed| of an active Coulomb term over its scale
    #: (|ω2|, or |ω2|·L for the slide): near 0 the friction's sense is ill-defined.
    min_sense_speed: float = math.inf


def friction_terms(model: Model, q: Vector, qd: Vector, qd_sense: Vector) -> Friction:
    case = model.case
    f = case.preset.friction
    viscous = np.zeros(9)
    pins: list[tuple[int, int, int, float]] = []
    slide_visc = 0.0
    slide = 0.0
    if f is None:
        return Friction(viscous, 0.0, pins, 0.0)
    w_in = abs(float(qd_sense[2]))
    speeds: list[float] = []
    for k, p in enumerate(model.pins):
        i, j = p.i, p.j
        c = f.viscous.get(p.name, 0.0)
        if c:
            moment = -c * (link_omega(qd, j) - link_omega(qd, i))
            for link, sgn in ((j, 1.0), (i, -1.0)):
                if link != 1:
                    viscous[COL[link] + 2] += sgn * moment
        arm = f.mu * f.pin_radius.get(p.name, 0.0)
        if arm > 0.0:
            rel = link_omega(qd_sense, j) - link_omega(qd_sense, i)
            speeds.append(abs(rel) / w_in)
            pins.append((2 * k, i, j, arm * sense(rel, w_in)))
    if model.slide is not None:
        u = model.slide[0]
        c = f.viscous.get("slide", 0.0)
        if c:
            slide_visc = -c * float(u @ qd[6:8])
            viscous[6:8] += slide_visc * u
        mu_s = f.slide_coefficient()
        if mu_s > 0.0:
            s_dot = float(u @ qd_sense[6:8])
            speeds.append(abs(s_dot) / (w_in * case.scale))
            slide = mu_s * sense(s_dot, w_in * case.scale)
    return Friction(viscous, slide_visc, pins, slide, min(speeds, default=math.inf))


def coulomb(model: Model, fr: Friction, lam: Vector) -> tuple[Vector, Matrix]:
    """Q_c(λ) of the Coulomb terms and its Jacobian ∂Q_c/∂λ."""
    out = np.zeros(9)
    d = np.zeros((9, 9))
    for r, i, j, coef in fr.pins:
        f = lam[r:r + 2]
        mag = float(np.hypot(*f))
        grad = -coef * f / mag if mag > 0.0 else np.zeros(2)
        for link, sgn in ((j, 1.0), (i, -1.0)):
            if link != 1:
                out[COL[link] + 2] += sgn * (-coef * mag)
                d[COL[link] + 2, r:r + 2] += sgn * grad
    if fr.slide and model.slide is not None:
        u = model.slide[0]
        force = -fr.slide * abs(lam[6])
        out[6:8] += force * u
        d[6:8, 6] += -fr.slide * sign(float(lam[6])) * u
    return out, d


@dataclass
class Reference:
    """The reference's answer: CONVENTIONS quantities (SI, radians) plus kinematics."""

    values: dict[str, float]
    q: Vector
    qd: Vector
    qdd: Vector
    condition: float  # of the dimensionless Φ_q with the driver on drive_link (the forces')
    iterations: dict[str, int] = field(default_factory=dict)
    #: See :attr:`Friction.min_sense_speed` (inf without Coulomb friction).
    min_sense_speed: float = math.inf
    #: Condition number of the dimensionless kinematic Jacobian (driver on link 2):
    #: large at a toggle of the prescribed-crank motion, where ω3, ω4 (and the
    #: inertia forces) blow up even if the force equations are well conditioned,
    #: as happens for drive_link = 4 at a rocker toggle.
    kinematic_condition: float = math.inf


def dimensionless_condition(model: Model, jac: Matrix) -> float:
    """cond of Φ_q with length rows divided by L and x, y columns multiplied by L."""
    length = model.case.scale
    rows = np.ones(9)
    rows[:2 * len(model.pins)] = 1.0 / length
    if model.slide is not None:
        rows[6] = 1.0 / length
    cols = np.array([length, length, 1.0] * 3)
    return float(np.linalg.cond(rows[:, None] * jac * cols[None, :]))


def kinematic_condition(case: Case) -> float:
    """:attr:`Reference.kinematic_condition` from the positions alone (no forces solved)."""
    model = build_model(case)
    q, _ = solve_positions(model, initial_guess(case))
    return dimensionless_condition(model, model.jacobian(q, 2))


def solve(case: Case) -> Reference:
    """Kinematics, drive torque and every joint reaction of ``case``."""
    model = build_model(case)
    q, pos_it = solve_positions(model, initial_guess(case))
    qd = velocities(model, q, case.preset.motion.omega)
    qdd = accelerations(model, q, qd, case.preset.motion.alpha)
    if case.preset.motion.omega != 0.0:
        qd_sense = qd
    else:
        friction = case.preset.friction
        qd_sense = velocities(model, q, float(friction.direction) if friction else 0.0)

    jac = model.jacobian(q, case.preset.drive_link)
    jt = jac.T
    fr = friction_terms(model, q, qd, qd_sense)
    known = applied_forces(case, q) + fr.viscous - inertia_terms(case, q, qd, qdd)
    lam: Vector = np.asarray(np.linalg.solve(jt, known), dtype=np.float64)
    iterations = 0
    if fr.pins or fr.slide:
        polished = False
        while not polished:
            iterations += 1
            if iterations > NEWTON_MAX_ITERATIONS:
                raise ReferenceError("the Coulomb friction equations did not converge")
            qc, dqc = coulomb(model, fr, lam)
            residual = jt @ lam - known - qc
            step = np.linalg.solve(jt - dqc, residual)
            lam = np.asarray(lam - step, dtype=np.float64)
            small = np.max(np.abs(step)) <= NEWTON_RTOL * max(np.max(np.abs(lam)), 1e-300)
            if small:  # one polishing step, then stop
                qc, dqc = coulomb(model, fr, lam)
                lam = np.asarray(lam - np.linalg.solve(jt - dqc, jt @ lam - known - qc),
                                 dtype=np.float64)
                iterations += 1
                polished = True

    values: dict[str, float] = {"theta13": float(q[5])}
    values["F12_x"], values["F12_y"] = lam[0:2]
    values["F23_x"], values["F23_y"] = lam[2:4]
    values["F34_x"], values["F34_y"] = lam[4:6]
    if model.slide is None:
        values["theta14"] = float(q[8])
        values["F14_x"], values["F14_y"] = lam[6:8]
    else:
        u, n, _, _ = model.slide
        along = fr.slide_viscous - fr.slide * abs(float(lam[6]))
        f14 = lam[6] * n + along * u
        values["s14"] = float(u @ q[6:8])
        values["F14_x"], values["F14_y"] = f14
        values["M14"] = float(lam[7])
    values[f"T1{case.preset.drive_link}"] = float(lam[8])
    values = {k: float(v) for k, v in values.items()}
    return Reference(values, q, qd, qdd, dimensionless_condition(model, jac),
                     {"positions": pos_it, "friction": iterations}, fr.min_sense_speed,
                     dimensionless_condition(model, model.jacobian(q, 2)))


def point_state(ref: Reference, link: int, local: tuple[float, float]
                ) -> tuple[Vector, Vector]:
    """Global position and velocity of a body-fixed point (for power balances)."""
    c = COL[link]
    r = rot(ref.q[c + 2]) @ np.asarray(local)
    return ref.q[c:c + 2] + r, ref.qd[c:c + 2] + perp(r) * ref.qd[c + 2]
