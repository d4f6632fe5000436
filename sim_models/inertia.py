"""A link's inertia as the Case gives it, for either simulator's model."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mechcheck.analytic.linkage import Linkage, LinkMass


@dataclass(frozen=True)
class Inertial:
    """A body's mass (kg), centre of mass (global, drawn pose, m) and planar inertia about
    it (kg·m²)."""

    mass: float
    com: tuple[float, float]
    inertia: float


def link_extent(linkage: Linkage, link: str) -> float:
    """The largest distance between two points of a link, or the linkage's size for a
    one-point link (a slider, a block): a length for fictitious inertias."""
    xy = np.array([linkage.points[p] for p in next(k for k in linkage.links
                                                   if k.name == link).points])
    span = float(np.max(np.linalg.norm(xy[:, None] - xy[None], axis=2)))
    return span if span > 0.0 else linkage.scale


def real_inertial(linkage: Linkage, link: str) -> Inertial | None:
    """The link's masses combined (parallel-axis theorem), or None for a massless link."""
    masses: list[LinkMass] = [m for m in linkage.masses if m.link == link]
    if not masses:
        return None
    total = sum(m.mass for m in masses)
    com = np.sum([m.mass * np.array(m.com) for m in masses], axis=0) / total
    inertia = sum(m.inertia + m.mass * float(np.sum((np.array(m.com) - com) ** 2))
                  for m in masses)
    return Inertial(total, (float(com[0]), float(com[1])), inertia)
