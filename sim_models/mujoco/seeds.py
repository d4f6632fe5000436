"""The seed examples (SEEDS.md E1, E2) built in code.

They are the cases the golden XML files, the stiffness study and the
benchmarks use until the shared case files (``compare/cases/*.toml``) exist.
"""

from __future__ import annotations

import math

from analytic.case import Case, FourBarGeometry, Friction, Load, SliderCrankGeometry


def _polar(magnitude: float, degrees: float) -> tuple[float, float]:
    angle = math.radians(degrees)
    return (magnitude * math.cos(angle), magnitude * math.sin(angle))


def fourbar_e1() -> Case:
    """Söylemez Example 6.3 (SEEDS.md E1): loads at C on the coupler and D on the rocker."""
    alpha = math.acos((-80.0**2 + 100.0**2 + 70.0**2) / (2.0 * 70.0 * 100.0))
    return Case(
        name="E1-fourbar",
        geometry=FourBarGeometry(a1=0.140, a2=0.080, a3=0.100, a4=0.120),
        theta12=math.radians(60.0),
        loads=(
            Load(link=3, at=(0.070 * math.cos(alpha), 0.070 * math.sin(alpha)),
                 force=_polar(50.0, 50.0)),
            Load(link=4, at=(0.090, 0.0), force=_polar(100.0, 20.0)),
        ),
    )


def slidercrank_e2(*, with_friction: bool = True) -> Case:
    """SEEDS.md E2: centric slider-crank, 100 N against the slider, μ = 0.1 everywhere."""
    friction = Friction(mu=0.1, pin_radius={"A0": 0.050, "A": 0.250, "B": 0.050},
                        direction=-1) if with_friction else None
    return Case(
        name="E2-slidercrank" if with_friction else "E2-slidercrank-frictionless",
        geometry=SliderCrankGeometry(a2=0.200, a3=0.800),
        theta12=math.radians(55.0),
        loads=(Load(link=4, at=(0.0, 0.0), force=(-100.0, 0.0)),),
        friction=friction,
    )


def seed_cases() -> list[Case]:
    """Every seed case with a golden MuJoCo model."""
    return [fourbar_e1(), slidercrank_e2(with_friction=False), slidercrank_e2()]
