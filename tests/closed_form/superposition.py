"""The ``superposition`` backend: solve each load alone, then add.

Valid only when the equations are linear in the loads, i.e. without Coulomb
friction (the seed: "conservative systems"). Every external load, each link's
weight, each link's inertia force and each viscous term counts as one load.
"""

from __future__ import annotations

import time

import numpy as np
from numpy.typing import ArrayLike

from mechcheck.analytic.case import Case
from mechcheck.analytic.kinematics import as_angles, pose_of
from mechcheck.analytic.solution import Solution

from .equilibrium import condition, eliminate, known_vectors
from .forces import PoseResults, named_values, solution_from

REFUSAL = ("superposition applies only to frictionless (linear) systems; this case has "
           "Coulomb friction, whose moments depend on the total reactions, so the sum of "
           "single-load solutions would be wrong")


def solve_poses(case: Case, theta12_rad: ArrayLike | None = None) -> PoseResults:
    """Sum of the single-load solutions at each θ12 (rad)."""
    # A pose that does not assemble is NaN by design (its verdict is no_solution):
    # the arithmetic on it must not warn.
    with np.errstate(invalid="ignore", divide="ignore"):
        if case.has_coulomb_friction:
            raise ValueError(REFUSAL)
        angles = as_angles(case.preset.theta12 if theta12_rad is None else theta12_rad)
        pose = pose_of(case, angles)
        x = np.zeros((angles.shape[0], 9))
        for _, b in known_vectors(case, pose):
            x += eliminate(case, pose, b)
        results = PoseResults(angles, {}, condition(case, pose),
                              np.zeros(angles.shape[0], dtype=int), np.ones(angles.shape[0], bool))
        x[results.singular] = np.nan
        values = named_values(case, pose, x)
        return PoseResults(angles, values, results.condition, results.iterations, results.converged)


def solve(case: Case) -> Solution:
    """The ``superposition`` backend for one Case (refuses friction cases)."""
    if not case.is_preset:
        raise TypeError(f"case {case.name!r} is a linkage: it has no closed form")
    if case.has_coulomb_friction:
        return Solution(case.name, "superposition", {}, status="not_applicable", message=REFUSAL)
    start = time.perf_counter()
    results = solve_poses(case)
    return solution_from(case, "superposition", results, method="superposition of single loads",
                         elapsed=time.perf_counter() - start)
