"""Reading a pymunk model: the quantity table every pymunk module passes around
(:data:`Values`), and the four-bar model's loop violation for the turning experiments
(:mod:`.turning`); a linkage's reactions are read by :func:`.linkage.reactions`.
"""

from __future__ import annotations

import pymunk

from mechcheck.sim_models.pymunk.model import Model

Values = dict[str, float]


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
