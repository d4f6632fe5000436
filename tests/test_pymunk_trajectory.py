"""pymunk on trajectory cases (``mechcheck simulate``, :mod:`mechcheck.sim_models.pymunk.trajectory`):
the linkage released to move freely, read from pymunk's own bodies, against closed forms
written here — the block between two springs (seed 002's exam Q2), a compound pendulum's
exact nonlinear swing, a wheel under a torque — and against the exact recurrence of
pymunk's own step; its convergence with the time step; the ladder and its refusals."""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from scipy.special import ellipj, ellipk

import mechcheck
from mechcheck.analytic.case import Case
from mechcheck.analytic.trajectory import Trajectory
from mechcheck.sim_models.pymunk import backend as pm, trajectory as pt
from tests.exam_block import MASS, STIFFNESS, X0, exam_block, pushed

#: A first-order method's error halves with the step: the ratio of the errors of two runs a
#: halving apart, at steps where the next order is a few percent of the first (ω·dt ≤ 0.03
#: here), is 2 within ±10 %.
FIRST_ORDER = (1.8, 2.2)
#: Rounding only: a run that repeats a recurrence in the same floating-point operations, a
#: few thousand steps of numbers about 0.1 m (ε ≈ 2.2e-16 a step, ≤ 1e-12 m after 5000).
ROUNDING = 1e-12

# Seed 002's exam Q2 (SEEDS.md; compare/cases/linkages/exam_q2_mass_springs.toml): a block
# m = 2 kg between springs k1 = 300 N/m and k2 = 200 N/m unstretched at x = 0, on a
# horizontal slide: m ẍ + (k1 + k2) x = F. Released at x0 = 40 mm from rest under a
# constant force F on the slide's driver.


# A uniform bar (m = 2 kg, L = 0.5 m) pinned at one end, drawn horizontal and released from
# rest under g = 9.81: a compound pendulum 90° from its hanging pose.
PENDULUM = """
[[case]]
name = "pendulum"
mechanism = "linkage"
length_unit = "m"
gravity = [0.0, -9.81]
[case.points]
O = [0.0, 0.0]
P = [0.5, 0.0]
[[case.links]]
name = "ground"
points = ["O"]
[[case.links]]
name = "bar"
points = ["O", "P"]
[[case.joints]]
name = "pivot"
kind = "revolute"
links = ["ground", "bar"]
at = "O"
[[case.masses]]
link = "bar"
mass = 2.0
com = [0.25, 0.0]
inertia = 0.041666666666666667
[case.simulate]
end = 0.5
outputs = 11
"""


def case_of(text: str, tmp_path: Path, name: str = "case.toml") -> Case:
    path = tmp_path / name
    path.write_text(text)
    return mechcheck.load_cases(path)[0]


def block(tmp_path: Path, force: str = "0.0", end: float = 0.5, mu: float | None = None) -> Case:
    friction = "" if mu is None else f"[case.friction]\nmu = {mu}"
    return case_of(exam_block("block", drawn_at=0.0, drivers=pushed(force), end=end, outputs=51,
                              extra=friction), tmp_path)


def run_at(case: Case, dt: float, iterations: int = 10) -> Trajectory:
    """One run of ``case`` at a step and iterations of its own choosing (not the ladder)."""
    start = pt.start_state(case)
    assert not isinstance(start, str), start
    inertia = pt.free_inertia(case.linkage, start.q)
    assert not isinstance(inertia, str), inertia
    return pt.run(case, start, inertia, pt.Rung(dt, iterations))


def errors(case: Case, steps: list[float], exact: np.ndarray, column: int,
           scale: float = 1.0) -> np.ndarray:
    """The worst |simulated − exact| of one coordinate over the output times, per step."""
    return np.array([np.abs(run_at(case, dt).coordinates[:, column] - exact).max() / scale
                     for dt in steps])


def test_block_moves_by_pymunks_own_recurrence(tmp_path: Path) -> None:
    """pymunk steps the block exactly as its semi-implicit Euler step says, with the
    springs' force at the new position and the driver's force: x₊ = x + h·v,
    v₊ = v + h·(F − k·x₊)/m — so its model of the block, the springs and the effort is
    exact, and what is left is the integrator's."""
    h, force = 1e-3, 5.0
    case = block(tmp_path, force=str(force))
    x, v, xs = X0, 0.0, [X0]
    for _ in range(round(0.5 / h)):
        x = x + h * v
        v = v + h * (force - STIFFNESS * x) / MASS
        xs.append(x)
    run = run_at(case, h)
    assert np.abs(run.coordinates[:, 0] - np.array(xs)[::10]).max() < ROUNDING
    assert np.abs(run.coordinates[:, 1:]).max() == 0.0      # the slide holds y and φ


def test_block_converges_to_the_harmonic_closed_form(tmp_path: Path) -> None:
    """Exam Q2 released under a constant force F: x(t) = F/k + (x0 − F/k)·cos ωt,
    ω = √(k/m); pymunk's error halves with its step (first order: the state is given at
    t = 0 and the step updates the position with the old velocity)."""
    force = 5.0
    case = block(tmp_path, force=str(force))
    t = np.array(case.simulation.outputs)  # type: ignore[union-attr]
    offset = force / STIFFNESS
    exact = offset + (X0 - offset) * np.cos(math.sqrt(STIFFNESS / MASS) * t)
    e = errors(case, [1e-3, 5e-4, 2.5e-4], exact, 0)
    assert np.all((e[:-1] / e[1:] > FIRST_ORDER[0]) & (e[:-1] / e[1:] < FIRST_ORDER[1])), e


def pendulum_angle(t: np.ndarray) -> np.ndarray:
    """The compound pendulum's exact angle φ(t) (rad, from the drawn horizontal pose).

    With α the angle from the hanging pose, I_O·α̈ = −m·g·d·sin α, I_O = m·L²/3 about the
    pin (0.1667 kg·m²), d = L/2. Released from rest at α0 = π/2, its solution is
    sin(α/2) = k·sn(K(k) − ω0·t; k) with k = sin(α0/2), ω0 = √(m·g·d/I_O) (the exact
    nonlinear pendulum; Lawden, Elliptic Functions and Applications, §5.2); φ = α − π/2.
    """
    inertia = 0.041666666666666667 + 2.0 * 0.25 ** 2
    omega0 = math.sqrt(2.0 * 9.81 * 0.25 / inertia)
    k = math.sin(math.pi / 4.0)
    sn, _, _, _ = ellipj(ellipk(k * k) - omega0 * t, k * k)
    return np.asarray(2.0 * np.arcsin(k * sn) - math.pi / 2.0)


def test_pendulum_converges_to_the_exact_nonlinear_swing(tmp_path: Path) -> None:
    """A compound pendulum released from 90°: pymunk's angle converges to the elliptic
    closed form at first order, and its pin's gap (pymunk's default error correction
    leaves part of each step's drift) shrinks with the step too."""
    case = case_of(PENDULUM, tmp_path)
    exact = pendulum_angle(np.array(case.simulation.outputs))  # type: ignore[union-attr]
    steps = [1 / 960, 1 / 1920, 1 / 3840]
    e = errors(case, steps, exact, 2)
    assert np.all((e[:-1] / e[1:] > FIRST_ORDER[0]) & (e[:-1] / e[1:] < FIRST_ORDER[1])), e
    gaps = np.array([run_at(case, dt).diagnostics["closure_gap_m"] for dt in steps])
    assert np.all((gaps[:-1] / gaps[1:] > FIRST_ORDER[0]) & (gaps[:-1] / gaps[1:] < FIRST_ORDER[1]))


# A wheel on a pin at its centre of mass, no gravity, turned by a torque on its pin.
WHEEL = """
[[case]]
name = "wheel"
mechanism = "linkage"
length_unit = "m"
[case.points]
O = [0.0, 0.0]
R = [0.2, 0.0]
[[case.links]]
name = "ground"
points = ["O"]
[[case.links]]
name = "wheel"
points = ["O", "R"]
[[case.joints]]
name = "axle"
kind = "revolute"
links = ["ground", "wheel"]
at = "O"
[[case.drivers]]
joint = "axle"
rotation = 0.0
torque = [[0.0, 0.0], [0.2, 0.6]]
[[case.masses]]
link = "wheel"
mass = 3.0
com = "O"
inertia = 0.06
[case.simulate]
end = 0.2
outputs = 21
"""


def test_a_torque_table_turns_the_wheel_by_its_recurrence(tmp_path: Path) -> None:
    """A driver's torque acts on the joint's link (links[1]) positively, read from its
    table at each step's end time: ω₊ = ω + h·τ(t₊)/I, φ₊ = φ + h·ω; the exact motion
    under τ = 3·t N·m is φ = t³/(2·I), which it approaches."""
    h, inertia = 1e-3, 0.06
    case = case_of(WHEEL, tmp_path)
    phi, omega, phis = 0.0, 0.0, [0.0]
    for n in range(200):
        phi = phi + h * omega
        omega = omega + h * 3.0 * (n + 1) * h / inertia
        phis.append(phi)
    run = run_at(case, h)
    assert np.abs(run.coordinates[:, 2] - np.array(phis)[::10]).max() < ROUNDING
    # The recurrence sums to φ_n = (t³ − t·h²)/(2·I) at t = n·h: second order in h here.
    t = run.times
    assert np.abs(run.coordinates[:, 2] - t ** 3 / (2.0 * inertia)).max() \
        < 0.2 * h ** 2 / (2.0 * inertia) + ROUNDING


def test_an_effort_between_two_links_keeps_their_angular_momentum(tmp_path: Path) -> None:
    """A torque on a joint between two moving links is a pair (+τ on links[1], −τ on
    links[0]): two wheels on one axle, turned against each other, keep I₁·ω₁ + I₂·ω₂ = 0,
    so I₁·φ₁ + I₂·φ₂ = 0 at all times."""
    text = WHEEL.replace('points = ["O", "R"]\n', 'points = ["O", "R"]\n[[case.links]]\n'
                         'name = "rotor"\npoints = ["O"]\n', 1)
    text = text.replace('[[case.drivers]]\njoint = "axle"', '[[case.joints]]\nname = "inner"\n'
                        'kind = "revolute"\nlinks = ["wheel", "rotor"]\nat = "O"\n'
                        '[[case.drivers]]\njoint = "inner"')
    text += '[[case.masses]]\nlink = "rotor"\nmass = 1.0\ncom = "O"\ninertia = 0.02\n'
    case = case_of(text, tmp_path)
    run = run_at(case, 1e-3)
    wheel, rotor = run.coordinates[:, 2], run.coordinates[:, 5]
    assert rotor[-1] > 0.1                  # the torque turned the rotor (links[1]) forward
    assert np.abs(0.06 * wheel + 0.02 * rotor).max() < 1e-9 * 0.02 * rotor[-1]


def test_a_driver_without_effort_keeps_its_prescribed_motion(tmp_path: Path) -> None:
    """A driver without an effort moves its joint as q = value + v·t + a·t²/2 (its lock
    moved every step, its error corrected completely): the driven crank's angle is that at
    every output after the first step, whose position update takes the velocity at t = 0
    (off by a·h²/2), while the pendulum hung from its tip swings freely."""
    text = PENDULUM.replace('[[case.masses]]', '''[[case.links]]
name = "bob"
points = ["P", "B"]
[[case.joints]]
name = "tip"
kind = "revolute"
links = ["bar", "bob"]
at = "P"
[[case.drivers]]
joint = "pivot"
rotation = 0.0
velocity = 2.0
acceleration = 1.0
[[case.masses]]
link = "bob"
mass = 1.0
com = [0.5, -0.15]
inertia = 0.01
[[case.masses]]''', 1).replace('P = [0.5, 0.0]', 'P = [0.5, 0.0]\nB = [0.5, -0.3]')
    case = case_of(text, tmp_path)
    h = 1e-3
    run = run_at(case, h, iterations=100)
    t = run.times
    prescribed = 2.0 * t + 0.5 * t ** 2
    assert np.abs(run.coordinates[:, 2] - prescribed).max() < 0.5 * 1.0 * h * h + 1e-9
    assert np.ptp(run.coordinates[:, 5] - run.coordinates[:, 2]) > 0.1  # the bob swings


def test_coulomb_friction_stops_the_block_where_the_closed_form_does(tmp_path: Path) -> None:
    """Exam Q2 released from 40 mm with μ = 0.1 on the slide: each half cycle is harmonic
    about ±μ·m·g/k with its amplitude 2·μ·m·g/k smaller, and the block sticks at the first
    turning point within μ·m·g/k of the springs' rest (|k·x| ≤ μ·m·g): at −0.76 mm after
    five half cycles (t = 5π/ω = 0.99 s). pymunk's friction (from its own normal force and
    rate) converges to that motion and stops there."""
    case = block(tmp_path, end=1.5, mu=0.1)
    t = np.array(case.simulation.outputs)  # type: ignore[union-attr]
    exact = stick_slip(t, X0, math.sqrt(STIFFNESS / MASS), 0.1 * MASS * 9.81 / STIFFNESS)
    assert abs(exact[-1] - (-0.00076)) < 1e-12        # the hand value above
    e = errors(case, [1e-3, 5e-4], exact, 0)
    assert FIRST_ORDER[0] < e[0] / e[1] < FIRST_ORDER[1], e


def stick_slip(t: np.ndarray, x0: float, omega: float, band: float) -> np.ndarray:
    """The closed-form stick-slip motion of a block released from x0 > band at rest:
    half cycles of π/ω, each a cosine about the offset band·sign(a) (friction opposes the
    motion toward −sign(a)) from its start a to 2·band·sign(a) − a, until |a| ≤ band."""
    x = np.empty_like(t)
    start, a = 0.0, x0
    pieces = []
    while abs(a) > band:
        offset = band * math.copysign(1.0, a)
        pieces.append((start, a, offset))
        start, a = start + math.pi / omega, 2.0 * offset - a
    for i, ti in enumerate(t):
        moving = [p for p in pieces if p[0] <= ti < p[0] + math.pi / omega]
        if moving:
            s, a0, offset = moving[0]
            x[i] = offset + (a0 - offset) * math.cos(omega * (ti - s))
        else:
            x[i] = a
    return x


def test_the_ladder_ends_at_its_finest_rung_and_starts_at_pymunks_defaults(tmp_path: Path) -> None:
    """One run per rung, coarsest first: pymunk's defaults (10 iterations, a 60 Hz frame
    or the outputs' spacing where finer) the first and only default one; the step halved
    down to the budget, each at 10 and 100 iterations; the last the finest step."""
    case = case_of(PENDULUM, tmp_path)
    runs = pm.simulate(case)
    settings = [(r.settings["dt"], r.settings["iterations"]) for r in runs]
    assert [r.default for r in runs] == [True] + [False] * (len(runs) - 1)
    assert settings[0] == (pytest.approx(0.05 / 3), 10)   # 0.05 s between outputs: 3 steps
    assert settings[-1][0] == min(dt for dt, _ in settings)
    assert settings == sorted(settings, key=lambda s: (-s[0], s[1]))
    assert all(r.status == "ok" and r.times.tolist() == list(case.simulation.outputs)  # type: ignore[union-attr]
               for r in runs)
    assert [r.steps for r in runs[::2]] == [30 * 2 ** k for k in range(len(runs) // 2)]


def test_a_run_past_the_step_budget_is_refused_by_its_setting(tmp_path: Path) -> None:
    """A case whose coarsest step would take more steps than pymunk's budget is not run:
    ``not_applicable``, naming the step and the budget."""
    case = case_of(PENDULUM.replace("end = 0.5", "end = 2000.0"), tmp_path)
    [run] = pm.simulate(case)
    assert run.status == "not_applicable"
    assert "0.01667 s" in run.message and str(pt.STEP_BUDGET) in run.message
    assert np.isnan(run.coordinates).all()


@pytest.mark.parametrize(("change", "named"), [
    (lambda text: text.replace("inertia = 0.041666666666666667\n", ""), "no moment of inertia"),
    (lambda text: text.replace('[[case.masses]]\nlink = "bar"', '[[case.masses]]\nlink = "ground"'),
     "no mass"),
])
def test_what_pymunk_cannot_integrate_is_refused(tmp_path: Path, change: Callable[[str], str],
                                                named: str) -> None:
    """A link without mass, or one that turns without a moment, cannot be a pymunk body
    without changing the motion: ``not_applicable``, naming the link."""
    [run] = pm.simulate(case_of(change(PENDULUM), tmp_path))
    assert run.status == "not_applicable" and named in run.message and "bar" in run.message


def test_a_run_that_diverges_says_so_and_reads_nothing_after(tmp_path: Path) -> None:
    """A run whose bodies' positions become non-finite gives no numbers from there on
    (``not_settled``, saying when), rather than NaN read as a position."""
    case = case_of(PENDULUM, tmp_path)
    start = pt.start_state(case)
    assert not isinstance(start, str)
    inertia = pt.free_inertia(case.linkage, start.q)
    assert not isinstance(inertia, str)
    lost = pt.Start(start.q, np.array([0.0, 0.0, math.nan]))
    run = pt.run(case, lost, inertia, pt.Rung(0.01, 10))
    assert run.status == "not_settled" and "diverged by t = 0.05 s" in run.message
    assert np.all(run.coordinates[0] == 0.0) and np.isnan(run.coordinates[1:]).all()
