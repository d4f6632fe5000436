"""README's test command passes the same way on every run: the property tests draw the same
examples each time, and only a chosen profile draws new ones."""

from __future__ import annotations

import pytest
from hypothesis import given, settings, strategies as st

DRAWN: list[float] = []


def test_the_default_profile_is_derandomized(pytestconfig: pytest.Config) -> None:
    """Without --hypothesis-profile, hypothesis runs derandomized and keeps no example
    database, so a first run on a new machine meets exactly the draws CI meets."""
    if pytestconfig.getoption("hypothesis_profile", None) not in (None, "deterministic"):
        pytest.skip("another profile was chosen on the command line")
    assert settings.default.derandomize is True
    assert settings.default.database is None


def _draw_twice() -> list[list[float]]:
    runs: list[list[float]] = []
    for _ in range(2):
        DRAWN.clear()

        @settings(max_examples=20)
        @given(st.floats(-1e6, 1e6))
        def record(x: float) -> None:
            DRAWN.append(x)

        record()
        runs.append(list(DRAWN))
    return runs


def test_two_runs_draw_the_same_examples(pytestconfig: pytest.Config) -> None:
    """The same property run twice in one session tries the same values in the same order."""
    if pytestconfig.getoption("hypothesis_profile", None) not in (None, "deterministic"):
        pytest.skip("another profile was chosen on the command line")
    first, second = _draw_twice()
    assert first == second and len(first) == 20
