"""External loads and weights, applied to the bodies before every step.

Chipmunk clears body forces after each step, so they are re-applied each
step at the *current* pose of the body: a body-fixed load point moves with
the body, the force keeps its global direction.
"""

from __future__ import annotations

import math
from collections.abc import Hashable, Iterable, Mapping, Sequence
from typing import Any, Protocol

import numpy as np
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


class LoadTerms:
    """Every body's load force and torque as a function of its angle alone.

    A load keeps its global direction while its point turns with the body, so the force
    on a body is constant and its torque about the centre of gravity, Σ (R(φ)·d) × F with
    d = point − cog in the body's frame, is A·cos φ − B·sin φ + T with A = Σ d × F,
    B = Σ d·F and T the couples, i.e. R·cos(φ + δ) + T with R = |(A, B)|, tan δ = B/A:
    what :func:`apply_forces` adds, computed for all bodies at once (rounding apart).
    In plain floats, for loops that run every step: ``forces`` (fx, fy body after body)
    and ``turning``, (body index, R, δ, T) of the bodies with any torque.
    """

    def __init__(self, loads: Iterable[LoadLike], masses: Iterable[MassLike], gravity: Vec,
                 bodies: Mapping[Any, pymunk.Body]):
        index = {link: k for k, link in enumerate(bodies)}
        cogs = [tuple(b.center_of_gravity) for b in bodies.values()]
        self.force = np.zeros((len(index), 2))
        a, b, self.couple = (np.zeros(len(index)) for _ in range(3))
        gx, gy = gravity
        loads = list(loads)
        points = [(ld.link, ld.at, ld.force) for ld in loads]
        points += [(m.link, m.com, (m.mass * gx, m.mass * gy)) for m in masses if gx or gy]
        for link, (px, py), (fx, fy) in points:
            k = index[link]
            dx, dy = px - cogs[k][0], py - cogs[k][1]
            self.force[k] += (fx, fy)
            a[k] += dx * fy - dy * fx
            b[k] += dx * fx + dy * fy
        for ld in loads:
            self.couple[index[ld.link]] += ld.torque
        amplitude, phase = np.hypot(a, b), np.arctan2(b, a)
        self.forces: list[float] = self.force.ravel().tolist()
        self.turning = [(k, float(amplitude[k]), float(phase[k]), float(self.couple[k]))
                        for k in range(len(index)) if amplitude[k] or self.couple[k]]
        self._none = [0.0] * len(index)

    def torques(self, angles: Sequence[float]) -> list[float]:
        """Each body's load torque about its centre of gravity at ``angles`` (one per body),
        N·m."""
        out = self._none.copy()
        for k, r, phase, couple in self.turning:
            out[k] = r * math.cos(angles[k] + phase) + couple
        return out
