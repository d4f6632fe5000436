"""The analytic backends, declared (:class:`~mechcheck.analytic.contract.Backend`).

``analytic`` is the reference every other backend is compared with; ``superposition`` and
``virtual_work`` solve the same equations another way and are judged as such.
"""

from __future__ import annotations

from mechcheck.analytic.contract import Backend

REFERENCE = "analytic"

BACKENDS = (
    Backend(REFERENCE, "mechcheck.analytic.forces:solve", "reference",
            "the member-equilibrium matrix method (the reference)",
            sweep="mechcheck.analytic.forces:solve_poses",
            linkage_sweep="mechcheck.analytic.linkage_backends:analytic_results",
            vectorised=True),
    Backend("superposition", "mechcheck.analytic.superposition:solve", "analytic",
            "each load alone, the solutions added (no Coulomb friction)",
            sweep="mechcheck.analytic.superposition:solve_poses",
            linkage_sweep="mechcheck.analytic.linkage_backends:superposition_results",
            vectorised=True),
    Backend("virtual_work", "mechcheck.analytic.virtual_work:solve", "analytic",
            "drive efforts from the power of every known force (no Coulomb friction)",
            sweep="mechcheck.analytic.virtual_work:solve_poses",
            linkage_sweep="mechcheck.analytic.linkage_backends:virtual_work_results",
            vectorised=True),
)
