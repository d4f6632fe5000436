"""The MuJoCo backends for ``mechanism = "linkage"`` cases (issue 12).

- :func:`settle_linkage` — backend ``mujoco``: a static linkage held by its drivers is
  started at rest in the analytic pose and settled by the stop rules and refinement
  passes of :mod:`.settle`, the forces read from MuJoCo's state
  (:class:`.linkage_rig.LinkageRig`); free coordinates settle to their equilibrium from
  the drawn pose (:mod:`.linkage_free`); a moving linkage, or a static one with Coulomb
  friction, is driven through its prescribed (or quasi-static) motion
  (:mod:`.linkage_dynamics`).
- :func:`solve_linkage_at_pose` — backend ``mujoco_solve``: the constraint forces that make
  the analytic motion exact, from MuJoCo's own constraint Jacobian (as :mod:`.solve`),
  Coulomb friction iterated from the solved reactions.

Both are called only at poses that pass the pose gate (:func:`mechcheck.run.gated`), and
refuse, with the reason, what the builder cannot model (a loop without a revolute joint).
"""

from __future__ import annotations

import functools
import threading
import time

import mujoco
import numpy as np

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage_backends import analytic_results, quantity_units
from mechcheck.analytic.linkage_forces import LinkageResults, coulomb_terms
from mechcheck.analytic.solution import Solution
from mechcheck.sim_models.diagnostics import RunDiagnostics
from mechcheck.sim_models.inertia import real_inertial
from mechcheck.sim_models.linkage_motion import (
    driven_sweep,
    has_free_coordinates,
    is_driven,
    strain_verdict,
    unmodelled,
)
from mechcheck.sim_models.mujoco import _fast
from mechcheck.sim_models.mujoco.batch_settle import (
    BatchSettler,
    built_models,
    copies_needed,
    kept_models,
)
from mechcheck.sim_models.mujoco.joint_kinds import BUILDS
from mechcheck.sim_models.mujoco.linkage_dynamics import drive_linkage, drive_stretch
from mechcheck.sim_models.mujoco.linkage_free import settle_free
from mechcheck.sim_models.mujoco.linkage_friction import (
    apply_friction,
    clear_friction,
    friction_change,
)
from mechcheck.sim_models.mujoco.linkage_members import split_members
from mechcheck.sim_models.mujoco.linkage_mesh import pushing
from mechcheck.sim_models.mujoco.linkage_model import Unbuildable, spanning_tree
from mechcheck.sim_models.mujoco.linkage_rig import LinkageRig, Snapshot
from mechcheck.sim_models.mujoco.model import EXACT
from mechcheck.sim_models.mujoco.settle import (
    settle_refined,
    settled_solution,
    settled_solutions,
)
from mechcheck.sim_models.mujoco.solve import (
    FRICTION_MAX_PASSES,
    FRICTION_RTOL,
    batch_rigid_forces,
    impose_rigid_forces,
)

FREE_SWEEP_REFUSAL = ("the mujoco backend settles free coordinates case by case, from the "
                      "drawn pose; a sweep of them is not simulated")


def refused(case: Case, backend: str, why: str) -> Solution:
    return Solution(case.name, backend, {}, status="not_applicable", message=why,
                    units=quantity_units(case.linkage))


def driver_values(case: Case) -> np.ndarray:
    return np.array([d.value for d in case.linkage.drivers])


def unbuildable(case: Case) -> str | None:
    """Why the builder has no model of the linkage, or None."""
    try:
        spanning_tree(case.linkage)
    except Unbuildable as error:
        return str(error)
    return None


#: Why elastic members are settled only where the drivers hold everything.
HELD_MEMBERS_ONLY = ("the MuJoCo model settles elastic members only in a linkage held still "
                     "by its drivers: a driven run and free coordinates are not simulated with "
                     "them")


def unsettled_members(case: Case) -> str | None:
    """Why the ``mujoco`` backend does not run a linkage with split members
    (:mod:`.linkage_members`), or None: it moves, or has free coordinates."""
    if split_members(case.linkage) and (is_driven(case) or has_free_coordinates(case)):
        return HELD_MEMBERS_ONLY
    return None


def rigid_only(case: Case) -> str | None:
    """Why the exact solve has no answer: a kind it does not build, or a redundant
    linkage's members' stretch (its constraint forces are those of rigid bodies)."""
    return unmodelled(case.linkage, BUILDS, "MuJoCo")


def settle_linkage(case: Case, rig: LinkageRig | None = None,
                   results: LinkageResults | None = None) -> Solution:
    """The ``mujoco`` backend for a static linkage held by its drivers.

    ``rig`` and ``results`` (the analytic pose analysis) may be given by a sweep.
    """
    start = time.perf_counter()
    why = unbuildable(case) or unsettled_members(case)
    if why is not None:
        return refused(case, "mujoco", why)
    results = results if results is not None else analytic_results(case)
    if is_driven(case):
        return drive_linkage(case, results)
    if has_free_coordinates(case):
        return settle_free(case, results)
    held = rig or LinkageRig(case)

    def run() -> Solution:
        qpos = seed(held, held.joint_states(results.pose)[0][0], driver_values(case))
        result = settle_refined(held, qpos)
        return strain_verdict(held.members,
                              settled_solution(held, qpos, result, time.perf_counter() - start),
                              "MuJoCo")

    return pushing([held.meshes], run, lambda solution: solution.values)


def seed(rig: LinkageRig, qpos: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """At rest in the analytic pose ``qpos``, drivers held at ``targets``, nothing
    carried; returns ``qpos``."""
    mujoco.mj_resetData(rig.model, rig.data)
    rig.set_state(qpos, np.zeros_like(qpos))
    rig.set_targets(targets)
    rig.reset_carried()
    return qpos


def exact_linkage_rig(case: Case) -> LinkageRig:
    """A rig for the exact solve: the Case's own masses, massless links massless.

    MuJoCo's compiler refuses massless moving bodies and zero inertias, but the solve only
    multiplies by M, so the fictitious mass of a massless link and the floor inertia of
    a point mass are removed after compiling (a unit armature on every joint, subtracted
    exactly, keeps M invertible; see :data:`.model.EXACT`).
    """
    rig = LinkageRig(case, EXACT)
    model = rig.model
    for link in case.linkage.moving_links:
        body = rig.body[link]
        real = real_inertial(case.linkage, link)
        model.body_mass[body] = 0.0 if real is None else real.mass
        model.body_inertia[body] = 0.0 if real is None else real.inertia
    # MuJoCo caches the inertia of "simple" bodies at compile time (dof_M0), and its
    # mj_setConst refuses a massless moving body: the cache is switched off instead.
    model.body_simple[:] = 0
    model.dof_simplenum[:] = 0
    return rig


@functools.lru_cache(maxsize=8)
def sweep_rig(case: Case) -> LinkageRig:
    """:func:`exact_linkage_rig`, kept for the next exact sweep of the same Case (a Case is
    immutable, and so is the model built from it): building it is a sweep's largest fixed
    cost. :func:`exact_sweep` sets everything it reads (state, targets, loads, forces) and
    resets the rest of the data and the emulated friction before it starts; one sweep at a
    time uses it (:data:`SWEEP_RIG_LOCK`)."""
    return exact_linkage_rig(case)


#: Held while a kept rig (:func:`sweep_rig`) is in use: threads would share its MjData.
SWEEP_RIG_LOCK = threading.Lock()


def solve_linkage_at_pose(case: Case, rig: LinkageRig | None = None,
                          results: LinkageResults | None = None, index: int = 0) -> Solution:
    """The ``mujoco_solve`` backend: exact constraint forces at the analytic pose (row
    ``index`` of ``results``, the analytic pose analysis, which a sweep may give)."""
    start = time.perf_counter()
    why = unbuildable(case) or rigid_only(case)
    if why is not None:
        return refused(case, "mujoco_solve", why)
    exact = rig or exact_linkage_rig(case)
    results = results if results is not None else analytic_results(case)
    states = exact.joint_states(results.pose)

    def run() -> Solution:
        return exact_solution(case, exact, tuple(a[index] for a in states),
                              results.pose.drivers[index], start, senses_at(results, index))

    return pushing([exact.meshes], run, lambda solution: solution.values)


def senses_at(results: LinkageResults, index: int) -> dict[str, float]:
    """The sense of each Coulomb joint's relative motion at pose ``index``, as the analytic
    motion prescribes it (the drivers' velocities or quasi-static senses)."""
    return {t.joint.name: float(t.sense[index]) for t in coulomb_terms(results.pose)}


def constraint_solve(rig: LinkageRig, qacc: np.ndarray) -> tuple[dict[str, float], float]:
    """The rigid constraint forces at the rig's state and the reading; the equations'
    residual."""
    residual = constraint_forces_at(rig, qacc)
    return rig.read(), residual


def constraint_forces_at(rig: LinkageRig, qacc: np.ndarray) -> float:
    """Impose the rigid constraint forces of the motion ``qacc`` at the rig's state, the
    loads applied there; returns the equations' residual (:func:`.solve.impose_rigid_forces`)."""
    m, d = rig.model, rig.data
    mujoco.mj_kinematics(m, d)  # load points and centres of mass for the loads
    mujoco.mj_comPos(m, d)
    rig.apply_loads()
    mujoco.mj_forward(m, d)
    return impose_rigid_forces(m, d, qacc)


def exact_solution(case: Case, rig: LinkageRig, state: tuple[np.ndarray, ...],
                   targets: np.ndarray, start: float,
                   senses: dict[str, float] | None = None) -> Solution:
    """The exact solve at the analytic joint ``state`` (qpos, qvel, qacc) with the drivers
    at ``targets``; ``start`` times it.

    With Coulomb friction (``senses``: each joint's sense of motion) the friction loads
    come from the reactions and the reactions from the loads, repeated until they agree
    to :data:`.solve.FRICTION_RTOL`.
    """
    qpos, qvel, qacc = state
    clear_friction(rig)
    rig.set_state(qpos, qvel)
    rig.set_targets(targets)
    values, residual = constraint_solve(rig, qacc)
    passes = 0
    if senses:
        for passes in range(1, FRICTION_MAX_PASSES + 1):  # noqa: B007 - reported
            apply_friction(rig, values, {j.name: senses.get(j.name, 0.0)
                                         for j in case.linkage.joints})
            new, residual = constraint_solve(rig, qacc)
            change, values = friction_change(new, values), new
            if change <= FRICTION_RTOL:
                break
    diagnostics = RunDiagnostics("constraint_solve", passes, time.perf_counter() - start,
                                 0.0, rig.loop_violation(), 0.0).as_dict(equation_residual=residual)
    return Solution(case.name, "mujoco_solve", values, diagnostics=diagnostics,
                    units=rig.units or {})


def exact_sweep(case: Case, rig: LinkageRig, results: LinkageResults) -> list[Solution]:
    """The exact solve (:func:`exact_solution`) at every pose of ``results``, without
    Coulomb friction (nothing to iterate), in three passes over the poses so that the
    linear algebra and the read-out run once for all of them: the load points (MuJoCo's
    kinematics), the constraint equations (its forward pass: Jacobian and smooth forces),
    then, with the batch's forces imposed, ``mj_rnePostConstraint``
    (:func:`post_constraint`), read at once (:meth:`.linkage_rig.LinkageRig.values`). The
    wall time reported per pose is the sweep's share."""
    start = time.perf_counter()
    state = rig.joint_states(results.pose)
    clear_friction(rig)
    # A rig may be reused (:func:`sweep_rig`): MuJoCo warns once per MjData, so its
    # warnings are reset with the rest of the data, to be raised again where they apply.
    mujoco.mj_resetData(rig.model, rig.data)
    sites, centres = rig.load_points(state[0])
    loads = rig.wrenches(sites, centres, state[1])
    jac, rhs, efc_pos = constraint_equations(rig, state, results.pose.drivers, loads)
    forces, residual = batch_rigid_forces(jac, rhs)
    known = {"qpos": state[0], "qvel": state[1], "qacc": state[2], "efc_force": forces,
             "efc_pos": efc_pos, "site_xpos": sites}
    columns = rig.values(post_constraint(rig, state, loads, known))
    share = (time.perf_counter() - start) / max(len(state[0]), 1)
    common = RunDiagnostics("constraint_solve", 0, share, 0.0, 0.0, 0.0).as_dict()
    return Solution.batch(
        case.name, "mujoco_solve", tuple(columns),
        np.column_stack(list(columns.values())).tolist(),
        ({**common, "loop_violation": gap, "equation_residual": r}
         for gap, r in zip(rig.loop_gaps(efc_pos).tolist(), residual.tolist(), strict=True)),
        rig.units or {})


def post_constraint(rig: LinkageRig, state: tuple[np.ndarray, ...], loads: np.ndarray,
                    known: dict[str, np.ndarray]) -> Snapshot:
    """The read-out arrays of every pose of ``state`` (qpos, qvel, qacc) with the
    constraint forces ``known["efc_force"]`` imposed: MuJoCo's kinematics (the whole
    forward pass if the linkage has springs: their tendons' lengths and pull on their
    sites), then ``mj_rnePostConstraint`` with ``loads`` as xfrc_applied. The arrays
    ``known`` already (the state, the constraint arrays, the sites' positions from the
    same kinematics) are taken as they are; of the rest, only what the read-out reads is
    copied per pose (:attr:`.linkage_rig.LinkageRig.derived`)."""
    m, d = rig.model, rig.data
    qpos, qvel, qacc = state
    snapshot = rig.snapshot(len(qpos))
    for field, given in known.items():
        getattr(snapshot, field)[:] = given
    copies = [(getattr(snapshot, field), source) for field, source in rig.derived
              if field not in known]
    forces = known["efc_force"]
    if _fast.post(m, d, rig.nefc, state, loads, forces, copies):
        return snapshot
    # qacc is written at each pose where a forward pass overwrites it or the poses accelerate.
    tendons, rolling = bool(m.ntendon), bool(qvel.any())
    steady = not (tendons or qacc.any())
    d.qacc[:] = 0.0
    for i in range(len(qpos)):
        d.qpos[:] = qpos[i]
        if rolling:  # else qvel is 0 since the data was reset (:func:`exact_sweep`)
            d.qvel[:] = qvel[i]
        d.xfrc_applied[:] = loads[i]
        if tendons:
            mujoco.mj_forward(m, d)
        else:  # what the RNE reads
            mujoco.mj_kinematics(m, d)
            mujoco.mj_comPos(m, d)
            mujoco.mj_comVel(m, d)
        d.efc_force[:rig.nefc] = forces[i]
        if not steady:
            d.qacc[:] = qacc[i]
        mujoco.mj_rnePostConstraint(m, d)
        for target, source in copies:
            target[i] = source
    return snapshot


def constraint_equations(rig: LinkageRig, state: tuple[np.ndarray, ...], targets: np.ndarray,
                         loads: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """MuJoCo's forward pass at each pose of ``state`` (qpos, qvel, qacc: (N, nv) each),
    drivers at ``targets``, with ``loads`` as xfrc_applied: the constraint Jacobians J
    (N, nefc, nv), the right-hand sides M·qacc − qfrc_smooth of Jᵀ f = rhs (armature
    excluded, as :func:`.solve.impose_rigid_forces`) and the constraints' efc_pos
    (N, nefc)."""
    m, d = rig.model, rig.data
    qpos, qvel, qacc = state
    n, nefc = len(qpos), rig.nefc
    size = nefc * m.nv
    jac = np.empty((n, size))
    smooth = np.empty((n, m.nv))
    inertial = np.zeros((n, m.nv))
    efc_pos = np.empty((n, nefc))
    moving, rolling = bool(qacc.any()), bool(qvel.any())
    d.qvel[:] = 0.0
    # The drivers' targets (:meth:`.linkage_rig.LinkageRig.set_targets`) as whole columns of
    # eq_data, one per pose: one copy each instead of a scatter.
    held = m.eq_data[:, 0]
    columns = np.repeat(held[None], n, axis=0)
    columns[:, rig.driver_eqs] = targets
    if _fast.equations(m, d, nefc, state, columns, loads, (jac, efc_pos, smooth, inertial)):
        return finish_equations(rig, jac, inertial, smooth, qacc, efc_pos)
    for i in range(n):
        d.qpos[:] = qpos[i]
        if rolling:
            d.qvel[:] = qvel[i]
        held[:] = columns[i]
        d.xfrc_applied[:] = loads[i]
        mujoco.mj_forward(m, d)
        jac[i] = d.efc_J[:size]
        efc_pos[i] = d.efc_pos[:nefc]
        smooth[i] = d.qfrc_smooth
        if moving:
            mujoco.mj_mulM(m, d, inertial[i], qacc[i])
    return finish_equations(rig, jac, inertial, smooth, qacc, efc_pos)


def finish_equations(rig: LinkageRig, jac: np.ndarray, inertial: np.ndarray,
                     smooth: np.ndarray, qacc: np.ndarray, efc_pos: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(J, rhs, efc_pos) of :func:`constraint_equations` from its per-pose arrays."""
    m = rig.model
    rhs = inertial - m.dof_armature * qacc - smooth
    return jac.reshape(len(jac), rig.nefc, m.nv), rhs, efc_pos


def sweep_linkage(case: Case, first: np.ndarray, backend: str = "mujoco",
                  results: LinkageResults | None = None, *,
                  continuation: bool = True) -> list[Solution]:
    """Either backend at every value of the linkage's first driver (rad or m, from the
    drawn pose; the other drivers at the case's values), in order.

    The analytic pose analysis (``results``, computed here unless given) is done once,
    vectorised, and each pose is seeded from its analytic pose. Settled statics are
    stepped in batches (:func:`settled_sweep`); poses continue from their settled
    neighbours' constraint forces — MuJoCo's own — as carried loads (:mod:`.rig`), so the
    constraints hold only the change from pose to pose and settle sooner. The refinement
    passes still end only when two passes agree, so the start changes the steps, not the
    equilibrium (``continuation=False``: every pose from nothing carried, as when solved
    alone). The exact solve runs as one batch (:func:`exact_sweep`), pose by pose with
    Coulomb friction.
    """
    first = np.asarray(first, dtype=float)
    why = unbuildable(case) or (unsettled_members(case) if backend == "mujoco" else rigid_only(case))
    if backend == "mujoco" and why is None and is_driven(case):
        return driven_sweep(case, first, settle_linkage, drive_stretch, results)
    if backend == "mujoco":
        why = why or (FREE_SWEEP_REFUSAL if has_free_coordinates(case) else None)
    if why is not None:
        return [refused(case, backend, why)] * len(first)
    if results is None:
        results = analytic_results(case, np.asarray(first, dtype=float))
    if spanning_tree(case.linkage).meshes or split_members(case.linkage):
        # A member's spring is never carried as a load, as the batches carry every row.
        return pose_by_pose(case, backend, results)
    if backend == "mujoco":
        return settled_sweep(case, first, results, continuation)
    if not coulomb_terms(results.pose):  # buildable (checked above), nothing to iterate
        with SWEEP_RIG_LOCK:
            return exact_sweep(case, sweep_rig(case), results)
    rig = exact_linkage_rig(case)
    states = rig.joint_states(results.pose)
    targets = results.pose.drivers
    out = []
    for i in range(len(first)):
        start = time.perf_counter()
        out.append(exact_solution(case, rig, tuple(a[i] for a in states), targets[i], start,
                                  senses_at(results, i)))
    return out


def pose_by_pose(case: Case, backend: str, results: LinkageResults) -> list[Solution]:
    """Either backend at each pose of ``results`` with one model, one pose at a time: a gear
    mesh's tendon is put on its line of action from the model's state before every forward
    pass (:mod:`.linkage_mesh`), which the batched sweeps do not do."""
    if backend == "mujoco":
        return [held_at(case, LinkageRig(case), results, i) for i in range(len(results.pose.q))]
    exact = exact_linkage_rig(case)
    return [solve_linkage_at_pose(case, exact, results, i) for i in range(len(results.pose.q))]


def held_at(case: Case, rig: LinkageRig, results: LinkageResults, index: int) -> Solution:
    """Settled statics at pose ``index`` of ``results``, its drivers held there."""
    start = time.perf_counter()
    pose = rig.joint_states(results.pose)[0][index]

    def run() -> Solution:
        qpos = seed(rig, pose, results.pose.drivers[index])
        return strain_verdict(rig.members, settled_solution(rig, qpos, settle_refined(rig, qpos),
                                                            time.perf_counter() - start), "MuJoCo")

    return pushing([rig.meshes], run, lambda solution: solution.values)


def settled_sweep(case: Case, first: np.ndarray, results: LinkageResults,
                  continuation: bool) -> list[Solution]:
    """Settled statics at every pose of ``results``, stepped in batches by MuJoCo's rollout
    (:class:`.batch_settle.BatchSettler`); ``continuation``: the poses between every
    STRIDE-th start from the constraint forces those settled at. The wall time reported
    per pose is the sweep's share."""
    start = time.perf_counter()
    try:
        models = kept_models(case)
    except TypeError:  # should a Case ever hold an unhashable value: built for this sweep
        models = built_models(case)
    rig = models.rig
    with models.lock, _fast.model_copies(rig.model, copies_needed(rig.model, len(first))) as pool:
        qpos = rig.joint_states(results.pose)[0]
        settled = BatchSettler(models, pool, qpos).settle(results.pose.drivers,
                                                          first if continuation else None)
        share = (time.perf_counter() - start) / max(len(first), 1)
        return settled_solutions(rig, qpos, settled, share)
