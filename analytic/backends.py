"""The analytic backends, declared (:class:`~mechcheck.analytic.contract.Backend`).

``analytic`` is the reference every other backend is compared with; ``superposition`` and
``virtual_work`` solve the same equations another way and are judged as such. All three
are the one engine's (:mod:`mechcheck.analytic.linkage_backends`).
"""

from __future__ import annotations

from mechcheck.analytic.contract import Backend

REFERENCE = "analytic"

_ENGINE = "mechcheck.analytic.linkage_backends"

BACKENDS = (
    Backend(REFERENCE, f"{_ENGINE}:solve", "reference",
            "the member-equilibrium matrix method (the reference)",
            sweep=f"{_ENGINE}:analytic_results", vectorised=True,
            simulate="mechcheck.analytic.trajectory:simulate"),
    Backend("superposition", f"{_ENGINE}:superposition", "analytic",
            "each load alone, the solutions added (no Coulomb friction)",
            sweep=f"{_ENGINE}:superposition_results", vectorised=True),
    Backend("virtual_work", f"{_ENGINE}:virtual_work", "analytic",
            "drive efforts from the power of every known force (no Coulomb friction)",
            sweep=f"{_ENGINE}:virtual_work_results", vectorised=True),
)
