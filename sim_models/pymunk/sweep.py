"""Full-cycle sweeps over θ12 with continuation: one Space, re-posed from pose to pose.

For statics the model is built once. At each θ12 the bodies are re-posed on
the closed-form pose (a seed), the drive lock's held angle is changed, and
the run settles (``pymunk``) or iterates at the fixed pose (``pymunk_solve``)
starting from the previous pose's accumulated impulses — pymunk's warm start
carries them over, which is what makes a neighbouring pose cheap.
Driven (dynamic or friction) cases are run pose by pose.

The harness passes only poses that pass the pose gate (:func:`mechcheck.sweep.gated_poses`);
a pose that cannot be assembled is still ``no_solution`` here, as there is nothing to place.
"""

from __future__ import annotations

import time

import numpy as np
from numpy.typing import ArrayLike

from mechcheck.analytic.case import Case
from mechcheck.analytic.forces import unassemblable_solution
from mechcheck.analytic.kinematics import pose_of
from mechcheck.analytic.solution import Solution
from mechcheck.sim_models.pymunk.model import build_model, place
from mechcheck.sim_models.pymunk.settings import SETTLE, SOLVE
from mechcheck.sim_models.pymunk.settle import solution_of, step_until_settled
from mechcheck.sim_models.pymunk.solve import iterate_at_pose

BACKENDS = ("pymunk", "pymunk_solve")


def sweep(case: Case, theta12: ArrayLike, backend: str = "pymunk") -> list[Solution]:
    """One Solution per θ12 (rad), in order, for backend ``pymunk`` or ``pymunk_solve``.

    A linkage sweeps its first driver instead (``theta12`` holds its values, rad or m
    from the drawn pose): :func:`mechcheck.sim_models.pymunk.linkage_sweep.sweep`.
    """
    if case.mechanism == "linkage":
        from mechcheck.sim_models.pymunk import linkage_sweep

        return linkage_sweep.sweep(case, theta12, backend)
    if backend not in BACKENDS:
        raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
    angles = np.atleast_1d(np.asarray(theta12, dtype=float))
    if case.kind != "static":
        return _driven_sweep(case, angles, backend)
    poses = pose_of(case, angles, omega=0.0, alpha=0.0)
    settings = SETTLE if backend == "pymunk" else SOLVE
    model = None
    out = []
    for k, theta in enumerate(angles):
        if not (np.isfinite(poses.theta13[k]) and np.isfinite(poses.theta14[k])):
            out.append(unassemblable_solution(case, backend, float(theta)))
            continue
        start = time.perf_counter()
        at = case.with_(theta12=float(theta))
        if model is None:
            model = build_model(at, settings)
        model.case = at
        place(model, poses, k)
        if backend == "pymunk":
            run = step_until_settled(model)
            method = "settle"
        else:
            run = iterate_at_pose(model, poses, k)
            method = "constraint_solve"
        sol = solution_of(model, run, backend, method, time.perf_counter() - start)
        out.append(Solution(sol.case, sol.backend, sol.values, sol.status, sol.message,
                            {**sol.diagnostics, "theta12": float(theta)}))
    return out


def _driven_sweep(case: Case, angles: np.ndarray, backend: str) -> list[Solution]:
    """Dynamic/friction cases: an independent driven run per pose (``pymunk`` only)."""
    from mechcheck.sim_models.pymunk.dynamics import drive
    from mechcheck.sim_models.pymunk.solve import not_applicable

    out = []
    for theta in angles:
        at = case.with_(theta12=float(theta)) if _assembles(case, float(theta)) else None
        if at is None:
            out.append(unassemblable_solution(case, backend, float(theta)))
        elif backend == "pymunk_solve":
            out.append(not_applicable(at))
        else:
            out.append(drive(at))
    return out


def _assembles(case: Case, theta: float) -> bool:
    pose = pose_of(case, np.array([theta]), omega=0.0, alpha=0.0)
    return bool(np.isfinite(pose.theta13[0]) and np.isfinite(pose.theta14[0]))
