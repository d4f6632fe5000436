"""Mechanism theory of seed 001: mobility, Grashof's rule, dead (limit)
positions, transmission angle extremes and slider-crank rotatability.

Examples
--------
>>> mobility(4, {"R": 4})
1
>>> grashof(ground=250, crank=100, coupler=220, rocker=150).kind
'crank-rocker'
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from mechcheck.analytic.case import (
    Case,
    CaseError,
    FourBarGeometry,
    Preset,
    SliderCrankGeometry,
    preset_of,
)
from mechcheck.analytic.joint_kinds import JointKind
from mechcheck.analytic.kinematics import pose_of
from mechcheck.analytic.linkage import Linkage

#: Freedom of each joint type (seed 001): revolute, prismatic, cylinder in a
#: slot, gear contact, cylindrical, spherical, spherical with a key.
JOINT_FREEDOM: dict[str, int] = {"R": 1, "P": 1, "Cs": 2, "G": 2, "C": 2, "S": 3, "Ss": 2}


def mobility(links: int, joints: Mapping[str, int], *, spatial: bool = False) -> int:
    """Gruebler–Kutzbach: S = λ(u − m − 1) + ΣSi.

    ``links`` is u (ground included), ``joints`` maps joint type → count
    (m is their total), λ = 6 if ``spatial`` else 3.
    """
    if links < 1:
        raise CaseError(f"must be >= 1, got {links}", key="links")
    unknown = sorted(set(joints) - set(JOINT_FREEDOM))
    if unknown:
        raise CaseError(f"unknown joint type {unknown[0]!r}; known: {', '.join(JOINT_FREEDOM)}",
                        key="joints")
    lam = 6 if spatial else 3
    m = sum(joints.values())
    return lam * (links - m - 1) + sum(JOINT_FREEDOM[j] * n for j, n in joints.items())


def mobility_meaning(s: int) -> str:
    """What a mobility means: a mechanism with S inputs, or a structure."""
    if s > 0:
        return f"mechanism with {s} degree{'s' if s > 1 else ''} of freedom"
    if s == 0:
        return "statically determinate structure"
    return "statically indeterminate (over-constrained) structure"


@dataclass(frozen=True)
class GrashofClass:
    """Grashof classification of a four-bar; ``s + l`` against ``p + q``."""

    #: crank-rocker | double-crank | double-rocker | change-point | non-Grashof double-rocker
    kind: str
    grashof: bool      # s + l <= p + q
    shortest: str      # ground | crank | coupler | rocker
    s_plus_l: float
    p_plus_q: float


#: Lengths closer than this (relative) count as equal: s + l = p + q is a change point.
EQUALITY_RTOL = 1e-12


def grashof(*, ground: float, crank: float, coupler: float, rocker: float) -> GrashofClass:
    """Classify a four-bar by Grashof's rule and which link is shortest (seed 001).

    s + l < p + q: shortest adjacent to ground → crank-rocker; shortest is
    ground → double-crank; shortest opposite ground → double-rocker.
    s + l > p + q: non-Grashof double-rocker (no link turns fully).
    s + l = p + q: change point (the links fold flat in one pose).
    """
    lengths = {"ground": ground, "crank": crank, "coupler": coupler, "rocker": rocker}
    for key, value in lengths.items():
        if not (math.isfinite(value) and value > 0):
            raise CaseError(f"must be a finite length > 0, got {value}", key=key)
    ordered = sorted(lengths.values())
    s, p, q, l_ = ordered
    longest = max(lengths, key=lambda k: lengths[k])
    if l_ >= (s + p + q) * (1 - EQUALITY_RTOL):
        raise CaseError(f"{l_:g} cannot close a loop with the other three ({s:g} + {p:g} + "
                        f"{q:g} = {s + p + q:g}): the longest link must be shorter than the "
                        "other three together", key=longest)
    shortest = min(lengths, key=lambda k: lengths[k])
    total = s + l_ - (p + q)
    if abs(total) <= EQUALITY_RTOL * (s + l_):
        kind = "change-point"
    elif total > 0:
        kind = "non-Grashof double-rocker"
    elif shortest == "ground":
        kind = "double-crank"
    elif shortest in ("crank", "rocker"):
        kind = "crank-rocker"
    else:
        kind = "double-rocker"
    return GrashofClass(kind, total <= EQUALITY_RTOL * (s + l_), shortest, s + l_, p + q)


def crank_turns_fully(g: FourBarGeometry) -> bool:
    """True when link 2 can turn a full revolution relative to the ground."""
    return g.a2 + g.a1 <= g.a3 + g.a4 and abs(g.a1 - g.a2) >= abs(g.a3 - g.a4)


@dataclass(frozen=True)
class LimitPosition:
    """A dead (limit) position of a crank-rocker: crank and coupler collinear."""

    name: str          # "extended" (|A0B| = a2 + a3) or "folded" (|A0B| = a3 − a2)
    distance: float    # |A0B| there
    theta12: float     # rad
    theta14: float     # rad


def limit_positions(case: Case | Preset) -> tuple[LimitPosition, LimitPosition]:
    """The two rocker extremes of a crank-rocker on the case's branch.

    There the crank and coupler are collinear, so B lies at |A0B| = a2 + a3
    (extended) or a3 − a2 (folded) from A0 and at a4 from B0; of the two
    mirror-image solutions, the one on the case's branch is kept.
    """
    g = preset_of(case).geometry
    if not isinstance(g, FourBarGeometry):
        raise CaseError("limit positions are defined here for a four_bar", key="mechanism")
    out = []
    for name, d in (("extended", g.a2 + g.a3), ("folded", g.a3 - g.a2)):
        cos_b0 = (g.a1**2 + d**2 - g.a4**2) / (2.0 * g.a1 * d)
        if abs(cos_b0) > 1.0 or d <= 0.0:
            raise CaseError(f"has no {name} dead position (not a crank-rocker)", key="geometry")
        phi = math.acos(cos_b0)  # angle of A0B from the ground line
        candidates = []
        for sign in (1.0, -1.0):
            direction = preset_of(case).ground_angle + sign * phi
            theta12 = direction if name == "extended" else direction + math.pi
            b = d * np.array([math.cos(direction), math.sin(direction)])
            p = pose_of(case, theta12, omega=0.0, alpha=0.0)
            if np.all(np.isfinite(p.joints["B"])):
                candidates.append((float(np.linalg.norm(p.joints["B"][0] - b)), theta12,
                                   float(p.theta14[0])))
        _, theta12, theta14 = min(candidates)  # the mirror image on the case's branch
        out.append(LimitPosition(name, d, math.remainder(theta12, math.tau),
                                 math.remainder(theta14, math.tau)))
    return out[0], out[1]


@dataclass(frozen=True)
class TransmissionExtremes:
    """Transmission-angle extremes over a full turn and where they occur (rad)."""

    mu_min: float
    theta12_at_min: float
    mu_max: float
    theta12_at_max: float

    @property
    def worst(self) -> float:
        """The smaller of μmin and 180° − μmax: the worst transmission (seed: take the smaller)."""
        return min(self.mu_min, math.pi - self.mu_max)


def transmission_extremes(case: Case | Preset) -> TransmissionExtremes:
    """μmin and μmax in closed form.

    Four-bar: μ is the angle at B of triangle A-B-B0, cos μ = (a3² + a4² − d²)/(2 a3 a4)
    with d = |AB0| growing from |a1 − a2| (crank along the ground, towards B0) to a1 + a2
    (crank away from B0); the crank angles are the ground direction and its opposite.
    Slider-crank: μ is the angle between the rod and the slide normal,
    cos μ = |e − a2 sin φ12|/a3, smallest μ with the crank perpendicular to the slide.
    """
    g = preset_of(case).geometry
    gd = preset_of(case).ground_angle
    if isinstance(g, FourBarGeometry):
        def mu(d: float) -> float:
            c = (g.a3**2 + g.a4**2 - d**2) / (2.0 * g.a3 * g.a4)
            return math.acos(max(-1.0, min(1.0, c)))
        d_min, d_max = abs(g.a1 - g.a2), g.a1 + g.a2
        lo, hi = max(d_min, abs(g.a3 - g.a4)), min(d_max, g.a3 + g.a4)
        return TransmissionExtremes(mu(lo), math.remainder(gd, math.tau),
                                    mu(hi), math.remainder(gd + math.pi, math.tau))
    assert isinstance(g, SliderCrankGeometry)
    worst_sin = 1.0 if g.offset <= 0 else -1.0   # crank at ±90° from the slide, away from e
    cos_mu = min(1.0, (abs(g.offset) + g.a2) / g.a3)
    best = min(1.0, max(0.0, abs(g.offset) - g.a2) / g.a3)
    return TransmissionExtremes(math.acos(cos_mu), math.remainder(gd + worst_sin * math.pi / 2,
                                                                  math.tau),
                                math.acos(best), math.remainder(gd - worst_sin * math.pi / 2,
                                                                math.tau))


def slider_crank_rotates(g: SliderCrankGeometry) -> bool:
    """The crank turns fully iff a2 + |e| < a3 (seed: a < b and b − a > e)."""
    return g.a2 + abs(g.offset) < g.a3


def slider_stroke(g: SliderCrankGeometry) -> float:
    """Stroke of a fully rotating slider-crank: √((a3+a2)² − e²) − √((a3−a2)² − e²); 2·a2 if centric."""
    if not slider_crank_rotates(g):
        raise CaseError("the crank does not turn fully (a2 + |e| >= a3)", key="geometry")
    return math.sqrt((g.a3 + g.a2) ** 2 - g.offset**2) - math.sqrt((g.a3 - g.a2) ** 2 - g.offset**2)


# -- any linkage ----------------------------------------------------------------------------

#: How far each driver is moved, both ways, when its reachable range is searched: a full
#: turn for a revolute joint, five times the linkage's size for a prismatic one.
RANGE_TURN = 2 * math.pi
RANGE_SIZES = 5.0


@dataclass(frozen=True)
class DriverRange:
    """Where one driver, moved alone from the drawn pose, locks in each direction (in its
    joint's unit from the drawn pose: rad or m); None where it does not lock within the
    searched travel (a revolute driver then turns fully)."""

    joint: str
    kind: JointKind
    low: float | None
    high: float | None
    travel: float


def driver_ranges(linkage: Linkage) -> list[DriverRange]:
    """Each driver's reachable range from the drawn pose, the others held at the drawn pose."""
    from mechcheck.analytic.linkage_kinematics import positions

    out = []
    for k, driver in enumerate(linkage.drivers):
        kind = linkage.joint(driver.joint).kind
        travel = RANGE_TURN if kind.rotates else RANGE_SIZES * linkage.scale
        values = np.zeros((2, len(linkage.drivers)))
        values[:, k] = (-travel, travel)
        _, locked = positions(linkage, values)
        low, high = (None if np.isnan(s) else float(s) * v for s, v in zip(locked, values[:, k],
                                                                            strict=True))
        out.append(DriverRange(driver.joint, kind, low, high, travel))
    return out


def mechanical_advantage(case: Case) -> list[tuple[str, float, float]]:
    """For a single-driver linkage: each load's force magnitude and the driver effort it
    needs alone at the pose (superposition of single loads), as (label, |F|, Q)."""
    from mechcheck.analytic.linkage_backends import single_loads
    from mechcheck.analytic.linkage_forces import coefficient_matrix
    from mechcheck.analytic.linkage_kinematics import solve_batched, solve_pose

    linkage = case.linkage
    if len(linkage.drivers) != 1 or linkage.dof != 1:
        return []
    pose = solve_pose(linkage)
    if not pose.assembled[0]:
        return []
    k = coefficient_matrix(pose)
    column = k.shape[2] - 1
    out = []
    for load, b in zip(linkage.loads, single_loads(linkage, pose)[:len(linkage.loads)],
                       strict=True):
        effort = float(solve_batched(k, -b)[0, column])
        out.append((f"load on {load.link}", math.hypot(*load.force), effort))
    return out


#: A loaded point has stopped (an output toggle) where its speed per unit rate of the driver
#: is below this fraction of the linkage's size (a link's turning rate: of 1); Brent's
#: method puts the stop to rounding, so a point that only turns (a crank's) stays far above.
TOGGLE_SPEED_RTOL = 1e-6


@dataclass(frozen=True)
class _Loaded:
    """What a load acts on: a point fixed to ``link`` (drawn at ``at``), or the link's turning
    (``at`` None) for a couple."""

    link: str
    at: tuple[float, float] | None


def output_toggles(linkage: Linkage, first: np.ndarray) -> np.ndarray:
    """The output toggles the first driver passes on the ascending grid ``first`` (its unit,
    rad or m, from the drawn pose; the other drivers held): values where a loaded point (a
    force's point, a weight's centre of mass) or a link loaded by a couple stops while the
    driver moves. There the load's share of the drive effort passes through zero, although
    the load does not change, and the reactions stay finite (the statics is well posed).

    Between two neighbouring poses whose velocity ratios (velocity per unit driver rate)
    point opposite ways, the stop is found by Brent's method on the ratio's component along
    the first pose's direction, and kept where the whole ratio vanishes there: a point that
    only turns (on a crank) is no toggle; a grid pose where it has stopped is one itself.
    Sorted, each toggle once."""
    from mechcheck.analytic.rigid import link_column

    loaded = [p for p in _loaded(linkage) if link_column(linkage, p.link) >= 0]
    grid = np.asarray(first, dtype=float)
    if not loaded or not linkage.drivers or grid.size < 2:
        return np.zeros(0)
    ratios = _velocity_ratios(linkage, grid, loaded)
    size = linkage.scale
    slides = not linkage.joint(linkage.drivers[0].joint).kind.rotates
    found: list[float] = []
    for probe, v in zip(loaded, ratios, strict=True):
        stopped = TOGGLE_SPEED_RTOL * (size if probe.at is not None else 1.0) \
            / (size if slides else 1.0)
        speed = np.linalg.norm(v, axis=1)
        at_pose = speed == 0.0     # a pose of the grid on the toggle itself: no direction
        found += list(grid[at_pose])
        turn = np.einsum("ij,ij->i", v[:-1], v[1:])
        for i in np.flatnonzero((turn < 0.0) & ~at_pose[:-1] & ~at_pose[1:]):
            t = _stop_between(linkage, probe, grid[i], grid[i + 1], v[i] / speed[i])
            if t is not None and np.linalg.norm(
                    _velocity_ratios(linkage, np.array([t]), [probe])[0][0]) <= stopped:
                found.append(t)
    return _distinct(np.sort(np.array(found)), 1e-9 * max(1.0, float(np.ptp(grid))))


def _stop_between(linkage: Linkage, probe: _Loaded, a: float, b: float,
                  u: np.ndarray) -> float | None:
    """Where the velocity ratio's component along ``u`` (its direction at ``a``) passes
    zero between ``a`` and ``b``, by Brent's method; None where it does not there."""
    from scipy.optimize import brentq

    def along(t: float) -> float:
        return float(_velocity_ratios(linkage, np.array([t]), [probe])[0][0] @ u)

    try:
        return float(brentq(along, a, b, xtol=1e-14 * max(1.0, abs(a))))
    except ValueError:  # no sign change once recomputed (a rounding-level grazing)
        return None


def _loaded(linkage: Linkage) -> list[_Loaded]:
    """What the linkage's loads act on: forces' points, couples' links, and the centres of
    mass when there is gravity."""
    out = []
    for load in linkage.loads:
        if any(load.force):
            out.append(_Loaded(load.link, load.at))
        if load.torque:
            out.append(_Loaded(load.link, None))
    if any(linkage.gravity):
        out += [_Loaded(m.link, m.com) for m in linkage.masses]
    return list(dict.fromkeys(out))


def _velocity_ratios(linkage: Linkage, first: np.ndarray, loaded: list[_Loaded]) -> list[np.ndarray]:
    """Per loaded thing, its velocity per unit rate of the first driver at each value of it:
    (N, 2) for a point, (N, 1) for a link's turning."""
    from mechcheck.analytic.linkage_kinematics import solve_pose

    d = len(linkage.drivers)
    values = np.tile([drv.value for drv in linkage.drivers], (first.size, 1)).astype(float)
    values[:, 0] = first
    rates = np.zeros((first.size, d))
    rates[:, 0] = 1.0
    pose = solve_pose(linkage, values, rates, np.zeros((first.size, d)))
    out = []
    for p in loaded:
        if p.at is None:
            out.append(pose.link_state(p.link, pose.qdot)[1][:, None])
        else:
            out.append(pose.point(p.link, p.at)[1])
    return out


def _distinct(values: np.ndarray, gap: float) -> np.ndarray:
    """Sorted values without repeats closer than ``gap`` (several loads stopping at once)."""
    if values.size == 0:
        return values
    keep = np.concatenate([[True], np.diff(values) > gap])
    return values[keep]
