"""The model's reactions, drive torque and pose in CONVENTIONS quantities.

Every force here comes from pymunk's accumulated impulses
(:mod:`mechcheck.sim_models.pymunk.forces`) divided by the constant step; the only
additions are the forces this backend itself applied on the slide (Coulomb
and viscous slide friction), which are part of the guide's reaction F14.
"""

from __future__ import annotations

import math

import pymunk

from mechcheck.analytic.case import Case
from mechcheck.sim_models.pymunk.forces import force_on_b, torque_on_b
from mechcheck.sim_models.pymunk.model import Model, analytic_pose, link_lengths, slide_axes

Values = dict[str, float]


def drive_quantity(case: Case) -> str:
    """``T12`` or ``T14``, after the link the drive acts on."""
    return f"T1{case.drive_link}"


def reactions(model: Model, slide_force: float = 0.0) -> Values:
    """F_ij (by i on j), the drive torque and, for a slider, M14, from the last step.

    ``slide_force`` is the friction force along u this backend applied to
    the slider at B during that step (part of the guide's reaction).
    """
    dt = model.settings.dt
    out: Values = {}
    for joint, name in (("A0", "F12"), ("A", "F23"), ("B", "F34")):
        out[f"{name}_x"], out[f"{name}_y"] = force_on_b(model.pins[joint], dt)
    if model.groove is not None and model.slider_lock is not None:
        nx, ny = force_on_b(model.groove, dt)
        (ux, uy), _ = slide_axes(model.case)
        out["F14_x"], out["F14_y"] = nx + slide_force * ux, ny + slide_force * uy
        out["M14"] = torque_on_b(model.slider_lock, dt)
    else:
        out["F14_x"], out["F14_y"] = force_on_b(model.pins["B0"], dt)
    out[drive_quantity(model.case)] = torque_on_b(model.drive, dt)
    return out


def pose_values(model: Model) -> Values:
    """theta13 and theta14 (four-bar) or s14 (slider-crank) of the simulated bodies."""
    out = {"theta13": model.bodies[3].angle}
    if model.groove is None:
        out["theta14"] = model.bodies[4].angle
    else:
        (ux, uy), _ = slide_axes(model.case)
        p = model.bodies[4].position
        out["s14"] = p.x * ux + p.y * uy
    return out


def residual_velocity(model: Model) -> float:
    """Largest point speed of any body, m/s: |v| + |ω|·(link length)."""
    reach = link_lengths(model.case)
    return max(abs(b.velocity) + abs(b.angular_velocity) * reach[k]
               for k, b in model.bodies.items())


def loop_violation(model: Model) -> float:
    """Largest distance between the two anchors of any pin or groove (loop violation), m."""
    worst = 0.0
    for pin in model.pins.values():
        pa = pin.a.local_to_world(pin.anchor_a)
        pb = pin.b.local_to_world(pin.anchor_b)
        worst = max(worst, abs(pa - pb))
    if model.groove is not None:
        worst = max(worst, _groove_distance(model.groove))
    return worst


def _groove_distance(groove: pymunk.GrooveJoint) -> float:
    a, b = pymunk.Vec2d(*groove.groove_a), pymunk.Vec2d(*groove.groove_b)
    p = groove.b.local_to_world(groove.anchor_b)
    n = (b - a).perpendicular_normal()
    return abs((p - a).dot(n))


def pose_drift(model: Model, theta12: float) -> float:
    """Largest distance of any link-frame origin from its analytic place, plus angle × length, m.

    Measured against the closed-form pose at the θ12 the drive actually reached.
    """
    pose = analytic_pose(model.case, theta12)
    reach = link_lengths(model.case)
    worst = 0.0
    for link, body in model.bodies.items():
        state = pose.links[link]
        dx = body.position.x - float(state.origin[0, 0])
        dy = body.position.y - float(state.origin[0, 1])
        da = _wrap(body.angle - float(state.angle[0]))
        worst = max(worst, math.hypot(dx, dy) + abs(da) * reach[link])
    return worst


def _wrap(angle: float) -> float:
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def crank_angle(model: Model) -> float:
    """θ12 the crank body actually has."""
    return float(model.bodies[2].angle)
