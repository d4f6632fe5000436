"""The ``mujoco`` backend for statics: hold the mechanism and let it settle.

The crank (or, for ``drive_link = 4``, the rocker) is held by a joint
equality at the pose's angle; the loads are re-applied at the current pose
every step; the model is stepped until it has SETTLED — its joints at rest and
its forces no longer changing — never for a fixed number of steps.
Settling damps itself: with the driven link locked the mechanism has no
freedom left, and the only motion is the critically damped (dampratio 1)
relaxation of the soft constraints.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import mujoco
import numpy as np

from analytic.case import Case
from analytic.solution import Solution, quantity_kind
from sim_models.mujoco.rig import Rig

#: Settled when, between two steps, no force (and no torque divided by the
#: mechanism's length scale) changes by more than this fraction of the largest
#: of them. The relaxation is geometric (ratio ≈ 0.75 per step, measured), so
#: the error left is about 3× the last change: ~3e-9, well inside the 1e-6
#: static target.
FORCE_CHANGE_RTOL = 1e-9
#: ... and no joint moves faster than this (a point speed at the scale length, m/s).
VELOCITY_TOL = 1e-9
#: Step budget; a pose that has not settled by then is reported ``not_settled``.
#: Ordinary poses settle in 40–60 steps; near a change point the relaxation
#: slows like 1/δ² and the budget runs out, which is the honest verdict there.
MAX_STEPS = 3000


@dataclass(frozen=True)
class Settled:
    """What a settling run ended with."""

    values: dict[str, float]
    steps: int
    settled: bool
    residual_velocity: float
    loop_violation: float


def run_until_settled(rig: Rig, max_steps: int | None = None) -> Settled:
    """Step ``rig`` from its current state until settled or out of budget
    (``max_steps``, default :data:`MAX_STEPS`)."""
    max_steps = MAX_STEPS if max_steps is None else max_steps
    m, d = rig.model, rig.data
    mujoco.mj_kinematics(m, d)
    mujoco.mj_comPos(m, d)
    previous: np.ndarray | None = None
    settled = False
    step = 0
    for step in range(max_steps + 1):  # noqa: B007 - the step count is reported
        rig.apply_loads()
        mujoco.mj_forward(m, d)
        # The equality forces determine every reaction (the loads are known),
        # so their change is the force-change criterion; cheap to read each step.
        current = rig.constraint_forces()
        if previous is not None and has_settled(rig, current, previous):
            settled = True
            break
        previous = current
        mujoco.mj_Euler(m, d)
    return Settled(rig.read(), step, settled, rig.joint_velocity(), rig.loop_violation())


def has_settled(rig: Rig, current: np.ndarray, previous: np.ndarray) -> bool:
    """Forces unchanged (relative to the largest) and joints at rest."""
    size = max(float(np.abs(current).max()), 1e-300)
    change = float(np.abs(current - previous).max())
    return change <= FORCE_CHANGE_RTOL * size and rig.joint_velocity() <= VELOCITY_TOL


def seed_at(rig: Rig, theta12: float) -> None:
    """Start at rest in the analytic pose, with the driven link locked there."""
    q, _, _ = rig.qpos_at(theta12, 0.0, 0.0)
    mujoco.mj_resetData(rig.model, rig.data)
    rig.set_state(q, np.zeros(3))
    rig.set_lock(rig.lock_target(theta12))


def settled_solution(rig: Rig, theta12: float, result: Settled, elapsed: float) -> Solution:
    """A Solution from a settling run: forces only if it settled."""
    case = rig.case
    diagnostics: dict[str, float | str] = {
        "method": "settle", "steps": result.steps, "wall_time_s": elapsed,
        "residual_velocity": result.residual_velocity,
        "loop_violation": result.loop_violation,
        "pose_drift": rig.pose_drift(theta12),
    }
    if not result.settled:
        pose = {q: v for q, v in result.values.items() if quantity_kind(q) == "pose"}
        return Solution(case.name, "mujoco", pose, status="not_settled",
                        message=f"no equilibrium within {result.steps} steps "
                                f"(residual velocity {result.residual_velocity:.2e} m/s)",
                        diagnostics=diagnostics)
    return Solution(case.name, "mujoco", result.values, diagnostics=diagnostics)


def settle_static(case: Case, rig: Rig | None = None) -> Solution:
    """Static equilibrium of ``case`` by settling (no motion, no friction)."""
    start = time.perf_counter()
    rig = rig or Rig(case)
    seed_at(rig, case.theta12)
    result = run_until_settled(rig)
    return settled_solution(rig, case.theta12, result, time.perf_counter() - start)
