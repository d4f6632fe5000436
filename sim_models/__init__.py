"""The simulator backends: one package per simulator (``mujoco``, ``pymunk``)."""

from __future__ import annotations

from mechcheck.analytic.case import Case
from mechcheck.analytic.solution import Solution


def unmodelled_linkage(case: Case, backend: str) -> Solution | None:
    """``not_applicable`` for a ``mechanism = "linkage"`` case, which the simulators' model
    builders do not take yet (they build the four-bar and the slider-crank); else None."""
    if case.mechanism != "linkage":
        return None
    return Solution(case.name, backend, {}, status="not_applicable",
                    message=f"the {backend} model builder takes the four-bar and the "
                            "slider-crank; general linkages are not modelled in it yet")
