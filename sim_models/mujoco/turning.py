"""Seed 001's mechanism theory measured in MuJoCo: turn the crank and see.

Two experiments, both read from MuJoCo's own state (joint coordinates,
actuator and equality forces); the analytic side only seeds the first pose.

- :func:`turn_crank` drives the crank with a **velocity servo of bounded
  torque** (a MuJoCo velocity actuator with ``forcerange``) and records θ12,
  θ13 and θ14 (or s14) every step. A crank that can turn (Grashof crank-rocker,
  double-crank, rotatable slider-crank) completes its turns; one that cannot
  runs into a toggle — coupler and rocker (or rod and slide normal) in line —
  where the servo saturates and the crank stops: the run is then repeated in
  the other sense, and the two rest angles are the **reachable range** of θ12.
  From a completed turn, :meth:`TurnResult.rocker_extremes` finds the
  extremes of θ14 and the crank angles where they occur (the dead positions
  of :func:`mechcheck.analytic.theory.limit_positions`).
- :func:`amplification` holds the crank (the model's ``drive`` joint equality)
  at each θ12 against a pure torque on the rocker (or a force along the slide)
  and lets the model settle; the equality's force is the holding torque T12,
  so T12 / T_out is the force amplification, which for a rigid linkage is
  −ω4/ω2 (virtual work) and grows without bound toward a toggle.

The simulator-independent parts (the run protocol, the result types and the
extreme finder) are in :mod:`mechcheck.sim_models.turning`, shared with
:mod:`mechcheck.sim_models.pymunk.turning` so that both simulators are judged by the
same rules.
"""

from __future__ import annotations

import math
import time
from typing import Literal

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from mechcheck.analytic.case import Case
from mechcheck.sim_models.mujoco.locks import add_servo
from mechcheck.sim_models.mujoco.model import (
    SETTLE_MASS,
    Settings,
    build_spec,
    place_frames_exactly,
)
from mechcheck.sim_models.turning import (
    JOINT_DAMPING,
    SERVO_SPEED,
    TIMESTEP,
    TORQUE_LIMIT,
    Amplification,
    Sample,
    TurnResult,
    amplification_result,
    branch_sign,
    seed_pose,
    turn_result,
)

Array = NDArray[np.float64]
Ending = Literal["turned", "jammed", "budget"]

SIMULATOR = "mujoco"

#: Links of the settling mass (model.SETTLE_MASS, as uniform bars): heavy, so
#: the soft constraints' violation under inertia forces stays tiny.
TURN_SETTINGS = Settings(timestep=TIMESTEP, masses="settle")


def inertia_unit(case: Case) -> float:
    """m·L², kg·m²: the unit of the servo gain, torque bound and joint damping."""
    return SETTLE_MASS * case.geometry.scale**2


def output_joint(case: Case) -> str:
    return "B0" if case.mechanism == "four_bar" else "slide"


def turning_spec(case: Case) -> mujoco.MjSpec:
    """The model of ``case`` (:func:`~mechcheck.sim_models.mujoco.model.build_spec`) with its crank
    lock switched off, a bounded-torque velocity servo on the crank hinge and damped
    passive joints."""
    spec = build_spec(case, TURN_SETTINGS)
    spec.equality("drive").active = False
    unit = inertia_unit(case)
    spec.joint("A").damping = [JOINT_DAMPING * unit, 0.0, 0.0]
    out = output_joint(case)
    spec.joint(out).damping = [JOINT_DAMPING * (unit if out == "B0" else SETTLE_MASS), 0.0, 0.0]
    add_servo(spec, "A0", unit)
    return spec


class MujocoTurner:
    """The servo-driven MuJoCo model of a Case (a :class:`Turner`)."""

    def __init__(self, case: Case) -> None:
        self.case = case
        self.timestep = TIMESTEP
        self.torque_limit = TORQUE_LIMIT * inertia_unit(case) * SERVO_SPEED**2
        self.model = turning_spec(case).compile()
        place_frames_exactly(self.model)
        self.data = mujoco.MjData(self.model)
        m = self.model
        self.q = [int(m.joint(j).qposadr[0]) for j in ("A0", "A", output_joint(case))]
        self.loop_eq = int(m.equality("loop_B").id)
        self.loop_rows: NDArray[np.int_] = np.zeros(0, dtype=int)  # set by reset()

    def reset(self, sense: int) -> None:
        m, d = self.model, self.data
        mujoco.mj_resetData(m, d)
        t12, t13, out = seed_pose(self.case, self.case.theta12)
        d.qpos[self.q] = (t12, t13 - t12, out)
        d.ctrl[0] = sense * SERVO_SPEED
        mujoco.mj_forward(m, d)
        self.loop_rows = np.flatnonzero(
            (d.efc_type[:d.nefc] == mujoco.mjtConstraint.mjCNSTR_EQUALITY)
            & (d.efc_id[:d.nefc] == self.loop_eq))

    def step(self) -> Sample:
        m, d = self.model, self.data
        mujoco.mj_step(m, d)
        q = d.qpos
        # efc_pos and actuator_force belong to the state at the start of the step.
        return Sample(float(q[self.q[0]]), float(q[self.q[0]] + q[self.q[1]]), float(q[self.q[2]]),
                      float(d.actuator_force[0]), float(np.linalg.norm(d.efc_pos[self.loop_rows])))


def turn_crank(case: Case, turns: float = 1.0, sense: int = 1) -> TurnResult:
    """Drive the crank of ``case`` in MuJoCo through ``turns`` turns (``sense`` +1 CCW).

    Starts at rest on the case's pose at ``case.theta12`` (on its branch).
    If the crank jams against a toggle, it is also driven the other way from
    the same start, so ``reach`` is the whole reachable range of θ12.
    """
    start = time.perf_counter()
    return turn_result(SIMULATOR, MujocoTurner(case), turns, sense, start)


# -- MuJoCo amplification ----------------------------------------------------------------------

#: Holding runs use the static settings: settling masses, crank lock at
#: 2·dt stiffness, Euler (model.STATIC).
HOLD_SETTINGS = Settings(timestep=1.0e-3, masses="settle")

#: Settled when, over the last HOLD_WINDOW steps, no joint moved faster than
#: HOLD_SPEED (as a point speed at the longest link, m/s) and T12 stayed
#: within HOLD_FORCE_RTOL of itself; T12 is then the window's mean. With the
#: links at rest MuJoCo's solver still leaves T12 on a small limit cycle next
#: to a toggle (measured: 1e-8 to 1e-7 relative at 0.01°–0.1° of crank from
#: the non-Grashof toggle, 1.3e-6 at 0.03° from the offset slider-crank's),
#: so the force criterion is a spread, not a step-to-step change, and the
#: mean removes most of it. The speed criterion is what makes the answer
#: exact: at 1e-9 m/s T12 was still relaxing, 1e-6 off; at 1e-11, 5e-8
#: (measured on the non-Grashof series).
HOLD_FORCE_RTOL = 1.0e-5
HOLD_SPEED = 1.0e-11
HOLD_WINDOW = 20
HOLD_MAX_STEPS = 20000


def hold_model(case: Case) -> tuple[mujoco.MjModel, mujoco.MjData, list[int], int, int]:
    """(model, data, qpos addresses of A0, A, B0|slide, drive equality id, body of link 4)."""
    model = build_spec(case, HOLD_SETTINGS).compile()
    place_frames_exactly(model)
    q = [int(model.joint(j).qposadr[0]) for j in ("A0", "A", output_joint(case))]
    return model, mujoco.MjData(model), q, int(model.equality("drive").id), int(model.body("link4").id)


def hold_at(case: Case, theta12: float, load: float,
            parts: tuple[mujoco.MjModel, mujoco.MjData, list[int], int, int]
            ) -> tuple[tuple[float, float, float], float, bool, int]:
    """Hold the crank at ``theta12`` against ``load`` until settled.

    Returns (pose θ12, θ13, output; T12; settled; steps).
    """
    m, d, q, drive, body4 = parts
    mujoco.mj_resetData(m, d)
    t12, t13, out = seed_pose(case, theta12)
    d.qpos[q] = (t12, t13 - t12, out)
    m.eq_data[drive, 0] = theta12
    if case.mechanism == "four_bar":
        d.xfrc_applied[body4, 5] = load  # a pure couple: the same wherever it acts
    else:
        # Along u through the slider's centre of mass, which lies on the slide
        # axis through B: the same as at B (no moment).
        g = case.ground_angle
        d.xfrc_applied[body4, 0:2] = (load * math.cos(g), load * math.sin(g))
    scale = case.geometry.scale
    slide_scale = scale if case.mechanism == "four_bar" else 1.0
    rows: NDArray[np.int_] | None = None
    recent = np.full(HOLD_WINDOW, math.nan)   # T12 of the last steps
    calm = 0                                   # consecutive steps at rest
    settled = False
    steps = 0
    for steps in range(1, HOLD_MAX_STEPS + 1):
        mujoco.mj_forward(m, d)
        if rows is None:
            rows = np.flatnonzero(
                (d.efc_type[:d.nefc] == mujoco.mjtConstraint.mjCNSTR_EQUALITY)
                & (d.efc_id[:d.nefc] == drive))
        recent[steps % HOLD_WINDOW] = d.efc_force[rows[0]]
        speed = max(float(np.abs(d.qvel[q[:2]]).max()) * scale, abs(float(d.qvel[q[2]])) * slide_scale)
        calm = calm + 1 if speed <= HOLD_SPEED else 0
        if calm >= HOLD_WINDOW and np.ptp(recent) <= HOLD_FORCE_RTOL * abs(recent.mean()):
            settled = True
            break
        mujoco.mj_Euler(m, d)
    torque = float(recent.mean()) if settled else float(recent[steps % HOLD_WINDOW])
    pose = (float(d.qpos[q[0]]), float(d.qpos[q[0]] + d.qpos[q[1]]), float(d.qpos[q[2]]))
    return pose, torque, settled, steps


def amplification(case: Case, theta12_values: ArrayLike, output_load: float = 1.0) -> Amplification:
    """T12 needed to hold ``output_load`` at each θ12, measured in MuJoCo.

    ``output_load`` is a pure torque on the rocker (N·m, CCW +) for a
    four-bar, a force on the slider along the slide direction u (N) for a
    slider-crank; it is the only load (the case's own loads and masses are
    not applied). The crank is held by the model's ``drive`` equality at each
    θ12, starting from the analytic pose at rest, and the model is stepped
    until settled; T12 is the equality's force.
    """
    start = time.perf_counter()
    thetas = np.atleast_1d(np.asarray(theta12_values, dtype=float))
    parts = hold_model(case)
    seed_branch = branch_sign(case, *np.array([seed_pose(case, t)[1:] for t in thetas]).T)
    rows = [hold_at(case, float(t), output_load, parts) for t in thetas]
    return amplification_result(SIMULATOR, case, output_load, rows, seed_branch, start)
