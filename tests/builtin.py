"""Test helpers: the built-in cases by name."""

from __future__ import annotations

from functools import cache

from analytic.case import Case
from compare.casefile import builtin_case_files, load_cases


@cache
def builtin_cases() -> dict[str, Case]:
    return {c.name: c for c in load_cases(*builtin_case_files())}


def builtin(name: str) -> Case:
    """A built-in case (compare/cases/*.toml) by its name."""
    return builtin_cases()[name]
