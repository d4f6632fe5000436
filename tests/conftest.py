"""Session-wide guards for the test suite."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

# README's test command is deterministic: every run tries the same hypothesis examples,
# so a user's first run and CI see the same verdicts. `pytest --hypothesis-profile=explore`
# draws new examples (and keeps failing ones in .hypothesis/); a failure it finds prints the
# example, which then becomes a pinned test (`@example(...)` or a test of its own).
settings.register_profile("deterministic", derandomize=True, database=None, print_blob=True)
settings.register_profile("explore", derandomize=False, print_blob=True,
                          suppress_health_check=[HealthCheck.too_slow])
settings.load_profile("deterministic")


@pytest.fixture(autouse=True, scope="session")
def no_mujoco_log_left_behind() -> Iterator[None]:
    """MuJoCo's warnings are routed into Python: a run leaves no MUJOCO_LOG.TXT where it ran."""
    log = Path.cwd() / "MUJOCO_LOG.TXT"
    existed = log.exists()
    yield
    assert existed or not log.exists(), f"MuJoCo wrote {log}: a warning escaped the handler"
