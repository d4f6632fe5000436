"""Seed cases E1 and E2 built in code (until compare.casefile ships them as TOML).

Source: SEEDS.md — E1 is Söylemez, *Mechanisms*, Example 6.3; E2 is the
slider-crank with friction in every joint of seed 000.
"""

from __future__ import annotations

import math

from analytic.case import Case, FourBarGeometry, Friction, Load, SliderCrankGeometry


def polar(magnitude: float, degrees: float) -> tuple[float, float]:
    """A force of given magnitude at an angle in degrees, as (x, y)."""
    a = math.radians(degrees)
    return magnitude * math.cos(a), magnitude * math.sin(a)


def e1() -> Case:
    """Four-bar 140/80/100/120 mm at θ12 = 60°, 50 N at 50° on C, 100 N at 20° on D.

    Analytic T12 = +2.90133 N·m.
    """
    alpha = math.acos((-80.0**2 + 100.0**2 + 70.0**2) / (2.0 * 70.0 * 100.0))
    return Case(
        name="E1",
        geometry=FourBarGeometry(a1=0.14, a2=0.08, a3=0.10, a4=0.12),
        theta12=math.radians(60.0),
        loads=(Load(3, at=(0.07 * math.cos(alpha), 0.07 * math.sin(alpha)), force=polar(50, 50)),
               Load(4, at=(0.09, 0.0), force=polar(100, 20))),
    )


def e2() -> Case:
    """Slider-crank 200/800 mm at θ12 = 55°, −100 N on the slider, μ = 0.1, crank turning cw.

    Analytic T12 = −22.897 N·m (frictionless −18.783 N·m).
    """
    return Case(
        name="E2",
        geometry=SliderCrankGeometry(a2=0.2, a3=0.8),
        theta12=math.radians(55.0),
        loads=(Load(4, at=(0.0, 0.0), force=(-100.0, 0.0)),),
        friction=Friction(mu=0.1, pin_radius={"A0": 0.05, "A": 0.25, "B": 0.05}, direction=-1),
    )
