"""The fence: everything MuJoCo's Python objects are opened up for, for speed, and the one
seam the physics modules call it through (this module).

- :mod:`.pointers`: MuJoCo's C library (its functions' pointers, models' and data's
  addresses, the constraint arrays' place in MjData's arena, models copied in place);
- :mod:`.plans`: what the kernels are handed (named arrays);
- :mod:`.exact_kernel`, :mod:`.step_kernel`, :mod:`.stop_kernel`, :mod:`.drive_kernel`: the
  numba kernels.

Every function here either does its work compiled and says so (True, or a result), or
says it cannot (False, None), and the caller runs its own Python: the same MuJoCo calls
on the same data, so the same numbers (``tests/test_mujoco_compiled.py``). The kernels
compile only where numba is installed (:func:`mechcheck.sim_models.compiled.kernel`:
the ``fast`` extra; ``MECHCHECK_PURE_PYTHON=1`` switches them off), and the C pointers
only where MuJoCo's library is at a known place.
"""

from __future__ import annotations

import contextlib
import copy
import threading
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ThreadPoolExecutor
from types import ModuleType
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from mechcheck.sim_models.compiled import kernel
from mechcheck.sim_models.mujoco._fast.plans import (
    Capture,
    DrivePlan,
    EquationsPlan,
    PassData,
    PassPlan,
    PointsPlan,
    PostPlan,
    ReadsPlan,
)
from mechcheck.sim_models.mujoco._fast.pointers import (
    ArenaMoved,
    calls,
    check_arena,
    constraint_views,
    copy_into,
    copy_model,
    library,
)

if TYPE_CHECKING:
    from mechcheck.sim_models.mujoco.linkage_dynamics import PointLoads
    from mechcheck.sim_models.mujoco.linkage_rig import LinkageRig, Snapshot

Array = np.ndarray
_HERE = "mechcheck.sim_models.mujoco._fast"
#: The compiled stop rules, the per-pose loops, the passes.
STOP_KERNEL = f"{_HERE}.stop_kernel"
EXACT_KERNEL = f"{_HERE}.exact_kernel"
STEP_KERNEL = f"{_HERE}.step_kernel"
DRIVE_KERNEL = f"{_HERE}.drive_kernel"


# -- the stop rules -------------------------------------------------------------------
def first_stops(history: Array, readings: Array, speed: Array,
                rounding: float = 0.0) -> tuple[Array, Array]:
    """:func:`..settle.first_stops`, compiled where numba is installed."""
    compiled = kernel(STOP_KERNEL)
    if compiled is not None:
        return compiled.first_stops(history, readings, speed, rounding)
    from mechcheck.sim_models.mujoco.settle import first_stops as python
    return python(history, readings, speed, rounding)


# -- the per-pose loops ----------------------------------------------------------------
def loops() -> ModuleType | None:
    """The compiled per-pose loops, or None (the Python ones run)."""
    return kernel(EXACT_KERNEL) if library() is not None else None


def load_points(model: mujoco.MjModel, data: mujoco.MjData,
                qpos: Array) -> tuple[Array, Array] | None:
    """(site_xpos, xipos) after MuJoCo's kinematics at each pose of ``qpos``, compiled; None
    where it cannot be."""
    loop = loops()
    if loop is None:
        return None
    sites = np.empty((len(qpos), *data.site_xpos.shape))
    centres = np.empty((len(qpos), *data.xipos.shape))
    loop.load_points(calls(model, data), PointsPlan(np.ascontiguousarray(qpos), data.qpos,
                                                    data.site_xpos, data.xipos, sites, centres))
    return sites, centres


def lay_out(model: mujoco.MjModel, data: mujoco.MjData, nefc: int, qpos: Array, qvel: Array,
            held: Array, loads: Array) -> tuple[Array, ...]:
    """A forward pass at one pose, so that MjData's constraint arrays are laid out; views
    of them (:func:`.pointers.constraint_views`)."""
    data.qpos[:], data.qvel[:], model.eq_data[:, 0], data.xfrc_applied[:] = qpos, qvel, held, loads
    mujoco.mj_forward(model, data)
    return constraint_views(data, nefc, model.nv)


def in_place(model: mujoco.MjModel, data: mujoco.MjData, nefc: int, views: tuple[Array, ...],
             run: Callable[[], None]) -> bool:
    """``run`` a kernel writing through ``views``; whether the arena stayed put (else the
    caller's Python loop redoes the work)."""
    run()
    try:
        check_arena(data, views, nefc, model.nv)
    except ArenaMoved:
        return False
    return True


def equations(model: mujoco.MjModel, data: mujoco.MjData, nefc: int,
              state: tuple[Array, ...], columns: Array, loads: Array,
              out: tuple[Array, Array, Array, Array]) -> bool:
    """:func:`..linkage.constraint_equations`'s loop compiled, writing ``out`` (jac,
    efc_pos, qfrc_smooth, M·qacc per pose); whether it ran."""
    loop = loops()
    qpos, qvel, qacc = state
    if loop is None or not len(qpos):
        return False
    views = lay_out(model, data, nefc, qpos[0], qvel[0], columns[0], loads[0])
    plan = EquationsPlan(qpos, qvel, qacc, columns, loads, data.qpos, data.qvel,
                         model.eq_data[:, 0], data.xfrc_applied, views[0], views[1],
                         data.qfrc_smooth, *out, rolling=bool(qvel.any()),
                         moving=bool(qacc.any()))
    return in_place(model, data, nefc, views, lambda: loop.equations(calls(model, data), plan))


def post(model: mujoco.MjModel, data: mujoco.MjData, nefc: int, state: tuple[Array, ...],
         loads: Array, forces: Array, copies: Sequence[tuple[Array, Array]]) -> bool:
    """:func:`..linkage.post_constraint`'s loop compiled, copying each of ``copies``'
    sources into its target's row; whether it ran."""
    loop = loops()
    qpos, qvel, qacc = state
    if loop is None or not len(qpos) or not copies:
        return False
    rolling, tendons = bool(qvel.any()), bool(model.ntendon)
    views = lay_out(model, data, nefc, qpos[0], qvel[0] if rolling else data.qvel,
                    model.eq_data[:, 0], loads[0])
    plan = PostPlan(qpos, qvel, np.ascontiguousarray(qacc), loads, forces, data.qpos,
                    data.qvel, data.qacc, data.xfrc_applied, views[2],
                    tuple(t.reshape(len(qpos), -1) for t, _ in copies),
                    tuple(source.reshape(-1) for _, source in copies), rolling, tendons,
                    steady=not (tendons or qacc.any()))
    return in_place(model, data, nefc, views, lambda: loop.post(calls(model, data), plan))


def reads(rig: LinkageRig, states: Array, targets: Array, xfrc: Array, drives: Array,
          snapshot: Snapshot) -> bool:
    """:meth:`..batch_settle.BatchSettler.read`'s loop compiled: the same calls on the same
    data, so the same numbers. Not before the rig's data has had a forward pass (its
    constraint arrays are not laid out yet), nor if a pass laid them out elsewhere (then
    False, and the caller's loop runs again from the start)."""
    loop = loops()
    m, d = rig.model, rig.data
    if loop is None or d.efc_force.size != rig.nefc:
        return False
    views = constraint_views(d, rig.nefc, m.nv)
    n = len(states)
    plan = ReadsPlan(np.ascontiguousarray(states), int(mujoco.mjtState.mjSTATE_FULLPHYSICS),
                     m.eq_data, np.asarray(rig.driver_eqs, dtype=np.int64), targets, xfrc,
                     d.xfrc_applied, d.qfrc_applied, np.asarray(rig.drive_dofs, dtype=np.int64),
                     np.ascontiguousarray(drives).reshape(n, -1),
                     capture_plan(rig, views, snapshot, n))
    return in_place(m, d, rig.nefc, views, lambda: loop.reads(calls(m, d), plan))


def capture_plan(rig: LinkageRig, views: tuple[Array, ...], snapshot: Snapshot,
                 n: int) -> Capture:
    """What a kernel copies out at each of ``n`` reads (:meth:`..linkage_readout.RigReadout.
    capture`): the constraint ``views`` into ``snapshot``'s, each of the rig's captured
    arrays into its own."""
    return Capture(rig.carried, views[2], views[1], snapshot.efc_force, snapshot.efc_pos,
                   tuple(getattr(snapshot, field).reshape(n, -1) for field, _ in rig.captured),
                   tuple(source.reshape(-1) for _, source in rig.captured))


def drive(rig: LinkageRig, loads: PointLoads, steps: Array, snapshot: Snapshot) -> bool:
    """:func:`..linkage_dynamics.plain_stretch`'s loop compiled from the rig's current
    state: ``steps[k]`` steps, then reading k into row k of ``snapshot``; whether it ran
    (False: the state is untouched, or the arena moved and the caller starts again)."""
    compiled = kernel(DRIVE_KERNEL) if library() is not None else None
    if compiled is None:
        return False
    m, d = rig.model, rig.data
    # A forward pass lays the constraint arrays out; it changes nothing a step reads (the
    # solver's warm start is the last step's, kept by mj_Euler).
    mujoco.mj_forward(m, d)
    if d.efc_force.size != rig.nefc:
        return False
    views = constraint_views(d, rig.nefc, m.nv)
    n = len(steps)
    plan = DrivePlan(np.asarray(steps, dtype=np.int64), int(mujoco.mjtStage.mjSTAGE_POS),
                     loads.base + rig.extra, np.asarray(loads.sites, dtype=np.int64),
                     np.asarray(loads.bodies, dtype=np.int64), loads.fx, loads.fy,
                     loads.torques, d.xfrc_applied, d.site_xpos, d.xipos,
                     capture_plan(rig, views, snapshot, n))
    return in_place(m, d, rig.nefc, views, lambda: compiled.drive(calls(m, d), plan))


# -- model copies ----------------------------------------------------------------------
#: Copies of models, by their sizes (:func:`sizes`), and the lock a sweep holds while it
#: steps them (:func:`model_copies`).
COPIES: dict[tuple[int, ...], tuple[threading.Lock, list[mujoco.MjModel]]] = {}
COPIES_LOCK = threading.Lock()


def sizes(model: mujoco.MjModel) -> tuple[int, ...]:
    """Every size of ``model`` (its integer fields n…, the buffer's included): two models
    with the same sizes have the same layout, so one can be copied into the other."""
    return tuple(getattr(model, name) for name in dir(model)
                 if name.startswith("n") and isinstance(getattr(model, name), int))


@contextlib.contextmanager
def model_copies(model: mujoco.MjModel, n: int) -> Iterator[list[mujoco.MjModel]]:
    """``n`` copies of ``model`` for a batch's poses in flight (each its own drivers'
    targets), held while within. Models of the same sizes are copied into the ones the last
    such batch used, in place (``mj_copyModel``: 14 µs against 180 µs for a new copy through
    the Python binding, a tenth of a seed E1 sweep); where MuJoCo's library is not at a
    known place, new copies are made."""
    copier = copy_model()
    if copier is None:
        yield [copy.copy(model) for _ in range(n)]
        return
    with COPIES_LOCK:
        lock, kept = COPIES.setdefault(sizes(model), (threading.Lock(), []))
    with lock:
        kept += [copy.copy(model) for _ in range(n - len(kept))]
        for dest in kept[:n]:
            copy_into(copier, dest, model)
        yield kept[:n]


# -- the settling passes ---------------------------------------------------------------
def compiled_passes(model: mujoco.MjModel) -> ModuleType | None:
    """The compiled passes (:mod:`.step_kernel`) where numba is installed and MuJoCo's
    library is at a known place, for a model that is all the kernel sets up (no actuators
    or mocap bodies: the rollout would reset those); else None, and the rollouts run."""
    if model.nu or model.nmocap or library() is None:
        return None
    return kernel(STEP_KERNEL)


def pass_data(model: mujoco.MjModel, data: mujoco.MjData, driver_eqs: Array) -> PassData:
    """What :func:`.step_kernel.passes` resets and reads of ``model`` and ``data``."""
    controls = mujoco.mjtState.mjSTATE_XFRC_APPLIED | mujoco.mjtState.mjSTATE_QFRC_APPLIED
    return PassData(int(mujoco.mjtState.mjSTATE_FULLPHYSICS), int(controls), model.eq_data,
                    np.asarray(driver_eqs, dtype=np.int64), data.eq_active, model.eq_active0,
                    data.warning.number, data.qacc_warmstart, data.sensordata, data.qvel)


def step_passes(stepper: ModuleType, threads: ThreadPoolExecutor,
                lanes: Sequence[tuple[mujoco.MjModel, mujoco.MjData]], driver_eqs: Array,
                plans: Sequence[PassPlan]) -> None:
    """Each of ``plans`` (one per lane: a model copy and its data, the first lane this
    thread's) stepped by ``stepper`` (:func:`compiled_passes`), the others on ``threads``."""
    # Every argument made here first: a thread that ran Python while this one does
    # would hand Python's lock back and forth (measured: a tenth of a sweep).
    inputs = [(calls(m, d), pass_data(m, d, driver_eqs), plan)
              for (m, d), plan in zip(lanes, plans, strict=True)]
    jobs = [threads.submit(stepper.passes, mj, v, p) for mj, v, p in inputs[1:]]
    stepper.passes(*inputs[0])
    for job in jobs:
        job.result()
