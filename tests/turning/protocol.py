"""Turning and holding experiments shared by both simulators (seed 001's theory).

The run protocol (:func:`run_leg`, :func:`turn_result`), the result types
(:class:`TurnResult`, :class:`Amplification`) and the extreme finder
(:func:`rocker_extremes`) are simulator-independent, so MuJoCo
(:mod:`.mujoco_turning`) and pymunk (:mod:`.pymunk_turning`)
are judged by the same rules. Each simulator supplies a :class:`Turner`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mechcheck.analytic.case import Case, Load, Motion, preset_of
from mechcheck.analytic.kinematics import pose_of
from mechcheck.analytic.presets import redrawn

Array = NDArray[np.float64]
Ending = Literal["turned", "jammed", "budget"]

# -- the run protocol ---------------------------------

#: Time step of a turning run, s. With :data:`SERVO_SPEED` it gives a sample
#: every 0.057° of crank, so the extreme of θ14 is bracketed by samples ten
#: times closer than the 0.1° the dead-position check asks for (and the
#: parabola through them, :func:`rocker_extremes`, does far better).
TIMESTEP = 1.0e-3

#: Target crank speed of the servo, rad/s. The pose of a rigid linkage does
#: not depend on speed; slow keeps the inertia forces — hence the constraint
#: violations that would blur the pose — small (measured: loop closure within
#: 3e-6 m on 0.25 m links).
SERVO_SPEED = 1.0

#: Velocity gain of MuJoCo's servo, in units of m·L² (m the link mass, L the
#: longest link), so 1/s: the crank's speed error relaxes in ~1/50 s.
#: (pymunk's SimpleMotor has no gain: it is a velocity constraint that holds
#: the speed exactly until it needs more than its torque bound.)
SERVO_GAIN = 50.0

#: The servo's torque bound, in units of m·L²·ω². Enough to drive the links'
#: inertia and the joint damping at ω with margin (measured: the double-crank,
#: whose rocker turns up to 3.7 times as fast as the crank, needs 0.3 of it at
#: full speed; spin-up saturates it for a few degrees), finite so that a
#: toggle stops the crank instead of tearing the loop open.
TORQUE_LIMIT = 50.0

#: Viscous damping of the passive joints (coupler hinge A, rocker hinge B0 or
#: the slide), in units of m·L² per second (m per second on the slide). It
#: only dissipates. Without it a jammed linkage does not come to rest: the
#: rocker swings through the toggle, the crank bounces back (measured on the
#: non-Grashof example: θ12 between 95.5° and 97.26° for ever) and the rest
#: angle is never reached; with it, the crank settles at the toggle.
JOINT_DAMPING = 1.0

#: Armature of the crank hinge, in units of m·L² (MuJoCo only). A grounded
#: hinge's armature is a pure couple between ground and crank: it changes no
#: pose, only the inertia the servo drives. Without it a crank much shorter
#: than the other links (a bar of 1/12 of the longest link has 1/1700 of its
#: m·L²) faces a servo gain and loop forces scaled to the long links: measured
#: on (375, 31.25, 250, 250) mm the saturated servo could not keep the crank
#: from creeping backwards with the loop 1.7e-5 m open.
CRANK_ARMATURE = 1.0

#: Crank rotation before recording starts (the servo's spin-up: measured, it
#: saturates for up to 16° on the double-crank in pymunk, whose rigid motor
#: chatters at its bound while the fast rocker is brought up to speed), and
#: after the requested turns (so an extreme near the end has neighbours).
LEAD_ANGLE = math.radians(20.0)

#: A crank is jammed when, for STALL_TIME, its angle stays within
#: STALL_ANGLE while the servo pushes at its bound (within SATURATION). On the
#: non-Grashof example the rest angle is approached geometrically and is
#: within 1e-9 rad about 1 s after the first contact (measured).
STALL_TIME = 1.0
STALL_ANGLE = 1.0e-9
SATURATION = 0.999

#: Time budget of one sense, as a multiple of the time the turns take at
#: SERVO_SPEED, plus room for the stall to be recognised. A run that neither
#: turns nor jams within it ends as ``budget`` (undecided, never a verdict).
BUDGET_FACTOR = 3.0
BUDGET_EXTRA_TIME = 10.0 * STALL_TIME


def wrap(angle: float) -> float:
    """An angle in (−π, π]."""
    return math.remainder(angle, math.tau)


def branch_sign(case: Case, theta13: ArrayLike, output: ArrayLike) -> Array:
    """+1 or −1: which assembly branch a pose is on, from its link angles.

    Four-bar: the sign of sin(θ14 − θ13), which changes only where coupler and
    rocker are in line (a toggle). Slider-crank: the sign of cos(θ13 − g) (the
    rod pointing along or against the slide), which changes only where the
    rod is perpendicular to the slide.
    """
    t13 = np.asarray(theta13, dtype=float)
    if preset_of(case).geometry.rocker:
        return np.sign(np.sin(np.asarray(output, dtype=float) - t13))
    return np.sign(np.cos(t13 - preset_of(case).ground_angle))


@dataclass(frozen=True)
class Sample:
    """One step of a turning run, from the simulator's state after the step."""

    theta12: float       # rad, unwrapped
    theta13: float       # rad
    output: float        # θ14 (rad, unwrapped) or s14 (m)
    torque: float        # servo torque on link 2, N·m, CCW +
    violation: float     # loop-closure error at B, m


class Turner(Protocol):
    """A simulator model whose crank is driven by a bounded-torque velocity servo."""

    case: Case
    timestep: float
    torque_limit: float

    def reset(self, sense: int) -> None:
        """Put the mechanism at rest on its pose at case.theta12, servo aimed at sense·ω."""

    def step(self) -> Sample:
        """Advance one step and read the state."""


@dataclass(frozen=True)
class Leg:
    """One run of the servo in one sense."""

    sense: int
    samples: Array       # (n, 5): θ12, θ13, output, torque, violation per step
    ending: Ending
    start: float         # θ12 where it started, rad

    @property
    def progress(self) -> Array:
        """Crank rotation in the run's sense since the start, rad."""
        return self.sense * (self.samples[:, 0] - self.start)

    @property
    def rest(self) -> float:
        """Last θ12 (where a jammed crank came to rest), rad."""
        return float(self.samples[-1, 0])


def run_leg(turner: Turner, sense: int, turns: float) -> Leg:
    """Drive the crank in ``sense`` until it has turned, jammed, or used up its budget.

    Turned: LEAD_ANGLE + turns·2π + LEAD_ANGLE of rotation. Jammed: for
    STALL_TIME the crank stayed within STALL_ANGLE with the servo saturated.
    """
    turner.reset(sense)
    dt = turner.timestep
    # A preset's crank starts at its θ12; a linkage's driver at its drawn pose.
    start = turner.case.preset.theta12 if turner.case.preset is not None else 0.0
    target = 2.0 * LEAD_ANGLE + turns * math.tau
    budget = math.ceil((BUDGET_FACTOR * target / SERVO_SPEED + BUDGET_EXTRA_TIME) / dt)
    window = max(2, round(STALL_TIME / dt))
    rows = np.empty((budget, 5))
    ending: Ending = "budget"
    n = 0
    for n in range(1, budget + 1):
        s = turner.step()
        rows[n - 1] = (s.theta12, s.theta13, s.output, s.torque, s.violation)
        if sense * (s.theta12 - start) >= target:
            ending = "turned"
            break
        if n % window == 0 and stalled(rows[n - window:n], turner.torque_limit):
            ending = "jammed"
            break
    return Leg(sense, rows[:n].copy(), ending, start)


def stalled(rows: Array, torque_limit: float) -> bool:
    """The crank kept still while the servo pushed at its bound."""
    spread = float(np.ptp(rows[:, 0]))
    saturated = bool(np.all(np.abs(rows[:, 3]) >= SATURATION * torque_limit))
    return spread <= STALL_ANGLE and saturated


@dataclass(frozen=True)
class RockerExtremes:
    """Extremes of θ14 over a crank turn and the crank angles where they occur (rad, wrapped)."""

    theta12_at_max: float
    theta14_max: float
    theta12_at_min: float
    theta14_min: float


def parabola_vertex(x: Array, y: Array) -> tuple[float, float]:
    """(x, y) of the vertex of the least-squares parabola through the points."""
    x0 = float(x[len(x) // 2])
    c2, c1, c0 = np.polyfit(x - x0, y, 2)
    xv = -c1 / (2.0 * c2)
    return x0 + float(xv), float(c0 - c1**2 / (4.0 * c2))


#: Samples on each side of a sampled extreme that the parabola is fitted to.
#: θ14 is smooth there; 3 + 1 + 3 samples span 0.34° of crank, where the
#: cubic term of θ14(θ12) shifts the vertex by far less than 1e-3°.
VERTEX_HALF_WIDTH = 3


def rocker_extremes(theta12: Array, theta14: Array) -> RockerExtremes:
    """The max and min of θ14 over sampled (θ12, θ14), refined by a parabola.

    Each sampled extreme is refined with the parabola through it and its
    :data:`VERTEX_HALF_WIDTH` neighbours on each side (θ14 is flat there, so
    the vertex finds it between samples); at the ends of the record the
    sample itself is taken.
    """
    out = []
    for pick in (np.argmax, np.argmin):
        i = int(pick(theta14))
        lo, hi = i - VERTEX_HALF_WIDTH, i + VERTEX_HALF_WIDTH + 1
        if lo < 0 or hi > len(theta14):
            out.append((float(theta12[i]), float(theta14[i])))
        else:
            out.append(parabola_vertex(theta12[lo:hi], theta14[lo:hi]))
    (t12_max, t14_max), (t12_min, t14_min) = out
    return RockerExtremes(wrap(t12_max), wrap(t14_max), wrap(t12_min), wrap(t14_min))


@dataclass(frozen=True)
class TurnResult:
    """What driving the crank showed, in one simulator.

    ``theta12``, ``theta13``, ``output`` (θ14 in rad, or s14 in m for a
    slider-crank) and ``drive_torque`` (the servo's torque on link 2, N·m) are
    the forward run's samples after its spin-up (:data:`LEAD_ANGLE`); angles
    are unwrapped (cumulative). ``completed``: the crank made the requested
    turns. ``reach``: the lowest and highest θ12 the crank reached, over the
    forward run and, if it jammed, the backward run; ``jams``: where it came
    to rest against a toggle turning CW and CCW (None if it did not).
    """

    simulator: str
    case: Case
    theta12: Array
    theta13: Array
    output: Array
    drive_torque: Array
    completed: bool
    reach: tuple[float, float]
    jams: tuple[float | None, float | None]
    diagnostics: dict[str, float | str] = field(default_factory=dict)

    @property
    def theta14(self) -> Array:
        """θ14 (rad, unwrapped): four-bar only."""
        if not preset_of(self.case).geometry.rocker:
            raise ValueError(f"{self.case.name}: a slider-crank has no θ14 (use output = s14)")
        return self.output

    @property
    def span(self) -> float:
        """Width of the reachable θ12 range, rad."""
        return self.reach[1] - self.reach[0]

    def rocker_extremes(self) -> RockerExtremes:
        """The measured rocker extremes over the completed turn(s)."""
        if not self.completed:
            raise ValueError(f"{self.case.name}: the crank did not turn fully in {self.simulator}; "
                             "a rocker extreme over a turn is undefined")
        if float(np.ptp(self.theta14)) >= math.pi:
            raise ValueError(f"{self.case.name}: the rocker turns fully in {self.simulator} "
                             "(a double-crank); it has no extremes")
        return rocker_extremes(self.theta12, self.theta14)

    def output_at(self, theta12: float) -> float:
        """θ14 (or s14) where the crank passed ``theta12`` (unwrapped), interpolated."""
        order = np.argsort(self.theta12)
        return float(np.interp(theta12, self.theta12[order], self.output[order]))


def turn_result(simulator: str, turner: Turner, turns: float, sense: int,
                start_time: float) -> TurnResult:
    """Run the protocol: forward; if that jams, backward too; and package the result."""
    case = turner.case
    forward = run_leg(turner, sense, turns)
    backward = run_leg(turner, -sense, turns) if forward.ending != "turned" else None
    legs = [forward] + ([backward] if backward is not None else [])
    every = np.concatenate([[preset_of(case).theta12]] + [leg.samples[:, 0] for leg in legs])
    recorded = forward.samples[forward.progress >= LEAD_ANGLE]
    jams: list[float | None] = [None, None]  # (CW, CCW)
    overshoot = 0.0
    for leg in legs:
        if leg.ending == "jammed":
            jams[(leg.sense + 1) // 2] = leg.rest
            overshoot = max(overshoot, float(leg.progress.max()) - leg.sense * (leg.rest - leg.start))
    # A jammed crank's limit is where it came to rest; on the way in it may
    # overshoot by the loop's elastic give under the impact (``overshoot``).
    low = jams[0] if jams[0] is not None else float(every.min())
    high = jams[1] if jams[1] is not None else float(every.max())
    diagnostics: dict[str, float | str] = {
        "forward": forward.ending,
        "backward": backward.ending if backward is not None else "not run",
        "steps": int(sum(len(leg.samples) for leg in legs)),
        "wall_time_s": time.perf_counter() - start_time,
        "timestep": turner.timestep,
        "servo_speed": SERVO_SPEED,
        "torque_limit": turner.torque_limit,
        "jam_overshoot_rad": overshoot,
        "max_loop_violation": float(recorded[:, 4].max()) if len(recorded) else math.nan,
        "saturated_fraction": float(np.mean(np.abs(recorded[:, 3])
                                            >= SATURATION * turner.torque_limit))
        if len(recorded) else math.nan,
    }
    return TurnResult(simulator, case, recorded[:, 0].copy(), recorded[:, 1].copy(),
                      recorded[:, 2].copy(), recorded[:, 3].copy(),
                      completed=forward.ending == "turned",
                      reach=(low, high),
                      jams=(jams[0], jams[1]), diagnostics=diagnostics)


# -- amplification: shared result ----------------------------------------------------------------

@dataclass(frozen=True)
class Amplification:
    """The holding torque of the crank against an output load, pose by pose.

    Every array has one entry per requested θ12 and comes from the
    simulator's settled state: ``theta12`` is where the held crank actually
    sits, ``theta13`` and ``output`` (θ14 rad, or s14 m) the pose it settled
    to, ``drive_torque`` T12 (N·m) and ``ratio`` = T12 / load (dimensionless
    for a torque on the rocker; metres for a force on the slider).
    ``settled``: the run met the settling criteria; ``branch_kept``: the
    pose stayed on the case's assembly branch (a near-toggle structure can
    snap through to the mirror image).
    """

    simulator: str
    case: Case
    load: float
    theta12: Array
    theta13: Array
    output: Array
    drive_torque: Array
    settled: NDArray[np.bool_]
    branch_kept: NDArray[np.bool_]
    steps: NDArray[np.int_]
    wall_time_s: float

    @property
    def ratio(self) -> Array:
        """T12 / load."""
        return self.drive_torque / self.load

    @property
    def magnitude(self) -> Array:
        """|T12 / load|: the force amplification."""
        return np.abs(self.ratio)

    @property
    def transmission_angle(self) -> Array:
        """μ (rad) of the settled poses (the seed's definition, as in
        :mod:`mechcheck.analytic.transmission`), from the simulator's own link angles."""
        if preset_of(self.case).geometry.rocker:
            return np.abs(np.remainder(self.theta13 - self.output + np.pi, 2 * np.pi) - np.pi)
        rod = np.abs(np.remainder(self.theta13 - preset_of(self.case).ground_angle + np.pi / 2, np.pi)
                     - np.pi / 2)
        return np.pi / 2 - rod


def seed_pose(case: Case, theta12: float) -> tuple[float, float, float]:
    """(θ12, θ13, θ14 or s14) of the analytic pose: only ever the starting configuration."""
    p = pose_of(case, np.array([theta12]), omega=0.0, alpha=0.0)
    out = p.links[4].angle[0] if p.s14 is None else p.s14[0]
    return theta12, float(p.links[3].angle[0]), float(out)


#: A simulator's holding run: (case, θ12, load) -> (pose θ12, θ13, output; T12; settled; steps).
HoldAt = Callable[[Case, float, float], tuple[tuple[float, float, float], float, bool, int]]


def measure_amplification(simulator: str, hold_at: HoldAt, case: Case, theta12_values: ArrayLike,
                          load: float) -> Amplification:
    """The simulator's holding runs (``hold_at``) at each θ12, packaged as an
    :class:`Amplification`; each pose's branch is judged against its analytic seed's."""
    start = time.perf_counter()
    thetas = np.atleast_1d(np.asarray(theta12_values, dtype=float))
    seed_branch = branch_sign(case, *np.array([seed_pose(case, t)[1:] for t in thetas]).T)
    rows = [hold_at(case, float(t), load) for t in thetas]
    poses = np.array([r[0] for r in rows], dtype=float).reshape(-1, 3)
    kept = branch_sign(case, poses[:, 1], poses[:, 2]) == seed_branch
    return Amplification(simulator, case, load, poses[:, 0], poses[:, 1], poses[:, 2],
                         np.array([r[1] for r in rows], dtype=float),
                         np.array([r[2] for r in rows], dtype=bool), kept,
                         np.array([r[3] for r in rows], dtype=int), time.perf_counter() - start)


def bare(case: Case, theta12: float | None = None) -> Case:
    """The case at rest without its loads, masses and friction (the turning and holding
    experiments apply their own), at ``theta12`` if given."""
    return redrawn(case, theta12=preset_of(case).theta12 if theta12 is None else theta12,
                   loads=(), masses=(), friction=None, motion=Motion())


def held_against(case: Case, theta12: float, load: float) -> Case:
    """The bare case at ``theta12`` with only the holding runs' output load
    (:func:`output_load`)."""
    return redrawn(bare(case, theta12), loads=(output_load(case, load),))


def output_load(case: Case, load: float) -> Load:
    """The output load of the holding runs: a pure couple ``load`` on the rocker, or a force
    ``load`` on the slider along the slide direction u through B (no moment)."""
    if preset_of(case).geometry.rocker:
        return Load(4, at=(0.0, 0.0), force=(0.0, 0.0), torque=load)
    g = preset_of(case).ground_angle
    return Load(4, at=(0.0, 0.0), force=(load * math.cos(g), load * math.sin(g)))
