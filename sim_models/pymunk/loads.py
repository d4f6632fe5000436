"""External loads and weights, applied to the bodies before every step.

Chipmunk clears body forces after each step, so they are re-applied each
step at the *current* pose of the body: a body-fixed load point moves with
the body, the force keeps its global direction.
"""

from __future__ import annotations

from collections.abc import Hashable, Iterable, Mapping
from typing import Any, Protocol

import pymunk

Vec = tuple[float, float]


class LoadLike(Protocol):
    """A force (N, global direction) at a point of a link's frame, and a couple (N·m)."""

    @property
    def link(self) -> Hashable: ...
    @property
    def at(self) -> Vec: ...
    @property
    def force(self) -> Vec: ...
    @property
    def torque(self) -> float: ...


class MassLike(Protocol):
    """A real mass (kg) at a centre of mass in a link's frame."""

    @property
    def link(self) -> Hashable: ...
    @property
    def mass(self) -> float: ...
    @property
    def com(self) -> Vec: ...


def apply_forces(loads: Iterable[LoadLike], masses: Iterable[MassLike], gravity: Vec,
                 bodies: Mapping[Any, pymunk.Body]) -> None:
    """Add every load and every real weight m·g to the body forces.

    Load points and centres of mass are in the frame of the body their link is
    (the four-bar's link frames, or a linkage's drawn-pose coordinates).
    Weights are applied explicitly at the real centre of mass (``Space.gravity``
    stays zero) so that fictitious masses carry no weight.
    """
    for load in loads:
        body = bodies[load.link]
        body.apply_force_at_world_point(load.force, body.local_to_world(load.at))
        if load.torque:
            body.torque += load.torque
    gx, gy = gravity
    if gx or gy:
        for m in masses:
            body = bodies[m.link]
            body.apply_force_at_world_point((m.mass * gx, m.mass * gy),
                                            body.local_to_world(m.com))
