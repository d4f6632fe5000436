"""A deliberately simple speed reference for the frictionless preset statics: the four-bar's
and slider-crank's force analysis written as straight-line numpy on float64 arrays.

It computes what :func:`mechcheck.solve_poses` returns for a static,
frictionless four-bar or slider-crank (CONVENTIONS.md names): the pose angles (theta13,
theta14 or s14), F12, F23, F34, F14 (and M14 of a slider), the drive torque T12 (T14 for a
four-bar driven on its rocker) and the condition number, with the forces withheld (NaN) beyond
``SINGULAR_CONDITION``. ``bench_analytic.py`` times it in the same run as the library,
so the library's rate is judged against what plain numpy does on this machine now.

It is written from the free-body diagrams, not from the library's elimination, so
``tests/test_fast_path.py`` also uses it as an independent check:

* every load on a link is folded into one resultant: the force sum F and, since a
  body-fixed point c (link frame) sits at R(θ)·c from the frame origin, the moment about
  that origin ``cos θ·P − sin θ·Q + T`` with P = Σ c × f and Q = Σ c · f;
* four-bar: the rocker's moments about B0 and the coupler's about A fix F34 (2×2, by
  Cramer's rule); force balances give F23, F12, F14; the crank's moment about A0 gives T12
  (driven on the rocker: the crank's moment about A0 and the coupler's fix F34, and the
  rocker's about B0 gives T14);
* slider-crank: the slider's force balance along the slide and the rod's moments about A
  fix F34; the slide's normal reaction and the guide's moment M14 follow from the slider.

:func:`worst_error` judges the library against it as the tolerance policy judges two
analytic backends: each quantity's error over its kind's scale at that pose.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from mechcheck.analytic.case import Case, FourBarGeometry, SliderCrankGeometry

Array = NDArray[np.float64]

#: The library's threshold (equilibrium.SINGULAR_CONDITION), restated: the same outputs.
SINGULAR_CONDITION = 1.0e8


def resultants(case: Case) -> dict[int, tuple[float, float, float, float, float]]:
    """Per moving link: (Fx, Fy, P, Q, T), the fixed loads and weights folded together."""
    out = {link: [0.0, 0.0, 0.0, 0.0, 0.0] for link in (2, 3, 4)}
    items = [(ld.link, ld.at, ld.force, ld.torque) for ld in case.preset.loads]
    items += [(m.link, m.com, (m.mass * case.gravity[0], m.mass * case.gravity[1]), 0.0)
              for m in case.preset.masses]
    for link, (cx, cy), (fx, fy), torque in items:
        r = out[link]
        r[0] += fx
        r[1] += fy
        r[2] += cx * fy - cy * fx
        r[3] += cx * fx + cy * fy
        r[4] += torque
    return {link: (r[0], r[1], r[2], r[3], r[4]) for link, r in out.items()}


def _check(case: Case) -> None:
    if case.kind != "static":
        raise NotImplementedError("the reference covers static, frictionless cases")


def _condition(dot: Array, norms: Array) -> Array:
    """Condition number of a 2×2 matrix with unit rows whose dot product is dot/norms."""
    cos = np.abs(dot) / norms
    return np.sqrt((1.0 + cos) / (1.0 - cos))


def _withhold(forces: dict[str, Array], cond: Array) -> dict[str, Array]:
    """Forces as NaN where the pose is singular (or does not assemble: cond is NaN)."""
    singular = ~(cond <= SINGULAR_CONDITION)
    return {q: np.where(singular, np.nan, v) for q, v in forces.items()}


def _wrap(angle: Array) -> Array:
    return np.remainder(angle + np.pi, 2.0 * np.pi) - np.pi


def fourbar_statics(case: Case, theta12: Array) -> dict[str, Array]:
    """The four-bar's static force analysis at each θ12 (rad)."""
    _check(case)
    g = case.preset.geometry
    assert isinstance(g, FourBarGeometry)
    a1, a2, a3, a4 = g.a1, g.a2, g.a3, g.a4
    (f2x, f2y, p2, q2, t2), (f3x, f3y, p3, q3, t3), (f4x, f4y, p4, q4, t4) = \
        resultants(case).values()
    cg, sg = np.cos(case.preset.ground_angle), np.sin(case.preset.ground_angle)
    c12, s12 = np.cos(theta12), np.sin(theta12)
    # The closed form in the ground frame (CONVENTIONS.md "Branches").
    c12g, s12g = c12 * cg + s12 * sg, s12 * cg - c12 * sg
    cc = a1 * a1 + a2 * a2 + a4 * a4 - a3 * a3 - 2.0 * a1 * a2 * c12g
    aa = 2.0 * a2 * a4 * c12g - 2.0 * a1 * a4
    bb = 2.0 * a2 * a4 * s12g
    sign = -1.0 if case.preset.branch == "open" else 1.0
    theta14 = np.arctan2(bb, aa) + sign * np.arccos(cc / np.hypot(aa, bb)) + case.preset.ground_angle
    c14, s14 = np.cos(theta14), np.sin(theta14)
    ax, ay = a2 * c12, a2 * s12
    b0x, b0y = a1 * cg, a1 * sg
    ux, uy = a4 * c14, a4 * s14            # B − B0
    bx, by = b0x + ux, b0y + uy
    vx, vy = bx - ax, by - ay              # B − A
    theta13 = np.arctan2(vy, vx)
    c13, s13 = vx / a3, vy / a3
    m2 = p2 * c12 - q2 * s12 + t2          # loads' moments about each link's frame origin
    m3 = p3 * c13 - q3 * s13 + t3
    m4 = p4 * c14 - q4 * s14 + t4
    if case.preset.drive_link == 2:
        # Rocker about B0: u × F34 + m4 = 0; coupler about A: v × (−F34) + m3 = 0.
        det = ux * vy - uy * vx
        f34x = -(m4 * vx + m3 * ux) / det
        f34y = -(m4 * vy + m3 * uy) / det
        cond = _condition(ux * vx + uy * vy, np.hypot(ux, uy) * np.hypot(vx, vy))
    else:
        # Crank about A0: A × (−F23) + m2 = 0 with F23 = F34 − F3, so A × F34 = m2 + A × F3;
        # coupler about A: v × F34 = m3.
        w = m2 + ax * f3y - ay * f3x
        det = ax * vy - ay * vx
        f34x = (w * vx - m3 * ax) / det
        f34y = (w * vy - m3 * ay) / det
        cond = _condition(ax * vx + ay * vy, np.hypot(ax, ay) * np.hypot(vx, vy))
    f23x, f23y = f34x - f3x, f34y - f3y
    f12x, f12y = f23x - f2x, f23y - f2y
    out = {"F12_x": f12x, "F12_y": f12y, "F23_x": f23x, "F23_y": f23y, "F34_x": f34x,
           "F34_y": f34y, "F14_x": -f34x - f4x, "F14_y": -f34y - f4y}
    if case.preset.drive_link == 2:
        out["T12"] = ax * f23y - ay * f23x - m2   # crank about A0: A × (−F23) + m2 + T12 = 0
    else:
        out["T14"] = -(ux * f34y - uy * f34x) - m4  # rocker about B0: u × F34 + m4 + T14 = 0
    return _withhold(out, cond) | {"theta13": _wrap(theta13), "theta14": _wrap(theta14),
                                   "condition": cond}


def slidercrank_statics(case: Case, theta12: Array) -> dict[str, Array]:
    """The slider-crank's static force analysis at each θ12 (rad)."""
    _check(case)
    g = case.preset.geometry
    assert isinstance(g, SliderCrankGeometry)
    a2, a3, e = g.a2, g.a3, g.offset
    (f2x, f2y, p2, q2, t2), (f3x, f3y, p3, q3, t3), (f4x, f4y, p4, q4, t4) = \
        resultants(case).values()
    cg, sg = np.cos(case.preset.ground_angle), np.sin(case.preset.ground_angle)   # u; n = (−sg, cg)
    c12, s12 = np.cos(theta12), np.sin(theta12)
    ax, ay = a2 * c12, a2 * s12
    # Rod across the slide line: n · (B − A) = e − n · A.
    s13g = (e - (ay * cg - ax * sg)) / a3
    c13g = np.sqrt(1.0 - s13g * s13g) * (1.0 if case.preset.branch == "right" else -1.0)
    s14 = (ax * cg + ay * sg) + a3 * c13g
    bx, by = s14 * cg - e * sg, s14 * sg + e * cg
    vx, vy = bx - ax, by - ay              # B − A
    theta13 = np.arctan2(vy, vx)
    c13, s13 = vx / a3, vy / a3
    m2 = p2 * c12 - q2 * s12 + t2
    m3 = p3 * c13 - q3 * s13 + t3
    m4 = p4 * cg - q4 * sg + t4            # the slider's frame turns with the slide
    # Slider along u: u · F34 + u · F4 = 0; rod about A: v × (−F34) + m3 = 0.
    along = -(f4x * cg + f4y * sg)
    det = cg * vx + sg * vy
    f34x = (along * vx - sg * m3) / det
    f34y = (cg * m3 + vy * along) / det
    f23x, f23y = f34x - f3x, f34y - f3y
    f12x, f12y = f23x - f2x, f23y - f2y
    normal = sg * (f34x + f4x) - cg * (f34y + f4y)   # N along n balances the slider
    t12 = ax * f23y - ay * f23x - m2
    cond = _condition(-vy * cg + vx * sg, np.hypot(vx, vy))
    out = {"F12_x": f12x, "F12_y": f12y, "F23_x": f23x, "F23_y": f23y, "F34_x": f34x,
           "F34_y": f34y, "F14_x": -normal * sg, "F14_y": normal * cg,
           "M14": np.full_like(theta12, -m4), "T12": t12}
    return _withhold(out, cond) | {"theta13": _wrap(theta13), "s14": s14, "condition": cond}


def worst_error(case: Case, reference: dict[str, Array], library: dict[str, Array],
                poses: NDArray[np.bool_]) -> float:
    """The largest error of ``library`` against ``reference`` at the selected poses, each
    over its kind's scale there (tables.kind_scales, pose by pose): forces over the largest
    reaction (or drive torque over the longest link; at least FORCE_FLOOR_N = 0.01 N),
    torques over that times the longest link, angles over 1 rad (the difference wrapped),
    s14 over the longest link."""
    length = case.scale
    forces = np.array([np.abs(v) for q, v in reference.items() if q.startswith("F")])
    torques = np.array([np.abs(v) for q, v in reference.items() if q[0] in "TM"])
    force_scale = np.maximum(np.maximum(forces.max(axis=0), torques.max(axis=0) / length), 0.01)
    worst = 0.0
    for q, ref in reference.items():
        if q == "condition":
            continue
        diff = library[q][poses] - ref[poses]
        if q.startswith("theta"):
            diff = np.remainder(diff + np.pi, 2.0 * np.pi) - np.pi
        scale = {"F": force_scale, "T": force_scale * length, "M": force_scale * length}.get(
            q[0], 1.0 if q.startswith("theta") else length)
        scale = scale[poses] if isinstance(scale, np.ndarray) else scale
        worst = max(worst, float(np.max(np.abs(diff) / scale, initial=0.0)))
    return worst
