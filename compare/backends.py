"""Backend registry: name → function ``Case -> Solution``.

Backends are imported lazily so that a missing or broken simulator affects
only the runs that ask for it, with a clear message. Adding a simulator means
adding one line here and one module under ``sim_models/``.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable

from analytic.case import Case
from analytic.solution import Solution

Backend = Callable[[Case], Solution]

#: name → "module:function"; ``analytic`` is the reference every other is compared with.
REGISTRY: dict[str, str] = {
    "analytic": "analytic.forces:solve",
    "superposition": "analytic.superposition:solve",
    "virtual_work": "analytic.virtual_work:solve",
    "mujoco": "sim_models.mujoco:settle",
    "mujoco_solve": "sim_models.mujoco:solve_at_pose",
    "pymunk": "sim_models.pymunk:settle",
    "pymunk_solve": "sim_models.pymunk:solve_at_pose",
}
REFERENCE = "analytic"


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


def available() -> list[str]:
    """The registered backends that can be loaded on this installation."""
    names = []
    for name in REGISTRY:
        try:
            load(name)
        except BackendUnavailable:
            continue
        names.append(name)
    return names
