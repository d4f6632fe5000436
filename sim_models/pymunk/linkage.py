"""The ``pymunk`` and ``pymunk_solve`` backends for any linkage (``mechanism = "linkage"``).

- :func:`settle` (``pymunk``): statics by simulation. Drivers are held by their
  locks (:mod:`mechcheck.sim_models.pymunk.linkage_model`), loads and weights are
  applied every step, velocities are damped, and the space is stepped with a
  constant dt until it is at rest and its forces stop changing — the stop rules
  and the ``not_settled`` verdict of :mod:`mechcheck.sim_models.pymunk.settle`.
  With every coordinate driven the run starts on the analytic pose (a seed);
  free coordinates start from the drawn pose, never from the equilibrium, and
  settle to it under the loads.
- :func:`solve_at_pose` (``pymunk_solve``): the bodies are put back on the
  analytic pose before every step, so pymunk's warm-started Gauss–Seidel solver
  converges on that one constraint problem (:mod:`mechcheck.sim_models.pymunk.solve`).

Every force is read from pymunk's own state: pivots', grooves' and gears'
accumulated impulses (:mod:`mechcheck.sim_models.pymunk.forces`), springs' signed
impulses, each / dt. The pose verdicts (``no_solution``, ``singular``,
``indeterminate``) are the analytic backends' (:func:`mechcheck.analytic.linkage_backends.verdict`),
decided on the pose alone, and withhold the simulation. Moving cases and Coulomb
friction are driven (:mod:`.linkage_dynamics`); here they are ``not_applicable``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from math import hypot
from operator import add, mul

import numpy as np

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage import Linkage
from mechcheck.analytic.linkage_backends import analytic_results, quantity_units
from mechcheck.analytic.linkage_forces import LinkageResults, pose_quantities
from mechcheck.analytic.linkage_kinematics import (
    Array,
    LinkagePose,
    constraint_system,
    positions,
    unit_scales,
)
from mechcheck.analytic.solution import FORCE_FLOOR_N, Solution
from mechcheck.sim_models.diagnostics import RunDiagnostics
from mechcheck.sim_models.linkage_motion import has_free_coordinates, is_driven, strain_verdict
from mechcheck.sim_models.pymunk import _fast
from mechcheck.sim_models.pymunk.joint_kinds import axis_now as axis_now
from mechcheck.sim_models.pymunk.linkage_model import (
    LinkageModel,
    build_linkage_model,
    coordinates,
    place,
    stage,
)
from mechcheck.sim_models.pymunk.members import member_settings, modelled
from mechcheck.sim_models.pymunk.settings import (
    LINKAGE_SETTLE,
    LINKAGE_SOLVE,
    PROBE_STEPS,
    SOFT_CONTRACTION,
    SolverSettings,
    near_change_point,
)
from mechcheck.sim_models.pymunk.settle import Reading, Run, run_until_settled, slow_window, stop_rule
from mechcheck.sim_models.pymunk.slow_mode import SlowMode

#: A held linkage that comes to rest farther than this × its size from the pose it was
#: held at has left that assembly (it settles within ~1e-12 of it otherwise).
ASSEMBLY_DRIFT = 1.0e-6
#: A held linkage's forces are those of the pose it came to rest in; read at the held pose
#: they are off by at most about condition number × drift / size (relative: the condition
#: number bounds the solution's sensitivity to the pose, to first order). A reading whose
#: bound exceeds the 1e-6 static target is withheld. Measured on seed E1 near its change
#: point before its slow mode was extrapolated (:mod:`.slow_mode`): 0.135° from it
#: (condition number 3.2e3) at rest 3.1e-10 m off the held pose after 62 000 steps, bound
#: 4.6e-6, forces 1.5e-6 off (withheld); 0.33° from it, bound 1.7e-7, forces 6.5e-8 off
#: (kept). With it, 0.135° from it rests 3e-16 m off in 22 steps.
DRIFT_EFFECT = 1.0e-6


# -- reading the model ------------------------------------------------------------------

def pose_table(linkage: Linkage, q: Array) -> dict[str, Array]:
    """x_, y_, phi_ and q_ of simulated poses q (M, 3n), as the analytic backends compute
    them (:func:`mechcheck.analytic.linkage_forces.pose_quantities`)."""
    zeros = np.zeros_like(q)
    pose = LinkagePose(linkage, np.zeros((q.shape[0], len(linkage.drivers))), q, zeros, zeros,
                       np.full(q.shape[0], np.nan))
    return pose_quantities(pose)


def loop_violations(linkage: Linkage, q: Array) -> Array:
    """Largest violation of any joint (loop closure) per pose q (M, 3n), m: pin gaps,
    distances off a slide, and a slide's angle error × the linkage's size."""
    phi, _ = constraint_system(linkage, q, np.zeros((q.shape[0], len(linkage.drivers))),
                               drivers=False)
    weights, _ = unit_scales(linkage, drivers=False)   # angle rows as lengths
    return np.asarray(np.abs(phi * weights).max(axis=1, initial=0.0), dtype=float)


def pose_drifts(radius: Array, q: Array, reference: Array) -> Array:
    """Per pose, the largest distance of a body's origin from the analytic pose, plus
    angle × the body's radius (m); q, reference (M, 3n), radius (n,)."""
    d = (q - np.nan_to_num(reference)).reshape(q.shape[0], -1, 3)
    return np.asarray((np.hypot(d[..., 0], d[..., 1]) + np.abs(d[..., 2]) * radius)
                      .max(axis=1, initial=0.0), dtype=float)


# -- the runs ---------------------------------------------------------------------------

def rounding_floor(model: LinkageModel) -> float:
    """The force scale below which a settling run's force changes are rounding noise (N).

    Pymunk's error correction turns a position rounding of ε·L into a force of up to
    about m·ε·L/dt² (fictitious mass m; measured 1.4e-12 N on an unloaded 0.2 m
    four-bar, estimate 4.4e-12 N). Against a smaller scale that noise alone would exceed
    ``settle_force_change`` and an unloaded linkage would never count as settled.
    """
    s = model.settings
    noise = s.fictitious_mass * float(np.finfo(float).eps) * model.scale / s.dt**2
    return max(FORCE_FLOOR_N, noise / s.settle_force_change)


def damped_and_loaded(model: LinkageModel) -> Callable[[Sequence[float]], list[float]]:
    """From the bodies' state (:meth:`~._fast.bulk.Bodies.read_flat`), what the next step starts
    from, body after body (:meth:`~._fast.bulk.Bodies.advance`): the velocities × damping^dt
    (:func:`~.linkage_model.damp`) and the loads' force and torque at the bodies' angles
    (:func:`~.linkage_model.apply_loads`, :class:`~.loads.LoadTerms`).

    Plain Python on lists: with a handful of bodies, numpy's per-call overhead costs more
    than the arithmetic."""
    s, loads = model.settings, model.loads
    damp = (s.damping ** s.dt).__mul__
    blank = [0.0] * (6 * len(model.bodies))  # vx, vy, ω, fx, fy, torque per body
    blank[3::6], blank[4::6] = loads.forces[0::2], loads.forces[1::2]
    torques = loads.torques

    def prepare(state: Sequence[float]) -> list[float]:
        push = blank.copy()
        push[0::6], push[1::6], push[2::6] = map(damp, state[3::6]), map(damp, state[4::6]), \
            map(damp, state[5::6])
        push[5::6] = torques(state[2::6])
        return push

    return prepare


def residual_velocity(radii: list[float], state: Sequence[float]) -> float:
    """The largest point speed |v| + |ω|·(radius) of any body in a state
    (:meth:`~._fast.bulk.Bodies.read_flat`), m/s."""
    return max(map(add, map(hypot, state[3::6], state[4::6]), map(mul, map(abs, state[5::6]), radii)))


def settle_run(model: LinkageModel, contraction: float = 0.0) -> Run:
    """Step the damped, loaded model until it is at rest and its forces stop changing.

    The bodies are read and written in bulk (:mod:`._fast.bulk`), and each step reads only what
    the stop rule needs: the impulses, and the residual velocity when the rule asks.
    ``contraction``: the slowest mode's shrinking per step, measured by the constraint
    solve that primed the run (:class:`~.slow_mode.SlowMode`), which adds a window to the
    stop rule (:func:`~.settle.slow_window`). Without a window the run is compiled where
    numba is installed (:mod:`._fast.compiled`: the same steps and readings).
    """
    if slow_window(contraction) == 0 and _fast.available():
        return compiled_run(model, rounding_floor(model))
    return python_settle_run(model, contraction)


def compiled_run(model: LinkageModel, floor: float, reposed: bool = False) -> Run:
    """The compiled loop's run (:func:`._fast.run`) with the force floor ``floor`` (N):
    damped and loaded steps, or the constraint solve's (``reposed``) once the bodies are
    staged and re-posed."""
    steps, settled, speed, change = _fast.run(model, stop_rule(model.settings, model.scale, floor),
                                              reposed)
    return Run(model.readout.values(), steps, settled, speed, change)


def python_settle_run(model: LinkageModel, contraction: float = 0.0) -> Run:
    """:func:`settle_run` stepped from Python (with or without a slow window)."""
    s, bodies, impulses = model.settings, model.bulk, model.readout.impulses
    prepare, radii, dt = damped_and_loaded(model), model.radii.tolist(), s.dt
    state = bodies.read_flat()

    def step() -> Reading:
        nonlocal state
        state = now = bodies.advance(prepare(state), dt)
        return impulses(), lambda: residual_velocity(radii, now)

    slowest = (lambda: contraction) if contraction > 0.0 else None
    run = run_until_settled(step, s, model.scale, model.readout.values, rounding_floor(model),
                            slowest)
    bodies.verify()
    return run


def primed_settle_run(model: LinkageModel, seed: Array,
                      soft: bool = False) -> tuple[LinkageModel, Run]:
    """Settle, after pymunk's own constraint solve at the seed has warmed its impulses;
    next to a change point with the settings that needs (:func:`~.settings.near_change_point`),
    in a model built anew with them. (The model that ran, and how the run ended.)

    From zero impulses the first steps' Gauss–Seidel leaves part of the load unresolved,
    and the bodies move by about (unresolved force)·dt²/m before the solver catches up.
    Next to a lock, where a second assembly of the held linkage lies millimetres away,
    that start-up jolt carried the Watt six-bar onto the other assembly (held 0.06° before
    its lock at 108.06°: 8 mm away, reactions reversed). The priming steps re-pose the
    bodies on the seed, exactly like the sweep's continuation from a neighbouring pose;
    the settling that follows is free to move them, and its stop rules decide.

    The first :data:`~.settings.PROBE_STEPS` of the priming look for a slow mode
    (:class:`~.slow_mode.SlowMode`); one slower than :data:`~.settings.SOFT_CONTRACTION`
    marks a pose next to a change point. The priming extrapolates the slow mode, and its
    measured contraction adds a window to the stop rules of the priming and of the
    settling (:func:`~.settle.slow_window`). ``soft``: with those settings whatever the
    probe finds (the second rung of :func:`settle`'s ladder).
    """
    slow, probed = probe(model, seed)
    if soft or slow.contraction > SOFT_CONTRACTION:
        model, slow, priming = soft_priming(model, seed)
    else:
        priming = solve_run(model, seed, slow)
    run = settle_run(model, slow.contraction)
    return model, Run(run.values, probed + priming.steps + run.steps, run.settled,
                      run.residual_velocity, run.force_change)


def soft_priming(model: LinkageModel, seed: Array) -> tuple[LinkageModel, SlowMode, Run]:
    """The priming next to a change point: a model built anew with
    :func:`~.settings.near_change_point`'s settings, its constraint solve at the seed
    without joint-error correction (:func:`hold_without_correction`: the correction of
    Newton's 1e-13·L gaps is a force ∝ the mass, measured on seed E1 0.05° from its change
    point 6e-11 of the reactions at 1 000 kg, 8e-10 at 1e4 kg, 9e-9 at 1e5 kg), which the
    settling then has back. (The model, its slow mode, the run.)"""
    model = build_linkage_model(model.case, near_change_point(model.settings), seed)
    slow = SlowMode(model.readout)
    hold_without_correction(model)
    priming = solve_run(model, seed, slow)
    set_correction(model, math.inf)
    return model, slow, priming


def probe(model: LinkageModel, seed: Array) -> tuple[SlowMode, int]:
    """Re-posed steps at the seed, under the loads, until a slow mode is measured or
    :data:`~.settings.PROBE_STEPS` have passed: (the watch, the steps taken)."""
    stage(model, seed, loaded=True)
    slow = SlowMode(model.readout)
    for n in range(1, PROBE_STEPS + 1):
        reposed_step(model, slow)
        if slow.contraction > 0.0:
            return slow, n
    return slow, PROBE_STEPS


def hold_without_correction(model: LinkageModel) -> None:
    """No joint-error correction in the constraint solve (``max_bias = 0``).

    The bodies are put back on the analytic pose before every step, so there is no drift
    to correct; but that pose closes the loops only to Newton's 1e-13·L, and correcting
    such a gap takes a force of about m·gap·(1 − error_bias^dt)/dt² (up to 2e-8 of the
    reactions measured on random slider-cranks). Without the bias, each step solves the
    rigid velocity constraints of that pose: statics.
    """
    set_correction(model, 0.0)


def set_correction(model: LinkageModel, max_bias: float) -> None:
    """Every constraint's ``max_bias``: 0 for none, ``math.inf`` (pymunk's default) for the
    full correction its ``error_bias`` asks."""
    for constraint in model.constraints():
        constraint.max_bias = max_bias


def reposed_step(model: LinkageModel, slow: SlowMode | None = None) -> None:
    """One step of the constraint solve: the bodies back on the staged pose, a step, and
    the slow mode watched (if ``slow``)."""
    model.bulk.repose()
    model.space.step(model.settings.dt)
    if slow is not None:
        slow.observe()


def at_rest() -> float:
    """The residual velocity of a re-posed step: none."""
    return 0.0


def solve_run(model: LinkageModel, q: Array, slow: SlowMode | None = None) -> Run:
    """Re-pose at q, with the loads there, and step until the impulses stop changing;
    ``slow``: watch the slow mode and extrapolate it (:class:`~.slow_mode.SlowMode`), its
    measured contraction adding a window to the stop rule. Without it the run is compiled
    where numba is installed (:func:`compiled_run`: the same steps and readings)."""
    stage(model, q, loaded=True)
    if slow is None and _fast.available():
        model.bulk.repose()
        run = compiled_run(model, FORCE_FLOOR_N, reposed=True)
    else:
        def step() -> Reading:
            reposed_step(model, slow)
            return model.readout.impulses(), at_rest

        run = run_until_settled(step, model.settings, model.scale, model.readout.values,
                                slowest=(lambda: slow.contraction) if slow is not None else None)
    place(model, q)  # report the pose the forces belong to
    return run


@dataclass(frozen=True)
class Outcome:
    """What one run left behind: how it ended, the bodies' coordinates (3n,), its wall
    time, and the pose of the analytic results it belongs to."""

    run: Run
    q: Array
    elapsed: float
    index: int = 0


def not_settled(case: str, backend: str, pose: dict[str, float], diag: dict[str, float | str],
                units: dict[str, str] | None = None,
                rule: tuple[float, float] | None = None) -> Solution:
    """``not_settled`` for any model: the pose it reached, its diagnostics, no forces; the
    message says which stop rule did not hold against its bound (``rule``: the residual
    velocity's, m/s, and the force change's) and the setting that governs it."""
    speed, change = float(diag["residual_velocity"]), float(diag["force_change"])
    if rule is None:
        held = f"residual velocity {speed:.3g} m/s, force change {change:.3g}"
    else:
        failing = [f"residual velocity {speed:.3g} m/s (rule: ≤ {rule[0]:.3g}, settle_speed "
                   "× size)"] if not speed <= rule[0] else []
        failing += [f"force change {change:.3g} of the forces a step (rule: ≤ {rule[1]:.0e}, "
                    "settle_force_change)"] if not change <= rule[1] else []
        held = "; ".join(failing) or (f"residual velocity {speed:.3g} m/s and force change "
                                      f"{change:.3g} within the rules, but not for "
                                      "settle_patience steps in a row")
    return Solution(case, backend, pose, status="not_settled",
                    message=f"did not settle within {diag['steps']} steps ({held}); governed "
                            "by the step budget max_steps of mechcheck.sim_models.pymunk."
                            f"settings (dt {diag.get('dt', '?')} s, {diag.get('iterations', '?')} "
                            "iterations a step)",
                    diagnostics=diag, units=units or {})


def outcome(model: LinkageModel, run: Run, start: float, index: int = 0) -> Outcome:
    return Outcome(run, coordinates(model), time.perf_counter() - start, index)


def solutions(model: LinkageModel, backend: str, method: str, outcomes: list[Outcome],
              results: LinkageResults, drivers: Array | None = None) -> list[Solution]:
    """The Solutions of finished runs, with the pymunk diagnostics (the four-bar's keys)
    and the linkage's dof and condition: forces only where the run settled, and (held
    linkages) stayed on the assembly it was held at. ``drivers``: a sweep's first driver
    per pose of ``results``, recorded as the diagnostic ``driver``.

    The pose quantities, loop closures and drifts of all runs are computed at once.
    """
    linkage = model.linkage
    dof, gruebler = linkage.dof, linkage.gruebler
    units = quantity_units(linkage)
    if not outcomes:
        return []
    q = np.array([o.q for o in outcomes])
    at = [o.index for o in outcomes]
    poses = pose_table(linkage, q)
    gaps = loop_violations(linkage, q)
    drifts = pose_drifts(model.radii, q, results.pose.q[at])
    # A structure of elastic members rests where its members' stretch puts it: that
    # deflection (about max_strain × its size) is its own, not a drift off the held pose.
    held = not (has_free_coordinates(model.case) or model.members)
    pose_lists = {k: v.tolist() for k, v in poses.items()}
    out = []
    for m, o in enumerate(outcomes):
        diag = RunDiagnostics(
            method, o.run.steps, o.elapsed, o.run.residual_velocity, float(gaps[m]),
            float(drifts[m]),
        ).as_dict(force_change=o.run.force_change, dt=model.settings.dt,
                  iterations=model.settings.iterations,
                  condition_number=float(results.condition[o.index]), dof=dof,
                  gruebler=gruebler)
        if drivers is not None:
            diag["driver"] = float(drivers[o.index])
        pose = {k: v[m] for k, v in pose_lists.items()}
        if not o.run.settled:
            s = model.settings
            out.append(not_settled(model.case.name, backend, pose, diag, units,
                                   (s.settle_speed * model.scale, s.settle_force_change)))
        elif held and drifts[m] > ASSEMBLY_DRIFT * model.scale:
            out.append(Solution(
                model.case.name, backend, pose, status="not_settled", diagnostics=diag, units=units,
                message=f"came to rest {drifts[m]:.3g} m away from the held assembly (rule: "
                        f"≤ {ASSEMBLY_DRIFT * model.scale:.3g} m, ASSEMBLY_DRIFT × size; another "
                        "assembly is that close, and the load made the joints' soft correction "
                        f"give way to it, with {model.settings.iterations} iterations a step "
                        "and the fictitious mass fictitious_mass of mechcheck.sim_models."
                        "pymunk.settings); forces withheld"))
        elif held and (effect := drift_effect(float(results.condition[o.index]), float(drifts[m]),
                                              model.scale)) > DRIFT_EFFECT:
            out.append(Solution(
                model.case.name, backend, pose, status="not_settled", diagnostics=diag, units=units,
                message=f"came to rest {drifts[m]:.3g} m from the held pose, which at condition "
                        f"number {float(results.condition[o.index]):.3g} moves the forces by about "
                        f"{effect:.1e} of their size (more than {DRIFT_EFFECT:.0e}); forces "
                        "withheld"))
        else:
            out.append(Solution(model.case.name, backend, pose | o.run.values, diagnostics=diag,
                                units=units))
    return out


def drift_effect(condition: float, drift: float, scale: float) -> float:
    """The forces' relative change, to first order, from reading them ``drift`` (m) away from
    the held pose of a linkage of size ``scale`` at ``condition`` (:data:`DRIFT_EFFECT`)."""
    return condition * drift / scale


def refusal(case: Case, backend: str) -> Solution | None:
    """``not_applicable`` for a case the held model cannot give (it moves, or it is static
    with Coulomb friction, a quasi-static motion), else None. The ``pymunk`` backend drives
    such a case (:mod:`.linkage_dynamics`); the fixed-pose solve does not."""
    if not is_driven(case):
        return None
    why = ("the constraint solve at a fixed pose is for statics; a moving linkage or Coulomb "
           "friction needs velocities (the 'pymunk' backend drives the case)"
           if backend == "pymunk_solve" else
           "the held model is for statics; a moving linkage or Coulomb friction is driven "
           "(mechcheck.sim_models.pymunk.linkage_dynamics.drive_linkage)")
    return Solution(case.name, backend, {}, status="not_applicable",
                    units=quantity_units(case.linkage), message=f"a {case.kind} linkage case: {why}")


def screened(case: Case, backend: str) -> Solution | LinkageResults:
    """The refusal, else the analytic results of the case's pose (its held pose, and the
    reference for the pose drift)."""
    refused = refusal(case, backend)
    return refused if refused is not None else analytic_results(case)


def free_start(case: Case, drivers: Array | None = None) -> Array:
    """Where free coordinates start: the drawn pose, the drivers brought to their values
    (default: the case's) with the free coordinates carried along (never the equilibrium)."""
    linkage = case.linkage
    values = np.array([[d.value for d in linkage.drivers]]) if drivers is None else drivers
    q, _ = positions(linkage, np.atleast_2d(values))
    return np.asarray(q[0], dtype=float)


def unstable(case: Case, backend: str, results: LinkageResults, index: int = 0) -> Solution | None:
    """``not_applicable`` where the free coordinates' equilibrium is unstable: a damped
    simulation moves away from it, so settling cannot measure it."""
    if results.stable is None or results.stable[index] != 0.0:
        return None
    return Solution(case.name, backend, {}, status="not_applicable",
                    units=quantity_units(case.linkage),
                    message="the equilibrium of the free coordinates reached from the drawn pose "
                            "is unstable: a damped simulation settles elsewhere or not at all")


def settle(case: Case, settings: SolverSettings = LINKAGE_SETTLE,
           seed: Array | None = None) -> Solution:
    """The ``pymunk`` backend for a linkage: statics settled by simulation.

    The run starts at ``seed`` (coordinates (3n,)) if given — e.g. other starting poses
    of free coordinates —, else on the analytic pose when every coordinate is driven,
    else from the drawn pose (:func:`free_start`).
    """
    backend = "pymunk"
    start = time.perf_counter()
    results = screened(case, backend)
    if isinstance(results, Solution):
        return results
    if has_free_coordinates(case):
        refused = unstable(case, backend, results)
        if refused is not None:
            return refused
        seed = free_start(case) if seed is None else seed
    elif seed is None:
        seed = results.pose.q[0]
    stretches = modelled(case.linkage)
    if stretches:   # the step its stiffest member needs
        settings = member_settings(case.linkage, settings)
    model = build_linkage_model(case, settings, seed)
    if has_free_coordinates(case) or stretches:
        # No priming: re-posed on the unstretched seed, the members would carry nothing.
        run = settle_run(model)
    else:
        built = model
        model, run = primed_settle_run(built, seed)
        solution = solutions(model, backend, "settle", [outcome(model, run, start)], results)[0]
        if solution.status == "not_settled" and model is built:
            # The ladder's second rung: the settings next to a change point (16× the
            # Gauss–Seidel iterations, 10× the fictitious mass). With the first, the scissor
            # lift's 200 kg platform, 0.265 m up its stroke (condition number 150), swung
            # onto its other assembly; with these it rests on its own in 24 steps.
            model, run = primed_settle_run(build_linkage_model(case, settings, seed), seed,
                                           soft=True)
    solution = solutions(model, backend, "settle", [outcome(model, run, start)], results)[0]
    return strain_verdict(case.linkage.elastic_links if stretches else (), solution, "pymunk")


def solve_at_pose(case: Case, settings: SolverSettings = LINKAGE_SOLVE) -> Solution:
    """The ``pymunk_solve`` backend for a linkage: constraint forces at the analytic pose."""
    backend = "pymunk_solve"
    start = time.perf_counter()
    results = screened(case, backend)
    if isinstance(results, Solution):
        return results
    q = results.pose.q[0]
    model = build_linkage_model(case, settings, q)
    hold_without_correction(model)
    run = solve_run(model, q)
    return solutions(model, backend, "constraint_solve", [outcome(model, run, start)], results)[0]
