"""Settled statics of many poses at once, stepped by ``mujoco.rollout`` (issue 13).

The poses of a static sweep settle exactly as :func:`.settle.settle_refined` settles one
(held by their drivers, started at rest in the analytic pose, passes with the constraint
forces carried, the same stop rules and budgets), but the stepping runs in MuJoCo's
multi-threaded rollout, ``CHUNK`` steps at a time for up to ``POOL`` poses, and Python
only looks at what it recorded:

- **What the stop rule watches.** Each step's forces come from MuJoCo's own force and
  torque sensors at every tree joint (the reaction of the parent on the child body,
  measured at the joint; torques divided by the size, as the single-pose rule divides the
  drivers'), recorded by the rollout at every step. With the loads fixed they change
  exactly when the equality forces :func:`.settle.run_until_settled` watches change, by
  the same modes; :func:`stop_steps` applies :class:`.settle.DecayWatch`'s three rules
  and the velocity bound to them, step by step, vectorised over the poses and steps.
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
"""

from __future__ import annotations

import bisect
import copy
from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass, field, replace

import mujoco
import numpy as np
from mujoco import rollout
from numpy.lib.stride_tricks import sliding_window_view

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage import Linkage
from mechcheck.analytic.solution import FORCE_FLOOR_N
from mechcheck.sim_models.convergence import disagreement
from mechcheck.sim_models.mujoco.linkage_model import body_name, spanning_tree
from mechcheck.sim_models.mujoco.linkage_rig import LinkageRig
from mechcheck.sim_models.mujoco.settle import (
    FLOOR_WINDOW,
    MAX_PASSES,
    MAX_STEPS,
    QUIET_RTOL,
    REFINE_RTOL,
    SETTLE_RTOL,
    STOP_WINDOW,
    VELOCITY_TOL,
    WOBBLE_RTOL,
    Settled,
    refinement_left,
)

Array = np.ndarray

#: Steps per rollout. A pass started from its neighbours' forces settles in 5–20 steps;
#: the steps stepped past the stop are wasted (measured on the Watt sweep: 8, 16 and 32
#: steps took 0.94, 0.84 and 1.07 ms/pose: shorter chunks cost more calls and rule checks).
CHUNK = 16
#: Poses in flight at once, each with its own copy of the model (178 µs a copy, measured).
POOL = 32
#: A sweep settles every STRIDE-th pose first, and starts the others from them
#: (:meth:`BatchSettler.settle`).
STRIDE = 8
#: Rollout threads: this machine's cores.
THREADS = 2
STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS
CONTROLS = mujoco.mjtState.mjSTATE_XFRC_APPLIED | mujoco.mjtState.mjSTATE_QFRC_APPLIED


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
    qpos: Array
    targets: Array
    state: Array = field(default_factory=lambda: np.zeros(0))
    control: Array = field(default_factory=lambda: np.zeros(0))
    carried: Array = field(default_factory=lambda: np.zeros(0))
    passes: int = 1
    steps: int = 0  # all passes
    pass_steps: int = 0  # readings taken in this pass
    history: Array = field(default_factory=lambda: np.zeros((0, 0)))
    previous: dict[str, float] | None = None
    differences: list[float] = field(default_factory=list)


def sensing_rig(case: Case) -> LinkageRig:
    """The static rig of ``case`` with :func:`add_reaction_sensors`."""
    return LinkageRig(case, customize=lambda spec: add_reaction_sensors(spec, case.linkage))


class BatchSettler:
    """Settles many poses of one linkage rig (:func:`sensing_rig`)."""

    def __init__(self, rig: LinkageRig) -> None:
        self.rig = rig
        m = rig.model
        self.pool = [copy.copy(m) for _ in range(POOL)]
        self.datas = [mujoco.MjData(m) for _ in range(THREADS)]
        self.nstate = mujoco.mj_stateSize(m, STATE)
        # Sensor columns: (fx, fy, fz, tx, ty, tz) per tree joint; the stop rule reads the
        # planar ones, torques over the size.
        n = m.nsensordata // 6
        cols = np.arange(n)[:, None] * 6 + np.array([0, 1, 5])
        self.columns = cols.ravel()
        self.column_scale = np.tile([1.0, 1.0, 1.0 / rig.scale], n)
        self.qvel_slice = self._state_slice(mujoco.mjtState.mjSTATE_QVEL)

    def _state_slice(self, part: mujoco.mjtState) -> slice:
        m = self.rig.model
        before = sum(mujoco.mj_stateSize(m, bit) for bit in
                     (mujoco.mjtState.mjSTATE_TIME, mujoco.mjtState.mjSTATE_QPOS)
                     if int(bit) < int(part))
        return slice(before, before + mujoco.mj_stateSize(m, part))

    # -- the rig's own data: seeds, controls, readings ------------------------------------
    def seeded(self, pose: Pose) -> None:
        """``pose`` at rest in its analytic pose, its carried forces as loads (the rig's data
        at that state; the pose's rollout state and controls from it)."""
        rig = self.rig
        m, d = rig.model, rig.data
        rig.set_state(pose.qpos, np.zeros(m.nv))
        rig.set_targets(pose.targets)
        rig.carried = pose.carried
        d.qfrc_applied[:] = 0.0  # set only while forces are carried
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        rig.apply_loads()
        pose.state = self.state_of(d)
        pose.control = np.concatenate([d.qfrc_applied, d.xfrc_applied.ravel()])
        pose.pass_steps = 0
        pose.history = np.full((FLOOR_WINDOW - 1, self.columns.size), np.nan)

    def state_of(self, d: mujoco.MjData) -> Array:
        out = np.empty(self.nstate)
        mujoco.mj_getState(self.rig.model, d, out, STATE)
        return out

    def reading(self, pose: Pose, state: Array, step: int, settled: bool, rule: str) -> Settled:
        """MuJoCo's reading at ``state`` of ``pose``: the loads at that state's own pose."""
        rig = self.rig
        m, d = rig.model, rig.data
        mujoco.mj_setState(m, d, state, STATE)
        rig.set_targets(pose.targets)
        rig.carried = pose.carried
        d.qfrc_applied[:] = 0.0
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        rig.apply_loads()
        mujoco.mj_forward(m, d)
        return Settled(rig.read(), step, settled, rig.joint_velocity(), rig.loop_violation(),
                       rule=rule, pose_drift=rig.pose_drift(qpos=pose.qpos))

    # -- the run -------------------------------------------------------------------------
    def settle(self, qpos: Array, targets: Array, first: Array | None = None) -> list[Settled]:
        """Every pose ``qpos[i]`` (drivers at ``targets[i]``) settled in passes, as
        :func:`.settle.settle_refined` settles one.

        ``first``: the poses are a sweep over these values of the first driver, in order.
        Every :data:`STRIDE`-th pose (and the last) then settles first, from nothing
        carried; each pose between starts with the constraint forces those two settled
        at, MuJoCo's own, interpolated in the driver's value (a sequential sweep would
        start each pose from the last ones). The start changes the
        steps, not the equilibrium: the passes still end only when two agree."""
        n = len(qpos)
        if first is None:
            return complete(self.settle_poses(qpos, targets, range(n), {})[0])
        coarse = sorted({*range(0, n, STRIDE), n - 1})
        out, forces = self.settle_poses(qpos, targets, coarse, {})
        fine = [i for i in range(n) if i not in forces and out[i] is None]
        starts = {i: start for i in fine
                  if (start := interpolated(i, coarse, forces, first)) is not None}
        rest, _ = self.settle_poses(qpos, targets, fine, starts)
        return complete([o if o is not None else r for o, r in zip(out, rest, strict=True)])

    def settle_poses(self, qpos: Array, targets: Array, which: Iterable[int],
                     starts: dict[int, Array]) -> tuple[list[Settled | None], dict[int, Array]]:
        """The poses ``which``, each starting with ``starts[i]`` carried (else nothing):
        their Settled (None for the others) and the constraint forces each settled pose
        ended with."""
        nefc = self.rig.nefc
        queue = deque(Pose(i, qpos[i], targets[i], carried=starts.get(i, np.zeros(nefc)))
                      for i in which)
        for pose in queue:
            self.seeded(pose)
        out: list[Settled | None] = [None] * len(qpos)
        forces: dict[int, Array] = {}
        while queue:
            wave = [queue.popleft() for _ in range(min(POOL, len(queue)))]
            for pose, result in zip(wave, self.run_chunk(wave), strict=True):
                if result is None:
                    queue.append(pose)
                    continue
                out[pose.index] = result
                if result.settled:
                    forces[pose.index] = pose.carried
        return out, forces

    def run_chunk(self, wave: list[Pose]) -> list[Settled | None]:
        """One rollout of ``CHUNK`` steps for the poses of ``wave``; for each, its final
        Settled, or None while it goes on."""
        for model, pose in zip(self.pool, wave, strict=False):
            model.eq_data[self.rig.driver_eqs, 0] = pose.targets
        initial = np.array([p.state for p in wave])
        control = np.array([p.control for p in wave])[:, None, :]
        states, sensors = rollout.rollout(self.pool[:len(wave)], self.datas, initial, control,
                                          control_spec=CONTROLS, nstep=CHUNK,
                                          persistent_pool=True)
        readings = sensors[:, :, self.columns] * self.column_scale
        # The state each reading was taken at: the chunk's start, then each step's end.
        before = np.concatenate([initial[:, None], states[:, :-1]], axis=1)
        speed = np.abs(before[:, :, self.qvel_slice] * self.rig.weight).max(axis=2)
        # A pass reads at most MAX_STEPS + 1 times (run_until_settled's budget).
        left = np.array([MAX_STEPS + 1 - p.pass_steps for p in wave])
        speed[np.arange(CHUNK)[None, :] >= left[:, None]] = np.inf
        first, rule = first_stops(np.array([p.history for p in wave]), readings, speed)
        return [self.advance(pose, int(first[k]), RULES[rule[k]], readings[k], before[k],
                             states[k, -1], int(left[k]))
                for k, pose in enumerate(wave)]

    def advance(self, pose: Pose, step: int, rule: str, readings: Array, before: Array,
                last: Array, left: int) -> Settled | None:
        """Finish ``pose``'s pass (and maybe the pose) where the rule fired at ``step`` of the
        chunk, or carry on (``step`` −1); out of budget after ``left`` readings."""
        if step >= 0:
            result = self.reading(pose, before[step], pose.steps + pose.pass_steps + step,
                                  True, rule)
            pose.steps += pose.pass_steps + step
            return self.end_pass(pose, result)
        if left <= CHUNK or not np.all(np.isfinite(readings)):
            taken = min(left, CHUNK)
            return self.unsettled(pose, before[taken - 1], pose.pass_steps + taken - 1)
        pose.pass_steps += CHUNK
        pose.history = np.concatenate([pose.history, readings])[-(FLOOR_WINDOW - 1):]
        pose.state = last
        return None

    def unsettled(self, pose: Pose, state: Array, step: int) -> Settled:
        result = self.reading(pose, state, pose.steps + step, False, "")
        return replace(result, passes=pose.passes, refinement=last_difference(pose))

    def end_pass(self, pose: Pose, result: Settled) -> Settled | None:
        """As :func:`.settle.settle_refined` after a settled pass."""
        rig = self.rig
        if not np.all(np.isfinite(list(result.values.values()))):
            return replace(result, settled=False, passes=pose.passes,
                           refinement=last_difference(pose))
        if pose.previous is not None:
            pose.differences.append(disagreement(result.values, pose.previous, rig.scale,
                                                 rig.units))
            if refinement_left(pose.differences) <= REFINE_RTOL:
                pose.carried = rig.total_constraint_forces().copy()  # what it ended with
                return replace(result, passes=pose.passes, refinement=last_difference(pose))
        if pose.passes == MAX_PASSES:
            return replace(result, settled=False, passes=MAX_PASSES,
                           refinement=last_difference(pose))
        pose.previous = result.values
        pose.carried = rig.total_constraint_forces().copy()
        pose.passes += 1
        self.seeded(pose)
        return None


RULES = ("decay", "quiet", "floor")


def complete(results: list[Settled | None]) -> list[Settled]:
    """Every pose's result (each pose is settled by exactly one of the runs)."""
    out = [r for r in results if r is not None]
    assert len(out) == len(results)
    return out


def last_difference(pose: Pose) -> float:
    return pose.differences[-1] if pose.differences else float("nan")


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


def first_stops(history: Array, readings: Array, speed: Array) -> tuple[Array, Array]:
    """For each pose of a wave, the first of its ``readings`` (P, T, m) at which
    :class:`.settle.DecayWatch` would say settled with the joints slower than
    :data:`.settle.VELOCITY_TOL` (``speed`` (P, T) at each reading): its index (−1 if
    none) and the rule that fired (an index into :data:`RULES`).

    ``history`` (P, FLOOR_WINDOW − 1, m) holds each pose's earlier readings of the pass,
    NaN where the pass has fewer: a window reaching back past the pass's first reading
    holds a NaN, and no rule fires on it, as no rule fires before its window is known.
    """
    back = history.shape[1]
    x = np.concatenate([history, readings], axis=1)
    size = np.maximum(np.abs(x).max(axis=2), FORCE_FLOOR_N)
    change = np.full(size.shape, np.nan)
    change[:, 1:] = np.abs(np.diff(x, axis=1)).max(axis=2) / size[:, 1:]
    # The windows ending at each reading of the chunk.
    windows = sliding_window_view(change, STOP_WINDOW, axis=1)[:, back - STOP_WINDOW + 1:]
    largest = windows.max(axis=2)
    with np.errstate(divide="ignore", invalid="ignore"):
        steps = windows[:, :, 1:] / windows[:, :, :-1]
        ratio = np.where(windows[:, :, :-1] > 0, steps, np.inf).max(axis=2)
        left = np.where(ratio < 1.0, largest * ratio / (1.0 - ratio), np.inf)
    decay = (largest == 0.0) | (left <= SETTLE_RTOL)
    quiet = largest <= QUIET_RTOL
    # The floor's spread only where the rest of its rule holds (a few readings): a window of
    # 32 readings at every one of them costs more than the rollout.
    floor = np.zeros_like(decay)
    for p, t in zip(*np.nonzero((largest <= WOBBLE_RTOL) & ~decay & ~quiet), strict=True):
        end = back + t + 1
        recent = x[p, end - FLOOR_WINDOW:end]
        floor[p, t] = (recent.max(axis=0) - recent.min(axis=0)).max() / size[p, end - 1] \
            <= WOBBLE_RTOL
    rule = np.where(decay, 0, np.where(quiet, 1, np.where(floor, 2, -1)))
    fired = (rule >= 0) & (speed <= VELOCITY_TOL)
    first = np.where(fired.any(axis=1), fired.argmax(axis=1), -1)
    return first, rule[np.arange(len(first)), first]
