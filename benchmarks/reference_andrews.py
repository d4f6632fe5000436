"""Andrews' squeezing mechanism as the IVP test set writes it: a hand-written numpy
right-hand side, the speed reference of the analytic trajectory engine
(``bench_trajectory.py``) and an independent route to the test set's published state
(``tests/test_trajectory_references.py``).

Source: F. Mazzia and C. Magherini, *Test Set for Initial Value Problem Solvers*,
release 2.4 (2008), problem "andrews" (https://archimede.uniba.it/~testset/problems/andrews.php),
its Fortran ``andrews.f`` (revision ``andrews.F,v 1.2 2006/10/02``), as redistributed in the R
package deTestSet (rforge/bvpsolve, ``pkg/deTestSet/src/Ex_andrews.f``); after E. Hairer and
G. Wanner, *Solving Ordinary Differential Equations II*, sec. VII.7.

Seven bodies turn about the origin O (crank K1, angle β) and the fixed points A, B; the
coordinates are the seven angles q = (β, Θ, γ, Φ, δ, Ω, ε). The test set writes the index-3
DAE M(q) q̈ = f(q, q̇) − G(q)ᵀ λ, g(q) = 0 (six loop-closure equations). Here it is written in
index-1 form: differentiating g twice, G q̈ = −(d²g/dt² at q̈ = 0), so q̈ and λ solve

    [[M, Gᵀ], [G, 0]] [q̈; λ] = [f; −h(q, q̇)],

with h the terms of d²g/dt² quadratic in q̇ (written out below from g). Integrating it keeps
g = 0 to the integrator's tolerance over the test set's 0.03 s.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]

# The test set's parameters (SI: kg, kg·m², m, N/m, N·m), named as in andrews.f.
m1, m2, m3, m4, m5, m6, m7 = 0.04325, 0.00365, 0.02373, 0.00706, 0.07050, 0.00706, 0.05498
i1, i2, i3, i4, i5, i6, i7 = 2.194e-6, 4.410e-7, 5.255e-6, 5.667e-7, 1.169e-5, 5.667e-7, 1.912e-5
xa, ya = -0.06934, -0.00227
xb, yb = -0.03635, 0.03273
xc, yc = 0.014, 0.072
d, da, e, ea = 28e-3, 115e-4, 2e-2, 1421e-5
rr, ra = 7e-3, 92e-5
ss, sa, sb, sc, sd = 35e-3, 1874e-5, 1043e-5, 18e-3, 2e-2
ta, tb, u, ua, ub = 2308e-5, 916e-5, 4e-2, 1228e-5, 449e-5
zf, zt, fa = 2e-2, 4e-2, 1421e-5
c0, l0, mom = 4530.0, 7785e-5, 33e-3

#: The consistent initial state (andrews.f, ``andini``): angles (rad), at rest.
Q0 = np.array([-0.0617138900142764496358948458001, 0.0, 0.455279819163070380255912382449,
               0.222668390165885884674473185609, 0.487364979543842550225598953530,
               -0.222668390165885884674473185609, 1.23054744454982119249735015568])
#: Its accelerations (rad/s²) and multipliers (N), published with it.
QDD0 = np.array([14222.4439199541138705911625887, -10666.8329399655854029433719415,
                 0.0, 0.0, 0.0, 0.0, 0.0])
LAMBDA0 = np.array([98.5668703962410896057654982170, -6.12268834425566265503114393122,
                    0.0, 0.0, 0.0, 0.0])
#: The reference angles at t = 0.03 s (andrews.f, ``andsoln``: PSIDE at rtol = atol = 1e-14,
#: Cray C90 double precision).
T_END = 0.03
Q_END = np.array([0.1581077119629904e2, -0.1575637105984298e2, 0.4082224013073101e-1,
                  -0.5347301163226948, 0.5244099658805304, 0.5347301163226948,
                  0.1048080741042263e1])
#: Its rates (rad/s) and accelerations (rad/s²), published with it.
QD_END = np.array([0.1139920302151208e4, -0.1424379294994111e4, 0.1103291221937134e2,
                   0.1929337464421385e2, 0.5735699284790808, -0.1929337464421385e2,
                   0.3231791658026955])
QDD_END = np.array([-0.2463176316945196e5, 0.5185037701610329e5, 0.3241025686413781e6,
                    0.5667493645176213e6, 0.1674362929479361e5, -0.5667493645176222e6,
                    0.9826520791458422e4])


def mass_matrix(q: Array) -> Array:
    """M(q), 7 × 7 (andrews.f's ``m``)."""
    _, th, _, ph, _, om, _ = q.tolist()     # Python floats: scalar math is cheaper than numpy's
    siph, siom, coth = math.sin(ph), math.sin(om), math.cos(th)
    m = np.zeros((7, 7))
    m[0, 0] = m1 * ra**2 + m2 * (rr**2 - 2 * da * rr * coth + da**2) + i1 + i2
    m[1, 0] = m[0, 1] = m2 * (da**2 - da * rr * coth) + i2
    m[1, 1] = m2 * da**2 + i2
    m[2, 2] = m3 * (sa**2 + sb**2) + i3
    m[3, 3] = m4 * (e - ea)**2 + i4
    m[4, 3] = m[3, 4] = m4 * ((e - ea)**2 + zt * (e - ea) * siph) + i4
    m[4, 4] = m4 * (zt**2 + 2 * zt * (e - ea) * siph + (e - ea)**2) + m5 * (ta**2 + tb**2) + i4 + i5
    m[5, 5] = m6 * (zf - fa)**2 + i6
    m[6, 5] = m[5, 6] = m6 * ((zf - fa)**2 - u * (zf - fa) * siom) + i6
    m[6, 6] = m6 * ((zf - fa)**2 - 2 * u * (zf - fa) * siom + u**2) + m7 * (ua**2 + ub**2) + i6 + i7
    return m


def spring_point(gamma: float) -> tuple[float, float]:
    """D, the spring's end on K3 (andrews.f's xd, yd); its other end is C."""
    return (sd * math.cos(gamma) + sc * math.sin(gamma) + xb,
            sd * math.sin(gamma) - sc * math.cos(gamma) + yb)


def forces(q: Array, qd: Array) -> Array:
    """f(q, q̇): the drive torque, the spring and the velocity terms (andrews.f's ``ff``)."""
    be, th, _, ph, de, om, ep = qd.tolist()
    _, theta, gamma, phi, _, omega, _ = q.tolist()
    sith, coga, siga = math.sin(theta), math.cos(gamma), math.sin(gamma)
    coph, coom = math.cos(phi), math.cos(omega)
    xd, yd = spring_point(gamma)
    length = math.hypot(xd - xc, yd - yc)
    tension = -c0 * (length - l0) / length
    fx, fy = tension * (xd - xc), tension * (yd - yc)
    return np.array([
        mom - m2 * da * rr * th * (th + 2 * be) * sith,
        m2 * da * rr * be**2 * sith,
        fx * (sc * coga - sd * siga) + fy * (sd * coga + sc * siga),
        m4 * zt * (e - ea) * de**2 * coph,
        -m4 * zt * (e - ea) * ph * (ph + 2 * de) * coph,
        -m6 * u * (zf - fa) * ep**2 * coom,
        m6 * u * (zf - fa) * om * (om + 2 * ep) * coom,
    ])


def closure(q: Array) -> Array:
    """g(q), the six loop-closure equations (E reached through K1–K2 against through K3, K4–K5
    and K6–K7)."""
    be, th, ga, ph, de, om, ep = q.tolist()
    ex, ey = rr * math.cos(be) - d * math.cos(be + th), rr * math.sin(be) - d * math.sin(be + th)
    return np.array([
        ex - ss * math.sin(ga) - xb,
        ey + ss * math.cos(ga) - yb,
        ex - e * math.sin(ph + de) - zt * math.cos(de) - xa,
        ey + e * math.cos(ph + de) - zt * math.sin(de) - ya,
        ex - zf * math.cos(om + ep) - u * math.sin(ep) - xa,
        ey - zf * math.sin(om + ep) + u * math.cos(ep) - ya,
    ])


def closure_jacobian(q: Array) -> Array:
    """G(q) = ∂g/∂q, 6 × 7 (andrews.f's ``gp``)."""
    be, th, ga, ph, de, om, ep = q.tolist()
    sibe, cobe = math.sin(be), math.cos(be)
    sibeth, cobeth = math.sin(be + th), math.cos(be + th)
    siphde, cophde = math.sin(ph + de), math.cos(ph + de)
    siomep, coomep = math.sin(om + ep), math.cos(om + ep)
    g = np.zeros((6, 7))
    g[0::2, 0], g[0::2, 1] = -rr * sibe + d * sibeth, d * sibeth
    g[1::2, 0], g[1::2, 1] = rr * cobe - d * cobeth, -d * cobeth
    g[0, 2], g[1, 2] = -ss * math.cos(ga), -ss * math.sin(ga)
    g[2, 3], g[2, 4] = -e * cophde, -e * cophde + zt * math.sin(de)
    g[3, 3], g[3, 4] = -e * siphde, -e * siphde - zt * math.cos(de)
    g[4, 5], g[4, 6] = zf * siomep, zf * siomep - u * math.cos(ep)
    g[5, 5], g[5, 6] = -zf * coomep, -zf * coomep - u * math.sin(ep)
    return g


def closure_curvature(q: Array, qd: Array) -> Array:
    """h(q, q̇): d²g/dt² at q̈ = 0, each term of g differentiated twice by hand
    (d²/dt² cos φ = −cos φ·φ̇² − sin φ·φ̈, d²/dt² sin φ = −sin φ·φ̇² + cos φ·φ̈)."""
    be, th, ga, ph, de, om, ep = q.tolist()
    bed, thd, gad, phd, ded, omd, epd = qd.tolist()
    bt, pd, oe = bed + thd, phd + ded, omd + epd
    hx = -rr * math.cos(be) * bed**2 + d * math.cos(be + th) * bt**2    # of E's x through K1–K2
    hy = -rr * math.sin(be) * bed**2 + d * math.sin(be + th) * bt**2
    return np.array([
        hx + ss * math.sin(ga) * gad**2,
        hy - ss * math.cos(ga) * gad**2,
        hx + e * math.sin(ph + de) * pd**2 + zt * math.cos(de) * ded**2,
        hy - e * math.cos(ph + de) * pd**2 + zt * math.sin(de) * ded**2,
        hx + zf * math.cos(om + ep) * oe**2 + u * math.sin(ep) * epd**2,
        hy + zf * math.sin(om + ep) * oe**2 - u * math.cos(ep) * epd**2,
    ])


def accelerations(q: Array, qd: Array) -> tuple[Array, Array]:
    """q̈ and λ from the index-1 system [[M, Gᵀ], [G, 0]] [q̈; λ] = [f; −h]."""
    g = closure_jacobian(q)
    system = np.zeros((13, 13))
    system[:7, :7] = mass_matrix(q)
    system[:7, 7:] = g.T
    system[7:, :7] = g
    solution = np.linalg.solve(system, np.concatenate([forces(q, qd), -closure_curvature(q, qd)]))
    return solution[:7], solution[7:]


def rhs(t: float, y: Array) -> Array:
    """The first-order right-hand side for y = (q, q̇), as ``scipy.integrate.solve_ivp`` calls it."""
    q, qd = y[:7], y[7:]
    return np.concatenate([qd, accelerations(q, qd)[0]])


def energy(q: Array, qd: Array) -> float:
    """T + V_spring − mom·β: constant along the motion (the drive torque's work is mom·Δβ,
    the joints are frictionless)."""
    xd, yd = spring_point(float(q[2]))
    stretch = math.hypot(xd - xc, yd - yc) - l0
    return float(0.5 * qd @ mass_matrix(q) @ qd + 0.5 * c0 * stretch**2 - mom * q[0])
