"""Joint friction emulated from MuJoCo's current reactions.

MuJoCo's own ``frictionloss`` is a constant limit, not μ·|F|, and pin B has no
joint at all (it is the loop's ``connect``). So each friction term is applied
as an external couple (pins) or force (slide) through ``xfrc_applied``, with
its magnitude from the reactions MuJoCo reports and its sense from the
relative motion (CONVENTIONS.md, analytic/friction.py semantics):

- pin (i, j) of radius r: moment on j −μ·r·|F_ij|·sign(ω_j − ω_i) − c·(ω_j − ω_i),
  the opposite on i (nothing on the ground);
- slide: force on the slider −μ_s·|N|·sign(ṡ) − c·ṡ along u through pin B,
  N the guide's normal reaction.
"""

from __future__ import annotations

import math

import numpy as np

from mechcheck.analytic.case import Case
from mechcheck.sim_models.mujoco.rig import Array, Rig

#: Links (i, j) of each pin, and the reaction whose magnitude loads it.
PINS = {"A0": (1, 2, "F12"), "A": (2, 3, "F23"), "B": (3, 4, "F34"), "B0": (1, 4, "F14")}


def relative_speeds(rig: Rig, qvel: Array) -> dict[str, float]:
    """ω_j − ω_i of every pin and ṡ of the slide from joint velocities (A0, A, out)."""
    w2, w32, out = float(qvel[0]), float(qvel[1]), float(qvel[2])
    w3 = w2 + w32
    if rig.four_bar:
        return {"A0": w2, "A": w32, "B": out - w3, "B0": out}
    return {"A0": w2, "A": w32, "B": -w3, "slide": out}


def magnitude(values: dict[str, float], name: str) -> float:
    return math.hypot(values[f"{name}_x"], values[f"{name}_y"])


def friction_loads(rig: Rig, values: dict[str, float], senses: dict[str, float],
                   speeds: dict[str, float]) -> tuple[Array, Array]:
    """(couples per body, forces per body) of every friction term at these reactions.

    ``senses`` give the signs Coulomb friction opposes (a quasi-static motion
    has no speed but a sense); ``speeds`` are the actual relative speeds, which
    viscous friction is proportional to.
    """
    case: Case = rig.case
    f = case.friction
    torque = np.zeros(rig.model.nbody)
    force = np.zeros((rig.model.nbody, 3))
    if f is None:
        return torque, force
    for joint, (i, j, reaction) in PINS.items():
        if joint not in speeds:
            continue
        moment = (-f.pin_moment_arm(joint) * magnitude(values, reaction)
                  * float(np.sign(senses[joint])) - f.viscous.get(joint, 0.0) * speeds[joint])
        torque[rig.layout.body[j]] += moment
        if i != 1:
            torque[rig.layout.body[i]] -= moment
    if "slide" in speeds:
        u = np.array([math.cos(case.ground_angle), math.sin(case.ground_angle)])
        normal = -values["F14_x"] * u[1] + values["F14_y"] * u[0]  # F14 · n
        along = (-f.slide_coefficient() * abs(normal) * float(np.sign(senses["slide"]))
                 - f.viscous.get("slide", 0.0) * speeds["slide"])
        force[rig.layout.body[4], 0:2] = along * u
    return torque, force
