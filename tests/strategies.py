"""Hypothesis strategies: random assemblable, well-conditioned Cases."""

from __future__ import annotations

import math

from hypothesis import assume, strategies as st

from mechcheck.analytic import forces
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


@st.composite
def geometries(draw: st.DrawFn, mechanism: str) -> FourBarGeometry | SliderCrankGeometry:
    if mechanism == "four_bar":
        return FourBarGeometry(draw(length), draw(length), draw(length), draw(length))
    return SliderCrankGeometry(draw(length), draw(length), draw(st.floats(-0.3, 0.3)))


@st.composite
def frictions(draw: st.DrawFn, mechanism: str, direction: int) -> Friction:
    pins = ("A0", "A", "B", "B0") if mechanism == "four_bar" else ("A0", "A", "B")
    radii = {p: draw(st.floats(0.0, 0.03)) for p in draw(st.sets(st.sampled_from(pins),
                                                                 min_size=1))}
    viscous = {p: draw(st.floats(0.0, 0.5)) for p in draw(st.sets(st.sampled_from(pins)))}
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
        case = Case(
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
