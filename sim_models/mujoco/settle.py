"""The ``mujoco`` backend for statics: hold the mechanism and let it settle.

Each driver is held by a joint equality at its value; the loads are re-applied at the current pose
every step; the model is stepped until it has SETTLED — its joints at rest and
its forces no longer changing — never for a fixed number of steps.
Settling damps itself: with the drivers held the mechanism has no
freedom left, and the only motion is the relaxation of the soft constraints —
critically damped (dampratio 1) at ordinary poses, a lightly damped slow mode
next to a change point (:func:`run_until_settled`, stop rule
:class:`DecayWatch`). The forces never come to rest exactly: they sit on a
floor set by the rounding of the positions, ~1e-8 of their size next to a
change point (:data:`WOBBLE_RTOL`), which the stop rule must accept as settled
without mistaking a slow oscillation's turning point for it.

A settled soft model is bent: each constraint holds its force with a small
violation. Next to a change point that bending costs far more than the 1e-6
static target (2e-5 at θ12 = 179° of seed E1, condition number 119; the error
grows as the cube of the condition number, and it is the settled state itself,
not an early stop: 4000 more steps leave it unchanged). So the backend settles
in passes (:func:`settle_refined`): the constraint forces of each settled state
are carried as explicit loads and the mechanism, re-seeded unbent, settles
again, holding in its constraints only what is left (:mod:`.rig`). Every
number is still MuJoCo's: carried forces are its own earlier constraint forces.
Next to a change point each pass removes only a fraction of what is left, and the
passes, measuring that fraction themselves, carry their forces extrapolated
(:class:`Refinement`): seed E1 settles within the static target up to condition number
10 300 (it stopped at ~5300 before).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Protocol

import mujoco
import numpy as np

from mechcheck.analytic.case import Case
from mechcheck.analytic.solution import FORCE_FLOOR_N, Solution, quantity_kind
from mechcheck.sim_models.convergence import disagreement, force_size
from mechcheck.sim_models.diagnostics import RunDiagnostics
from mechcheck.sim_models.mujoco import _fast

#: Settled when the forces' remaining change, estimated from their observed
#: geometric decay, is below this fraction of the largest force (torques divided
#: by the mechanism's length scale). Each step's change Δ shrinks by a ratio r
#: (≈ 0.74 at ordinary poses, measured: the relaxation of the critically damped
#: soft constraints), so what is still to come is Δ·r/(1 − r). 1e-8 is 100×
#: below the 1e-6 static target. (The old rule, "Δ ≤ 1e-9", ignored r: it was
#: safe at r = 0.74 but would stop a decay with r → 1 far too early, and it
#: stopped at random on a wobble it could never get below.)
SETTLE_RTOL = 1e-8
#: Δ and r are the largest change and step ratio over the last this-many
#: changes. Next to a change point the soft constraints leave a lightly damped
#: mode (half-period 13 steps at condition number 360, 18 at 880, 36 at 2100,
#: measured), whose change dips to almost nothing for a step or two at each
#: turning point; a window of 4 bridges the dip (a two-step estimate stopped
#: there, 4e-6 off), at ~3 steps' cost per pass.
STOP_WINDOW = 4
#: The forces cannot settle below the FLOOR set by the positions' rounding. The
#: loop closure at B is computed from site positions of ~0.1 m, which move in
#: steps of an ulp (~3e-17 m), and next to a change point the loop constraint
#: holds such a step with a large force: at rest the forces hop by ~1e-8 of
#: their size every few steps and decay back, for ever (seed E1, measured:
#: ≤ 1e-10 over most of the cycle, 4e-9 at θ12 = 175°, 1e-8–3e-8 from 178°
#: on, flat up to condition number 5000; the residual joint speed is then
#: ~1e-12 m/s). The old stop rule accepted such a wobble only below 1e-8, so
#: whether a pose settled was a lottery on the floor's size and phase: 4 of 40
#: poses between condition numbers 100 and 450 of seed E1 ran out of steps, all
#: on a floor of 1–3e-8, while poses closer to the change point settled.
#: A state is now settled on the floor when the forces' spread (max − min of
#: each, relative to the largest force) over the last :data:`FLOOR_WINDOW`
#: readings is at most this: every reading in the window, the last one
#: included, is then within it of the floor's centre. 1e-7 is 3× the largest
#: floor measured and 10× below the 1e-6 static target.
WOBBLE_RTOL = 1e-7
#: The window over which the floor's spread is judged. It must span a swing of
#: the slowest mode left, or the turning point of a decaying oscillation would
#: pass for a floor (the spread over a window ending at a turning point covers
#: the whole last swing only if the window is at least a half-period long):
#: 32 covers the half-periods measured up to condition number ~1900 (see
#: :data:`STOP_WINDOW`); a pass settling on its floor thereby costs ≥ 32 steps.
FLOOR_WINDOW = 32
#: A shortcut to the floor rule for poses whose floor is far below it (most of
#: the cycle: ≤ 1e-10, so a second pass would otherwise wait 32 steps for
#: nothing): settled when each of the last :data:`STOP_WINDOW` changes is at
#: most this. Around a turning point of a mode with a half-period of H steps,
#: the changes over 4 steps are ≥ ~2·A·(π/H)² for an amplitude A, so changes
#: ≤ 1e-9 mean A ≤ 7e-8 even for H = 36 (condition number ~2000).
QUIET_RTOL = 1e-9
#: ... and no joint moves faster than this (a point speed at the scale length,
#: m/s; on the floor it is ~1e-12).
VELOCITY_TOL = 1e-9
#: At rest the forces cannot settle below what the rounding of the positions makes of them,
#: whatever the loads: every site sits on a grid of ε·X (ε the machine epsilon, X the
#: largest coordinate), and a body that hops one step of it to and fro reverses a velocity
#: of ε·X/dt each step, a force of 2·m·ε·X/dt² each way (fictitious mass m, time step dt):
#: a spread of this many m·ε·X/dt² (:func:`rounding_floor`). It is the floor rule's and the
#: passes' absolute allowance besides their relative ones. Measured on every built-in
#: linkage without loads or gravity, drawn from 0.1 to 100 times its size, and on chains of
#: two and eight four-bars, at rest (joints at 1e-13 m/s or less): the equality forces'
#: spread over :data:`FLOOR_WINDOW` readings was at most 0.74 of it, a sweep's reaction
#: sensors' 0.92 (the counterbalanced bonnet at 0.6 m, alternating by ±2.4e-7 N from step
#: to step). Seed E1 at 0.42 m: its driver's torque climbing in a sawtooth to ±5.5e-10 N
#: while MuJoCo's solver took no step (its line search stops for a step under 1e-15), a
#: sweep's sensors cycling by ±1.5e-8 N. Judged against the 0.01 N force floor alone, such a
#: floor spreads wider than :data:`WOBBLE_RTOL` from about 0.2 m up, and an unloaded linkage
#: of that size settled by chance or not at all (1e-19 m/s, ``not_settled``). Bodies hopping
#: together with more than the heaviest one's mass could spread wider: not seen.
ROUNDING_STEPS = 4.0
#: Step budget of one settling run; a pose that has not settled by then is
#: reported ``not_settled``. Ordinary poses settle in 30–60 steps; next to a
#: change point the slow mode takes longer (about 270 steps at condition number
#: 880, 1100 at 2100, 2600 at 5400; a second pass somewhat more); a later pass
#: gets more where the passes before it needed it (:data:`PASS_GROWTH`). Beyond
#: what the passes' total budget reaches, ``not_settled`` is the honest verdict.
MAX_STEPS = 3000
#: Settling passes: after each one the constraint forces are carried as loads
#: (:meth:`~.linkage_rig.LinkageRig.carry`), the pose is re-seeded unbent and the mechanism
#: settles again. A single pass is off by the soft constraints' bending — 2e-5
#: of the forces at θ12 = 179° of seed E1 (condition number 119), 8e-3 at
#: condition number 880 — and each pass shrinks that by a factor c (measured:
#: c ≤ 2e-3 up to condition number 360, 0.01 at 880, 0.1 at 2100, 0.2 at 2650,
#: 0.3 at 3400), so the passes' differences d decay geometrically too, and the
#: last pass is within d·c/(1 − c) of the rigid answer (:func:`refinement_left`).
#: Done when that, and d itself, are below this fraction of the largest force:
#: above the floor (≤ 3e-8 measured), by which two readings of the same
#: equilibrium can differ, and 10× below the 1e-6 static target. The same
#: bound covers the stop rule's weak spot, a pass stopped at a turning point of
#: the slow mode (the decay estimate takes the approach to it for a decay): such
#: a pass is off by at most its own swing, which is the bending the previous pass
#: left, ~d.
REFINE_RTOL = 1e-7
#: Enough passes for the contraction measured up to condition number ~3500
#: (ordinary poses need two, 179° three, condition number 880 four, 2100 six); nearer
#: the change point the passes are extrapolated (:class:`Refinement`) and need seven at
#: condition number 5300, ten at 9970 and fifteen at 10 300 (seed E1, measured); at
#: 10 800 the last passes still differ by 4e-8 after sixteen, where the contraction
#: measured (0.89) asks for 1.2e-8, and 32 passes would settle it, at 11 300 not even
#: those: each further pass buys less. The old limit, 8, was reached from condition
#: number ~2100 on.
MAX_PASSES = 16
#: A pass may take this many times the steps of the longest pass before it, if that is
#: more than its budget: next to a change point the carried forces soften the slow mode,
#: so each pass settles more slowly than the last (seed E1 at condition number 10⁴,
#: measured: 2500 steps for the first pass, then 4400, 7000, 8900, 9500), and a pass
#: that the passes before it show to be slow is given the time they took. It grows with
#: the simulator's own progress only, within :data:`TOTAL_BUDGET` (:meth:`Refinement.budget`).
PASS_GROWTH = 2.0
#: All passes of a pose together have this many times a pass's budget (:data:`MAX_STEPS`).
TOTAL_BUDGET = 32
#: Passes are extrapolated (:meth:`Refinement.factor`) when the contraction measured says
#: plain passes would need more than this many more: an extrapolated pass's difference
#: from the one before is no measure of convergence, so extrapolating costs at least one
#: pass, and the ordinary poses, which two to four plain passes settle, go on unchanged.
EXTRAPOLATE_AFTER = 3
#: A contraction is measured (:func:`secant_slope`) only across a carry of at least this
#: fraction of the largest force: 30× the rounding floor (≤ 3e-8, :data:`WOBBLE_RTOL`),
#: so the floor moves the measured contraction by at most ~0.03; a carry at the floor
#: itself would measure only the floor.
MEASURABLE_CARRY = 1e-6
#: Where no secant is measured (the carries too small, or it read no contraction), plain
#: passes that contract steadily are extrapolated by the ratio of their differences
#: (Aitken's Δ²): steadily means three plain passes in a row whose two ratios agree within
#: this. Measured, seed E1 at condition number 8600 batched: a secant misread at pass 7
#: (c = 0.39 where the passes contract by 0.77) stopped its extrapolation, its later
#: carries were below MEASURABLE_CARRY, and plain passes with ratios 0.766, 0.766, 0.767
#: ran out the MAX_PASSES. As every extrapolation, it changes how many passes the
#: settling takes, never what it settles to: the last two passes must still agree.
STEADY_RATIO = 0.05
#: Once the passes have measured a contraction of at least this, none may stop before the
#: first pass's steps (:meth:`Refinement.minimum`). A pass starts at rest, at a turning
#: point of the slow mode, where the stop rules' windows (sized for half-periods up to ~36
#: steps, condition number ~2000: :data:`FLOOR_WINDOW`, :data:`QUIET_RTOL`) can take its
#: slow start for rest — measured at condition number 10⁴ (c = 0.86): a pass after an
#: extrapolated carry stopped by the floor rule after 55 steps still holding 5e-5 of the
#: forces, where the first pass took 2511. The passes contract by 0.1 at condition number
#: 2100 and by 0.3 at 3400 (:data:`REFINE_RTOL`), so the windows' measured range ends
#: about here.
SLOW_CONTRACTION = 0.3


def rounding_floor(mass: float, extent: float, timestep: float) -> float:
    """The spread (N) of forces that the rounding of the positions alone makes at rest, in a
    model whose heaviest body is ``mass`` (kg), whose sites lie within ``extent`` (m) of its
    origin, stepped by ``timestep`` (s): :data:`ROUNDING_STEPS` × m·ε·X/dt²."""
    return ROUNDING_STEPS * mass * float(np.finfo(float).eps) * extent / timestep ** 2


class SettlingRig(Protocol):
    """What settling needs of a model (:class:`~.linkage_rig.LinkageRig`)."""

    model: mujoco.MjModel
    data: mujoco.MjData
    case: Case
    scale: float
    units: dict[str, str] | None
    rounding: float  # :func:`rounding_floor`

    def apply_loads(self) -> None: ...
    def constraint_forces(self) -> np.ndarray: ...
    def joint_velocity(self) -> float: ...
    def read(self) -> dict[str, float]: ...
    def loop_violation(self) -> float: ...
    carried: np.ndarray
    efc_scale: np.ndarray

    def carry(self, factor: float = 1.0) -> None: ...
    def total_constraint_forces(self) -> np.ndarray: ...
    def set_state(self, qpos: np.ndarray, qvel: np.ndarray) -> None: ...
    def pose_drift(self, theta12: float | None = None, qpos: np.ndarray | None = None) -> float: ...


@dataclass(frozen=True)
class Settled:
    """What a settling run ended with."""

    values: dict[str, float]
    steps: int
    settled: bool
    residual_velocity: float
    loop_violation: float
    passes: int = 1
    refinement: float = float("nan")
    rule: str = ""  # the stop rule that ended the last pass (DecayWatch.rule)
    #: The reading's distance from the analytic pose, where the rig's data no longer holds
    #: it (a batch, :mod:`.batch_settle`); NaN: read it from the rig.
    pose_drift: float = float("nan")


def run_until_settled(rig: SettlingRig, max_steps: int | None = None,
                      min_steps: int = 0) -> Settled:
    """Step ``rig`` from its current state until settled or out of budget
    (``max_steps``, default :data:`MAX_STEPS`), not stopping before ``min_steps``
    (:meth:`Refinement.minimum`)."""
    max_steps = MAX_STEPS if max_steps is None else max_steps
    m, d = rig.model, rig.data
    watch = DecayWatch(rig.rounding)
    settled = False
    step = 0
    for step in range(max_steps + 1):
        mujoco.mj_kinematics(m, d)  # loads at the current positions (mj_Euler moved them)
        rig.apply_loads()
        mujoco.mj_forward(m, d)
        # The equality forces determine every reaction (the loads are known),
        # so their change is the force-change criterion; cheap to read each step.
        if (watch.settled(rig.constraint_forces()) and step >= min_steps
                and rig.joint_velocity() <= VELOCITY_TOL):
            settled = True
            break
        mujoco.mj_Euler(m, d)
    return Settled(rig.read(), step, settled, rig.joint_velocity(), rig.loop_violation(),
                   rule=watch.rule if settled else "")


#: The stop rules by their index in :func:`first_stops`'s answers.
RULES = ("decay", "quiet", "floor")


class DecayWatch:
    """The stop rules (:func:`first_stops`) on a sequence of force vectors read one at a
    time: settled when the change still to come of a decay is below :data:`SETTLE_RTOL`,
    when the last changes are all below :data:`QUIET_RTOL`, or when the forces sit on their
    rounding floor, spread over :data:`FLOOR_WINDOW` readings by at most
    :data:`WOBBLE_RTOL`, or by the model's ``rounding`` floor (N, :func:`rounding_floor`)
    where that is more. ``rule`` names the one that fired."""

    def __init__(self, rounding: float = 0.0) -> None:
        self.history: np.ndarray | None = None  # the readings before, NaN before the first
        self.rule = ""
        self.rounding = rounding

    def settled(self, current: np.ndarray) -> bool:
        """Record ``current``; True when the forces have settled."""
        reading = np.asarray(current, dtype=float).reshape(1, 1, -1)
        if self.history is None:
            self.history = np.full((1, FLOOR_WINDOW - 1, reading.shape[2]), np.nan)
        first, rule = _fast.first_stops(self.history, reading, RESTING, self.rounding)
        self.history = np.concatenate([self.history[:, 1:], reading], axis=1)
        self.rule = RULES[rule[0]] if first[0] >= 0 else ""
        return bool(first[0] >= 0)


#: The joints' speed the stop rules are told where the caller checks it itself.
RESTING = np.zeros((1, 1))


# The stop rules, written once: run as Python, or compiled as they are
# (:mod:`._fast.stop_kernel`), reading by reading. A maximum that meets a NaN is NaN, and
# every comparison with it is false, so a window reaching back past a pass's first
# reading (NaN) fires no rule.
def larger(a: float, b: float) -> float:
    """max(a, b), NaN if either is (numpy's maximum)."""
    if a != a or b != b:
        return math.nan
    return a if a >= b else b


def largest_entry(x: np.ndarray) -> float:
    """The largest |entry| of a reading, NaN if any is NaN."""
    out = 0.0
    for v in x:
        out = larger(out, abs(v))
    return out


def largest_step(new: np.ndarray, old: np.ndarray) -> float:
    """The largest |change| between two readings, NaN if any is NaN."""
    out = 0.0
    for j in range(new.size):
        out = larger(out, abs(new[j] - old[j]))
    return out


def relative_changes(recent: np.ndarray, size: np.ndarray, change: np.ndarray) -> None:
    """Each reading's size (its largest force, at least :data:`FORCE_FLOOR_N`) and its
    change from the one before relative to it, into ``size`` and ``change``."""
    for i in range(recent.shape[0]):
        size[i] = larger(largest_entry(recent[i]), FORCE_FLOOR_N)
    for i in range(recent.shape[0] - 1):
        change[i] = largest_step(recent[i + 1], recent[i]) / size[i + 1]


def window_rule(change: np.ndarray, t: int) -> tuple[int, float]:
    """Over the window of :data:`STOP_WINDOW` changes from ``change[t]`` on: the decay rule
    (0: the change Δ·r/(1 − r) still to come below :data:`SETTLE_RTOL`, Δ the largest
    change and r the largest step ratio, so that neither a dip of one step nor an
    alternation passes for a decay) or the quiet rule (1: every change below
    :data:`QUIET_RTOL`), −1 for neither; and Δ."""
    largest = change[t]
    for k in range(1, STOP_WINDOW):
        largest = larger(largest, change[t + k])
    ratio = -math.inf
    for k in range(STOP_WINDOW - 1):
        step = change[t + k + 1] / change[t + k] if change[t + k] > 0 else math.inf
        ratio = larger(ratio, step)
    left = largest * ratio / (1.0 - ratio) if ratio < 1.0 else math.inf
    if largest == 0.0 or left <= SETTLE_RTOL:
        return 0, largest
    return (1 if largest <= QUIET_RTOL else -1), largest


def step_jumps(whole: np.ndarray, jumps: np.ndarray) -> None:
    """The largest |change| from each reading of ``whole`` to the next, into ``jumps``."""
    for i in range(whole.shape[0] - 1):
        jumps[i] = largest_step(whole[i + 1], whole[i])


def widest(jumps: np.ndarray, start: int, count: int) -> float:
    """The largest of ``count`` jumps from ``start`` on."""
    out = jumps[start]
    for i in range(start + 1, start + count):
        out = larger(out, jumps[i])
    return out


def window_spread(whole: np.ndarray, start: int) -> float:
    """The largest spread (max − min) of a force over the :data:`FLOOR_WINDOW` readings
    of ``whole`` from ``start`` on."""
    spread = 0.0
    for j in range(whole.shape[1]):
        low, high = whole[start, j], whole[start, j]
        for i in range(start + 1, start + FLOOR_WINDOW):
            low = -larger(-low, -whole[i, j])
            high = larger(high, whole[i, j])
        spread = larger(spread, high - low)
    return spread


def first_stops(history: np.ndarray, readings: np.ndarray, speed: np.ndarray,
                rounding: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """For each pose of a wave, the first of its ``readings`` (P, T, m) at which a stop
    rule fires with the joints slower than :data:`VELOCITY_TOL` (``speed`` (P, T) at each
    reading): its index (−1 if none) and the rule that fired (an index into
    :data:`RULES`; the last reading's where none fires).

    ``history`` (P, FLOOR_WINDOW − 1, m) holds each pose's earlier readings of the pass,
    NaN where the pass has fewer: a window reaching back past the pass's first reading
    holds a NaN, and no rule fires on it, as no rule fires before its window is known.
    ``rounding``: the model's rounding floor (N, :func:`rounding_floor`), the floor rule's
    allowance where it is more than :data:`WOBBLE_RTOL` of a reading. The floor's spread
    is only looked at where the rest of its rule holds and no single step in its window is
    larger than the spread allowed (a spread is at least every step within it).
    """
    poses, back, m = history.shape
    chunk = readings.shape[1]
    first = np.full(poses, -1, dtype=np.int64)
    rules = np.full(poses, -1, dtype=np.int64)
    whole = np.empty((back + chunk, m))
    size = np.empty(STOP_WINDOW + chunk)
    change = np.empty(STOP_WINDOW + chunk - 1)
    jumps = np.empty(back + chunk - 1)
    for p in range(poses):
        whole[:back] = history[p]
        whole[back:] = readings[p]
        relative_changes(whole[back - STOP_WINDOW:], size, change)
        jumps_known = False
        for t in range(chunk):
            rule, largest = window_rule(change, t)
            here = size[STOP_WINDOW + t]
            wobble = larger(WOBBLE_RTOL, rounding / here)
            if rule < 0 and largest <= wobble and speed[p, t] <= VELOCITY_TOL:
                if not jumps_known:
                    step_jumps(whole, jumps)
                    jumps_known = True
                if (widest(jumps, t, back) <= wobble * here
                        and window_spread(whole, back + t + 1 - FLOOR_WINDOW) / here <= wobble):
                    rule = 2
            rules[p] = rule
            if rule >= 0 and speed[p, t] <= VELOCITY_TOL:
                first[p] = t
                break
    return first, rules


#: What :mod:`._fast.stop_kernel` compiles along with :func:`first_stops`.
STOP_RULE_HELPERS = (larger, largest_entry, largest_step, relative_changes, window_rule,
                     step_jumps, widest, window_spread)


def reseed(rig: SettlingRig, qpos: np.ndarray) -> None:
    """Back to rest in the analytic pose ``qpos``, keeping what is carried: the
    constraints restart unbent and take up only the forces not yet carried
    (else the bending of the last pass would spring back through them)."""
    rig.set_state(qpos, np.zeros_like(qpos))


def settle_refined(rig: SettlingRig, qpos: np.ndarray,
                   restart: Callable[[], None] | None = None,
                   max_steps: int | None = None) -> Settled:
    """Settle, carry the constraint forces (extrapolated where the passes converge
    slowly, :class:`Refinement`), re-seed the pose, settle again, until the passes have
    converged (:func:`refinement_left` ≤ :data:`REFINE_RTOL`) or one does not settle.

    ``restart`` replaces the re-seeding in ``qpos`` (free coordinates have no analytic
    pose to re-seed: they go on from where they settled); ``max_steps`` is a pass's
    budget (:func:`run_until_settled`; :meth:`Refinement.budget`)."""
    refinement = Refinement()
    previous: Settled | None = None
    for passes in range(1, MAX_PASSES + 1):
        result = run_until_settled(rig, refinement.budget(max_steps), refinement.minimum())
        refinement.ran(result.steps)
        done = replace(result, steps=refinement.total, passes=passes,
                       refinement=refinement.last_difference)
        if not result.settled or not np.all(np.isfinite(list(result.values.values()))):
            return replace(done, settled=False)
        if previous is not None and refinement.converged(
                disagreement(result.values, previous.values, rig.scale, rig.units),
                rig.rounding / force_size(previous.values, rig.scale, rig.units)):
            return replace(done, refinement=refinement.last_difference)
        previous = result
        rig.carry(refinement.factor(rig.carried, rig.total_constraint_forces(), rig.efc_scale))
        if restart is None:
            reseed(rig, qpos)
        else:
            restart()
    return replace(done, settled=False, refinement=refinement.last_difference)


@dataclass
class Refinement:
    """The passes of one settling so far (:func:`settle_refined`; a batch's
    :meth:`.batch_settle.BatchSettler.end_pass`): the differences between successive
    passes' readings, the contraction measured, the steps taken.

    Each pass settles with what the passes before it carried, and holds in its
    constraints the rest, λ. Carrying λ leaves the next pass holding c·λ: the passes
    contract by c (a fixed point iteration), and c → 1 next to a change point (0.49 at
    condition number 5300, 0.86 at 10⁴, measured), where plain passes crawl. The
    contraction is measured from the passes themselves, as a secant: two passes that
    started with carried C₁ and C₂ and held λ₁ and λ₂ give 1 − c = −(λ₂ − λ₁)·(C₂ − C₁)
    / |C₂ − C₁|² (:func:`secant_slope`). Carrying λ/(1 − c) instead of λ then lands on
    the fixed point, up to how far c varies (Aitken's extrapolation where the passes
    were plain). The fixed point is unchanged, every number is still MuJoCo's at a
    settled state, and the last two passes must still agree: what an extrapolated
    carry changes is only how many passes that takes.
    """

    differences: list[float] = field(default_factory=list)
    #: How many of the last differences are of plain passes in a row (since the last
    #: extrapolated carry): a ratio of two is a measured contraction (:meth:`steady_ratio`).
    plain_run: int = 0
    #: The largest contraction measured: :func:`refinement_left` never takes less.
    contraction: float = 0.0
    last: tuple[np.ndarray, np.ndarray] | None = None  # the last pass's carried and held
    extrapolated: bool = False  # the last carry was: the next difference is no pass's
    first: int = 0  # the first pass's steps
    longest: int = 0
    total: int = 0

    @property
    def last_difference(self) -> float:
        return self.differences[-1] if self.differences else float("nan")

    def budget(self, max_steps: int | None = None) -> int:
        """The next pass's step budget: ``max_steps`` (default :data:`MAX_STEPS`), or
        :data:`PASS_GROWTH` × the longest pass so far, within what is left of
        :data:`TOTAL_BUDGET` × ``max_steps`` for all passes."""
        base = MAX_STEPS if max_steps is None else max_steps
        return max(0, min(max(base, int(PASS_GROWTH * self.longest)),
                          TOTAL_BUDGET * base - self.total))

    def minimum(self) -> int:
        """The steps before which the next pass may not stop: none, or once the passes
        contract slowly (:data:`SLOW_CONTRACTION`), the first pass's."""
        return self.first if self.contraction >= SLOW_CONTRACTION else 0

    def ran(self, steps: int) -> None:
        self.first = self.first or steps
        self.total += steps
        self.longest = max(self.longest, steps)

    def converged(self, difference: float, rounding: float = 0.0) -> bool:
        """Record ``difference`` (this pass's reading against the last pass's, relative
        to the largest force); True when :func:`refinement_left` ≤ :data:`REFINE_RTOL`, or
        ≤ ``rounding`` (the rounding floor, :func:`rounding_floor`, relative to the same
        force) where that is more: two readings of one equilibrium differ by that much.
        Across an extrapolated carry it is no pass's difference and is not recorded."""
        if self.extrapolated:
            self.extrapolated = False
            self.plain_run = 0
            return False
        self.differences.append(difference)
        self.plain_run += 1
        return refinement_left(self.differences, self.contraction) <= max(REFINE_RTOL, rounding)

    def steady_ratio(self) -> float | None:
        """The contraction of the last plain passes, if they contract steadily: the ratio
        of the last two differences, when three in a row give two ratios below 1 that
        agree within :data:`STEADY_RATIO`; else None."""
        if self.plain_run < 3:
            return None
        d = self.differences
        last, before = d[-1] / d[-2], d[-2] / d[-3]
        steady = 0.0 < last < 1.0 and 0.0 < before < 1.0 and abs(last - before) <= STEADY_RATIO
        return last if steady else None

    def factor(self, carried: np.ndarray, total: np.ndarray, scale: np.ndarray) -> float:
        """By what to multiply the held forces ``total − carried`` (constraint rows,
        ``scale`` making torques forces) as they are carried into the next pass: 1 for a
        plain pass, 1/(1 − c) for an extrapolated one, c from the passes' secant, or where
        that measures none, from the plain passes' steady ratio (:meth:`steady_ratio`)."""
        carried, held = carried * scale, (total - carried) * scale
        size = max(float(np.abs(total * scale).max(initial=0.0)), FORCE_FLOOR_N)
        held_part = float(np.abs(held).max(initial=0.0)) / size
        factor = 1.0
        if self.last is not None and np.abs(carried - self.last[0]).max() > MEASURABLE_CARRY * size:
            slope = secant_slope(self.last, (carried, held))
            if 0.0 < slope < 1.0:
                self.contraction = max(self.contraction, 1.0 - slope)
                if plain_passes_left(held_part, 1.0 - slope) > EXTRAPOLATE_AFTER:
                    factor = 1.0 / slope
        if factor == 1.0 and (c := self.steady_ratio()) is not None:
            self.contraction = max(self.contraction, c)
            if plain_passes_left(held_part, c) > EXTRAPOLATE_AFTER:
                factor = 1.0 / (1.0 - c)
        self.last = (carried, held)
        self.extrapolated = factor != 1.0
        return factor


def secant_slope(first: tuple[np.ndarray, np.ndarray], second: tuple[np.ndarray, np.ndarray]
                 ) -> float:
    """1 − c from two passes' (carried, held) forces: how much less the second held per
    force carried more, along the carried forces' change."""
    step = second[0] - first[0]
    return float(-np.dot(second[1] - first[1], step) / np.dot(step, step))


def plain_passes_left(held: float, c: float) -> float:
    """How many more plain passes, contracting by ``c``, until :func:`refinement_left`
    is below :data:`REFINE_RTOL`, the last pass holding the fraction ``held``."""
    return math.log(REFINE_RTOL * (1.0 - c) / (held * c)) / math.log(c) if held > 0.0 else 0.0


def refinement_left(differences: list[float], contraction: float = 0.0) -> float:
    """How far the last pass may still be from the rigid answer, given the
    differences ``d`` between successive passes (relative to the largest force).

    With a contraction c = d_k/d_(k−1) < 1 per pass, what is left is d·c/(1 − c);
    never taken as less than d itself (the last step is known only to d), nor c as
    less than ``contraction``, the largest measured over the passes
    (:class:`Refinement`): at c near 1 two passes can agree closely by chance (the
    floor, a pass stopped at a turning point), which d_k/d_(k−1) alone would take for
    a fast contraction. Two passes are all ordinary poses need and give no c; their
    difference is then taken as it is (a bending small enough for two passes to agree
    to 1e-7 is shrunk ≥ 50× by the second). A difference that no longer shrinks (c ≥ 1)
    is the floor: both passes read the same equilibrium, up to the floor.
    """
    d = differences[-1]
    c = contraction
    if len(differences) > 1 and d < differences[-2]:
        c = max(c, d / differences[-2])
    return d * max(1.0, c / (1.0 - c))


def settle_diagnostics(rig: SettlingRig, qpos: np.ndarray, result: Settled,
                       elapsed: float) -> dict[str, float | str]:
    """The diagnostics of a settling run's Solution."""
    drift = rig.pose_drift(qpos=qpos) if np.isnan(result.pose_drift) else result.pose_drift
    return RunDiagnostics(
        "settle", result.steps, elapsed, result.residual_velocity, result.loop_violation, drift,
    ).as_dict(passes=result.passes, pass_disagreement=result.refinement, stop_rule=result.rule)


def settled_solutions(rig: SettlingRig, qpos: np.ndarray, results: list[Settled],
                      elapsed: float) -> list[Solution]:
    """:func:`settled_solution` of each pose of a sweep, ``elapsed`` its share of the time;
    the settled ones made as a batch (:meth:`Solution.batch`: one check of the names, one
    copy of the units), as their quantities are the same."""
    settled = [k for k, r in enumerate(results) if r.settled]
    names = tuple(results[settled[0]].values) if settled else ()
    if any(tuple(results[k].values) != names for k in settled):
        settled = []
    out: list[Solution | None] = [None] * len(results)
    batch = Solution.batch(
        rig.case.name, "mujoco", names, (list(results[k].values.values()) for k in settled),
        (settle_diagnostics(rig, qpos[k], results[k], elapsed) for k in settled),
        rig.units or {})
    for k, solution in zip(settled, batch, strict=True):
        out[k] = solution
    return [s if s is not None else settled_solution(rig, q, r, elapsed)
            for s, q, r in zip(out, qpos, results, strict=True)]


def settled_solution(rig: SettlingRig, qpos: np.ndarray, result: Settled, elapsed: float) -> Solution:
    """A Solution from a settling run: forces only if it settled."""
    case = rig.case
    diagnostics = settle_diagnostics(rig, qpos, result, elapsed)
    if not result.settled:
        units = rig.units or {}
        pose = {q: v for q, v in result.values.items()
                if quantity_kind(q, units.get(q)) == "pose"}
        why = (f"passes {result.passes - 1} and {result.passes} still differ by "
               f"{result.refinement:.1e} of the forces" if result.passes >= MAX_PASSES
               else f"residual velocity {result.residual_velocity:.2e} m/s")
        return Solution(case.name, "mujoco", pose, status="not_settled",
                        message=f"no equilibrium within {result.steps} steps ({why})",
                        diagnostics=diagnostics, units=units)
    return Solution(case.name, "mujoco", result.values, diagnostics=diagnostics,
                    units=rig.units or {})
