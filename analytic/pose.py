"""The pose of a four-bar or slider-crank: link frames, their velocities and accelerations,
vectorised over θ12 (the types the closed forms fill in).

The mechanism-specific closed forms live in :mod:`mechcheck.analytic.fourbar_kinematics`
and :mod:`mechcheck.analytic.slidercrank_kinematics`; both return a :class:`Pose`, whose
link frames (CONVENTIONS.md) let any body-fixed point be located, and
differentiated, the same way for either mechanism. Statics needs positions only: the
closed forms give those first, as a :class:`Placement` of flat coordinate arrays, and
build the :class:`Pose` on it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from mechcheck.analytic.values import Vec2

Array = NDArray[np.float64]


def unit(angle: Array) -> Array:
    """Unit vectors (cos, sin) of an array of angles, shape (..., 2)."""
    return np.stack([np.cos(angle), np.sin(angle)], axis=-1)


def perp(v: Array) -> Array:
    """v turned +90°: k × v."""
    return np.stack([-v[..., 1], v[..., 0]], axis=-1)


def cross(r: Array, f: Array) -> Array:
    """z-component of r × f for arrays of planar vectors."""
    return r[..., 0] * f[..., 1] - r[..., 1] * f[..., 0]


#: A planar vector per pose as its (x, y) coordinate arrays; a coordinate that is the same
#: at every pose (a ground pin, the slide's direction) is a plain float.
Coordinates = tuple[Array | float, Array | float]


@dataclass(frozen=True)
class Placement:
    """Where the links are at N input angles, and nothing else (what statics needs).

    ``angles`` maps each turning link (2, 3, and a rocker 4) to its frame's angle,
    ``directions`` every moving link to its frame's x axis (cos θ, sin θ), ``joints`` the
    CONVENTIONS joint names to their positions; ``s14`` is the slider coordinate
    (slider-crank only, else None).
    """

    theta12: Array
    angles: dict[int, Array]
    directions: dict[int, Coordinates]
    joints: dict[str, Coordinates]
    s14: Array | None = None

    @property
    def theta13(self) -> Array:
        return self.angles[3]

    @property
    def theta14(self) -> Array:
        return self.angles[4]


def coordinates(joints: dict[str, Array]) -> dict[str, Coordinates]:
    """A Pose's (N, 2) joint positions as coordinate arrays (views, not copies)."""
    return {name: (p[:, 0], p[:, 1]) for name, p in joints.items()}


def stacked(v: Coordinates, n: int) -> Array:
    """Coordinates as an (n, 2) array (a Pose's layout)."""
    zeros = np.zeros(n)
    return np.stack([v[0] + zeros, v[1] + zeros], axis=-1)


@dataclass(frozen=True)
class LinkState:
    """A link frame's origin and orientation with their first two derivatives."""

    origin: Array        # (N, 2)
    velocity: Array      # (N, 2)
    acceleration: Array  # (N, 2)
    angle: Array         # (N,)
    omega: Array         # (N,)
    alpha: Array         # (N,)


@dataclass(frozen=True)
class Pose:
    """The whole mechanism at N input angles; every array has leading length N.

    ``joints`` maps the CONVENTIONS joint names to global positions (N, 2);
    ``links`` maps link number (2, 3, 4) to its :class:`LinkState`.
    ``s14``, ``s14_dot``, ``s14_ddot`` are the slider coordinate along the
    slide axis and its derivatives (slider-crank only, else None).
    """

    theta12: Array
    joints: dict[str, Array]
    links: dict[int, LinkState]
    s14: Array | None = None
    s14_dot: Array | None = None
    s14_ddot: Array | None = None

    def point(self, link: int, local: Vec2 | Array) -> tuple[Array, Array, Array]:
        """Global position, velocity and acceleration of a body-fixed point.

        ``local`` is in the link frame, metres.
        """
        s = self.links[link]
        c = np.asarray(local, dtype=float)
        e = unit(s.angle)
        r = c[..., 0:1] * e + c[..., 1:2] * perp(e)  # R(θ) c
        position = s.origin + r
        velocity = s.velocity + s.omega[:, None] * perp(r)
        acceleration = s.acceleration + s.alpha[:, None] * perp(r) - (s.omega**2)[:, None] * r
        return position, velocity, acceleration

    @property
    def theta13(self) -> Array:
        return self.links[3].angle

    @property
    def theta14(self) -> Array:
        return self.links[4].angle
