"""Joint friction emulated from pymunk's reactions and velocities, consistent within a step.

- Coulomb at a pin (i, j): the friction-circle moment −μ·r·|F_ij|·sign(ω_j − ω_i)
  on j and the opposite on i. (It was a SimpleMotor(rate = 0) whose
  ``max_force`` was set to μ·r·|F_ij|: the motor's sense came from the
  solver's clamp, which did not saturate where the joint turns slowly, and a
  non-finite limit made Chipmunk abort the whole process on a C assertion.)
- Coulomb on the slide: a force −μ_s·|N|·sign(ṡ) along u at pin B, N the
  guide's normal reaction.
- Viscous: −c·(ω_j − ω_i) on j (and the opposite on i), −c·ṡ·u on the slider.

These loads must be set before pymunk solves a step, but they depend on the
reactions and velocities that step produces. Taking them from the previous
step lags them by one step, an error of order dt·dF/dt that only falls as
dt: measured on a random slider-crank at 16.6 rad/s (μ = 0.28), readings at
dt and dt/2 still differed by 8.8e-4 and 4.4e-4 of the force scale down to
dt = 2.5e-5 s. So each step is taken from a *prediction* of its own state,
the linear extrapolation of the last two steps' (error O(dt²)), and then
repeated from the same start with the loads of the state it produced
(:data:`~mechcheck.sim_models.pymunk.dynamics.FRICTION_PASSES`): a
fixed-point pass that makes the loads those of the step's own reactions and
velocities to within the friction's feedback gain times that O(dt²) error.
All of this is computed from pymunk's numbers only (:class:`State`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from mechcheck.analytic.case import Case
from mechcheck.sim_models.pymunk.model import Model, pin_anchors, slide_axes

#: The reaction whose magnitude loads each pin (CONVENTIONS names).
PIN_REACTIONS = {"A0": "F12", "A": "F23", "B": "F34", "B0": "F14"}

#: What a step's friction depends on: the reaction components by CONVENTIONS
#: name and the speeds ``w2``, ``w3``, ``w4`` (rad/s) and ``sdot`` (m/s, along u).
State = dict[str, float]


class Diverged(RuntimeError):
    """The simulation produced a non-finite number: the run is lost, no reading."""


@dataclass(frozen=True)
class FrictionLoads:
    """One step's friction: moments per link (N·m) and the force along u on the slider at B (N)."""

    torques: dict[int, float] = field(default_factory=dict)
    slide: float = 0.0


def speeds(model: Model) -> State:
    """The links' angular velocities and, for a slider, ṡ along the slide axis."""
    out = {f"w{link}": float(body.angular_velocity) for link, body in model.bodies.items()}
    if model.groove is not None:
        (ux, uy), _ = slide_axes(model.case)
        v = model.bodies[4].velocity
        out["sdot"] = v.x * ux + v.y * uy
    return out


def relative_speed(state: State, i: int, j: int) -> float:
    """ω_j − ω_i at a pin (ω of the ground is 0)."""
    wi = state[f"w{i}"] if i != 1 else 0.0
    return state[f"w{j}"] - wi


def friction_loads(case: Case, state: State) -> FrictionLoads:
    """The friction loads that belong to ``state`` (see the module doc)."""
    f = case.friction
    if f is None:
        return FrictionLoads()
    torques = {2: 0.0, 3: 0.0, 4: 0.0}
    for joint, (i, _, j, _) in pin_anchors(case).items():
        name = PIN_REACTIONS[joint]
        turning = relative_speed(state, i, j)
        moment = (-f.pin_moment_arm(joint) * math.hypot(state[f"{name}_x"], state[f"{name}_y"])
                  * sign(turning) - f.viscous.get(joint, 0.0) * turning)
        torques[j] += moment
        if i != 1:
            torques[i] -= moment
    slide = 0.0
    if case.mechanism == "slider_crank":
        _, (nx, ny) = slide_axes(case)
        normal = state["F14_x"] * nx + state["F14_y"] * ny
        sdot = state["sdot"]
        slide = -f.slide_coefficient() * abs(normal) * sign(sdot) - f.viscous.get("slide", 0.0) * sdot
    return FrictionLoads(torques, slide)


def apply_friction(model: Model, loads: FrictionLoads,
                   extras: dict[int, tuple[float, float, float]]) -> None:
    """Set the explicit forces the velocity callbacks apply (a non-finite one stops the run)."""
    if not all(math.isfinite(v) for v in (loads.slide, *loads.torques.values())):
        raise Diverged("a friction load became non-finite")
    (ux, uy), _ = slide_axes(model.case)
    extras.clear()
    for link in model.bodies:
        push = loads.slide if link == 4 and model.groove is not None else 0.0
        extras[link] = (push * ux, push * uy, loads.torques.get(link, 0.0))


def sign(x: float) -> float:
    """Sign with sign(0) = 0."""
    return math.copysign(1.0, x) if x else 0.0
