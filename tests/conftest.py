"""Session-wide guards for the test suite."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest


@pytest.fixture(autouse=True, scope="session")
def no_mujoco_log_left_behind() -> Iterator[None]:
    """MuJoCo's warnings are routed into Python: a run leaves no MUJOCO_LOG.TXT where it ran."""
    log = Path.cwd() / "MUJOCO_LOG.TXT"
    existed = log.exists()
    yield
    assert existed or not log.exists(), f"MuJoCo wrote {log}: a warning escaped the handler"
