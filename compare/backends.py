"""The backend registry: every :class:`~mechcheck.analytic.contract.Backend` there is.

Nothing here names a backend. The analytic ones are declared in
:mod:`mechcheck.analytic.backends`; every package under ``mechcheck.sim_models`` declares its
own as ``BACKENDS``, and is found by walking that package's path, so a new simulator is a
new package there and needs no edit here. Declarations are light: listing the backends
imports no simulator (availability is decided by whether the simulator's package is
installed, without importing it).
"""

from __future__ import annotations

import importlib
import pkgutil
from collections.abc import Callable, Mapping
from types import ModuleType
from typing import TYPE_CHECKING

from mechcheck.analytic import backends as analytic_backends
from mechcheck.analytic.contract import Backend, BackendUnavailable, Family

if TYPE_CHECKING:
    from mechcheck.analytic.case import Case
    from mechcheck.analytic.solution import Solution
    from mechcheck.sim_models.protocol import Simulator

__all__ = ["REFERENCE", "REGISTRY", "Backend", "BackendUnavailable", "available", "family",
           "get", "load", "missing_requirement", "names_of_family", "simulators"]

SolveFunction = Callable[["Case"], "Solution"]

#: The backend every other is compared with.
REFERENCE = analytic_backends.REFERENCE


def simulator_packages() -> list[ModuleType]:
    """Each package under ``mechcheck.sim_models``, by name."""
    import mechcheck.sim_models as simulators

    return [importlib.import_module(f"{simulators.__name__}.{module.name}")
            for module in sorted(pkgutil.iter_modules(simulators.__path__), key=lambda m: m.name)
            if module.ispkg]


def simulators() -> list[Simulator]:
    """Every simulator package's declaration (``SIMULATOR``), installed or not."""
    return [p.SIMULATOR for p in simulator_packages() if hasattr(p, "SIMULATOR")]


def discovered() -> dict[str, Backend]:
    """The analytic backends, then each simulator package's, by name."""
    found = {b.name: b for b in analytic_backends.BACKENDS}
    for package in simulator_packages():
        for backend in getattr(package, "BACKENDS", ()):
            if backend.name in found:
                raise RuntimeError(f"backend {backend.name!r} is declared twice "
                                   f"(again in {package.__name__})")
            found[backend.name] = backend
    return found


#: name → Backend, in the order ``mechcheck backends`` lists them.
REGISTRY: dict[str, Backend] = discovered()


def get(name: str) -> Backend:
    """The backend called ``name``."""
    try:
        return REGISTRY[name]
    except KeyError:
        raise BackendUnavailable(
            f"unknown backend {name!r}; known backends: {', '.join(REGISTRY)}") from None


def load(name: str) -> SolveFunction:
    """The single-case solve of backend ``name``, imported now."""
    solve: SolveFunction = get(name).solver()
    return solve


def missing_requirement(name: str) -> str | None:
    """The package backend ``name`` needs and this installation lacks, if any."""
    return get(name).missing_requirement()


def available() -> list[str]:
    """The registered backends whose simulator is installed here."""
    return [name for name, b in REGISTRY.items() if b.missing_requirement() is None]


def family(name: str) -> Family:
    """The tolerance family backend ``name`` is judged by."""
    return get(name).family


def names_of_family(kind: Family, registry: Mapping[str, Backend] | None = None) -> list[str]:
    """The backends of one family (``settled``: the simulations the studies run)."""
    return [n for n, b in (registry or REGISTRY).items() if b.family == kind]
