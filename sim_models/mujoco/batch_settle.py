"""Settled statics of many poses at once, stepped by ``mujoco.rollout`` (issue 13).

The poses of a static sweep settle exactly as :func:`.settle.settle_refined` settles one
(held by their drivers, started at rest in the analytic pose, passes with the constraint
forces carried, the same stop rules and budgets), but the stepping runs in MuJoCo's
multi-threaded rollout, ``CHUNK`` steps at a time (a refinement pass starts with
``REFINE_CHUNK``) for up to ``POOL`` poses, and Python
only looks at what it recorded:

- **What the stop rule watches.** Each step's forces come from MuJoCo's own force and
  torque sensors at every tree joint (the reaction of the parent on the child body,
  measured at the joint; torques divided by the size, as the single-pose rule divides the
  drivers'), recorded by the rollout at every step. With the loads fixed they change
  exactly when the equality forces :func:`.settle.run_until_settled` watches change, by
  the same modes; :func:`.settle.first_stops` applies the three stop rules
  and the velocity bound to them, reading by reading.
- **The loads** of a rollout are its controls: the xfrc_applied and qfrc_applied of the
  pose it starts the chunk from (loads, carried forces), held for the chunk. The single-
  pose loop re-applies them at every step's pose; a settling pose moves by the soft
  constraints' bending only, and each chunk starts from the last, so by the end the two
  agree to that motion.
- **The reading** is MuJoCo's, at the state where the rule fired: the state is put back
  into the rig, the loads applied at its own pose, one forward pass, and read as any
  settled state (:meth:`.linkage_rig.LinkageRig.read`).

A driver's value is the model's (an equality's ``eq_data``), so each pose in flight needs
a model of its own: ``POOL`` copies of the rig's model take turns.

**Compiled passes.** Where numba is installed, the same passes are stepped by
:mod:`._fast.step_kernel` instead (:meth:`BatchSettler.settle_compiled`): MuJoCo's step called
through its C pointer, the rollouts' resets where each rollout would begin, the same stop
rules read step by step, and each pass stepped to its stop and no further, with Python's
lock released, one thread per core, each with one model copy whose drivers it sets pose
by pose. Python then reads and reseeds every pose whose pass ended, once a round. The
numbers and steps are the rollouts', bit for bit (``tests/test_mujoco_compiled.py``); what
goes is the steps past each stop (a third of the rollouts' on seed E1) and a return to
Python every chunk.
"""

from __future__ import annotations

import bisect
import contextlib
import functools
import os
import threading
from collections import deque
from collections.abc import Iterable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field, replace

import mujoco
import numpy as np
from mujoco import rollout

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage import Linkage
from mechcheck.analytic.solution import FORCE_FLOOR_N, quantity_kind
from mechcheck.sim_models.mujoco import _fast
from mechcheck.sim_models.mujoco._fast.plans import PassPlan
from mechcheck.sim_models.mujoco.linkage_model import body_name, spanning_tree
from mechcheck.sim_models.mujoco.linkage_rig import LinkageRig
from mechcheck.sim_models.mujoco.settle import (
    FLOOR_WINDOW,
    MAX_PASSES,
    RULES,
    STOP_WINDOW,
    Refinement,
    Settled,
)

Array = np.ndarray

#: Steps per rollout. A pass started from its neighbours' forces settles in 5–20 steps;
#: the steps stepped past the stop are wasted, and shorter chunks cost more calls and rule
#: checks (measured on the Watt sweep, CPU time: 8, 16 and 32 steps took 0.94, 0.84 and
#: 1.07 ms/pose, and 0.61, 0.55 and 0.63 once the readings were batched).
CHUNK = 16
#: The first rollout of a refinement pass: the readings up to the first at which a rule can
#: fire (the quiet and decay rules need STOP_WINDOW changes). A pass started with the
#: last pass's forces carried almost always stops right there (measured, 360-pose sweeps
#: of seed E1 and the Watt six-bar: the median and the 10th–90th percentiles of the second
#: passes are 4 steps), and a CHUNK would step 11 more for nothing.
REFINE_CHUNK = STOP_WINDOW + 1
#: Poses in flight at once, each with its own copy of the model (178 µs a new copy, 14 µs
#: refreshed in place: :func:`._fast.model_copies`). Fewer, larger waves spend less Python per
#: pose (measured, seed E1's 360-pose sweep, models kept: 32, 64 and 128 took 0.223–0.229,
#: 0.211–0.219 and 0.206–0.210 ms/pose); 64 keeps a new copy set near 11 ms.
POOL = 64
#: A sweep settles every STRIDE-th pose first, and starts the others from them
#: (:meth:`BatchSettler.settle`).
STRIDE = 8
#: Rollout threads: the machine's cores.
THREADS = os.cpu_count() or 1
STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS
CONTROLS = mujoco.mjtState.mjSTATE_XFRC_APPLIED | mujoco.mjtState.mjSTATE_QFRC_APPLIED


def copies_needed(model: mujoco.MjModel, poses: int) -> int:
    """Model copies a batch of ``poses`` steps with: one per pose in flight for the
    rollouts (:data:`POOL` at most), one per thread for the compiled passes (each sets its
    pose's drivers before stepping it)."""
    return min(THREADS if _fast.compiled_passes(model) is not None else POOL, poses)


def add_reaction_sensors(spec: mujoco.MjSpec, linkage: Linkage) -> None:
    """A force and a torque sensor at every tree joint, on its child body's origin (the
    joint's point: bodies are placed at their tree joint)."""
    for t in spanning_tree(linkage).tree:
        site = spec.body(body_name(t.child)).add_site(name=f"reaction_{t.joint.name}",
                                                      pos=[0.0, 0.0, 0.0])
        for kind in (mujoco.mjtSensor.mjSENS_FORCE, mujoco.mjtSensor.mjSENS_TORQUE):
            spec.add_sensor(type=kind, objtype=mujoco.mjtObj.mjOBJ_SITE, objname=site.name)


@dataclass
class Pose:
    """One pose in flight: where it is in its passes and its pass's readings so far."""

    index: int
    targets: Array
    carried: Array
    state: Array = field(default_factory=lambda: np.zeros(0))
    control: Array = field(default_factory=lambda: np.zeros(0))
    passes: int = 1
    pass_steps: int = 0  # readings taken in this pass
    #: This pass's reading budget (+1) and the readings before it may stop
    #: (:meth:`.settle.Refinement.budget`, :meth:`~.settle.Refinement.minimum`), fixed for
    #: the pass: the refinement changes only at a pass's end.
    readings_left: int = 0
    earliest: int = 0
    history: Array = field(default_factory=lambda: np.zeros((0, 0)))
    previous: Array | None = None  # the last pass's forces (:attr:`Readings.forces`)
    refinement: Refinement = field(default_factory=Refinement)  # the passes' progress, steps


@dataclass(frozen=True)
class Readings:
    """MuJoCo's readings of some poses' states, read at once."""

    names: list[str]  # every quantity
    table: Array  # (n, quantities)
    forces: Array  # (n, m): the forces the passes compare, torques over the size
    totals: Array  # (n, nefc): the equality forces, carried ones included
    speed: Array
    gap: Array
    drift: Array

    def values(self, j: int) -> dict[str, float]:
        return dict(zip(self.names, self.table[j].tolist(), strict=True))

    def finite(self) -> Array:
        return np.all(np.isfinite(self.table), axis=1)


def sensing_rig(case: Case) -> LinkageRig:
    """The static rig of ``case`` with :func:`add_reaction_sensors`."""
    return LinkageRig(case, customize=lambda spec: add_reaction_sensors(spec, case.linkage))


@dataclass
class Models:
    """What a batch settles with, besides its model copies (:func:`._fast.model_copies`): a sensing
    rig (:func:`sensing_rig`), one MjData per rollout thread, and the lock one sweep at a
    time holds while it uses them."""

    rig: LinkageRig
    datas: list[mujoco.MjData]
    lock: threading.Lock = field(default_factory=threading.Lock)


def built_models(case: Case) -> Models:
    """:class:`Models` for ``case``."""
    rig = sensing_rig(case)
    return Models(rig, [mujoco.MjData(rig.model) for _ in range(THREADS)])


@functools.lru_cache(maxsize=8)
def kept_models(case: Case) -> Models:
    """:func:`built_models`, kept for the next settled sweep of the same Case (immutable, and
    so are the models built from it). A sweep sets everything it reads: the drivers'
    targets of each model it steps, and the rig's data it reads in (reset by
    :class:`BatchSettler`); the rollout sets each trajectory's whole state."""
    return built_models(case)


class BatchSettler:
    """Settles the poses ``qpos`` (N, nq) with ``models`` and the copies ``pool`` of the
    rig's model (both held by the caller: their locks)."""

    def __init__(self, models: Models, pool: list[mujoco.MjModel], qpos: Array) -> None:
        rig = self.rig = models.rig
        self.qpos = qpos
        m, d = rig.model, rig.data
        self.pool = pool  # copies of the rig's model (:func:`._fast.model_copies`)
        self.eq_data = [model.eq_data for model in pool]  # views: the drivers' targets
        # Kept data carry nothing over: the rollout sets each trajectory's whole state
        # (``tests/test_mujoco_compiled.py``: kept and new models, the same numbers).
        self.datas = models.datas
        self.runner: rollout.Rollout | None = None  # during :meth:`settle`
        self.stepper = _fast.compiled_passes(m)
        #: Threads stepping the compiled passes, each with its own model copy and data.
        self.lanes = min(THREADS, len(pool), len(self.datas))
        self.threads: ThreadPoolExecutor | None = None  # during :meth:`settle`
        # Sensor columns: (fx, fy, fz, tx, ty, tz) per tree joint; the stop rule reads the
        # planar ones, torques over the size.
        n = m.nsensordata // 6
        cols = np.arange(n)[:, None] * 6 + np.array([0, 1, 5])
        self.columns = cols.ravel()
        self.column_scale = np.tile([1.0, 1.0, 1.0 / rig.scale], n)
        # Rollout states at rest in each analytic pose; the loads there and the arms the
        # carried connect forces act with (:meth:`.linkage_rig.LinkageRig.carried_loads`).
        mujoco.mj_resetData(m, d)
        template = np.empty(mujoco.mj_stateSize(m, STATE))
        mujoco.mj_getState(m, d, template, STATE)
        self.qpos_slice = state_slice(m, mujoco.mjtState.mjSTATE_QPOS)
        self.qvel_slice = state_slice(m, mujoco.mjtState.mjSTATE_QVEL)
        self.seeds = np.tile(template, (len(qpos), 1))
        self.seeds[:, self.qpos_slice] = qpos
        sites, centres = rig.load_points(qpos)
        self.loads = rig.wrenches(sites, centres, np.zeros((len(qpos), m.nv)))
        self.arms = sites[:, rig.pairs.sites] - centres[:, rig.pairs.bodies]
        # The forces two passes compare, as :func:`mechcheck.sim_models.convergence.disagreement`
        # takes them: every force and torque (over the size), no pose quantity.
        units = rig.units or {}
        kinds = {q: quantity_kind(q, units.get(q)) for q in rig.plan.order}
        self.force_names = [q for q in rig.plan.order if kinds[q] != "pose"]
        self.force_scale = np.array([1.0 / rig.scale if kinds[q] == "torque" else 1.0
                                     for q in self.force_names])

    # -- seeds and readings --------------------------------------------------------------
    def seed(self, poses: list[Pose]) -> None:
        """Each of ``poses`` at rest in its analytic pose, its carried forces as loads: its
        rollout state and controls (a new pass)."""
        if not poses:
            return
        rig = self.rig
        index = np.array([p.index for p in poses])
        xfrc, drives = rig.carried_loads(np.array([p.carried for p in poses]), self.arms[index])
        qfrc = np.zeros((len(poses), rig.model.nv))
        qfrc[:, rig.drive_dofs] = drives
        controls = np.concatenate([qfrc, (self.loads[index] + xfrc).reshape(len(poses), -1)],
                                  axis=1)
        history = np.full((FLOOR_WINDOW - 1, self.columns.size), np.nan)
        for pose, control in zip(poses, controls, strict=True):
            pose.state = self.seeds[pose.index]
            pose.control = control
            pose.pass_steps = 0
            pose.history = history
            pose.readings_left = pose.refinement.budget() + 1
            pose.earliest = pose.refinement.minimum()

    def read(self, poses: list[Pose], states: Array) -> Readings:
        """MuJoCo's reading of each pose at its state: the loads applied at that state's
        own pose, a forward pass, the read-out of all at once (:meth:`.linkage_rig.LinkageRig.values`)."""
        rig = self.rig
        m, d = rig.model, rig.data
        qpos = states[:, self.qpos_slice]
        # The loads at each state's own pose, computed for all at once from its kinematics.
        sites, centres = rig.load_points(qpos)
        carried = np.array([p.carried for p in poses])
        xfrc, drives = rig.carried_loads(carried, sites[:, rig.pairs.sites]
                                         - centres[:, rig.pairs.bodies])
        xfrc += rig.wrenches(sites, centres, states[:, self.qvel_slice])
        snapshot = rig.snapshot(len(poses))
        rig.reset_carried()  # added to the equality forces below, for all at once
        targets = np.array([p.targets for p in poses]).reshape(len(poses), -1)
        if not _fast.reads(rig, states, targets, xfrc, drives, snapshot):
            for k in range(len(poses)):
                mujoco.mj_setState(m, d, states[k], STATE)
                rig.set_targets(targets[k])
                d.xfrc_applied[:] = xfrc[k]
                d.qfrc_applied[rig.drive_dofs] = drives[k]
                mujoco.mj_forward(m, d)
                mujoco.mj_rnePostConstraint(m, d)
                rig.capture(snapshot, k)
        snapshot.efc_force[:, :rig.nefc] += carried
        columns = rig.values(snapshot)
        analytic = self.qpos[[p.index for p in poses]]
        return Readings(
            names=list(columns),
            table=np.stack(list(columns.values()), axis=1),
            forces=np.stack([columns[q] for q in self.force_names], axis=1) * self.force_scale,
            totals=snapshot.efc_force[:, :rig.nefc].copy(),
            speed=np.abs(snapshot.qvel * rig.weight).max(axis=1, initial=0.0),
            gap=rig.loop_gaps(snapshot.efc_pos),
            drift=np.abs((snapshot.qpos - analytic) * rig.weight).max(axis=1, initial=0.0))

    # -- the run -------------------------------------------------------------------------
    def settle(self, targets: Array, first: Array | None = None) -> list[Settled]:
        """Every pose ``qpos[i]`` (drivers at ``targets[i]``) settled in passes, as
        :func:`.settle.settle_refined` settles one.

        ``first``: the poses are a sweep over these values of the first driver, in order.
        Every :data:`STRIDE`-th pose (and the last) then settles first, from nothing
        carried; each pose between starts with the constraint forces those two settled
        at, MuJoCo's own, interpolated in the driver's value (a sequential sweep would
        start each pose from the last ones). The start changes the steps, not the
        equilibrium: the passes still end only when two agree."""
        n = len(self.qpos)
        # A thread pool of this run's own: a pool kept in the process would be inherited,
        # without its threads, by a process forked from it (a sweep's workers), whose
        # rollouts then wait for ever (measured: the test suite hung).
        with contextlib.ExitStack() as stack:
            if self.stepper is None:
                self.runner = stack.enter_context(
                    rollout.Rollout(nthread=THREADS if THREADS > 1 else 0))
            else:
                # This thread steps one share of each round; the pool the others.
                self.threads = stack.enter_context(
                    ThreadPoolExecutor(max_workers=max(self.lanes - 1, 1)))
            if first is None:
                return complete(self.settle_poses(targets, range(n), {})[0])
            coarse = sorted({*range(0, n, STRIDE), n - 1})
            out, forces = self.settle_poses(targets, coarse, {})
            fine = [i for i in range(n) if out[i] is None]
            starts = {i: start for i in fine
                      if (start := interpolated(i, coarse, forces, first)) is not None}
            rest, _ = self.settle_poses(targets, fine, starts)
            rest = self.again_from_nothing(targets, rest, starts)
        return complete([o if o is not None else r for o, r in zip(out, rest, strict=True)])

    def again_from_nothing(self, targets: Array, results: list[Settled | None],
                           starts: dict[int, Array]) -> list[Settled | None]:
        """``results`` with every pose that started from its neighbours' forces and did not
        settle settled again from nothing carried, as alone, its steps counting both runs.

        Next to a change point the forces change too fast from pose to pose for a linear
        interpolation: measured on seed E1 between condition numbers 4 200 and 8 600, such
        a start held its first pass past the 3000 steps a pass from nothing needs."""
        again = [i for i in starts if (r := results[i]) is not None and not r.settled]
        if not again:
            return results
        retried, _ = self.settle_poses(targets, again, {})
        out = list(results)
        for i in again:
            first, second = results[i], retried[i]
            assert first is not None and second is not None
            out[i] = replace(second, steps=first.steps + second.steps)
        return out

    def settle_poses(self, targets: Array, which: Iterable[int], starts: dict[int, Array]
                     ) -> tuple[list[Settled | None], dict[int, Array]]:
        """The poses ``which``, each starting with ``starts[i]`` carried (else nothing):
        their Settled (None for the others) and the constraint forces each settled pose
        ended with."""
        nefc = self.rig.nefc
        poses = [Pose(i, targets[i], starts.get(i, np.zeros(nefc))) for i in which]
        self.seed(poses)
        if self.stepper is not None:
            return self.settle_compiled(poses)
        # The poses waiting, by the length of their next rollout: a refinement pass's
        # first is short (:data:`REFINE_CHUNK`); a wave takes poses of one length.
        queues = {CHUNK: deque(poses), REFINE_CHUNK: deque[Pose]()}
        out: list[Settled | None] = [None] * len(self.qpos)
        forces: dict[int, Array] = {}
        while any(queues.values()):
            # Short rollouts once they fill a wave, or when nothing else is left.
            short = queues[REFINE_CHUNK]
            nstep = REFINE_CHUNK if len(short) >= POOL or not queues[CHUNK] else CHUNK
            queue = queues[nstep]
            wave = [queue.popleft() for _ in range(min(POOL, len(queue)))]
            for pose, result in zip(wave, self.run_chunk(wave, nstep), strict=True):
                if result is not None:
                    out[pose.index] = result
                    if result.settled:
                        forces[pose.index] = pose.carried
                else:
                    queues[REFINE_CHUNK if pose.pass_steps == 0 else CHUNK].append(pose)
        return out, forces

    def settle_compiled(self, poses: list[Pose]
                        ) -> tuple[list[Settled | None], dict[int, Array]]:
        """:meth:`settle_poses` with each pass stepped to its end in numba, all the poses'
        passes at once (:meth:`step_passes`): the same passes, readings and stops."""
        out: list[Settled | None] = [None] * len(self.qpos)
        forces: dict[int, Array] = {}
        first_chunk = CHUNK  # a first pass's rollouts are all CHUNK long
        while poses:
            ended_at, rules, states = self.step_passes(poses, first_chunk)
            read = self.read(poses, states)
            finite = read.finite()
            going = []
            for j, pose in enumerate(poses):
                rule = RULES[rules[j]] if rules[j] >= 0 else ""
                result = self.end_pass(pose, read, j, int(ended_at[j]), rule, bool(finite[j]))
                if result is None:
                    going.append(pose)
                    continue
                out[pose.index] = result
                if result.settled:
                    forces[pose.index] = pose.carried
            self.seed(going)
            poses, first_chunk = going, REFINE_CHUNK
        return out, forces

    def step_passes(self, poses: list[Pose], first_chunk: int) -> tuple[Array, Array, Array]:
        """Each pose's pass stepped to its end (:func:`._fast.step_kernel.passes`), the
        poses dealt in turn to one thread per model copy (this one among them): where each
        pass's last reading is, the rule that fired there (−1: none), the state it was
        read at."""
        n = len(poses)
        targets = np.array([p.targets for p in poses]).reshape(n, -1)
        starts = np.array([p.state for p in poses])
        controls = np.array([p.control for p in poses])
        left = np.array([p.readings_left for p in poses], dtype=np.int64)
        early = np.array([p.earliest for p in poses], dtype=np.int64)
        ended_at = np.empty(n, dtype=np.int64)
        rules = np.empty(n, dtype=np.int64)
        states = np.empty_like(starts)
        shares = [np.arange(k, n, self.lanes) for k in range(min(self.lanes, n))]
        plans = [PassPlan(targets[rows], starts[rows], controls[rows], first_chunk, CHUNK,
                          left[rows], early[rows], self.columns, self.column_scale,
                          self.rig.weight, self.rig.rounding, np.empty(len(rows), dtype=np.int64),
                          np.empty(len(rows), dtype=np.int64), np.empty_like(starts[rows]))
                 for rows in shares]
        assert self.stepper is not None and self.threads is not None, "within settle()"
        _fast.step_passes(self.stepper, self.threads,
                          list(zip(self.pool, self.datas, strict=False))[:len(shares)],
                          self.rig.driver_eqs, plans)
        for rows, plan in zip(shares, plans, strict=True):
            ended_at[rows], rules[rows], states[rows] = plan.ended_at, plan.rules, plan.ended_state
        return ended_at, rules, states

    def run_chunk(self, wave: list[Pose], nstep: int) -> list[Settled | None]:
        """One rollout of ``nstep`` steps for the poses of ``wave``; for each, its final
        Settled, or None while it goes on."""
        eqs = self.rig.driver_eqs
        for eq_data, pose in zip(self.eq_data, wave, strict=False):
            eq_data[eqs, 0] = pose.targets
        initial = np.array([p.state for p in wave])
        # The controls held for the chunk, and the outputs, as the wrapper would make them
        # (tiled over the steps, allocated): its checks of every model, every call, were a
        # twentieth of a sweep, and the models are copies of one rig's.
        control = np.repeat(np.array([p.control for p in wave])[:, None, :], nstep, axis=1)
        states = np.empty((len(wave), nstep, initial.shape[1]))
        sensors = np.empty((len(wave), nstep, self.rig.model.nsensordata))
        assert self.runner is not None, "within settle()"
        self.runner.rollout(self.pool[:len(wave)], self.datas, initial, control,
                            control_spec=CONTROLS, nstep=nstep, skip_checks=True, state=states,
                            sensordata=sensors)
        readings = sensors[:, :, self.columns] * self.column_scale
        # The state each reading was taken at: the chunk's start, then each step's end.
        before = np.concatenate([initial[:, None], states[:, :-1]], axis=1)
        speed = np.abs(before[:, :, self.qvel_slice] * self.rig.weight).max(axis=2)
        # A pass reads at most its budget + 1 times and stops no earlier than its minimum
        # (run_until_settled's).
        left = np.array([p.readings_left - p.pass_steps for p in wave])
        early = np.array([p.earliest - p.pass_steps for p in wave])
        at = np.arange(nstep)[None, :]
        speed[(at >= left[:, None]) | (at < early[:, None])] = np.inf
        first, rule = _fast.first_stops(np.array([p.history for p in wave]), readings, speed,
                                  self.rig.rounding)
        out_of_budget = (left <= nstep) | ~np.isfinite(readings).all(axis=(1, 2))
        ended: list[tuple[int, int, str]] = []  # (pose in wave, step in chunk, rule or "")
        for k, pose in enumerate(wave):
            if first[k] >= 0:
                ended.append((k, int(first[k]), RULES[rule[k]]))
            elif out_of_budget[k]:
                ended.append((k, min(int(left[k]), nstep) - 1, ""))
            else:
                pose.pass_steps += nstep
                pose.history = np.concatenate([pose.history, readings[k]])[-(FLOOR_WINDOW - 1):]
                pose.state = states[k, -1]
        out: list[Settled | None] = [None] * len(wave)
        if ended:
            read = self.read([wave[k] for k, _, _ in ended],
                             np.array([before[k, step] for k, step, _ in ended]))
            finite = read.finite()
            for j, (k, step, stop) in enumerate(ended):
                out[k] = self.end_pass(wave[k], read, j, step, stop, bool(finite[j]))
            self.seed([wave[k] for k, _, _ in ended if out[k] is None])
        return out

    def end_pass(self, pose: Pose, read: Readings, j: int, step: int, rule: str,
                 finite: bool) -> Settled | None:
        """After ``pose``'s pass ended at ``step`` of the chunk (reading ``j`` of ``read``;
        ``rule`` "": out of budget), as :func:`.settle.settle_refined` goes on."""
        pose.refinement.ran(pose.pass_steps + step)
        if not rule or not finite:
            return self.result(pose, read, j, "", settled=False)
        forces = read.forces[j]
        size = max(float(np.abs(pose.previous).max()), FORCE_FLOOR_N) \
            if pose.previous is not None else FORCE_FLOOR_N
        if pose.previous is not None and pose.refinement.converged(
                float(np.abs(forces - pose.previous).max()) / size, self.rig.rounding / size):
            pose.carried = read.totals[j]  # what it ended with
            return self.result(pose, read, j, rule, settled=True)
        if pose.passes == MAX_PASSES:
            return self.result(pose, read, j, rule, settled=False)
        pose.previous = forces
        factor = pose.refinement.factor(pose.carried, read.totals[j], self.rig.efc_scale)
        pose.carried = pose.carried + factor * (read.totals[j] - pose.carried)
        pose.passes += 1
        return None  # seeded anew by the caller

    @staticmethod
    def result(pose: Pose, read: Readings, j: int, rule: str, settled: bool) -> Settled:
        return Settled(read.values(j), pose.refinement.total, settled, float(read.speed[j]),
                       float(read.gap[j]), passes=pose.passes,
                       refinement=pose.refinement.last_difference,
                       rule=rule if settled else "", pose_drift=float(read.drift[j]))


def state_slice(m: mujoco.MjModel, part: mujoco.mjtState) -> slice:
    """Where ``part`` (QPOS or QVEL) lies in a FULLPHYSICS state (time, qpos, qvel, …)."""
    before = sum(mujoco.mj_stateSize(m, bit) for bit in
                 (mujoco.mjtState.mjSTATE_TIME, mujoco.mjtState.mjSTATE_QPOS)
                 if int(bit) < int(part))
    return slice(before, before + mujoco.mj_stateSize(m, part))


def complete(results: list[Settled | None]) -> list[Settled]:
    """Every pose's result (each pose is settled by exactly one of the runs)."""
    out = [r for r in results if r is not None]
    assert len(out) == len(results)
    return out


def interpolated(i: int, coarse: list[int], forces: dict[int, Array],
                 first: Array) -> Array | None:
    """The constraint forces to start pose ``i`` with: those of the settled coarse poses on
    either side, linear in the first driver's value; the one settled, if only one did."""
    k = bisect.bisect(coarse, i)
    lo, hi = coarse[k - 1], coarse[k]
    if lo in forces and hi in forces and first[hi] != first[lo]:
        w = (first[i] - first[lo]) / (first[hi] - first[lo])
        return forces[lo] + w * (forces[hi] - forces[lo])
    return forces.get(lo, forces.get(hi))
