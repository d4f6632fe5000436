"""Trajectory cases in pymunk (backend ``pymunk``, ``mechcheck simulate``): the linkage
released to move freely, run on a ladder of time steps and solver iterations.

The model is the linkage builder's (:mod:`.linkage_model`, the joints of
:mod:`.joint_kinds`, pymunk's own springs) with each link's **real** mass and moment
(:func:`free_inertia`: no fictitious inertia, which a free motion could not remove). What
moves it (:func:`install_free_loads`):

- weights through the space's gravity (each body's centre of gravity is its link's centre
  of mass);
- loads, fixed in direction, at their points (:mod:`.loads`), applied inside the body's
  velocity integration, at the pose of the step;
- joint friction from pymunk's own reactions and joint rates, as the driven runs take it
  (:mod:`.linkage_friction`, :meth:`.linkage_dynamics.Twins.step_with_friction`);
- a driver's **effort**: pymunk has no actuator of given torque (a ``SimpleMotor``
  prescribes a rate), so the effort is a load pair on the joint's two bodies, applied as a
  joint's friction is (:func:`.linkage_friction.apply_joint_friction`): a couple +τ on
  ``links[1]`` and −τ on ``links[0]`` at a revolute joint; a force +F along the axis at
  ``at`` on ``links[1]`` and −F on ``links[0]`` at a sliding one; read from its table at
  the step's end time (the pose the step's velocity integration is at).

A driver **without** an effort keeps its prescribed motion q(t) = value + velocity·t +
acceleration·t²/2 through its lock, moved every step as a driven run moves it (the lock's
target is where the next position update must land, its error correction complete); every
other constraint keeps pymunk's default error correction (``error_bias`` (1 − 0.1)⁶⁰: a
joint's error shrinks by 10 % every 1/60 s, to 0.18 % of it after a second, whatever the
step).

The run starts at t = 0 on the linkage's pose with the drivers at their values and every
free coordinate as drawn, its rates consistent with the constraints
(:func:`start_state`: the analytic kinematics seeds the state, nothing more), and is read at
the output times from pymunk's own bodies: each body's origin and angle are the link's
(t_x, t_y, φ) (the body frame is the drawn pose's, :mod:`.linkage_model`), its angle
keeping its turns. Steps land on every output time (:func:`step_times`).

The ladder (:func:`ladder`): pymunk's defaults first (10 iterations a step, the step of a
60 Hz frame, 1/60 s, or the outputs' spacing where that is finer), then the step halved
:data:`HALVINGS` times, each at 10 and at :data:`MORE_ITERATIONS` iterations, the rungs
within the step and solver budgets (:func:`affordable`); the last rung is the finest.
Its findings: docs/backends.md, "Trajectories in pymunk".
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from functools import cache

import numpy as np
import pymunk
from scipy.linalg import null_space

from mechcheck.analytic.case import Case, Simulation
from mechcheck.analytic.linkage import Driver, Linkage
from mechcheck.analytic.linkage_dynamics import independent_joints
from mechcheck.analytic.linkage_kinematics import (
    Array,
    joint_system_at,
    solve_pose,
    unit_scales,
)
from mechcheck.analytic.solution import Status
from mechcheck.analytic.trajectory import Trajectory
from mechcheck.sim_models.inertia import real_inertial
from mechcheck.sim_models.linkage_motion import prescribed_motion
from mechcheck.sim_models.pymunk.linkage import loop_violations
from mechcheck.sim_models.pymunk.linkage_dynamics import Twins, drive_to, set_velocities, step_once
from mechcheck.sim_models.pymunk.linkage_friction import Diverged, JointLoads, apply_joint_friction
from mechcheck.sim_models.pymunk.linkage_model import (
    LinkageModel,
    build_linkage_model,
    coordinates,
    gyration_radius,
)
from mechcheck.sim_models.pymunk.loads import LoadLike, apply_forces
from mechcheck.sim_models.pymunk.readout import Values
from mechcheck.sim_models.pymunk.settings import SolverSettings

BACKEND = "pymunk"

#: s, the coarsest step of the ladder: one frame at 60 Hz, the step pymunk's own examples
#: and the games it is made for take (pymunk has no default step; ``Space.step`` takes one).
#: Where the outputs are closer than that, their spacing: every output time is a step's end.
FRAME = 1.0 / 60.0
#: The step is halved this many times at most from the coarsest (8: 1/15 360 s from a frame).
HALVINGS = 8
#: Steps a run may take: a step runs some Python around Chipmunk's (the space's step, a
#: driver's lock, the efforts and loads of the bodies that have them: 20–130 µs measured on
#: the built-in cases), so a run at the budget takes seconds.
STEP_BUDGET = 2 ** 16
#: A run with joint friction reads its reactions and joint rates every step and takes each
#: step twice (:meth:`.linkage_dynamics.Twins.step_with_friction`): 0.7–1 ms a step on exam
#: Q2 against 60–130 µs without friction; its step budget is the budget over this.
FRICTION_COST = 8
#: Gauss–Seidel work a run may take, in constraint rows × iterations × steps: Chipmunk's
#: solve costs about 0.08 µs a row and iteration (the N four-bar, 242 rows: 0.2 ms a step
#: at 10 iterations), so a run at the budget takes about 3 s.
SOLVE_BUDGET = 2 ** 25
#: Gauss–Seidel iterations a step of the ladder's second series: ten times pymunk's default.
MORE_ITERATIONS = 100
#: A link's rotation counts as moving when the joints allow it this much turning per unit
#: of motion (the null space of their Jacobian, in lengths): below it the link cannot turn.
TURNS_RTOL = 1e-9


@cache
def pymunk_defaults() -> tuple[int, float]:
    """pymunk's own defaults, read from pymunk: a new space's Gauss–Seidel iterations a
    step and a new constraint's ``error_bias``."""
    a, b = pymunk.Body(1.0, 1.0), pymunk.Body(1.0, 1.0)
    return pymunk.Space().iterations, pymunk.PivotJoint(a, b, (0.0, 0.0)).error_bias


@dataclass(frozen=True)
class Rung:
    """One run's settings: its largest step (s) and its iterations a step; ``default``:
    pymunk's defaults."""

    dt: float
    iterations: int
    default: bool = False


@dataclass(frozen=True)
class Start:
    """The state at t = 0: every moving link's coordinates q and rates q̇ (3n,)."""

    q: Array
    qdot: Array


def ladder(case: Case) -> list[Rung]:
    """The rungs a case runs on, coarsest first: each step of :func:`time_steps` at pymunk's
    default iterations and at :data:`MORE_ITERATIONS`, those within the budgets
    (:func:`affordable`); at one step, the fewer iterations first, so the last rung is the
    finest step at the most iterations it affords."""
    default, _ = pymunk_defaults()
    assert case.simulation is not None
    rungs = [Rung(dt, iterations, default=k == 0 and iterations == default)
             for k, dt in enumerate(time_steps(case.simulation))
             for iterations in (default, MORE_ITERATIONS)]
    return [rung for rung in rungs if affordable(case, rung) is None]


def affordable(case: Case, rung: Rung) -> str | None:
    """Why a run at ``rung`` is past pymunk's budgets, or None: its steps
    (:data:`STEP_BUDGET`, over :data:`FRICTION_COST` with joint friction) or its solver's
    work (:data:`SOLVE_BUDGET`)."""
    assert case.simulation is not None
    linkage = case.linkage
    steps = sum(n for _, _, n in stretches(case.simulation, rung.dt))
    budget = STEP_BUDGET // FRICTION_COST if linkage.friction is not None else STEP_BUDGET
    if steps > budget:
        return (f"a step of {rung.dt:.4g} s takes {steps} steps to the last output, above "
                f"pymunk's budget of {budget}")
    work = steps * rung.iterations * max(linkage.constraint_rows, 1)
    if work > SOLVE_BUDGET:
        return (f"{steps} steps of {rung.iterations} iterations on {linkage.constraint_rows} "
                f"constraint rows, above pymunk's solver budget of {SOLVE_BUDGET} row-iterations")
    return None


def time_steps(simulation: Simulation) -> list[float]:
    """The steps of the ladder: :data:`FRAME` (or the outputs' spacing, if finer) halved
    :data:`HALVINGS` times."""
    spacing = np.diff((0.0, *simulation.outputs))
    coarsest = min([FRAME, *spacing[spacing > 0.0]])
    return [coarsest / 2 ** k for k in range(HALVINGS + 1)]


def step_times(simulation: Simulation, dt: float) -> Array:
    """The end time of every step from 0 (first) to the last output: each stretch between
    outputs in equal steps of at most ``dt``, so that a step ends on every output time."""
    times = [np.zeros(1)]
    times += [np.linspace(a, b, n + 1)[1:] for a, b, n in stretches(simulation, dt)]
    return np.concatenate(times)


def stretches(simulation: Simulation, dt: float) -> list[tuple[float, float, int]]:
    """Each stretch between consecutive outputs (from 0) and the steps of at most ``dt``
    it takes."""
    edges = (0.0, *simulation.outputs)
    return [(a, b, math.ceil((b - a) / dt * (1.0 - 1e-12)))
            for a, b in itertools.pairwise(edges) if b > a]


def largest_step(simulation: Simulation, dt: float) -> float:
    """The longest step a run at ``dt`` takes (s)."""
    return max(((b - a) / n for a, b, n in stretches(simulation, dt)), default=dt)


# -- the start ----------------------------------------------------------------------------

def _scaled_joints(linkage: Linkage, q: Array) -> Array:
    """The joints' Jacobian at q in lengths (:func:`.linkage_kinematics.unit_scales`)."""
    rows, cols = unit_scales(linkage, drivers=False)
    return np.asarray(joint_system_at(linkage, q).at(0).toarray() * rows[:, None] * cols[None, :])


def start_state(case: Case) -> Start | str:
    """The state at t = 0: the drivers at their values with their velocities, the joints
    of ``simulation.rates`` at their rates, every other free coordinate as drawn and at
    rest (:func:`~mechcheck.analytic.linkage_dynamics.independent_joints`, the
    analytic reference's choice), positions and rates from the analytic kinematics; or
    why there is none."""
    linkage = case.linkage
    assert case.simulation is not None
    rates = case.simulation.rates
    joints = independent_joints(linkage, tuple(rates))
    own = {d.joint: d for d in linkage.drivers}
    held = replace(linkage, drivers=tuple(Driver(j, own[j].value if j in own else 0.0)
                                          for j in joints))
    velocities = [own[j].velocity if j in own else rates.get(j, 0.0) for j in joints]
    pose = solve_pose(held, [d.value for d in held.drivers], velocities, np.zeros(len(joints)))
    if not np.all(np.isfinite(pose.q)):
        return "the linkage does not assemble with its drivers at their values"
    return Start(pose.q[0], pose.qdot[0])


# -- the model ------------------------------------------------------------------------------

def turning_links(linkage: Linkage, q: Array) -> set[str]:
    """The moving links whose angle the joints let change at coordinates q (a link joined
    to the ground by a prismatic joint cannot turn)."""
    free = null_space(_scaled_joints(linkage, q))
    turning = np.abs(free[2::3]).max(axis=1, initial=0.0) > TURNS_RTOL
    return {link for link, turns in zip(linkage.moving_links, turning, strict=True) if turns}


#: A body's mass (kg), moment about its centre of mass (kg·m²) and centre of mass (drawn).
Inertia = tuple[float, float, tuple[float, float]]


def free_inertia(linkage: Linkage, q: Array) -> list[Inertia] | str:
    """Each moving link's real mass, moment about its centre of mass and centre of mass
    (coordinates q: the start); or why pymunk cannot have them: a link without mass, or one
    that turns without a moment (a point mass: pymunk needs a positive moment, and any it
    got would change the motion). A link that cannot turn gets a bar's moment (m·r²/3): it
    never acts."""
    out = []
    for link in linkage.moving_links:
        real = real_inertial(linkage, link)
        if real is None:
            return (f"link {link} has no mass: pymunk integrates bodies of positive mass, and "
                    "one given to it would change the motion; give the link its mass")
        moment = real.inertia
        if moment <= 0.0:
            if link in turning_links(linkage, q):
                return (f"link {link} turns but has no moment of inertia: pymunk needs a "
                        "positive moment, and one given to it would change the motion; give "
                        "the link its inertia")
            moment = real.mass * gyration_radius(linkage, link) ** 2 / 3.0
        out.append((real.mass, moment, real.com))
    return out


def free_bodies(linkage: Linkage, inertia: list[Inertia]) -> dict[str, pymunk.Body]:
    """One body per moving link, of ``inertia`` (:func:`free_inertia`)."""
    bodies = {}
    for link, (mass, moment, com) in zip(linkage.moving_links, inertia, strict=True):
        bodies[link] = pymunk.Body(mass, moment)
        bodies[link].center_of_gravity = com
    return bodies


def free_model(case: Case, start: Start, bodies: dict[str, pymunk.Body], rung: Rung
               ) -> LinkageModel:
    """The model of a free run: only the drivers without an effort hold their joints (their
    locks correct their error completely, as a driven run's), every other constraint at
    pymunk's default error correction; placed on ``start``."""
    linkage = case.linkage
    prescribed = replace(linkage, drivers=tuple(d for d in linkage.drivers if d.effort is None))
    _, error_bias = pymunk_defaults()
    settings = SolverSettings(dt=rung.dt, iterations=rung.iterations, error_bias=error_bias,
                              damping=1.0)
    model = build_linkage_model(case.with_(geometry=prescribed), settings, start.q,
                                bodies=bodies)
    for lock in (*model.drives.values(), *model.held.values()):
        lock.error_bias = 0.0
    set_velocities(model, start.qdot)
    return model


def install_free_loads(model: LinkageModel, friction: JointLoads, efforts: JointLoads) -> None:
    """Weights through the space's gravity (each body's centre of gravity is its link's
    centre of mass, and its mass the real one); each body with a point load, a frictional
    joint or an effort driver's joint applies them inside its velocity integration, at the
    pose of the step, the friction and efforts (by joint, on ``links[1]``) as read when the
    step runs: an effort is applied as a joint's friction is
    (:func:`.linkage_friction.apply_joint_friction`). The other bodies run no Python."""
    linkage = model.linkage
    model.space.gravity = linkage.gravity
    acting = {j.name for j in linkage.joints if j.name in efforts or _rubs(linkage, j.name)}
    for link, body in model.bodies.items():
        loads = [ld for ld in linkage.loads if ld.link == link]
        if not loads and not any(link in linkage.joint(j).links for j in acting):
            continue

        def velocity(b: pymunk.Body, gravity: tuple[float, float], damping: float, dt: float,
                     link: str = link, loads: Sequence[LoadLike] = loads) -> None:
            if loads:
                apply_forces(loads, (), (0.0, 0.0), {link: b})
            for joint_loads in (friction, efforts):
                if joint_loads:   # this runs for the body at every step
                    apply_joint_friction(model, link, b, joint_loads)
            pymunk.Body.update_velocity(b, gravity, damping, dt)

        body.velocity_func = velocity


def _rubs(linkage: Linkage, joint: str) -> bool:
    """The joint has friction (Coulomb or viscous)."""
    f = linkage.friction
    if f is None:
        return False
    j = linkage.joint(joint)
    return j.kind.coulomb_coefficient(f, j) > 0.0 or f.viscous.get(joint, 0.0) > 0.0


# -- the runs -------------------------------------------------------------------------------

def simulate(case: Case) -> tuple[Trajectory, ...]:
    """The ``pymunk`` backend's runs of a trajectory case, one per rung of :func:`ladder`
    (the last the finest); one ``not_applicable`` run where pymunk cannot run it."""
    assert case.simulation is not None, "a trajectory case has a [case.simulate] table"
    start = start_state(case)
    if isinstance(start, str):
        return (refused(case, start),)
    inertia = free_inertia(case.linkage, start.q)
    if isinstance(inertia, str):
        return (refused(case, inertia),)
    rungs = ladder(case)
    if not rungs:
        iterations, _ = pymunk_defaults()
        why = affordable(case, Rung(time_steps(case.simulation)[0], iterations))
        return (refused(case, f"{why}: a shorter end would fit"),)
    return tuple(run(case, start, inertia, rung) for rung in rungs)


def refused(case: Case, why: str) -> Trajectory:
    """A run that did not happen: ``not_applicable`` with the reason."""
    assert case.simulation is not None
    times = np.array(case.simulation.outputs)
    return Trajectory(BACKEND, times, np.full((times.size, 3 * len(case.linkage.moving_links)),
                                              np.nan),
                      status="not_applicable", message=f"pymunk: {why}")


def run(case: Case, start: Start, inertia: list[Inertia], rung: Rung) -> Trajectory:
    """One free run at ``rung``'s settings from ``start``, its links of ``inertia``
    (:func:`free_inertia`), read at every output time."""
    assert case.simulation is not None
    began = time.perf_counter()
    linkage = case.linkage
    model = free_model(case, start, free_bodies(linkage, inertia), rung)
    times = step_times(case.simulation, rung.dt)
    rows, status, message = integrate(model, case.linkage.efforts, times,
                                      case.simulation.outputs)
    q = np.array(rows)
    error_bias = model.settings.error_bias
    settings = {"dt": largest_step(case.simulation, rung.dt), "iterations": rung.iterations,
                "error_bias": error_bias, "integrator": "semi-implicit Euler"}
    gaps = loop_violations(linkage, q[np.all(np.isfinite(q), axis=1)])
    return Trajectory(BACKEND, np.array(case.simulation.outputs), q, status=status,
                      message=message, settings=settings, default=rung.default,
                      wall_time=time.perf_counter() - began, steps=times.size - 1,
                      diagnostics={"closure_gap_m": float(gaps.max(initial=0.0)),
                                   "error_correction_time_s": correction_time(error_bias)})


def correction_time(error_bias: float) -> float:
    """s, the time constant over which pymunk's error correction removes a joint's error
    (it leaves ``error_bias`` of it after a second: e^(−t/τ)): the drift of a step is left
    to pile up over about this long, whatever the step, so a joint's gap is about its drift
    rate × τ (docs/backends.md, "Trajectories in pymunk")."""
    if error_bias <= 0.0:
        return 0.0
    return -1.0 / math.log(error_bias) if error_bias < 1.0 else math.inf


def integrate(model: LinkageModel, drivers: Sequence[Driver], times: Array,
              outputs: Sequence[float]) -> tuple[list[Array], Status, str]:
    """Step the model through ``times`` (each step's end, from 0) under the efforts of
    ``drivers``, reading its coordinates at every output time; the rows (NaN from where it
    diverged), its status and message."""
    linkage = model.linkage
    effort_of = {d.joint: d.effort for d in drivers if d.effort is not None}
    friction: JointLoads = {}
    efforts: JointLoads = dict.fromkeys(effort_of, 0.0)
    install_free_loads(model, friction, efforts)
    twins = Twins([model], friction, viscous=True)
    # Each effort at every step's end time (the pose its velocity integration is at).
    pushes = {joint: effort.at(times).tolist() for joint, effort in effort_of.items()}
    # A lock's target is where the step after the one running must land (t_{n+2}).
    ahead = np.append(times, 2.0 * times[-1] - times[-2] if times.size > 1 else times[-1])
    locks, _, _ = prescribed_motion(model.case).at(ahead)
    wanted = iter(outputs)
    due = next(wanted)
    rows: list[Array] = []
    history: list[Values] = []
    n = 0
    try:
        while len(rows) < len(outputs):
            while due <= times[n] * (1.0 + 1e-12) and len(rows) < len(outputs):
                rows.append(coordinates(model))
                due = next(wanted, math.inf)
                if not np.all(np.isfinite(rows[-1])):
                    raise Diverged("a body's position became non-finite")
            if len(rows) == len(outputs):
                break
            dt = float(times[n + 1] - times[n])
            if abs(dt - model.readout.dt) > 1e-9 * dt:   # a reading is an impulse over its step
                model.readout = replace(model.readout, dt=dt)
            drive_to(model, locks[n + 2])
            for joint, values in pushes.items():
                efforts[joint] = values[n + 1]
            step_once(twins, history, dt)
            n += 1
    except Diverged as lost:
        shape = 3 * len(linkage.moving_links)
        rows = rows[:-1] if rows and not np.all(np.isfinite(rows[-1])) else rows
        rows += [np.full(shape, np.nan)] * (len(outputs) - len(rows))
        return rows, "not_settled", (f"pymunk: the run had diverged by t = {times[n]:.6g} s ({lost}); "
                                     "a smaller step or more iterations may hold it")
    return rows, "ok", ""
