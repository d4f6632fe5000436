"""Test helpers: the built-in cases by name."""

from __future__ import annotations

from functools import cache

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage import Joint, Link, Linkage, LinkMass
from mechcheck.casefile import builtin_case_files, load_cases


@cache
def builtin_cases() -> dict[str, Case]:
    return {c.name: c for c in load_cases(*builtin_case_files())}


def builtin(name: str) -> Case:
    """A built-in case (compare/cases/*.toml) by its name."""
    return builtin_cases()[name]


def rocker_load_case(name: str) -> str:
    """Case-file text of seed E1's geometry with 100 N at 20° on the rocker (SEEDS.md E1)."""
    return f"""
[[case]]
name = "{name}"
mechanism = "four_bar"
length_unit = "mm"
theta12 = 60.0
[case.geometry]
a1 = 140.0
a2 = 80.0
a3 = 100.0
a4 = 120.0
[[case.loads]]
link = 4
at = [90.0, 0.0]
force = {{ magnitude = 100.0, angle = 20.0 }}
"""


def sliding_collar() -> Case:
    """A bar pinned at O with a collar sliding freely along it, under gravity: its only
    equilibria are unstable (the potential falls without bound as the collar slides off a
    hanging bar, and a standing bar with the collar at O is an inverted pendulum), so the
    free-coordinate search can end only on an unstable one (tests/test_free_equilibrium.py
    derives it)."""
    linkage = Linkage(
        points={"O": (0.0, 0.0), "E": (1.0, 0.0), "G": (0.3, 0.0), "C": (0.5, 0.0)},
        links=(Link("ground", ("O",)), Link("bar", ("O", "E", "G")), Link("collar", ("C",))),
        joints=(Joint("O", "revolute", ("ground", "bar"), "O"),
                Joint("sleeve", "prismatic", ("bar", "collar"), "C", (1.0, 0.0))),
        masses=(LinkMass("bar", 2.0, (0.3, 0.0), 0.0), LinkMass("collar", 1.0, (0.5, 0.0), 0.0)),
        gravity=(0.0, -9.81),
    )
    return Case(name="sliding-collar", geometry=linkage)
