"""Test helper: a simple reference kept in ``benchmarks/`` (which is not installed), loaded
from its file."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import ModuleType


def benchmark_module(name: str) -> ModuleType:
    """``benchmarks/<name>.py`` as a module."""
    path = Path(__file__).resolve().parents[1] / "benchmarks" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
