"""MuJoCo's trajectories (backend ``mujoco``, :mod:`mechcheck.sim_models.mujoco.trajectory`)
against closed forms written here: pendulums released from rest (the exact nonlinear swing,
from the energy integral, in Jacobi's elliptic functions), a block between springs (free,
pushed by a constant force, pushed by a ramp), and the order of convergence of the
integrators with the time step. Nothing here compares with mechcheck's own reference.

The target of a trajectory is 1e-3 (positions over the linkage's size, angles in rad: the
trajectory row of the tolerance policy, design of ``mechcheck simulate``); the tests hold
MuJoCo to what its integrators promise, which is tighter.
"""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.special import ellipj, ellipk

from mechcheck import backends
from mechcheck.analytic.case import Case
from mechcheck.casefile import parse_cases, parse_toml
from mechcheck.sim_models.mujoco.backend import simulate
from mechcheck.sim_models.mujoco.linkage_model import spanning_tree
from mechcheck.sim_models.mujoco.trajectory import (
    DEFAULT_INTEGRATOR,
    DEFAULT_TIMESTEP,
    STEP_BUDGET,
    Rung,
    ladder,
    output_grid,
    simulate_case,
    step_budget,
)
from tests.exam_block import MASS, STIFFNESS, X0, exam_block

G = 9.81
#: The accuracy a trajectory is judged by (positions over the size, angles in rad).
TRAJECTORY_TOLERANCE = 1e-3


def case_of(text: str) -> Case:
    return parse_cases(parse_toml(text, "<test>"), "<test>")[0][0]


def swing(theta0: float, w0: float, t: np.ndarray) -> np.ndarray:
    """A pendulum's angle from its stable direction, released from rest at ``theta0``
    (rad), small-swing frequency ``w0`` (rad/s): the energy integral gives
    sin(θ/2) = k·sn(K − w0·t | k²) with k = sin(θ0/2) (exact, any amplitude)."""
    k = math.sin(theta0 / 2.0)
    sn = ellipj(ellipk(k * k) - w0 * t, k * k)[0]
    return np.asarray(2.0 * np.arcsin(k * sn))


def pendulum(theta0: float, end: float, extra: str = "", gravity: float = G,
             length: float = 1.0, mass: str = 'com = "B"') -> Case:
    """A bob (or a bar) on a pin at O, drawn at ``theta0`` from hanging straight down."""
    bx, by = length * math.sin(theta0), -length * math.cos(theta0)
    return case_of(f"""
[[case]]
name = "pendulum"
mechanism = "linkage"
gravity = [0.0, {-gravity}]
[case.points]
O = [0.0, 0.0]
B = [{bx!r}, {by!r}]
M = [{bx / 2!r}, {by / 2!r}]
[[case.links]]
name = "ground"
points = ["O"]
[[case.links]]
name = "arm"
points = ["O", "B", "M"]
[[case.joints]]
name = "pivot"
kind = "revolute"
links = ["ground", "arm"]
at = "O"
[[case.masses]]
link = "arm"
mass = 2.0
{mass}
{extra}
[case.simulate]
end = {end}
outputs = 21
""")


#: A fine rung, to keep the tests short (the backend's own ladder goes to its step budget):
#: RK4 at 0.5 ms, ω·dt ≤ 0.008 for every case here.
FINE = Rung(5e-4, "RK4")


def fine(case: Case) -> np.ndarray:
    """The coordinates of a fine RK4 run."""
    run = simulate_case(case, (FINE,))[0]
    assert run.status == "ok", run.message
    return run.coordinates


def test_simple_pendulum_swings_as_the_elliptic_solution() -> None:
    theta0 = math.radians(60.0)
    case = pendulum(theta0, 2.0)
    t = np.array(case.simulation.outputs)                       # type: ignore[union-attr]
    # φ is the rotation from the drawn pose: θ(t) − θ0.
    expected = swing(theta0, math.sqrt(G / 1.0), t) - theta0
    simulation = case.simulation
    assert simulation is not None
    default = ladder(simulation)[0]
    runs = simulate_case(case, (default, Rung(5e-4, "Euler"), FINE))
    errors = [float(np.abs(r.coordinates[:, 2] - expected).max()) for r in runs]
    # RK4: the point mass's floor inertia (1e-9·m·L²) moves the swing by ~2.6e-9 rad after
    # one period (measured at every step of the ladder), the integration error is below it.
    assert errors[-1] < 1e-8
    # MuJoCo's defaults (semi-implicit Euler, 2 ms) are first order: 1.6 rad/s × dt after
    # one period of this swing (measured 3.1e-3 at 2 ms), past the target; 0.5 ms meets it.
    error_at = {(r.settings["dt"], r.settings["integrator"]): e
                for r, e in zip(runs, errors, strict=True)}
    default = next(e for r, e in zip(runs, errors, strict=True) if r.default)
    assert error_at[(5e-4, "Euler")] < TRAJECTORY_TOLERANCE < default


def test_compound_pendulum_and_its_point_trajectory() -> None:
    """A uniform bar (mass at its middle, I = m·L²/12): w0² = m·g·(L/2)/(m·L²/3)."""
    theta0, length = math.radians(120.0), 0.5
    case = pendulum(theta0, 1.0, length=length,
                    mass=f'com = "M"\ninertia = {2.0 * length**2 / 12.0!r}')
    t = np.array(case.simulation.outputs)                       # type: ignore[union-attr]
    theta = swing(theta0, math.sqrt(1.5 * G / length), t)
    coordinates = fine(case)
    assert np.abs(coordinates[:, 2] - (theta - theta0)).max() < 1e-8
    # The bar turns about O, which stays put: t = O − R(φ)·O = 0 (O is the origin).
    assert np.abs(coordinates[:, :2]).max() < 1e-9


def test_fixed_direction_load_swings_like_gravity() -> None:
    """No gravity, a force of fixed direction F = (4, 0) N at the bob: a pendulum about +x,
    w0² = F/(m·L), released at 60° from +x (drawn at 150° from hanging down)."""
    case = pendulum(math.radians(150.0), 1.0, gravity=0.0,
                    extra='[[case.loads]]\nlink = "arm"\nat = "B"\nforce = { x = 4.0, y = 0.0 }')
    t = np.array(case.simulation.outputs)                       # type: ignore[union-attr]
    theta0 = math.radians(60.0)
    expected = swing(theta0, math.sqrt(4.0 / 2.0), t) - theta0
    assert np.abs(fine(case)[:, 2] - expected).max() < 1e-8


def parallelogram(theta0: float, end: float, extra: str = "") -> Case:
    """Two cranks of 1 m (uniform bars of 0.5 kg) and a coupler of 2 kg carried as a point
    mass: the coupler translates on a circle, so the linkage swings as one pendulum
    (a loop closed by a connect in MuJoCo)."""
    s, c = math.sin(theta0), -math.cos(theta0)
    return case_of(f"""
[[case]]
name = "parallelogram"
mechanism = "linkage"
gravity = [0.0, {-G}]
[case.points]
O1 = [0.0, 0.0]
O2 = [1.0, 0.0]
A = [{s!r}, {c!r}]
B = [{1.0 + s!r}, {c!r}]
[[case.links]]
name = "ground"
points = ["O1", "O2"]
[[case.links]]
name = "left"
points = ["O1", "A"]
[[case.links]]
name = "coupler"
points = ["A", "B"]
[[case.links]]
name = "right"
points = ["O2", "B"]
[[case.joints]]
name = "P1"
kind = "revolute"
links = ["ground", "left"]
at = "O1"
[[case.joints]]
name = "PA"
kind = "revolute"
links = ["left", "coupler"]
at = "A"
[[case.joints]]
name = "PB"
kind = "revolute"
links = ["coupler", "right"]
at = "B"
[[case.joints]]
name = "P2"
kind = "revolute"
links = ["ground", "right"]
at = "O2"
[[case.masses]]
link = "left"
mass = 0.5
com = [{s / 2!r}, {c / 2!r}]
inertia = {0.5 / 12.0!r}
[[case.masses]]
link = "right"
mass = 0.5
com = [{1.0 + s / 2!r}, {c / 2!r}]
inertia = {0.5 / 12.0!r}
[[case.masses]]
link = "coupler"
mass = 2.0
com = [{0.5 + s!r}, {c!r}]
inertia = 1e-12
{extra}
[case.simulate]
end = {end}
outputs = 11
""")


def test_parallelogram_with_a_loop_closure_swings_as_its_pendulum() -> None:
    """T = ½(2·m_c·L²/3 + M·L²)·θ̇², V = −(m_c + M)·g·L·cos θ: w0² = (m_c + M)·g /
    ((2·m_c/3 + M)·L) with m_c = 0.5, M = 2, L = 1."""
    theta0 = math.radians(45.0)
    case = parallelogram(theta0, 1.0)
    t = np.array(case.simulation.outputs)                       # type: ignore[union-attr]
    expected = swing(theta0, math.sqrt(2.5 * G / (1.0 / 3.0 + 2.0)), t) - theta0
    runs = simulate_case(case, (Rung(DEFAULT_TIMESTEP, DEFAULT_INTEGRATOR), Rung(1e-3, "RK4"),
                                FINE))
    last = runs[-1]
    k = case.linkage.link_number["left"]
    error = np.abs(last.coordinates[:, 3 * k + 2] - expected).max()
    # The coupler's point mass has the floor inertia 1e-5·m·L² (MuJoCo refuses none): it
    # adds ~4e-6 of the inertia; the soft closure (time constant 2·dt) bends by its gap.
    assert error < 1e-5
    assert last.diagnostics["closure_gap_m"] < 1e-6
    # Every rung reports its gap, and the coarse ones within the target.
    assert all(r.diagnostics["closure_gap_m"] < TRAJECTORY_TOLERANCE for r in runs)


def test_dampers_on_every_joint_of_the_loop_damp_it_as_the_linear_oscillator() -> None:
    """Viscous friction c on all four pins, one of which closes the loop (a damper there is
    a tendon over the hinges): each pin turns at ±θ̇, so J·θ̈ + 4·c·θ̇ + W·sin θ = 0 with
    J = 2·m_c·L²/3 + M·L², W = (m_c + M)·g·L. Released at θ0 = 0.01 rad: the linear
    oscillator θ0·e^(−ζωt)·(cos ω_d·t + ζω/ω_d·sin ω_d·t), whose neglected θ³/6 moves the
    swing by ~θ0³ (1e-6 rad)."""
    theta0, c = 0.01, 0.1
    viscous = ", ".join(f"{j} = {c}" for j in ("P1", "PA", "PB", "P2"))
    case = parallelogram(theta0, 2.0, f"[case.friction]\nviscous = {{ {viscous} }}")
    assert any(j.name in ("P1", "PA", "PB", "P2") for j in spanning_tree(case.linkage).closures)
    t = np.array(case.simulation.outputs)                       # type: ignore[union-attr]
    inertia, weight = 1.0 / 3.0 + 2.0, 2.5 * G
    omega = math.sqrt(weight / inertia)
    zeta = 4.0 * c / (2.0 * math.sqrt(inertia * weight))
    damped = omega * math.sqrt(1.0 - zeta**2)
    theta = theta0 * np.exp(-zeta * omega * t) * (np.cos(damped * t)
                                                  + zeta * omega / damped * np.sin(damped * t))
    k = case.linkage.link_number["left"]
    coordinates = fine(case)
    assert np.abs(coordinates[:, 3 * k + 2] - (theta - theta0)).max() < 3e-6

#: Exam Q2 (seed 002): m = 2 kg between k1 = 300 N/m and k2 = 200 N/m, both unstretched at
#: x = 0; the block drawn at x0 = 40 mm and released from rest: m·ẍ + (k1 + k2)·x = F.
OMEGA = math.sqrt(STIFFNESS / MASS)


def block_case(driver: str = "") -> Case:
    return case_of(exam_block("exam-q2-block", drivers=driver))


def test_block_between_springs_oscillates_as_x0_cos() -> None:
    case = block_case()
    t = np.array(case.simulation.outputs)                       # type: ignore[union-attr]
    # t_x is the displacement from the drawn pose x0: x − x0 = x0·(cos ωt − 1).
    expected = X0 * (np.cos(OMEGA * t) - 1.0)
    assert np.abs(fine(case)[:, 0] - expected).max() / case.scale < 1e-9


def test_constant_force_moves_the_centre_of_the_oscillation() -> None:
    """A driver with force = 5 N on the slide: x = F/K + (x0 − F/K)·cos ωt."""
    case = block_case('[[case.drivers]]\njoint = "slide"\nforce = 5.0')
    t = np.array(case.simulation.outputs)                       # type: ignore[union-attr]
    centre = 5.0 / STIFFNESS
    expected = centre + (X0 - centre) * np.cos(OMEGA * t) - X0
    assert np.abs(fine(case)[:, 0] - expected).max() / case.scale < 1e-9


def test_a_force_table_is_followed_row_by_row() -> None:
    """force = c·t for 0.5 s, then held (rows [0, 0], [0.5, 10]): from x0 at rest,
    x = x0·cos ωt + (c/K)·(t − sin ωt/ω) up to 0.5 s, and after it the oscillation about
    F_end/K from the state there (closed form of m·ẍ + K·x = F(t))."""
    case = block_case('[[case.drivers]]\njoint = "slide"\nforce = [[0.0, 0.0], [0.5, 10.0]]')
    t = np.array(case.simulation.outputs)                       # type: ignore[union-attr]
    c, t1 = 20.0, 0.5

    def ramp(s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        x = X0 * np.cos(OMEGA * s) + c / STIFFNESS * (s - np.sin(OMEGA * s) / OMEGA)
        v = -X0 * OMEGA * np.sin(OMEGA * s) + c / STIFFNESS * (1.0 - np.cos(OMEGA * s))
        return x, v

    x1, v1 = ramp(np.array(t1))
    centre = c * t1 / STIFFNESS
    late = centre + (x1 - centre) * np.cos(OMEGA * (t - t1)) + v1 / OMEGA * np.sin(OMEGA * (t - t1))
    expected = np.where(t <= t1, ramp(t)[0], late) - X0
    assert np.abs(fine(case)[:, 0] - expected).max() / case.scale < 1e-9


def block_errors(rungs: tuple[Rung, ...]) -> list[float]:
    case = block_case()
    t = np.array(case.simulation.outputs)                       # type: ignore[union-attr]
    expected = X0 * (np.cos(OMEGA * t) - 1.0)
    return [float(np.abs(r.coordinates[:, 0] - expected).max()) for r in simulate_case(case, rungs)]


@pytest.mark.parametrize(("integrator", "order"), [("Euler", 1.0), ("implicitfast", 1.0),
                                                   ("RK4", 4.0)])
def test_error_falls_with_the_integrators_order(integrator: str, order: float) -> None:
    """The error against x0·cos ωt at dt, dt/2, dt/4 (ω·dt = 0.032 … 0.008): the observed
    order log2(e(dt)/e(dt/2)) is the integrator's (semi-implicit Euler 1, RK4 4) within 0.3."""
    dts = (2e-3, 1e-3, 5e-4)
    errors = block_errors(tuple(Rung(dt, integrator) for dt in dts))
    orders = [math.log2(a / b) for a, b in itertools.pairwise(errors)]
    assert all(abs(p - order) < 0.3 for p in orders), (errors, orders)


def test_ladder_runs_the_defaults_first_and_the_finest_rk4_last() -> None:
    case = block_case()
    simulation = case.simulation
    assert simulation is not None
    rungs = ladder(simulation, step_budget(case))
    assert rungs[0] == Rung(DEFAULT_TIMESTEP, DEFAULT_INTEGRATOR, default=True)
    assert sum(r.default for r in rungs) == 1
    assert rungs[-1].integrator == "RK4" and rungs[-1].dt == min(r.dt for r in rungs)
    assert simulation.end / rungs[-1].dt <= STEP_BUDGET < 2 * simulation.end / rungs[-1].dt
    # 21 outputs over 1 s: every 0.05 s, which 2 ms divides.
    assert output_grid(simulation.outputs) == pytest.approx(0.05)


def test_outputs_between_steps_are_read_between_them() -> None:
    """Andrews-like spacing (1 ms) under MuJoCo's default 2 ms: the default rung reads every
    other output between two steps. RK4 at 2 ms is within ~1e-10 m of x0·cos ωt here
    ((ω·dt)⁴ = 1e-6 of a swing of 0.04 m, over half a radian); the cubic Hermite reading
    between steps adds dt⁴·ω⁴·x0/384 ≈ 1e-10 m (a straight line between the steps would
    add dt²·ω²·x0/8 = 5e-6 m)."""
    case = case_of(exam_block("exam-q2-block").replace("end = 1.0\noutputs = 21",
                                                   "end = 0.03\noutputs = 31"))
    simulation = case.simulation
    assert simulation is not None
    rungs = ladder(simulation)
    assert rungs[0].dt == DEFAULT_TIMESTEP and rungs[1].dt == pytest.approx(1e-3)
    t = np.array(simulation.outputs)
    run = simulate_case(case, (Rung(DEFAULT_TIMESTEP, "RK4"),))[0]
    error = np.abs(run.coordinates[:, 0] - X0 * (np.cos(OMEGA * t) - 1.0))
    assert error.max() < 1e-9


def test_a_run_past_the_step_budget_is_refused_naming_what_helps() -> None:
    case = case_of(exam_block("exam-q2-block").replace("end = 1.0", "end = 1000.0"))
    runs = simulate(case)
    assert all(r.status == "not_applicable" for r in runs)
    assert "simulate.end" in runs[0].message and str(STEP_BUDGET) in runs[0].message
    assert np.isnan(runs[0].coordinates).all()


def coulomb_block(t: np.ndarray, mu: float) -> np.ndarray:
    """Exam Q2 with Coulomb friction μ·m·g, released at x0: each half period π/ω the block
    swings about ±μ·m·g/K (the side it moves away from) and loses 2·μ·m·g/K of amplitude;
    it sticks at the first turn within μ·m·g/K of 0 (the static friction holds the spring)."""
    f = mu * MASS * G / STIFFNESS
    turns = [X0]
    while abs(turns[-1]) > f:
        c = f * math.copysign(1.0, turns[-1])
        turns.append(2.0 * c - turns[-1])
    half = math.pi / OMEGA
    k = np.minimum((t // half).astype(int), len(turns) - 1)
    start = np.array(turns)[k]
    centre = f * np.sign(start)
    moving = k < len(turns) - 1
    return np.where(moving, centre + (start - centre) * np.cos(OMEGA * (t - k * half)), start)


def test_coulomb_friction_stops_the_block_as_the_piecewise_solution() -> None:
    """μ = 0.1: the turns at 40, −32.152, 24.304, −16.456, 8.608 mm, stuck at −0.760 mm after
    five half periods. The friction is applied from the reactions before each step and held
    through it: first order in dt whatever the integrator (measured 5.6e-4 and 2.9e-4 of the
    size at 1 and 0.5 ms with Euler)."""
    case = case_of(exam_block("exam-q2-block", drivers="[case.friction]\nmu = 0.1")
                   .replace("end = 1.0\noutputs = 21", "end = 1.5\noutputs = 31"))
    t = np.array(case.simulation.outputs)                       # type: ignore[union-attr]
    expected = coulomb_block(t, 0.1) - X0
    runs = simulate_case(case, (Rung(1e-3, "Euler"), Rung(5e-4, "Euler")))
    errors = [float(np.abs(r.coordinates[:, 0] - expected).max()) / case.scale for r in runs]
    assert errors[1] < TRAJECTORY_TOLERANCE
    assert 1.6 < errors[0] / errors[1] < 2.4


ROTOR = """
[[case]]
name = "rotor"
mechanism = "linkage"
[case.points]
O = [0.0, 0.0]
R = [0.1, 0.0]
[[case.links]]
name = "ground"
points = ["O"]
[[case.links]]
name = "disk"
points = ["O", "R"]
[[case.joints]]
name = "axle"
kind = "revolute"
links = ["ground", "disk"]
at = "O"
[[case.drivers]]
joint = "axle"
torque = 0.2
[[case.masses]]
link = "disk"
mass = 1.0
com = "O"
inertia = 0.5
[case.simulate]
end = 1.0
outputs = 11
"""


def test_a_drive_torque_accelerates_a_rotor_as_each_integrator_promises() -> None:
    """τ = 0.2 N·m on I = 0.5 kg·m²: φ = a·t²/2 with a = τ/I. RK4 is exact on a quadratic;
    semi-implicit Euler (v += a·dt, then q += v·dt) gives a·dt²·n(n+1)/2, i.e. exactly
    a·t·dt/2 more (implicitfast too: nothing depends on velocity)."""
    case = case_of(ROTOR)
    t = np.array(case.simulation.outputs)                       # type: ignore[union-attr]
    a, dt = 0.2 / 0.5, 1e-2
    runs = simulate_case(case, (Rung(dt, "Euler"), Rung(dt, "implicitfast"), Rung(dt, "RK4")))
    for run in runs[:2]:
        np.testing.assert_allclose(run.coordinates[:, 2], a * t**2 / 2 + a * t * dt / 2,
                                   rtol=0, atol=1e-12)
    np.testing.assert_allclose(runs[2].coordinates[:, 2], a * t**2 / 2, rtol=0, atol=1e-12)


def test_a_prescribed_driver_carries_the_pendulum_at_constant_speed() -> None:
    """A carriage driven along x at 0.3 m/s (a driver without an effort: prescribed motion)
    with a pendulum hung from it: a frame moving at constant speed is inertial, so the arm
    swings as the fixed pendulum and the carriage is at 0.3·t."""
    theta0 = math.radians(40.0)
    bx, by = math.sin(theta0), -math.cos(theta0)
    case = case_of(f"""
[[case]]
name = "carriage"
mechanism = "linkage"
gravity = [0.0, {-G}]
[case.points]
W = [-1.0, 0.0]
C = [0.0, 0.0]
B = [{bx!r}, {by!r}]
[[case.links]]
name = "ground"
points = ["W"]
[[case.links]]
name = "carriage"
points = ["C"]
[[case.links]]
name = "arm"
points = ["C", "B"]
[[case.joints]]
name = "rail"
kind = "prismatic"
links = ["ground", "carriage"]
at = "C"
axis = [1.0, 0.0]
[[case.joints]]
name = "hinge"
kind = "revolute"
links = ["carriage", "arm"]
at = "C"
[[case.drivers]]
joint = "rail"
displacement = 0.0
velocity = 0.3
[[case.masses]]
link = "carriage"
mass = 1.0
com = "C"
[[case.masses]]
link = "arm"
mass = 2.0
com = "B"
[case.simulate]
end = 1.0
outputs = 21
""")
    t = np.array(case.simulation.outputs)                       # type: ignore[union-attr]
    coordinates = fine(case)
    carriage, arm = (3 * case.linkage.link_number[k] for k in ("carriage", "arm"))
    # The rail's equality follows the clock (a 1e9 kg·m² flywheel turning at 1 rad/s) with
    # a soft constraint of time constant 2·dt: measured 6e-10 m off 0.3·t, and the arm
    # 1.5e-9 rad off its swing (the bob's floor inertia), at 0.5 ms with RK4.
    assert np.abs(coordinates[:, carriage] - 0.3 * t).max() < 1e-8
    expected = swing(theta0, math.sqrt(G), t) - theta0
    assert np.abs(coordinates[:, arm + 2] - expected).max() < 1e-8


def test_a_gear_mesh_is_refused_with_the_reason() -> None:
    """The catalogue's gear pair released (its driver without an effort turning the pinion):
    one not_applicable run saying why, no number."""
    text = (Path(__file__).resolve().parents[1] / "compare" / "cases" / "catalogue"
            / "gear_pair.toml").read_text()
    case = case_of(text + "\n[case.simulate]\nend = 0.1\noutputs = 3\n")
    simulator = backends.get("mujoco").simulator()       # as the harness finds it
    assert simulator is not None
    (run,) = simulator(case)
    assert run.status == "not_applicable" and "gear mesh" in run.message
    assert np.isnan(run.coordinates).all() and run.coordinates.shape == (3, 6)
