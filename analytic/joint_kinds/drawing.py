"""What a drawing shows of a joint at one pose: plain data, no plotting library.

Each kind answers :meth:`~.base.JointKind.drawing` with a :class:`JointDrawing`: the marks
that draw it (a pin, a slide or slot along its axis, the pitch circles of a gear pair) and
the point its reaction acts at. Whoever renders the marks knows only these few shapes,
never the kinds (``mechcheck.drawing``). Positions are metres in the case file's frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

from mechcheck.analytic.values import GROUND, Vec2


class Placement(Protocol):
    """A linkage at one pose: where its named points are, how far each link has turned
    from the drawn pose (rad, the ground 0)."""

    def point(self, name: str) -> Vec2: ...

    def turn(self, link: str) -> float: ...


@dataclass(frozen=True)
class Pin:
    """A revolute pin at ``at`` (a pin on the ground stands on the ground's mark there)."""

    at: Vec2


@dataclass(frozen=True)
class Slide:
    """A block (``turns`` False: a prismatic joint) or a pin in a slot (``turns`` True) at
    ``at``, sliding along the unit ``axis``; ``grounded``: the guide is the ground."""

    at: Vec2
    axis: Vec2
    turns: bool = False
    grounded: bool = False


@dataclass(frozen=True)
class PitchCircle:
    """One gear's pitch circle: centre and radius (m)."""

    centre: Vec2
    radius: float


Mark = Pin | Slide | PitchCircle


@dataclass(frozen=True)
class JointDrawing:
    """A joint's marks and where its reaction (``F_<joint>``) acts."""

    marks: tuple[Mark, ...]
    acts_at: Vec2


def rotated(angle: float, v: Vec2) -> Vec2:
    """``v`` turned by ``angle`` (rad, CCW)."""
    c, s = math.cos(angle), math.sin(angle)
    return (c * v[0] - s * v[1], s * v[0] + c * v[1])


def grounded(links: tuple[str, str]) -> bool:
    return GROUND in links
