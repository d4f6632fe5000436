"""Constant loads folded per link: every external load and weight on a link, whatever the
pose, as one force and the two parts of its moment (:class:`Resultant`).

A load f at the body-fixed point c (link frame) sits at R(θ)·c from the frame's origin,
so its moment about the origin is (R(θ)·c) × f = cos θ·(c × f) − sin θ·(c · f). Summed
over a link's loads, five numbers give its wrench at every pose with one multiply-add:
statics never touches a load per pose. The four-bar and slider-crank
(:mod:`mechcheck.analytic.equilibrium`) and the linkage engine
(:mod:`mechcheck.analytic.linkage_statics`) both fold their loads here.
"""

from __future__ import annotations

from collections.abc import Hashable, Iterable
from dataclasses import dataclass
from typing import TypeVar

from mechcheck.analytic.pose import Array, Coordinates
from mechcheck.analytic.values import Vec2

#: A link's known loads at each pose: (Fx, Fy, moment about the link frame's origin, CCW).
#: A part that is the same at every pose is a plain float.
Wrench = tuple[Array | float, Array | float, Array | float]

Link = TypeVar("Link", bound=Hashable)


@dataclass(frozen=True)
class Resultant:
    """A link's constant loads folded: the force sum ``fx, fy``, ``p`` = Σ c × f,
    ``q`` = Σ c · f and the pure moments' sum ``torque``."""

    fx: float = 0.0
    fy: float = 0.0
    p: float = 0.0
    q: float = 0.0
    torque: float = 0.0

    def plus(self, at: Vec2, force: Vec2, torque: float = 0.0) -> Resultant:
        """This resultant with one more load: ``force`` at the body-fixed point ``at``."""
        (cx, cy), (fx, fy) = at, force
        return Resultant(self.fx + fx, self.fy + fy, self.p + cx * fy - cy * fx,
                         self.q + cx * fx + cy * fy, self.torque + torque)

    def wrench(self, direction: Coordinates) -> Wrench:
        """The wrench at each pose, from the frame's x axis (cos θ, sin θ) there."""
        if self.p == 0.0 and self.q == 0.0:  # forces at the origin: no pose dependence
            return self.fx, self.fy, self.torque
        cos, sin = direction
        return self.fx, self.fy, self.p * cos - self.q * sin + self.torque


def resultants(loads: Iterable[tuple[Link, Vec2, Vec2, float]]) -> dict[Link, Resultant]:
    """(link, body-fixed point, global force, pure moment) loads folded per link."""
    out: dict[Link, Resultant] = {}
    for link, at, force, torque in loads:
        out[link] = out.get(link, Resultant()).plus(at, force, torque)
    return out
