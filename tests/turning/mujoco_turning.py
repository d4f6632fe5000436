"""Seed 001's mechanism theory measured in MuJoCo: turn the crank and see.

Two experiments on the four-bar or slider-crank as its linkage (the linkage builder's model,
:mod:`mechcheck.analytic.presets`), both read from MuJoCo's own state (joint coordinates,
actuator and equality forces); the analytic side only seeds the first pose.

- :func:`turn_crank` drives the crank with a **velocity servo of bounded torque** (the
  servo of :mod:`.mujoco_locks`) and records θ12, θ13 and θ14 (or s14) every step. A crank that
  can turn (Grashof crank-rocker, double-crank, rotatable slider-crank) completes its
  turns; one that cannot runs into a toggle, where the servo saturates and the crank
  stops: the run is then repeated in the other sense, and the two rest angles are the
  **reachable range** of θ12. From a completed turn, :meth:`TurnResult.rocker_extremes`
  finds the extremes of θ14 and the crank angles where they occur.
- :func:`amplification` holds the crank (the linkage's ``drive_A0`` joint equality) at each
  θ12 against a pure torque on the rocker (or a force along the slide) and lets the model
  settle; the equality's force is the holding torque T12, so T12 / T_out is the force
  amplification, −ω4/ω2 for a rigid linkage, growing without bound toward a toggle.

The simulator-independent parts (the run protocol, the result types and the extreme finder)
are in :mod:`.protocol`, shared with :mod:`.pymunk_turning`.
"""

from __future__ import annotations

import math
import time

import mujoco
import numpy as np
from numpy.typing import ArrayLike

from mechcheck.analytic.case import Case, preset_of
from mechcheck.analytic.presets import Renaming, as_linkage
from mechcheck.sim_models.mujoco.linkage_readout import one_state
from mechcheck.sim_models.mujoco.linkage_rig import LinkageRig
from mechcheck.sim_models.mujoco.model import Settings

from .locks import held_at_drawn
from .mujoco_locks import LinkageServo
from .protocol import (
    Amplification,
    Sample,
    TurnResult,
    bare,
    held_against,
    measure_amplification,
    turn_result,
)

SIMULATOR = "mujoco"


class PresetPose:
    """θ12, θ13 and θ14 (or s14) of a preset from its linkage rig's own joint coordinates."""

    def __init__(self, case: Case, rig: LinkageRig) -> None:
        self.theta12 = preset_of(case).theta12
        self.renaming = Renaming.of(preset_of(case))
        self.rig = rig

    def read(self) -> tuple[float, float, float]:
        d = self.rig.data
        pose = one_state(self.rig._pose_columns(d.qpos[None], d.site_xpos[None]))
        values = self.renaming.values(pose)
        output = values.get("theta14", values.get("s14", math.nan))
        # θ13 and θ14 unwrapped: the drawn angles moved by the links' rotations.
        drawn = self.renaming.drawn
        if "theta14" in drawn:
            output = drawn["theta14"] + pose[self.renaming.rocker]
        return (self.theta12 + pose["phi_crank"], drawn["theta13"] + pose[self.renaming.coupler],
                output)


class MujocoTurner(LinkageServo):
    """The servo-driven MuJoCo model of a four-bar's or slider-crank's crank (a
    :class:`.protocol.Turner`): the lock servo on the crank of its
    linkage, sampled as the preset's θ12, θ13 and θ14 (or s14)."""

    def __init__(self, case: Case) -> None:
        super().__init__(held_at_drawn(as_linkage(bare(case))), "A0")
        # The protocol starts at the preset's θ12 (run_leg reads case.theta12).
        self.case = case
        self.pose = PresetPose(case, self.rig)

    def step(self) -> Sample:
        rig = self.rig
        mujoco.mj_step(rig.model, rig.data)
        t12, t13, out = self.pose.read()
        # efc_pos and actuator_force belong to the state at the start of the step.
        return Sample(t12, t13, out, float(rig.data.actuator_force[0]), rig.loop_violation())


def turn_crank(case: Case, turns: float = 1.0, sense: int = 1) -> TurnResult:
    """Drive the crank of ``case`` in MuJoCo through ``turns`` turns (``sense`` +1 CCW).

    Starts at rest on the case's pose at ``case.theta12`` (on its branch). If the crank
    jams against a toggle, it is also driven the other way from the same start, so
    ``reach`` is the whole reachable range of θ12.
    """
    start = time.perf_counter()
    return turn_result(SIMULATOR, MujocoTurner(case), turns, sense, start)


# -- MuJoCo amplification ----------------------------------------------------------------------

#: Holding runs use the static settings: settling masses, crank lock at 2·dt stiffness,
#: Euler (model.STATIC).
HOLD_SETTINGS = Settings(timestep=1.0e-3, masses="settle")

#: Settled when, over the last HOLD_WINDOW steps, no joint moved faster than HOLD_SPEED
#: (as a point speed at the longest link, m/s) and T12 stayed within HOLD_FORCE_RTOL of
#: itself; T12 is then the window's mean. With the links at rest MuJoCo's solver still
#: leaves T12 on a small limit cycle next to a toggle (measured on the four-bar's own
#: model: 1e-8 to 1e-7 relative at 0.01°–0.1° of crank from the non-Grashof toggle, 1.3e-6
#: at 0.03° from the offset slider-crank's), so the force criterion is a spread, not a
#: step-to-step change, and the mean removes most of it. The speed criterion is what
#: makes the answer exact: at 1e-9 m/s T12 was still relaxing, 1e-6 off; at 1e-11, 5e-8.
HOLD_FORCE_RTOL = 1.0e-5
HOLD_SPEED = 1.0e-11
HOLD_WINDOW = 20
HOLD_MAX_STEPS = 20000


def hold_at(case: Case, theta12: float, load: float
            ) -> tuple[tuple[float, float, float], float, bool, int]:
    """Hold the crank at ``theta12`` against ``load`` until settled (the linkage drawn at
    that pose, at rest in it). Returns (pose θ12, θ13, output; T12; settled; steps)."""
    held = held_against(case, theta12, load)
    rig = LinkageRig(as_linkage(held), HOLD_SETTINGS)
    pose = PresetPose(held, rig)
    m, d = rig.model, rig.data
    drive = int(rig.drive_rows["A0"][0])
    recent = np.full(HOLD_WINDOW, math.nan)   # T12 of the last steps
    calm = 0                                   # consecutive steps at rest
    settled = False
    steps = 0
    for steps in range(1, HOLD_MAX_STEPS + 1):
        mujoco.mj_kinematics(m, d)  # the loads at the current pose
        rig.apply_loads()
        mujoco.mj_forward(m, d)
        recent[steps % HOLD_WINDOW] = d.efc_force[drive]
        calm = calm + 1 if rig.joint_velocity() <= HOLD_SPEED else 0
        if calm >= HOLD_WINDOW and np.ptp(recent) <= HOLD_FORCE_RTOL * abs(recent.mean()):
            settled = True
            break
        mujoco.mj_Euler(m, d)
    torque = float(recent.mean()) if settled else float(recent[steps % HOLD_WINDOW])
    return pose.read(), torque, settled, steps


def amplification(case: Case, theta12_values: ArrayLike, output_load: float = 1.0) -> Amplification:
    """T12 needed to hold ``output_load`` at each θ12, measured in MuJoCo.

    ``output_load`` is a pure torque on the rocker (N·m, CCW +) for a four-bar, a force on
    the slider along the slide direction u (N) for a slider-crank; it is the only load (the
    case's own loads and masses are not applied). The crank is held by its driver's joint
    equality at each θ12, starting at rest from the analytic pose, and the model is stepped
    until settled; T12 is the equality's force.
    """
    return measure_amplification(SIMULATOR, hold_at, case, theta12_values, output_load)
