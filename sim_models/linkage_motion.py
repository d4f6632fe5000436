"""A linkage's prescribed motion along a driven run, for either simulator: each driver's
value, velocity and acceleration over time, and how far back a lead-in may start."""

from __future__ import annotations

import math
from collections.abc import Callable, Collection, Mapping, Sequence
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage import Joint, Link, Linkage
from mechcheck.analytic.linkage_backends import analytic_results, verdict
from mechcheck.analytic.linkage_forces import LinkageResults, solve_linkage
from mechcheck.analytic.linkage_kinematics import Array, solve_pose
from mechcheck.analytic.solution import Solution
from mechcheck.sim_models.convergence import LEAD_CONDITION_GROWTH, LeadLimit


@dataclass(frozen=True)
class Motion:
    """Each driver's value, velocity and acceleration at the instant (SI)."""

    value: Array
    velocity: Array
    acceleration: Array
    quasi_static: bool

    def at(self, t: Array) -> tuple[Array, Array, Array]:
        """Drivers' values, velocities and accelerations (N, d) at the times ``t``."""
        t = np.asarray(t, dtype=float)[:, None]
        return (self.value + self.velocity * t + 0.5 * self.acceleration * t**2,
                self.velocity + self.acceleration * t, np.broadcast_to(self.acceleration,
                                                                        (t.shape[0],
                                                                         self.value.size)))


def unmodelled(linkage: Linkage, built: Collection[str], simulator: str,
               stretches: bool = False) -> str | None:
    """What of ``linkage`` a simulator with joint builds for the kinds ``built`` has no
    counterpart for, or None: a kind of joint without a build, or members whose stretch
    decides a redundant linkage's forces, unless the model ``stretches`` them (otherwise
    its bodies are rigid)."""
    missing = [j for j in linkage.joints if j.kind.name not in built]
    if missing:
        j = missing[0]
        return (f"joint {j.name} is a {j.kind.name}, which the {simulator} model does not build: "
                "its forces are checked by the analytic backends only")
    if linkage.redundant and linkage.elastic_links and not stretches:
        return ("the forces of this redundant linkage follow its members' stretch "
                f"(axial_stiffness of {', '.join(m.name for m in linkage.elastic_links)}), and "
                f"the {simulator} model's bodies are rigid here (a constraint solve at a fixed "
                "pose, or a driven run): at the drawn pose nothing stretches to decide them, "
                "and the stretched pose would have to come from the analytic answer itself; the "
                f"'{simulator.lower()}' backend stretches them in a held structure, settled")
    return None


#: The largest strain |N|/(E·A) of a simulator's settled elastic members at which its
#: equilibrium is compared with the analytic one. The simulator's is the geometrically exact
#: equilibrium on the stretched members, the analytic one that of small displacements; they
#: differ by a few times the strain, which the tolerance policy allows for (its
#: small-displacement bound, ``mechcheck.tolerance.STRAIN_FACTOR``). Above 1e-3 the
#: displacements are no longer small: the bound reaches half a percent, and a steel
#: member (E = 210 GPa) would be past its yield stress (about 210 MPa at that strain).
STRAIN_LIMIT = 1e-3


def largest_strain(members: tuple[Link, ...], values: Mapping[str, float]) -> float:
    """max |N|/(E·A) over the members, N as the simulator read it (``N_<link>``)."""
    return max((abs(values[f"N_{m.name}"]) / float(m.axial_stiffness or math.inf)
                for m in members), default=0.0)


def strain_verdict(members: tuple[Link, ...], solution: Solution, simulator: str) -> Solution:
    """``solution`` with the simulator's largest strain among its diagnostics;
    ``not_applicable`` where it is above :data:`STRAIN_LIMIT` (a settled solution only)."""
    if not members or solution.status != "ok":
        return solution
    strain = largest_strain(members, solution.values)
    diagnostics = {**solution.diagnostics, "max_strain": strain}
    if strain <= STRAIN_LIMIT:
        return replace(solution, diagnostics=diagnostics)
    names = ", ".join(m.name for m in members)
    return replace(solution, values={}, status="not_applicable", diagnostics=diagnostics,
                   message=(f"the members (axial_stiffness of {names}) stretch by up to "
                            f"{strain:.3g} of their length in {simulator}'s equilibrium: it is "
                            "the geometrically exact one; above a strain of "
                            f"{STRAIN_LIMIT:g} the displacements are not small, and the analytic "
                            "answer, that of small displacements, is no reference for it; "
                            "stiffer members, or the analytic backend, check it"))


def prescribed_motion(case: Case) -> Motion:
    """A moving linkage's motion: each driver's own value, velocity and acceleration."""
    drivers = case.linkage.drivers
    return Motion(np.array([d.value for d in drivers]), np.array([d.velocity for d in drivers]),
                  np.array([d.acceleration for d in drivers]), False)


def is_driven(case: Case) -> bool:
    """A simulator drives the case: it moves, or it is static with Coulomb friction (a
    quasi-static motion); viscous friction alone does nothing at rest."""
    return case.linkage.is_moving or case.has_coulomb_friction


def has_free_coordinates(case: Case) -> bool:
    """The linkage has coordinates no driver holds (settled from the drawn pose)."""
    return case.linkage.dof > len(case.linkage.drivers)


#: rad/s or m/s: a joint slower than this at the reading is at rest for a simulator. In 1 s
#: it moves 1e-9, below what a driven run tracks its motion to; measured (four-bar,
#: 2026-11): MuJoCo read T12 7.8e-3 off at ω = −3e-232 rad/s, α = 0, where only the sign of
#: ω sets the Coulomb senses.
REST_SPEED = 1e-9


def coulomb_joints(case: Case) -> list[Joint]:
    """The joints with a Coulomb term (a pin radius and μ, or a prismatic μ)."""
    f = case.linkage.friction
    if f is None:
        return []
    return [j for j in case.linkage.joints if j.kind.coulomb_coefficient(f, j) > 0.0]


def at_rest_reason(case: Case, window: float, rest_speed: float = REST_SPEED) -> str:
    """Why a simulator cannot measure a moving linkage's Coulomb friction, or ``""``: the
    relative motion of a Coulomb joint is at rest at the reading (slower than
    ``rest_speed``, rad/s, a prismatic joint's m/s taken per the linkage's length scale),
    or reverses within ``window`` (s, the simulator's longest time step) before it. A
    simulator takes each Coulomb sense from its own joint rates, which a step's velocity
    error or a step across the reversal can turn over, while the analytic sense there is
    the prescribed one (or, at rest, the case's convention). Found by the random
    driven-friction test (2026-11-25): ω = 6e-8 rad/s with α = 1 rad/s² at the reading, the
    crank reversing 6e-8 s before it; MuJoCo read the pin friction with the other sign."""
    joints = coulomb_joints(case)
    if not (case.linkage.is_moving and joints):
        return ""
    motion = prescribed_motion(case)
    pose = solve_pose(case.linkage, *motion.at(np.array([-window, 0.0])))
    for joint in joints:
        _, rate, _ = pose.joint_coordinate(joint)
        before, now = float(rate[0]), float(rate[1])
        per_length = 1.0 if joint.kind.rotates else case.linkage.scale
        if abs(now) <= rest_speed * per_length or before * now <= 0.0:
            return (f"the relative motion at the Coulomb joint {joint.name} is at rest at the "
                    f"reading (slower than {rest_speed * per_length:g}, the speed this "
                    f"simulator's joint rates resolve) or reverses within {window:g} s of it "
                    f"(rate {now:.3g} at the reading, {before:.3g} {window:g} s before): the "
                    "sense its friction opposes there is not a property of the simulated "
                    "motion, so a simulator cannot measure it")
    return ""


def self_locking_note(results: LinkageResults) -> str:
    """Why a driven run with Coulomb friction may not settle at this pose ("" if nothing
    says so): the gain of the loop that takes friction from the last reactions, as both
    simulators take it, is 1 or more (:func:`.linkage_forces.friction_loop_gain`)."""
    gain = results.friction_gain
    if gain is None or not gain[0] >= 1.0:
        return ""
    return (f"; the friction loop's gain is {gain[0]:.3g} ≥ 1 at this pose: friction taken "
            "from the last reactions, as the simulators take it, cannot settle where a joint "
            "is held inside its friction angle (a slide whose rod makes φ with its axis "
            "jams when μ·|tan φ| ≥ 1)")


def driven_motion(case: Case, quasi_static_speed: float) -> Motion:
    """The motion a driven run follows: the drivers' own, or for a static case with Coulomb
    friction a slow one, ``quasi_static_speed`` (rad/s or m/s) in each driver's ``sense``
    (the analytic friction opposes that sense of motion at rest)."""
    if case.linkage.is_moving:
        return prescribed_motion(case)
    drivers = case.linkage.drivers
    return Motion(np.array([d.value for d in drivers]),
                  quasi_static_speed * np.array([float(d.sense) for d in drivers]),
                  np.zeros(len(drivers)), True)


def clock_times(steps: int, dt: float) -> Array:
    """The clock's angle (time) at each of the ``steps + 1`` forward passes."""
    return dt * np.arange(-steps, 1, dtype=float)


#: Lead-in poses analysed at once (:func:`lead_limit`). The analytic engine holds every pose's
#: dense force system, (3n) × (2j + d) for n moving links and j joints, and a scaled copy for
#: its condition number: the whole lead-in of a 64-loop chain of four-bars at once (1 601
#: poses, 129 links) reached 5.7 GB and 286 s. In chunks of this many it holds at most that
#: many poses' systems; the verdict is the same, pose for pose.
LEAD_CHUNK = 64


def lead_limit(case: Case, motion: Motion, instant: float) -> LeadLimit:
    """Why a lead-in of ``steps`` of ``dt`` may not be run: it would pass a pose whose
    condition number grows past ``LEAD_CONDITION_GROWTH`` times the instant's, or one that
    does not assemble (:mod:`mechcheck.sim_models.convergence`).

    A lead-in that doubles (:func:`~mechcheck.sim_models.convergence.lengthen_lead`) ends
    at the same instant on the same clock ticks, so only the poses it adds are analysed,
    :data:`LEAD_CHUNK` at a time."""
    checked: dict[float, int] = {}  # per time step, the lead-in steps found clear so far

    def limit(steps: int, dt: float) -> str:
        times = clock_times(steps, dt)
        new = times[:steps - checked.get(dt, -1)]  # the ticks not yet analysed
        if not new.size:
            return ""
        parts = [lead_conditions(case, motion, new[k:k + LEAD_CHUNK])
                 for k in range(0, new.size, LEAD_CHUNK)]
        cond = np.concatenate([c for c, _ in parts])
        assembled = np.concatenate([a for _, a in parts])
        worst = int(np.argmax(cond))
        if cond[worst] <= LEAD_CONDITION_GROWTH * instant:
            checked[dt] = steps
            return ""
        when = f"{-new[worst]:.3g} s before the instant"
        if not assembled[worst]:
            return f"a longer lead-in would start where the linkage does not assemble ({when})"
        return (f"a longer lead-in would pass a pose with condition number {cond[worst]:.3g} "
                f"against {instant:.3g} at the instant ({when})")

    return limit


def lead_conditions(case: Case, motion: Motion, times: Array) -> tuple[Array, Array]:
    """The condition number of the linkage on its prescribed motion at ``times`` (∞ where it
    does not assemble), and where it assembles."""
    lead = solve_linkage(case.linkage, *motion.at(times))
    assembled = np.asarray(lead.pose.assembled, dtype=bool)
    return np.where(assembled, lead.condition, np.inf), assembled


def at_first_driver(case: Case, value: float) -> Case:
    """``case`` with its first driver at ``value`` (rad or m from the drawn pose), its rates
    and every other driver as they are."""
    linkage = case.linkage
    first = replace(linkage.drivers[0], value=float(value))
    return replace(case, geometry=replace(linkage, drivers=(first, *linkage.drivers[1:])))


#: Sweep values within this fraction of the grid's step of an evenly spaced whole turn lie on
#: it (the CLI's degrees converted to radians round at 1e-16 of a turn).
GRID_RTOL = 1e-9
#: A continuous run's motion between two poses is checked for the condition rule at
#: STRETCH_SAMPLES − 1 points evenly between them (the midpoint: each is analysed with its
#: condition number, a third of a 360-pose sweep's analysis with three points).
STRETCH_SAMPLES = 2

#: A driven run over the poses of a stretch (the case at its first pose, the poses' values
#: in the order the motion passes them, their analytic analysis): one Solution per pose
#: (None: that pose is run alone), or None where the stretch cannot be run as one motion
#: (its poses are then run one by one).
StretchRun = Callable[[Case, Array, LinkageResults], "Sequence[Solution | None] | None"]


def continuous_reason(case: Case, first: Array) -> str:
    """Why a driven sweep over ``first`` is not one continuous motion ("" if it is): the
    case must turn its first driver at a constant speed with every other driver held, and
    the values must lie on an evenly spaced grid of one whole turn (a periodic motion, each
    pose passed once; the sweep's poses the gate withheld are not among them, so part of a
    turn on such a grid counts too)."""
    drivers = case.linkage.drivers
    lead, others = drivers[0], drivers[1:]
    if not case.linkage.is_moving:
        return "a quasi-static friction run: each pose is driven on its own at creeping speed"
    if lead.acceleration or any(d.acceleration for d in others) or not lead.velocity:
        return ("the drivers accelerate: the prescribed motion is not one constant-speed "
                "motion through the poses")
    if any(d.velocity for d in others):
        return "a driver other than the first moves: the sweep's poses are not on one motion"
    if not case.linkage.joint(lead.joint).kind.rotates:
        return "the first driver slides: its motion is not periodic"
    if grid_step(first) is None:
        return "the values are not on an evenly spaced grid of a whole turn"
    return ""


def grid_step(first: Array) -> float | None:
    """The step of the evenly spaced whole turn (2π/n) the values lie on, or None."""
    values = np.sort(np.asarray(first, dtype=float))
    if values.size < 2 or values[-1] - values[0] >= 2.0 * math.pi:
        return None
    step = float(np.diff(values).min())
    if step <= 0.0:
        return None
    n = round(2.0 * math.pi / step)
    step = 2.0 * math.pi / n
    offsets = (values - values[0]) / step
    return step if np.abs(offsets - np.round(offsets)).max() <= GRID_RTOL else None


def stretches(case: Case, first: Array, results: LinkageResults) -> list[NDArray[np.intp]]:
    """The poses of a continuous sweep (indices into ``first``) in the runs that pass them,
    each in the order its motion does: a run starts after a pose missing from the whole turn
    (one the gate withheld), and again wherever its motion since the last pose passes a pose
    whose condition number is more than ``LEAD_CONDITION_GROWTH`` times the one it reaches
    (the rule of a per-pose lead-in, :func:`lead_limit`)."""
    step = grid_step(first)
    assert step is not None
    sense = 1.0 if case.linkage.drivers[0].velocity > 0.0 else -1.0
    order: NDArray[np.intp] = np.argsort(sense * np.asarray(first, dtype=float), kind="stable")
    ticks = np.round(sense * (first[order] - first[order[0]]) / step).astype(int)
    gaps = np.diff(np.append(ticks, ticks[0] + round(2.0 * math.pi / step))) != 1
    start = (int(np.flatnonzero(gaps)[-1]) + 1) % order.size if gaps.any() else 0
    order = np.roll(order, -start)
    gaps = np.roll(gaps, -start)
    calm = calm_passages(case, first[order], sense * step, results.take(order))
    breaks = gaps[:-1] | np.logical_not(calm)
    return np.split(order, np.flatnonzero(breaks) + 1)


def calm_passages(case: Case, values: Array, step: float, results: LinkageResults) -> Array:
    """For each pose after the first, whether the motion from the one before passes no pose
    whose condition number exceeds ``LEAD_CONDITION_GROWTH`` times its own (and assembles)."""
    fractions = np.arange(1, STRETCH_SAMPLES) / STRETCH_SAMPLES
    between = (values[:-1, None] + step * fractions[None, :]).ravel()
    cond = np.concatenate([lead_samples(case, between[k:k + LEAD_CHUNK])
                           for k in range(0, between.size, LEAD_CHUNK)] or [np.empty(0)])
    worst = cond.reshape(values.size - 1, -1).max(axis=1, initial=0.0)
    return np.asarray(worst <= LEAD_CONDITION_GROWTH * np.asarray(results.condition)[1:], dtype=bool)


def lead_samples(case: Case, first: Array) -> Array:
    """The condition number at these values of the first driver (∞ where it does not
    assemble)."""
    found = analytic_results(case, first)
    return np.where(np.asarray(found.pose.assembled, dtype=bool), found.condition, np.inf)


#: Why a stretch's poses ran one by one when the simulator did not run it as one motion.
STRETCH_REFUSED = ("per pose: the simulator does not run this stretch as one motion (a gear "
                   "mesh, a Coulomb joint at rest or reversing at a pose, or no lead-in to it "
                   "converged)")


def driven_sweep(case: Case, first: Array, drive: Callable[[Case], Solution],
                 run: StretchRun | None = None,
                 results: LinkageResults | None = None) -> list[Solution]:
    """A driven linkage over values of its first driver. Where the sweep is one continuous
    motion (:func:`continuous_reason`) and the simulator can ``run`` stretches, each stretch
    of poses (:func:`stretches`) is one run read as it passes them; every other pose is one
    driven run of its own (``drive``), reaching its pose with the case's rates after its own
    lead-in. The diagnostic ``sweep_run`` says which, and why a sweep fell back.
    ``results``: the analytic analysis of ``first``, if already made."""
    first = np.atleast_1d(np.asarray(first, dtype=float))
    why = "no continuous run in this simulator" if run is None else continuous_reason(case, first)
    if why or run is None:
        return [noted(drive(at_first_driver(case, v)), f"per pose: {why}") for v in first]
    results = results if results is not None else analytic_results(case, first)
    out: list[Solution | None] = [None] * first.size
    for stretch in stretches(case, first, results):
        solved = run(at_first_driver(case, first[stretch[0]]), first[stretch],
                     results.take(stretch)) if stretch.size > 1 else None
        for k, i in enumerate(stretch.tolist()):
            found = solved[k] if solved is not None else None
            out[i] = (noted(found, f"continuous: one run through {stretch.size} poses")
                      if found is not None
                      else noted(drive(at_first_driver(case, first[i])),
                                 "per pose: no calm continuous motion from a neighbour"
                                 if stretch.size == 1 else STRETCH_REFUSED))
    return [s for s in out if s is not None]


def noted(solution: Solution, how: str) -> Solution:
    """``solution`` with how the sweep ran it (``sweep_run``) among its diagnostics."""
    return replace(solution, diagnostics={**solution.diagnostics, "sweep_run": how})


def gated_sweep(case: Case, first: Array, backend: str,
                sweep: Callable[[Array, LinkageResults], list[Solution]]) -> list[Solution]:
    """A sweep of ``case``'s first driver behind the pose gate, as the harness runs one
    (:func:`mechcheck.sweep.gated_poses`): where the analytic pose analysis finds no unique
    forces (the linkage does not assemble, is singular, redundant, or its friction reverses),
    ``backend`` is not run and reports that verdict; ``sweep`` runs on the other values, in
    order, given their analysis."""
    first = np.atleast_1d(np.asarray(first, dtype=float))
    results = analytic_results(case, first)
    candidates = np.ones(first.size, dtype=bool) if case.linkage.redundant else results.withheld
    given: dict[int, Solution] = {}
    for i in np.flatnonzero(candidates).tolist():
        found = verdict(case, results, i)
        if found is not None:
            given[i] = Solution(case.name, backend, {}, status=found[0],
                                message=f"{found[1]}; not run (the pose verdict of analytic)",
                                diagnostics={"condition_number": float(results.condition[i])})
    if not given:
        return sweep(first, results)
    run = np.array([i for i in range(first.size) if i not in given], dtype=np.intp)
    solved = iter(sweep(first[run], results.take(run)) if run.size else [])
    return [given[i] if i in given else next(solved) for i in range(first.size)]

