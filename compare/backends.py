"""Backend registry: name → function ``Case -> Solution``.

Backends are imported lazily so that a missing or broken simulator affects
only the runs that ask for it, with a clear message. Adding a simulator means
adding one line here and one module under ``sim_models/``.
"""

from __future__ import annotations

import importlib
import importlib.util
from collections.abc import Callable
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from mechcheck.analytic.case import Case
    from mechcheck.analytic.solution import Solution

Backend = Callable[["Case"], "Solution"]

#: name → "module:function"; ``analytic`` is the reference every other is compared with.
REGISTRY: dict[str, str] = {
    "analytic": "mechcheck.analytic.forces:solve",
    "superposition": "mechcheck.analytic.superposition:solve",
    "virtual_work": "mechcheck.analytic.virtual_work:solve",
    "mujoco": "mechcheck.sim_models.mujoco:settle",
    "mujoco_solve": "mechcheck.sim_models.mujoco:solve_at_pose",
    "pymunk": "mechcheck.sim_models.pymunk:settle",
    "pymunk_solve": "mechcheck.sim_models.pymunk:solve_at_pose",
}
REFERENCE = "analytic"

#: name → the simulator package it needs. Availability is decided by whether that
#: package is installed, without importing it: listing backends stays fast.
REQUIRES: dict[str, str] = {
    "mujoco": "mujoco", "mujoco_solve": "mujoco", "pymunk": "pymunk", "pymunk_solve": "pymunk",
}


class BackendUnavailable(LookupError):
    """An unknown backend, or one whose module is not there (yet)."""


def load(name: str) -> Backend:
    """The backend function called ``name``."""
    if name not in REGISTRY:
        raise BackendUnavailable(
            f"unknown backend {name!r}; known backends: {', '.join(REGISTRY)}")
    module_name, function = REGISTRY[name].split(":")
    try:
        module = importlib.import_module(module_name)
        backend: Backend = getattr(module, function)
        return backend
    except (ImportError, AttributeError) as error:
        raise BackendUnavailable(f"backend {name!r} is not available: {error}") from None


def missing_requirement(name: str) -> str | None:
    """The package backend ``name`` needs and this installation lacks, if any."""
    package = REQUIRES.get(name)
    return package if package and importlib.util.find_spec(package) is None else None


def available() -> list[str]:
    """The registered backends whose simulator is installed here."""
    return [name for name in REGISTRY if missing_requirement(name) is None]
