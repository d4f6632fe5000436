"""The MuJoCo backends for ``mechanism = "linkage"`` cases (issue 12).

- :func:`settle_linkage` — backend ``mujoco``: the drivers held by joint equalities at
  their values, the model started at rest in the analytic pose and settled by the stop
  rules and refinement passes of :mod:`.settle`, the forces read from MuJoCo's state
  (:class:`.linkage_rig.LinkageRig`).
- :func:`solve_linkage_at_pose` — backend ``mujoco_solve``: the constraint forces that make
  the analytic motion exact, from MuJoCo's own constraint Jacobian (as :mod:`.solve`).

Both give the pose verdict the analytic backend gives (a pose that does not assemble, a
singular or indeterminate one: no forces), and refuse, with the reason, what they do not
model yet.
"""

from __future__ import annotations

import time

import mujoco
import numpy as np

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage_backends import analytic_results, quantity_units, verdict
from mechcheck.analytic.linkage_forces import LinkageResults
from mechcheck.analytic.solution import Solution
from mechcheck.sim_models.mujoco.linkage_model import Unbuildable, real_inertial, spanning_tree
from mechcheck.sim_models.mujoco.linkage_rig import LinkageRig
from mechcheck.sim_models.mujoco.model import EXACT
from mechcheck.sim_models.mujoco.settle import settle_refined, settled_solution
from mechcheck.sim_models.mujoco.solve import impose_rigid_forces

SETTLE_REFUSALS = {
    "dynamic": "the mujoco backend settles linkages held by their drivers; a driven "
               "(moving) linkage is not simulated yet",
    "friction": "the mujoco backend does not emulate joint friction of linkages yet",
    "free": "the mujoco backend holds every coordinate by a driver; settling free "
            "coordinates to their equilibrium is not modelled yet",
}
COULOMB_REFUSAL = ("the mujoco_solve backend does not emulate Coulomb friction of "
                   "linkages yet")


def refused(case: Case, backend: str, why: str) -> Solution:
    return Solution(case.name, backend, {}, status="not_applicable", message=why,
                    units=quantity_units(case.linkage))


def withheld(case: Case, backend: str, results: LinkageResults) -> Solution | None:
    """The analytic backend's verdict on the pose (no forces there), or None."""
    found = verdict(case, results, 0)
    if found is None:
        return None
    return Solution(case.name, backend, {}, status=found[0], message=found[1],
                    units=quantity_units(case.linkage))


def driver_values(case: Case) -> np.ndarray:
    return np.array([d.value for d in case.linkage.drivers])


def unbuildable(case: Case) -> str | None:
    """Why the builder has no model of the linkage (checked before any pose verdict: no
    pose of it is modelled), or None."""
    try:
        spanning_tree(case.linkage)
    except Unbuildable as error:
        return str(error)
    return None


def settle_refusal(case: Case) -> str | None:
    if case.kind != "static":
        return SETTLE_REFUSALS[case.kind]
    if case.linkage.dof > len(case.linkage.drivers):
        return SETTLE_REFUSALS["free"]
    return None


def settle_linkage(case: Case, rig: LinkageRig | None = None,
                   results: LinkageResults | None = None) -> Solution:
    """The ``mujoco`` backend for a static linkage held by its drivers.

    ``rig`` and ``results`` (the analytic pose analysis) may be given by a sweep.
    """
    start = time.perf_counter()
    why = unbuildable(case) or settle_refusal(case)
    if why is not None:
        return refused(case, "mujoco", why)
    rig = rig or LinkageRig(case)
    results = results if results is not None else analytic_results(case)
    gated = withheld(case, "mujoco", results)
    if gated is not None:
        return gated
    qpos = seed(rig, results, driver_values(case))
    result = settle_refined(rig, qpos)
    return settled_solution(rig, qpos, result, time.perf_counter() - start)


def seed(rig: LinkageRig, results: LinkageResults, targets: np.ndarray, index: int = 0) -> np.ndarray:
    """At rest in the analytic pose (row ``index``), drivers held at ``targets``,
    nothing carried; returns the pose's joint coordinates."""
    qpos = rig.joint_states(results.pose)[0][index]
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


def solve_linkage_at_pose(case: Case, rig: LinkageRig | None = None,
                          results: LinkageResults | None = None, index: int = 0) -> Solution:
    """The ``mujoco_solve`` backend: exact constraint forces at the analytic pose (row
    ``index`` of ``results``, the analytic pose analysis, which a sweep may give)."""
    start = time.perf_counter()
    if case.has_coulomb_friction:
        return refused(case, "mujoco_solve", COULOMB_REFUSAL)
    why = unbuildable(case)
    if why is not None:
        return refused(case, "mujoco_solve", why)
    rig = rig or exact_linkage_rig(case)
    results = results if results is not None else analytic_results(case)
    gated = withheld(case, "mujoco_solve", results)
    if gated is not None:
        return gated
    m, d = rig.model, rig.data
    qpos, qvel, qacc = (a[index] for a in rig.joint_states(results.pose))
    rig.set_state(qpos, qvel)
    rig.set_targets(results.pose.drivers[index])
    mujoco.mj_kinematics(m, d)  # load points and centres of mass for the loads
    mujoco.mj_comPos(m, d)
    rig.apply_loads()
    mujoco.mj_forward(m, d)
    residual = impose_rigid_forces(m, d, qacc)
    values = rig.read()
    diagnostics: dict[str, float | str] = {
        "method": "constraint_solve", "steps": 0, "wall_time_s": time.perf_counter() - start,
        "residual_velocity": 0.0, "loop_violation": rig.loop_violation(), "pose_drift": 0.0,
        "equation_residual": residual,
    }
    return Solution(case.name, "mujoco_solve", values, diagnostics=diagnostics,
                    units=quantity_units(case.linkage))
