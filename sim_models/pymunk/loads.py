"""External loads and weights, applied to the bodies before every step.

Chipmunk clears body forces after each step, so they are re-applied each
step at the *current* pose of the body: a body-fixed load point moves with
the body, the force keeps its global direction.
"""

from __future__ import annotations

import pymunk

from mechcheck.analytic.case import Case
from mechcheck.sim_models.pymunk.model import Model


def apply_load_set(case: Case, bodies: dict[int, pymunk.Body]) -> None:
    """Add every external load and every real weight m·g to the body forces.

    Weights are applied explicitly at the real centre of mass (``Space.gravity``
    stays zero) so that fictitious masses carry no weight.
    """
    for load in case.loads:
        body = bodies[load.link]
        body.apply_force_at_world_point(load.force, body.local_to_world(load.at))
        if load.torque:
            body.torque += load.torque
    gx, gy = case.gravity
    if gx or gy:
        for m in case.masses:
            body = bodies[m.link]
            body.apply_force_at_world_point((m.mass * gx, m.mass * gy),
                                            body.local_to_world(m.com))


def apply_loads(model: Model) -> None:
    """Apply the case's loads and weights to the model for the next step."""
    apply_load_set(model.case, model.bodies)
