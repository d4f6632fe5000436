"""Hypothesis strategies: random assemblable, well-conditioned Cases."""

from __future__ import annotations

import math
from typing import Any

from hypothesis import assume, strategies as st

from mechcheck.analytic.case import (
    Case,
    CaseError,
    FourBarGeometry,
    Friction,
    Load,
    Mass,
    Motion,
    SliderCrankGeometry,
)
from mechcheck.analytic.linkage import Linkage
from mechcheck.analytic.presets import preset_case
from mechcheck.analytic.solution import Solution
from mechcheck.analytic.values import GROUND

from .closed_form import forces

#: Random poses closer than this to a toggle are left to the singular-pose
#: tests: their forces are amplified by the condition number and identities
#: then hold only to cond × eps.
MAX_CONDITION = 1e4

length = st.floats(0.05, 1.0)
coordinate = st.floats(-0.5, 0.5)
force_component = st.floats(-200.0, 200.0)
angle = st.floats(-math.pi, math.pi)


@st.composite
def loads(draw: st.DrawFn, max_size: int = 3) -> tuple[Load, ...]:
    n = draw(st.integers(1, max_size))
    return tuple(Load(link=draw(st.sampled_from((2, 3, 4))),
                      at=(draw(coordinate), draw(coordinate)),
                      force=(draw(force_component), draw(force_component)),
                      torque=draw(st.floats(-20.0, 20.0))) for _ in range(n))


@st.composite
def masses(draw: st.DrawFn) -> tuple[Mass, ...]:
    links = draw(st.sets(st.sampled_from((2, 3, 4))))
    return tuple(Mass(link=k, mass=draw(st.floats(0.1, 5.0)),
                      com=(draw(coordinate), draw(coordinate)),
                      inertia=draw(st.floats(0.0, 0.05))) for k in sorted(links))


def assembling(factory: Any, *lengths: float) -> Any:
    """A geometry that assembles at some θ12; others (which refuse themselves) are rejected."""
    try:
        return factory(*lengths)
    except CaseError:
        assume(False)
        raise  # unreachable: assume(False) raises


@st.composite
def geometries(draw: st.DrawFn, mechanism: str) -> FourBarGeometry | SliderCrankGeometry:
    if mechanism == "four_bar":
        return assembling(FourBarGeometry, draw(length), draw(length), draw(length), draw(length))
    return assembling(SliderCrankGeometry, draw(length), draw(length), draw(st.floats(-0.3, 0.3)))


@st.composite
def frictions(draw: st.DrawFn, mechanism: str, direction: int) -> Friction:
    pins = ("A0", "A", "B", "B0") if mechanism == "four_bar" else ("A0", "A", "B")
    # Sets of names are walked sorted: their own order follows PYTHONHASHSEED, and the draws
    # that follow them would differ from run to run.
    radii = {p: draw(st.floats(0.0, 0.03)) for p in sorted(draw(st.sets(st.sampled_from(pins),
                                                                        min_size=1)))}
    viscous = {p: draw(st.floats(0.0, 0.5)) for p in sorted(draw(st.sets(st.sampled_from(pins))))}
    return Friction(mu=draw(st.floats(0.01, 0.3)), pin_radius=radii,
                    slide_mu=draw(st.floats(0.0, 0.3)) if mechanism == "slider_crank" else None,
                    viscous=viscous, direction=direction)


@st.composite
def cases(draw: st.DrawFn, *, mechanism: str | None = None, friction: bool | None = False,
          dynamic: bool | None = None, gravity: bool | None = None) -> Case:
    """A random Case that assembles and is not near a toggle.

    ``None`` for a flag means "either".
    """
    mech = mechanism or draw(st.sampled_from(("four_bar", "slider_crank")))
    geometry = draw(geometries(mech))
    moving = draw(st.booleans()) if dynamic is None else dynamic
    motion = Motion(draw(st.floats(-30.0, 30.0)), draw(st.floats(-200.0, 200.0))) if moving \
        else Motion()
    with_friction = draw(st.booleans()) if friction is None else friction
    sense = draw(st.sampled_from((-1, 1)))
    if motion.omega:
        sense = 1 if motion.omega > 0 else -1
    branches = ("open", "crossed") if mech == "four_bar" else ("right", "left")
    with_gravity = draw(st.booleans()) if gravity is None else gravity
    try:
        case = preset_case(
            name="random", geometry=geometry, theta12=draw(angle),
            branch=draw(st.sampled_from(branches)), ground_angle=draw(angle),
            drive_link=draw(st.sampled_from((2, 4))) if mech == "four_bar" else 2,
            gravity=(draw(st.floats(-10, 10)), draw(st.floats(-10, 10))) if with_gravity
            else (0.0, 0.0),
            loads=draw(loads()), masses=draw(masses()), motion=motion,
            friction=draw(frictions(mech, sense)) if with_friction else None,
        )
    except CaseError:
        assume(False)
        raise  # unreachable: assume(False) raises
    solution = forces.solve(case)
    assume(solution.status == "ok")
    assume(float(solution.diagnostics["condition_number"]) < MAX_CONDITION)
    return case


# -- random linkages (LINKAGES.md tables) ---------------------------------------------------

def _number(lo: float, hi: float) -> st.SearchStrategy[float]:
    """A float in [lo, hi], never subnormal: a driver turned 2e-311 rad is no drawing."""
    return st.floats(lo, hi, allow_subnormal=False)


def _circle_intersection(p: tuple[float, float], r1: float, q: tuple[float, float], r2: float,
                         sign: int) -> tuple[float, float] | None:
    """The point at r1 from p and r2 from q on the side ``sign`` of p→q, or None."""
    dx, dy = q[0] - p[0], q[1] - p[1]
    d = math.hypot(dx, dy)
    if d == 0.0 or d > r1 + r2 or d < abs(r1 - r2):
        return None
    a = (r1 * r1 - r2 * r2 + d * d) / (2 * d)
    h = math.sqrt(max(r1 * r1 - a * a, 0.0))
    mx, my = p[0] + a * dx / d, p[1] + a * dy / d
    return (mx - sign * h * dy / d, my + sign * h * dx / d)


def _revolute(name: str, a: str, b: str) -> dict[str, object]:
    return {"name": name, "kind": "revolute", "links": [a, b], "at": name}


@st.composite
def linkage_tables(draw: st.DrawFn, *, friction: bool = False, moving: bool | None = None,
                   springs: bool = True) -> dict[str, object]:
    """A random linkage case table (lengths in m): a four-bar or slider-crank, optionally
    extended by a second dyad into a Watt or Stephenson six-bar, drawn in an assembled
    pose, with random loads, masses, gravity, springs and a driver moved up to ±20°."""
    size = _number(0.2, 1.0)
    points: dict[str, list[float]] = {"O2": [0.0, 0.0]}
    ground = ["O2"]
    crank_angle = draw(_number(-math.pi, math.pi))
    a2 = draw(_number(0.1, 0.4))
    points["A"] = [a2 * math.cos(crank_angle), a2 * math.sin(crank_angle)]
    links = [{"name": "crank", "points": ["O2", "A"]}]
    joints = [_revolute("O2", "ground", "crank"), _revolute("A", "crank", "coupler")]
    slider = draw(st.booleans())
    if slider:
        axis_angle = draw(_number(-math.pi, math.pi))
        axis = (math.cos(axis_angle), math.sin(axis_angle))
        along = draw(_number(0.3, 1.2)) * draw(st.sampled_from([-1, 1]))
        offset = draw(_number(-0.1, 0.1))
        b = (points["A"][0] + along * axis[0] - offset * axis[1],
             points["A"][1] + along * axis[1] + offset * axis[0])
        points["B"] = list(b)
        links += [{"name": "coupler", "points": ["A", "B"]}, {"name": "slider", "points": ["B"]}]
        joints += [_revolute("B", "coupler", "slider"),
                   {"name": "slide", "kind": "prismatic", "links": ["ground", "slider"],
                    "at": "B", "axis": list(axis)}]
        carrier = "coupler"
    else:
        o4 = (draw(size), draw(_number(-0.3, 0.3)))
        points["O4"] = list(o4)
        ground.append("O4")
        b = _circle_intersection(tuple(points["A"]), draw(size), o4, draw(size),  # type: ignore[arg-type]
                                 draw(st.sampled_from([-1, 1])))
        assume(b is not None)
        assert b is not None
        points["B"] = list(b)
        links += [{"name": "coupler", "points": ["A", "B"]},
                  {"name": "rocker", "points": ["O4", "B"]}]
        joints += [_revolute("B", "coupler", "rocker"), _revolute("O4", "ground", "rocker")]
        carrier = draw(st.sampled_from(["coupler", "rocker"]))
    if draw(st.booleans()):  # a second dyad C-D-O6: Watt (C on the rocker) or Stephenson
        c = (points["B"][0] + draw(_number(-0.2, 0.2)), points["B"][1] + draw(_number(-0.2, 0.2)))
        d = (c[0] + draw(_number(0.2, 0.6)), c[1] + draw(_number(-0.3, 0.3)))
        o6 = (d[0] + draw(_number(-0.3, 0.3)), d[1] - draw(_number(0.2, 0.6)))
        points.update(C=list(c), D=list(d), O6=list(o6))
        ground.append("O6")
        next(link for link in links if link["name"] == carrier)["points"].append("C")  # type: ignore[union-attr]
        links += [{"name": "link5", "points": ["C", "D"]}, {"name": "output", "points": ["O6", "D"]}]
        joints += [_revolute("C", carrier, "link5"), _revolute("D", "link5", "output"),
                   _revolute("O6", "ground", "output")]
    links.insert(0, {"name": "ground", "points": ground})
    # Two points of one link are at one place or a link length apart (a case file's rule:
    # at least a micrometre; here a tenth of a millimetre, so that scaled drawings keep it).
    for link in links:
        carried = [points[p] for p in link["points"]]  # type: ignore[union-attr]
        assume(all(math.dist(p, q) == 0.0 or math.dist(p, q) >= 1e-4
                   for i, p in enumerate(carried) for q in carried[i + 1:]))
    moving_links = [str(link["name"]) for link in links if link["name"] != "ground"]
    is_moving = draw(st.booleans()) if moving is None else moving
    driver: dict[str, object] = {"joint": "O2", "rotation": draw(_number(-20.0, 20.0))}
    if is_moving:
        driver.update(velocity=draw(_number(0.5, 20.0)) * draw(st.sampled_from([-1, 1])),
                      acceleration=draw(_number(-100.0, 100.0)))
    table: dict[str, object] = {
        "name": "random-linkage", "mechanism": "linkage",
        "gravity": [draw(_number(-10.0, 10.0)), draw(_number(-10.0, 10.0))],
        "points": points, "links": links, "joints": joints, "drivers": [driver],
        "loads": [{"link": draw(st.sampled_from(moving_links)),
                   "at": [draw(_number(-0.5, 1.0)), draw(_number(-0.5, 0.5))],
                   "force": {"x": draw(_number(-200.0, 200.0)), "y": draw(_number(-200.0, 200.0))},
                   "torque": draw(_number(-10.0, 10.0))} for _ in range(draw(st.integers(1, 3)))],
        "masses": [{"link": name, "mass": draw(_number(0.1, 5.0)),
                    "com": [draw(_number(-0.5, 1.0)), draw(_number(-0.5, 0.5))],
                    "inertia": draw(_number(0.0, 0.05))}
                   for name in sorted(draw(st.sets(st.sampled_from(moving_links))))],
    }
    if springs and draw(st.booleans()):
        a, b2 = draw(st.sampled_from(moving_links)), "ground"
        table["springs"] = [{"name": "k1", "ends": [[b2, "O2"], [a, points["A"] if a == "crank"
                                                                 else [0.3, 0.3]]],
                             "stiffness": draw(_number(10.0, 2000.0)),
                             "free_length": draw(_number(0.05, 0.8))},
                            {"name": "k2", "joint": "A", "stiffness": draw(_number(0.0, 20.0)),
                             "free_rotation": draw(_number(-30.0, 30.0))}]
    if friction:
        revolutes = [str(j["name"]) for j in joints if j["kind"] == "revolute"]
        table["friction"] = {"mu": draw(_number(0.01, 0.3)),
                             "pin_radius": {j: draw(_number(0.0, 0.03))
                                            for j in sorted(draw(st.sets(
                                                st.sampled_from(revolutes), min_size=1)))}}
        if not is_moving:
            driver["sense"] = draw(st.sampled_from(["increasing", "decreasing"]))
    return table


#: Relative to the largest joint force: an inner joint's force below this is the rounding of
#: a zero (a spring pulling a crank along itself onto its ground pin left 2e-15 N at every
#: inner joint against 3.75 N at the pin: a draw of README's test command, 2026-11-26).
ROUNDING = 1e-9


def inner_joints(linkage: Linkage) -> set[str]:
    """The joints between two moving links."""
    return {j.name for j in linkage.joints if GROUND not in j.links}


def carries_a_force(reference: Solution, joints: set[str]) -> bool:
    """Whether one of ``joints`` carries a force above the rounding of ``reference``'s
    largest joint force. Where none does, every load goes straight to the ground and the
    simulators' joint forces alternate about zero (docs/limitations.md)."""
    magnitudes = {q: abs(v) for q, v in reference.values.items() if q.startswith("F_")}
    largest = max(magnitudes.values(), default=0.0)
    return any(v > ROUNDING * largest for q, v in magnitudes.items() if q[2:-2] in joints)


def four_bar_table(points: dict[str, list[float]], **rest: Any) -> dict[str, Any]:
    """A ``mechanism = "linkage"`` table of the four-bar :func:`linkage_tables` draws
    (ground O2–O4, crank O2–A, coupler A–B, rocker O4–B, pins at their points), no
    gravity and no masses unless ``rest`` (drivers, loads, springs …) says otherwise."""
    links = (("ground", ["O2", "O4"]), ("crank", ["O2", "A"]), ("coupler", ["A", "B"]),
             ("rocker", ["O4", "B"]))
    pins = (("O2", ["ground", "crank"]), ("A", ["crank", "coupler"]),
            ("B", ["coupler", "rocker"]), ("O4", ["ground", "rocker"]))
    return {"name": "random-linkage", "mechanism": "linkage", "gravity": [0.0, 0.0],
            "points": points, "links": [{"name": n, "points": p} for n, p in links],
            "joints": [{"name": n, "kind": "revolute", "links": between, "at": n}
                       for n, between in pins],
            "masses": [], **rest}
