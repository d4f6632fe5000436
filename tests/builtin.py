"""Test helpers: the built-in cases by name."""

from __future__ import annotations

from functools import cache

from mechcheck.analytic.case import Case
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
