"""The built-in reference problems of forward dynamics (``compare/cases/trajectories/``),
each held to a value from outside the engine:

* Andrews' squeezing mechanism: the IVP test set's published state at t = 0.03 s
  (``tests/andrews.py``: the test set's equations by hand, with its source);
* the IFToMM benchmark A02, N four-bar: an exact pendulum (elliptic functions);
* seed 002's exam Q2 released: its closed-form piecewise solution, with and without friction;
* the seed four-bar and slider-crank released: their first acceleration by a hand Lagrange
  computation.

Two kinds of test: those that check a case file against its source now, through the
published equations and the engine's existing inverse dynamics (driven at the published or
hand acceleration, the effort must be the file's own), and those that integrate the case
with the analytic reference (:func:`mechcheck.analytic.trajectory.simulate`), skipped while
it is not there.
"""

from __future__ import annotations

import dataclasses
import math
from functools import cache
from pathlib import Path

import numpy as np
import pytest
from numpy.typing import NDArray
from scipy.integrate import solve_ivp
from scipy.special import ellipj, ellipk

import mechcheck
from mechcheck.analytic.case import Case, Simulation
from mechcheck.analytic.linkage import Driver, Linkage
from mechcheck.analytic.linkage_forces import LinkageResults, solve_linkage
from mechcheck.analytic.trajectory import Trajectory, simulate
from mechcheck.casefile import load_cases
from mechcheck.tolerance import rule

from .andrews import ANDREWS

Array = NDArray[np.float64]

TRAJECTORIES = Path(mechcheck.__file__).parent / "cases" / "trajectories"

#: The engine's inverse dynamics against a hand or published acceleration: the same
#: rigid-body equations another way, only rounding between them.
INVERSE_RTOL = rule("analytic", "torque", "dynamic").rtol
#: The analytic reference's targets: Andrews' angles to the test set's reference state
#: (whose own accuracy is about this; the hand transcription reaches 3e-10) and the closed
#: forms' positions; the energy balance, an identity, to the integrator's tolerance.
REFERENCE_RTOL = 1e-7
ENERGY_RTOL = 1e-9
#: Exam Q2 against its closed form, over the case's scale (the harness's error measure).
CLOSED_FORM_TOL = 1e-9
#: N four-bar: energy drift over 10 s, through every horizontal pass.
DRIFT_RTOL = 1e-8


@cache
def trajectory_cases(*, long: bool = True) -> dict[str, Case]:
    """The built-in trajectory cases, and (``long``) those not run by default."""
    files = sorted(TRAJECTORIES.glob("*.toml"))
    files += sorted((TRAJECTORIES / "long").glob("*.toml")) if long else []
    return {c.name: c for c in load_cases(*files)}


def trajectory_case(name: str) -> Case:
    return trajectory_cases()[name]


def reference_run(case: Case) -> Trajectory:
    """The analytic reference's run of ``case``; the test is skipped while it is a stub."""
    try:
        (run,) = simulate(case)
    except NotImplementedError:
        pytest.skip("the analytic trajectory reference is not there yet")
    assert run.status == "ok", run.message
    return run


def link_angles(linkage: Linkage, run: Trajectory) -> dict[str, Array]:
    """Each moving link's rotation from the drawn pose at the run's times, rad."""
    return {link: run.coordinates[:, 3 * i + 2] for i, link in enumerate(linkage.moving_links)}


def driven_at(linkage: Linkage, joint: str, value: float, velocity: float,
              acceleration: float) -> LinkageResults:
    """The inverse dynamics of ``linkage`` with ``joint`` driven to ``value`` (from the drawn
    pose) at the given rates: the same file as a case at one instant (no efforts, no free
    motion)."""
    driver = Driver(joint, value, velocity, acceleration)
    return solve_linkage(dataclasses.replace(linkage, drivers=(driver,), free_motion=False))


def direction(p: Array) -> float:
    return math.atan2(p[1], p[0])


def point(linkage: Linkage, name: str) -> Array:
    return np.asarray(linkage.points[name], dtype=float)


# -- every file -------------------------------------------------------------------------


def test_every_trajectory_file_loads_as_a_trajectory() -> None:
    """Each built-in trajectory file reads as trajectory cases (what ``validate`` checks)."""
    cases = trajectory_cases()
    assert set(cases) == {"andrews-squeezer", "n-four-bar", "exam-q2-released",
                          "exam-q2-released-friction", "seed-fourbar-released",
                          "seed-slidercrank-released"}
    assert all(c.is_trajectory and c.kind == "trajectory" for c in cases.values())


@pytest.mark.parametrize("name", sorted(trajectory_cases(long=False)))
def test_energy_balance_of_the_reference(name: str) -> None:
    """Kinetic + potential − work + dissipated stays at its start along the reference's run."""
    run = reference_run(trajectory_case(name))
    assert run.energy is not None
    assert np.max(np.abs(run.energy.residual)) <= ENERGY_RTOL * run.energy.scale


# -- Andrews' squeezing mechanism ---------------------------------------------------------
#
# Source of every value: F. Mazzia, C. Magherini, Test Set for Initial Value Problem Solvers,
# release 2.4, problem "andrews" (https://archimede.uniba.it/~testset/problems/andrews.php),
# Fortran andrews.f (revision andrews.F,v 1.2 2006/10/02), as in the R package deTestSet
# (github.com/rforge/bvpsolve, pkg/deTestSet/src/Ex_andrews.f): the consistent initial
# state ``andini`` (ANDREWS.Q0, QDD0, LAMBDA0) and the reference state at 0.03 s
# ``andsoln`` (ANDREWS.Q_END, QD_END, QDD_END; PSIDE at rtol = atol = 1e-14).


def test_andrews_hand_equations_reach_the_published_state() -> None:
    """The hand-written test-set equations, integrated by scipy's DOP853 from the consistent
    initial state, reach the published angles at 0.03 s: the transcription is the test set's."""
    start = np.concatenate([ANDREWS.Q0, np.zeros(7)])
    solution = solve_ivp(ANDREWS.rhs, (0.0, ANDREWS.T_END), start, method="DOP853",
                         rtol=1e-12, atol=1e-12)
    q, qd = solution.y[:7, -1], solution.y[7:, -1]
    assert np.max(np.abs(q - ANDREWS.Q_END) / np.abs(ANDREWS.Q_END)) <= REFERENCE_RTOL
    assert np.max(np.abs(ANDREWS.closure(q))) <= REFERENCE_RTOL * ANDREWS.ss
    assert abs(ANDREWS.energy(q, qd) - ANDREWS.energy(ANDREWS.Q0, np.zeros(7))) \
        <= ENERGY_RTOL * 0.5 * qd @ ANDREWS.mass_matrix(q) @ qd


def test_andrews_hand_equations_give_the_published_initial_accelerations() -> None:
    """At the consistent initial state the index-1 system gives the published q̈(0) and λ(0)."""
    qdd, lam = ANDREWS.accelerations(ANDREWS.Q0, np.zeros(7))
    np.testing.assert_allclose(qdd, ANDREWS.QDD0, rtol=0, atol=INVERSE_RTOL * ANDREWS.QDD0[0])
    np.testing.assert_allclose(lam, ANDREWS.LAMBDA0, rtol=0, atol=INVERSE_RTOL * ANDREWS.LAMBDA0[0])


def body_angles(q: Array) -> Array:
    """Each body's direction (β, β + Θ, γ, Φ + δ, δ, Ω + ε, ε) from the test set's angles
    (or their rates)."""
    return np.array([q[0], q[0] + q[1], q[2], q[3] + q[4], q[4], q[5] + q[6], q[6]])


def angles_of_bodies(bodies: Array) -> Array:
    """(β, Θ, γ, Φ, δ, Ω, ε) from the bodies' directions (the inverse of :func:`body_angles`)."""
    b = bodies
    return np.array([b[0], b[1] - b[0], b[2], b[3] - b[4], b[4], b[5] - b[6], b[6]])


def body_columns(linkage: Linkage) -> list[int]:
    """The rotation's column of K1 … K7 in a pose's or run's coordinates."""
    return [3 * linkage.moving_links.index(f"K{i}") + 2 for i in range(1, 8)]


def andrews_angles(linkage: Linkage) -> Array:
    """(β, Θ, γ, Φ, δ, Ω, ε) read from the file's points by the test set's loop equations
    (u(φ) = (cos φ, sin φ), n(φ) = (sin φ, −cos φ)): F = rr·u(β), E = F − d·u(β + Θ),
    E = B + ss·n(γ), G = A + zt·u(δ), E = G + e·n(Φ + δ), H = A + u·n(ε), E = H + zf·u(Ω + ε)."""
    o, a, b, e, f, g, h = (point(linkage, p) for p in "OABEFGH")
    beta = direction(f - o)
    beta_theta = direction(f - e)
    gamma = direction(e - b) + math.pi / 2
    delta = direction(g - a)
    phi_delta = direction(e - g) + math.pi / 2
    epsilon = direction(h - a) + math.pi / 2
    omega_epsilon = direction(e - h)
    return np.array([beta, beta_theta - beta, gamma, phi_delta - delta, delta,
                     omega_epsilon - epsilon, epsilon])


def test_andrews_file_is_drawn_at_the_consistent_initial_angles() -> None:
    """The file's points give back the test set's seven initial angles (15 digits written)."""
    angles = andrews_angles(trajectory_case("andrews-squeezer").linkage)
    np.testing.assert_allclose(angles, ANDREWS.Q0, rtol=0, atol=1e-13)


def test_andrews_file_needs_the_drive_torque_for_the_published_acceleration() -> None:
    """Driven at rest with the published β̈(0), the engine's inverse dynamics needs the test
    set's 0.033 N·m and moves every body with the published q̈(0): the file's masses,
    inertias, spring and geometry are the test set's."""
    linkage = trajectory_case("andrews-squeezer").linkage
    (torque,) = (d.effort.at(0.0) for d in linkage.drivers if d.effort is not None)
    results = driven_at(linkage, "O", 0.0, 0.0, ANDREWS.QDD0[0])
    assert results.values["Q_O"][0] == pytest.approx(float(torque), rel=INVERSE_RTOL)
    assert float(torque) == ANDREWS.mom
    got = results.pose.qddot[0, body_columns(linkage)]
    np.testing.assert_allclose(got, body_angles(ANDREWS.QDD0), rtol=0,
                               atol=INVERSE_RTOL * ANDREWS.QDD0[0])


def test_andrews_file_needs_the_drive_torque_at_the_published_end_state() -> None:
    """Driven to the published state at 0.03 s (β, β̇, β̈: 2.5 turns on), the engine's
    inverse dynamics reaches the published angles and rates of every body and needs the
    0.033 N·m again. At the start K3…K7 stand still for an instant (q̈(0) moves β and Θ
    only); here every body moves, so every mass and inertia of the file is checked.
    The published accelerations carry about 1e-7 of error (an index-3 variable's accuracy;
    the engine's q̈ of each body agrees with them to 1.2e-7 of the largest), so the torque
    is held to REFERENCE_RTOL of the inertia torque it balances."""
    linkage = trajectory_case("andrews-squeezer").linkage
    turned = ANDREWS.Q_END[0] - ANDREWS.Q0[0]
    rate, acceleration = ANDREWS.QD_END[0], ANDREWS.QDD_END[0]
    results = driven_at(linkage, "O", turned, rate, acceleration)
    coasting = driven_at(linkage, "O", turned, rate, 0.0).values["Q_O"][0]
    inertia_torque = results.values["Q_O"][0] - coasting
    assert abs(results.values["Q_O"][0] - ANDREWS.mom) <= REFERENCE_RTOL * abs(inertia_torque)
    columns = body_columns(linkage)
    turned_bodies = results.pose.q[0, columns]
    np.testing.assert_allclose(turned_bodies, body_angles(ANDREWS.Q_END) - body_angles(ANDREWS.Q0),
                               rtol=0, atol=INVERSE_RTOL * abs(ANDREWS.Q_END[0]))
    rates = body_angles(ANDREWS.QD_END)
    np.testing.assert_allclose(results.pose.qdot[0, columns], rates, rtol=0,
                               atol=INVERSE_RTOL * np.max(np.abs(rates)))


def test_andrews_reference_reaches_the_published_state() -> None:
    """The analytic reference integrates the case to the test set's angles at 0.03 s."""
    case = trajectory_case("andrews-squeezer")
    run = reference_run(case)
    assert run.times[-1] == pytest.approx(ANDREWS.T_END, rel=1e-12)
    bodies = body_angles(ANDREWS.Q0) + run.coordinates[-1, body_columns(case.linkage)]
    angles = angles_of_bodies(bodies)
    assert np.max(np.abs(angles - ANDREWS.Q_END) / np.abs(ANDREWS.Q_END)) <= REFERENCE_RTOL


# -- IFToMM A02: the N four-bar -------------------------------------------------------------


def n_four_bar_numbers(linkage: Linkage) -> tuple[int, float, float]:
    """N, the reduced inertia J and the weight moment W of the parallelogram chain.

    Every vertical bar (N + 1 of them, uniform, m, l) turns with the crank θ about its
    ground pin, T = ½·(m·l²/3)·θ̇², its centre at height (l/2)·sin θ; every coupler (N)
    translates with the bars' tops at speed l·θ̇, T = ½·m·l²·θ̇², its centre at l·sin θ. So
    J = (N + 1)·m·l²/3 + N·m·l² and V = W·sin θ with W = m·g·l·((N + 1)/2 + N)."""
    n = sum(1 for link in linkage.moving_links if link.startswith("coupler"))
    m, length, g = 1.0, 1.0, 9.81
    return n, (n + 1) * m * length**2 / 3 + n * m * length**2, m * g * length * ((n + 1) / 2 + n)


def pendulum_crank_angle(times: Array, inertia: float, weight: float, rate: float) -> Array:
    """The crank angle θ(t) (from +x, drawn at 90°, starting at ``rate`` rad/s < 0) of
    J·θ̈ = −W·cos θ, exactly.

    With φ = θ + π/2 (0 hanging) the energy equation reads ½·J·φ̇² − W·cos φ = E, E =
    ½·J·θ̇0² + W, above the separatrix (W): the chain turns round. Written with ψ = φ/2,
    φ̇² = Ω²·(1 − k²·sin²ψ), Ω² = 2(E + W)/J, k² = 2W/(E + W), so F(ψ | k²) = K(k²) − Ω·t/2
    (ψ starts at π/2 and decreases) and ψ = am(K − Ω·t/2 | k²), the Jacobi amplitude."""
    energy = 0.5 * inertia * rate**2 + weight
    m = 2.0 * weight / (energy + weight)
    big_omega = math.sqrt(2.0 * (energy + weight) / inertia)
    amplitude = ellipj(ellipk(m) - big_omega * times / 2.0, m)[3]
    return np.asarray(2.0 * amplitude - math.pi / 2)


def test_n_four_bar_file_is_the_benchmark() -> None:
    """The file holds the benchmark's N = 40 windows of unit bars, drawn upright, with B0
    moving at +1 m/s (the crank turning at −1 rad/s) and gravity along −y."""
    case = trajectory_case("n-four-bar")
    linkage = case.linkage
    n, _, _ = n_four_bar_numbers(linkage)
    assert n == 40 and len(linkage.moving_links) == 2 * n + 1
    assert all(m.mass == 1.0 and m.inertia == pytest.approx(1.0 / 12.0, rel=1e-15)
               for m in linkage.masses)
    assert case.simulation is not None and case.simulation.rates == {"P0": -1.0}
    assert case.simulation.end == 10.0
    assert linkage.gravity == (0.0, -9.81)
    tops = np.array([point(linkage, f"B{i}") - point(linkage, f"P{i}") for i in range(n + 1)])
    np.testing.assert_array_equal(tops, np.tile([0.0, 1.0], (n + 1, 1)))


@pytest.mark.parametrize(("turned_deg", "rate", "acceleration"),
                         [(0.0, -1.0, 2.0), (-60.0, -1.0, 2.0), (60.0, 3.0, -5.0)])
def test_n_four_bar_is_a_pendulum_of_constant_inertia(turned_deg: float, rate: float,
                                                      acceleration: float) -> None:
    """The engine's inverse dynamics of the chain's crank is J·θ̈ + W·cos θ at any θ and θ̇
    (on the drawn side of the horizontal poses, where continuation from the drawing stops):
    the reduced inertia J = (N + 1)·m·l²/3 + N·m·l² and weight moment W of the closed form."""
    linkage = trajectory_case("n-four-bar").linkage
    _, inertia, weight = n_four_bar_numbers(linkage)
    turned = math.radians(turned_deg)
    effort = driven_at(linkage, "P0", turned, rate, acceleration).values["Q_P0"][0]
    theta = math.pi / 2 + turned
    assert effort == pytest.approx(inertia * acceleration + weight * math.cos(theta),
                                   rel=INVERSE_RTOL, abs=INVERSE_RTOL * weight)


def test_n_four_bar_pendulum_closed_form_solves_its_equation() -> None:
    """The elliptic-function solution meets the pendulum's equation integrated by scipy (a
    check of the oracle itself, independent of mechcheck)."""
    _, inertia, weight = n_four_bar_numbers(trajectory_case("n-four-bar").linkage)
    times = np.linspace(0.0, 10.0, 41)
    exact = pendulum_crank_angle(times, inertia, weight, -1.0)
    solution = solve_ivp(lambda t, y: [y[1], -weight * math.cos(y[0]) / inertia], (0.0, 10.0),
                         [math.pi / 2, -1.0], t_eval=times, method="DOP853", rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(solution.y[0], exact, rtol=0, atol=REFERENCE_RTOL)


def assert_follows_the_pendulum(case: Case, passes: int) -> None:
    """The reference's crank follows the exact pendulum through ``passes`` horizontal
    (redundant) poses on the parallelogram branch, every vertical bar turning with it and
    every coupler translating, and the energy drifts less than 1e-8."""
    run = reference_run(case)
    _, inertia, weight = n_four_bar_numbers(case.linkage)
    exact = pendulum_crank_angle(run.times, inertia, weight, -1.0)
    angles = link_angles(case.linkage, run)
    crank = math.pi / 2 + angles["bar0"]
    np.testing.assert_allclose(crank, exact, rtol=0, atol=REFERENCE_RTOL * abs(exact[-1]))
    found = np.floor(crank[0] / math.pi) - np.floor(crank[-1] / math.pi)
    assert found == np.floor(exact[0] / math.pi) - np.floor(exact[-1] / math.pi) == passes
    for link, phi in angles.items():
        expected = angles["bar0"] if link.startswith("bar") else 0.0
        np.testing.assert_allclose(phi, expected, rtol=0, atol=REFERENCE_RTOL)
    assert run.energy is not None
    total = run.energy.kinetic + run.energy.potential
    assert np.max(np.abs(total - total[0])) <= DRIFT_RTOL * run.energy.scale


@pytest.mark.slow
def test_n_four_bar_reference_passes_every_horizontal_pose() -> None:
    """The whole run, 10 s, through all ten horizontal (redundant) passes: the crank on the
    exact pendulum, every bar turning with it, every coupler translating, energy drift
    below 1e-8 (about 12 s of one core)."""
    assert_follows_the_pendulum(trajectory_case("n-four-bar"), 10)


# -- Exam Q2 released -----------------------------------------------------------------------

Q2_MASS, Q2_STIFFNESS, Q2_MU, Q2_G, Q2_X0 = 2.0, 300.0 + 200.0, 0.1, 9.81, 0.040


def q2_released(times: Array, mu: float) -> tuple[Array, list[float]]:
    """x(t) of m·ẍ + k·x + μ·m·g·sign ẋ = 0 from x0 at rest, and the switching instants.

    While the block moves toward −x (x > 0 at its last turning point) friction pushes +x:
    x = d + (x_n − d)·cos ω(t − t_n), d = μ·m·g/k, for half a period π/ω, to the turning
    point 2d − x_n; mirrored toward +x. So every half cycle the turning point's distance from
    0 falls by 2d, and the block sticks at the first turning point where the springs' pull
    k·|x| no more exceeds what friction holds, μ·m·g (|x| ≤ d)."""
    omega = math.sqrt(Q2_STIFFNESS / Q2_MASS)
    d = mu * Q2_MASS * Q2_G / Q2_STIFFNESS
    x = np.full_like(times, np.nan)
    start, turning, switches = 0.0, Q2_X0, []
    while abs(turning) > d:
        centre = math.copysign(d, turning)
        piece = (times >= start) & (times < start + math.pi / omega)
        x[piece] = centre + (turning - centre) * np.cos(omega * (times[piece] - start))
        start, turning = start + math.pi / omega, 2.0 * centre - turning
        switches.append(start)
        if mu == 0.0 and start > times[-1]:
            break
    x[times >= start] = turning
    return x, switches


def test_q2_closed_form_numbers() -> None:
    """The piecewise solution's turning points and stick instant are the file's stated ones
    (40, −32.152, 24.304, −16.456, 8.608, −0.760 mm; stuck from 5π/ω = 0.99346 s)."""
    omega = math.sqrt(250.0)
    turns = np.arange(6) * math.pi / omega
    x, switches = q2_released(turns, Q2_MU)
    np.testing.assert_allclose(x * 1e3, [40.0, -32.152, 24.304, -16.456, 8.608, -0.760],
                               rtol=0, atol=1e-12)
    assert switches[-1] == pytest.approx(0.99346, abs=5e-6) == 5 * math.pi / omega


@pytest.mark.parametrize(("name", "velocity"), [("exam-q2-released", 0.0),
                                                ("exam-q2-released-friction", -0.5)])
def test_q2_file_releases_with_the_closed_form_acceleration(name: str, velocity: float) -> None:
    """Driven at x0 with the closed form's first acceleration ẍ = (−k·x0 + μ·m·g)/m (moving
    toward −x, friction pushing +x), the engine's inverse dynamics needs no force: the file
    has the exam's mass, springs and friction and starts at x0."""
    case = trajectory_case(name)
    mu = Q2_MU if case.linkage.friction is not None else 0.0
    (driver,) = case.linkage.drivers
    assert driver.value == Q2_X0 and driver.effort is not None and driver.effort.values == (0.0,)
    accel = (-Q2_STIFFNESS * Q2_X0 + mu * Q2_MASS * Q2_G) / Q2_MASS
    force = driven_at(case.linkage, "slide", Q2_X0, velocity, accel).values["Q_slide"][0]
    assert abs(force) <= INVERSE_RTOL * Q2_STIFFNESS * Q2_X0


@pytest.mark.parametrize("name", ["exam-q2-released", "exam-q2-released-friction"])
def test_q2_reference_follows_the_closed_form(name: str) -> None:
    """The reference's block follows the piecewise closed form within 1e-9 of the case's
    scale, and (with friction) sticks at 5π/ω."""
    case = trajectory_case(name)
    run = reference_run(case)
    mu = Q2_MU if case.linkage.friction is not None else 0.0
    exact, switches = q2_released(run.times, mu)
    x = run.quantities(case.linkage)["q_slide"]
    assert np.max(np.abs(x - exact)) <= CLOSED_FORM_TOL * case.scale
    if mu:
        stick = switches[-1]
        assert any(abs(t - stick) <= CLOSED_FORM_TOL * case.simulation.end for t, _ in run.events)


# -- the seed four-bar and slider-crank released ------------------------------------------


def unit(angle: float) -> Array:
    return np.array([math.cos(angle), math.sin(angle)])


def normal(angle: float) -> Array:
    return np.array([-math.sin(angle), math.cos(angle)])


def spin(omega: float, r: Array) -> Array:
    """ω k × r."""
    return omega * np.array([-r[1], r[0]])


def fourbar_first_acceleration() -> float:
    """θ̈12(0) of seed-fourbar-released by Lagrange: at rest, M(θ)·θ̈ = Q(θ).

    SEEDS.md E1 (m): a1 = 0.14, a2 = 0.08, a3 = 0.1, a4 = 0.12, θ12 = 60°, B on the open
    branch ((A − B0) × (B − B0) < 0), C = A + 0.07·u(θ13 + α), α = acos((−0.08² + 0.1² +
    0.07²)/(2·0.07·0.1)). Velocity coefficients for θ̇12 = 1 from the loop a2·n(θ12) +
    a3·ω3·n(θ13) = a4·ω4·n(θ14). M = Σ m|v_G|² + I·ω², Q = −Σ m·g·v_Gy − k(L − L0)·ê·v_C
    (ê along the spring from its ground end S to C). The masses, centres and spring are
    the file's stated choices."""
    a1, a2, a3, a4 = 0.14, 0.08, 0.1, 0.12
    theta2 = math.radians(60.0)
    alpha = math.acos((-0.08**2 + 0.1**2 + 0.07**2) / (2 * 0.07 * 0.1))
    b0 = np.array([a1, 0.0])
    a = a2 * unit(theta2)
    reach = np.linalg.norm(a - b0)
    along_ab = (a - b0) / reach
    along = (a4**2 - a3**2 + reach**2) / (2 * reach)
    b = b0 + along * along_ab + math.sqrt(a4**2 - along**2) * np.array([along_ab[1], -along_ab[0]])
    theta3, theta4 = direction(b - a), direction(b - b0)
    c = a + 0.07 * unit(theta3 + alpha)
    w3, w4 = np.linalg.solve(np.column_stack([a3 * normal(theta3), -a4 * normal(theta4)]),
                             -a2 * normal(theta2))
    v_a = spin(1.0, a)
    parts = [(0.3, 1.6e-4, spin(1.0, a / 2), 1.0),
             (0.6, 6.0e-4, v_a + spin(w3, (a + b + c) / 3 - a), w3),
             (0.4, 4.8e-4, spin(w4, (b0 + b) / 2 - b0), w4)]
    inertia = sum(m * v @ v + i * w**2 for m, i, v, w in parts)
    weight = -sum(m * 9.81 * v[1] for m, _, v, _ in parts)
    stretch = c - np.array([0.0, 0.15])
    length = float(np.linalg.norm(stretch))
    spring = -300.0 * (length - 0.04) * (stretch / length) @ (v_a + spin(w3, c - a))
    return float((weight + spring) / inertia)


def slidercrank_first_acceleration() -> float:
    """θ̈12(0) of seed-slidercrank-released by Lagrange: at rest, M(θ)·θ̈ = Q(θ).

    SEEDS.md E2 (m): a2 = 0.2, a3 = 0.8, centric, θ12 = 55°. The rod's angle φ from
    a3·sin φ = −a2·sin θ, so φ̇ = −a2·cos θ/(a3·cos φ) per θ̇; the slider's speed
    v_B = v_A + a3·φ̇·n(φ). Crank 1 kg and rod 2 kg uniform (centres at their middles,
    m·l²/12), slider 1.5 kg, a 400 N/m spring of free length 0.1 m from S = (0.1, 0.5) to A."""
    a2, a3 = 0.2, 0.8
    theta = math.radians(55.0)
    rod = math.asin(-a2 * math.sin(theta) / a3)
    w3 = -a2 * math.cos(theta) / (a3 * math.cos(rod))
    a, v_a = a2 * unit(theta), a2 * normal(theta)
    v_b = v_a + a3 * w3 * normal(rod)
    parts = [(1.0, 1.0 * a2**2 / 12, v_a / 2, 1.0),
             (2.0, 2.0 * a3**2 / 12, v_a + a3 / 2 * w3 * normal(rod), w3),
             (1.5, 0.0, v_b, 0.0)]
    inertia = sum(m * v @ v + i * w**2 for m, i, v, w in parts)
    weight = -sum(m * 9.81 * v[1] for m, _, v, _ in parts)
    stretch = a - np.array([0.1, 0.5])
    length = float(np.linalg.norm(stretch))
    spring = -400.0 * (length - 0.1) * (stretch / length) @ v_a
    return float((weight + spring) / inertia)


SEEDS_RELEASED = {"seed-fourbar-released": fourbar_first_acceleration,
                  "seed-slidercrank-released": slidercrank_first_acceleration}
#: The files state the hand values rounded to five digits.
STATED_FIRST_ACCELERATION = {"seed-fourbar-released": -22.304, "seed-slidercrank-released": 71.782}


@pytest.mark.parametrize("name", sorted(SEEDS_RELEASED))
def test_seed_released_first_acceleration_needs_no_drive(name: str) -> None:
    """Driven at rest at the hand Lagrange θ̈12(0), the engine's inverse dynamics needs no
    torque at the crank: the file's weights and spring accelerate it exactly so."""
    acceleration = SEEDS_RELEASED[name]()
    assert acceleration == pytest.approx(STATED_FIRST_ACCELERATION[name], abs=5e-4)
    linkage = trajectory_case(name).linkage
    driven = driven_at(linkage, "A0", 0.0, 0.0, acceleration)
    unbalanced = driven_at(linkage, "A0", 0.0, 0.0, 0.0).values["Q_A0"][0]   # the torque it replaces
    assert abs(driven.values["Q_A0"][0]) <= INVERSE_RTOL * abs(unbalanced)


@pytest.mark.parametrize("name", sorted(SEEDS_RELEASED))
def test_seed_released_reference_starts_with_the_hand_acceleration(name: str) -> None:
    """The reference's crank leaves rest with the hand θ̈12(0): from rest θ(t) − θ(0) =
    θ̈·t²/2 + c·t⁴ + O(t⁶) (θ⃛(0) = 0, the forces depending on θ alone), so two early
    outputs h and 2h give θ̈ = (16·Δθ(h) − Δθ(2h))/(6h²) up to O(h⁴)."""
    case = trajectory_case(name)
    h = 1e-3
    early = dataclasses.replace(case, simulation=Simulation(2 * h, (0.0, h, 2 * h)))
    run = reference_run(early)
    turned = run.quantities(case.linkage)["q_A0"]
    estimate = (16.0 * (turned[1] - turned[0]) - (turned[2] - turned[0])) / (6.0 * h**2)
    # the estimate's truncation (ω·h)⁴ with ω² ≲ |θ̈| ~ 1e2 s⁻² is 1e-8; the integrator's
    # absolute error on displacements of ~1e-5 rad leaves about 1e-5 of it.
    assert estimate == pytest.approx(SEEDS_RELEASED[name](), rel=1e-4)
