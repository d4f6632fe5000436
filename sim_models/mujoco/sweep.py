"""Full-cycle sweeps over θ12 with either MuJoCo backend.

One model is compiled per sweep and reused for every pose (only θ12 changes). The
harness passes only poses that pass the pose gate (:func:`mechcheck.sweep.gated_poses`):
at a singular pose a simulator returns finite but meaningless numbers (SIMULATORS.md).
"""

from __future__ import annotations

import time
from functools import partial

import numpy as np
from numpy.typing import ArrayLike

from mechcheck.analytic.case import Case
from mechcheck.analytic.forces import unassemblable_solution
from mechcheck.analytic.solution import Solution
from mechcheck.sim_models.mujoco.dynamics import DrivenRigs, driven, driven_rigs
from mechcheck.sim_models.mujoco.mjwarnings import noting_warnings
from mechcheck.sim_models.mujoco.rig import Rig
from mechcheck.sim_models.mujoco.settle import settle_static
from mechcheck.sim_models.mujoco.solve import exact_rig, solve_at_pose, solve_state

BACKENDS = ("mujoco", "mujoco_solve")


def sweep(case: Case, theta12: ArrayLike, backend: str = "mujoco") -> list[Solution]:
    """Solutions of ``case`` at every θ12 (rad), in order.

    Parameters
    ----------
    backend : ``"mujoco"`` (settled statics, driven dynamics/friction) or
        ``"mujoco_solve"`` (exact constraint solve at each analytic pose).
    """
    if backend not in BACKENDS:
        raise ValueError(f"unknown MuJoCo backend {backend!r}; use one of {BACKENDS}")
    angles = np.atleast_1d(np.asarray(theta12, dtype=float))
    rig = sweep_rig(case, backend)
    if backend == "mujoco_solve" and not case.has_friction:
        return exact_sweep(case, angles, rig)
    return [solve_one(case.with_(theta12=float(t)), backend, rig) for t in angles]


def exact_sweep(case: Case, angles: np.ndarray, rig: Rig | DrivenRigs) -> list[Solution]:
    """``mujoco_solve`` over many poses with the analytic states computed at once."""
    assert isinstance(rig, Rig)
    qpos, qvel, qacc = rig.states(angles)
    out = []
    for i in range(len(angles)):
        if not np.all(np.isfinite(qpos[i])):  # no state to give MuJoCo
            out.append(unassemblable_solution(case, "mujoco_solve", float(angles[i])))
            continue
        out.append(noting_warnings(
            partial(solve_state, case, rig, qpos[i], qvel[i], qacc[i], time.perf_counter())))
    return out


def sweep_rig(case: Case, backend: str) -> Rig | DrivenRigs:
    """The compiled model(s) a sweep reuses (a driven run may need two, see
    :func:`~.dynamics.driven_rigs`)."""
    if backend == "mujoco_solve":
        return exact_rig(case)
    if case.kind == "static":
        return Rig(case)
    return driven_rigs(case)


def solve_one(case: Case, backend: str, rig: Rig | DrivenRigs) -> Solution:
    if isinstance(rig, DrivenRigs):
        return noting_warnings(lambda: driven(case, rig))
    if backend == "mujoco_solve":
        return noting_warnings(lambda: solve_at_pose(case, rig))
    return noting_warnings(lambda: settle_static(case, rig))
