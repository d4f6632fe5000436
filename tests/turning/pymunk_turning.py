"""Seed 001's mechanism theory measured in pymunk: turn the crank and see.

The same two experiments as :mod:`.mujoco_turning`, on the four-bar or
slider-crank as its linkage (the linkage builder's model, :mod:`mechcheck.analytic.presets`),
judged by the same run protocol, result types and extreme finder
(:mod:`.protocol`):

- :func:`turn_crank` drives the crank with a :class:`pymunk.SimpleMotor` of bounded torque
  (``max_force``) in place of the crank's gear lock, every other joint damped (the servo
  model of :mod:`.pymunk_locks`);
- :func:`amplification` holds the crank with its own gear lock against a pure torque on
  the rocker (or a force along the slide) and steps until settled; the lock's signed
  accumulated impulse / dt (:mod:`mechcheck.sim_models.pymunk.forces`) is T12.

Everything is read from pymunk's bodies and constraints; the analytic pose only seeds the
first configuration.
"""

from __future__ import annotations

import math
import time

from numpy.typing import ArrayLike

from mechcheck.analytic.case import Case, preset_of
from mechcheck.analytic.linkage_kinematics import solve_pose
from mechcheck.analytic.presets import Renaming, as_linkage
from mechcheck.sim_models.pymunk.forces import torque_on_b
from mechcheck.sim_models.pymunk.linkage_model import (
    LinkageModel,
    apply_loads,
    build_linkage_model,
    damp,
)
from mechcheck.sim_models.pymunk.settings import SolverSettings

from .locks import held_at_drawn
from .protocol import (
    Amplification,
    Sample,
    TurnResult,
    bare,
    held_against,
    measure_amplification,
    turn_result,
)
from .pymunk_locks import LINK_MASS, LinkageServo, loop_gap

SIMULATOR = "pymunk"


def preset_pose(case: Case, renaming: Renaming, model: LinkageModel) -> tuple[float, float, float]:
    """θ12, θ13 and θ14 (or s14) of the preset ``case`` (``renaming``: its drawn pose) from
    its linkage model's bodies (each body's frame is the world frame at the drawn pose, so
    its angle is the link's rotation and its position the slider's displacement)."""
    drawn = renaming.drawn
    bodies = model.bodies
    crank, coupler = bodies["crank"], bodies["coupler"]
    if "theta14" in drawn:
        output = drawn["theta14"] + bodies["rocker"].angle
    else:
        g = preset_of(case).ground_angle
        slider = bodies["slider"].position
        output = drawn["s14"] + slider.x * math.cos(g) + slider.y * math.sin(g)
    return (preset_of(case).theta12 + crank.angle, drawn["theta13"] + coupler.angle, float(output))


class PymunkTurner(LinkageServo):
    """The servo-driven pymunk model of a four-bar's or slider-crank's crank (a
    :class:`.protocol.Turner`)."""

    def __init__(self, case: Case) -> None:
        super().__init__(held_at_drawn(as_linkage(bare(case))), "A0")
        # The protocol starts at the preset's θ12 (run_leg reads case.theta12).
        self.case = case
        self.renaming = Renaming.of(preset_of(case))

    def step(self) -> Sample:
        model, motor = self.model, self.motor
        assert model is not None and motor is not None, "reset() first"
        model.space.step(self.timestep)
        t12, t13, out = preset_pose(self.case, self.renaming, model)
        return Sample(t12, t13, out, torque_on_b(motor, self.timestep), loop_gap(model))


def turn_crank(case: Case, turns: float = 1.0, sense: int = 1) -> TurnResult:
    """Drive the crank of ``case`` in pymunk through ``turns`` turns (``sense`` +1 CCW).

    Starts at rest on the case's pose at ``case.theta12``; if the crank jams against a
    toggle it is also driven the other way from the same start, so ``reach`` is the whole
    reachable range of θ12.
    """
    start = time.perf_counter()
    return turn_result(SIMULATOR, PymunkTurner(case), turns, sense, start)


# -- amplification -----------------------------------------------------------------------------

#: Settings of a holding run. The static backend's long step (0.1 s) is
#: unstable next to a toggle: there the locked linkage is a near-flat
#: triangle A-B-B0 that warm-started Gauss–Seidel holds only loosely, the
#: rocker rings with growing amplitude and snaps through to the mirror
#: branch (measured on the non-Grashof example: from 0.1° of crank off the
#: toggle at dt = 0.1 s; 0.03° with 3000 iterations; 0.01 s still failed at
#: 0.003°). At dt = 1e-3 s with Chipmunk's default error_bias (0.9⁶⁰, ~1 %
#: of the error corrected per step), 300 iterations and strong damping
#: (1e-9 of the velocity kept per second, 2 % removed per step) every pose
#: down to 0.001° settled on its branch (measured).
HOLD_SETTINGS = SolverSettings(dt=1.0e-3, iterations=300, error_bias=0.9**60, damping=1.0e-9,
                               fictitious_mass=LINK_MASS)

#: Settled when, for HOLD_PATIENCE consecutive steps, T12 changes by at most
#: HOLD_FORCE_RTOL of itself and no point of any link moves faster than
#: HOLD_SPEED times the longest link per second.
HOLD_FORCE_RTOL = 1.0e-9
HOLD_SPEED = 1.0e-9
HOLD_PATIENCE = 3
HOLD_MAX_STEPS = 20000



def hold_at(case: Case, theta12: float, load: float
            ) -> tuple[tuple[float, float, float], float, bool, int]:
    """Hold the crank at ``theta12`` against ``load`` until settled (the linkage drawn at
    that pose, at rest in it). Returns (pose θ12, θ13, output; T12; settled; steps)."""
    held = held_against(case, theta12, load)
    linkage = as_linkage(held)
    model = build_linkage_model(linkage, HOLD_SETTINGS, solve_pose(linkage.linkage).q[0])
    dt = HOLD_SETTINGS.dt
    scale = linkage.linkage.scale
    previous = math.nan
    calm = 0
    torque = math.nan
    settled = False
    steps = 0
    for steps in range(1, HOLD_MAX_STEPS + 1):  # noqa: B007 - the step count is reported
        apply_loads(model)
        damp(model)
        model.space.step(dt)
        torque = torque_on_b(model.drives["A0"], dt)
        speed = max(abs(b.velocity) + abs(b.angular_velocity) * scale for b in model.bodies.values())
        calm = calm + 1 if (abs(torque - previous) <= HOLD_FORCE_RTOL * abs(torque)
                            and speed <= HOLD_SPEED * scale) else 0
        previous = torque
        if calm >= HOLD_PATIENCE:
            settled = True
            break
    return preset_pose(held, Renaming.of(preset_of(held)), model), torque, settled, steps


def amplification(case: Case, theta12_values: ArrayLike, output_load: float = 1.0) -> Amplification:
    """T12 needed to hold ``output_load`` at each θ12, measured in pymunk.

    ``output_load`` is a pure torque on the rocker (N·m, CCW +) for a four-bar, a force on
    the slider along the slide direction u (N) for a slider-crank; it is the only load (the
    case's own loads, masses and friction are not applied). Each θ12 gets a fresh model held
    there, seeded on the analytic pose at rest, stepped until settled.
    """
    return measure_amplification(SIMULATOR, hold_at, case, theta12_values, output_load)
