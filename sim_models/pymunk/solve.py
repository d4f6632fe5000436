"""The ``pymunk_solve`` backend: pymunk's constraint solver at the exact analytic pose.

Before every step the bodies are put back on the closed-form pose, at rest.
Nothing can drift, so each step is one more warm-started round of pymunk's
Gauss–Seidel solver on the *same* constraint problem, and the accumulated
impulses converge to the constraint forces of that pose. This checks the
model itself (frames, anchors, load points, signs) to rounding, separately
from the settling dynamics of :mod:`mechcheck.sim_models.pymunk.settle`.

Only statics is meaningful here: with velocities the constraint forces
depend on how the pose moves, which a re-posed step does not represent.
"""

from __future__ import annotations

import time

from mechcheck.analytic.case import Case
from mechcheck.analytic.kinematics import Pose
from mechcheck.analytic.solution import Solution
from mechcheck.sim_models.pymunk.loads import apply_loads
from mechcheck.sim_models.pymunk.model import Model, analytic_pose, build_model, place
from mechcheck.sim_models.pymunk.readout import Values, reactions
from mechcheck.sim_models.pymunk.settings import SOLVE, SolverSettings
from mechcheck.sim_models.pymunk.settle import Run, relative_change, solution_of
from mechcheck.sim_models.pymunk.verdict import singular_solution

BACKEND = "pymunk_solve"


def iterate_at_pose(model: Model, pose: Pose, index: int = 0,
                    settings: SolverSettings | None = None) -> Run:
    """Re-pose and step until the impulses stop changing (``settle_force_change``)."""
    s = settings or model.settings
    length = model.case.geometry.scale
    previous: Values | None = None
    calm = 0
    values: Values = {}
    change = float("inf")
    for step in range(1, s.max_steps + 1):
        place(model, pose, index)
        apply_loads(model)
        model.space.step(s.dt)
        values = reactions(model)
        change = relative_change(values, previous, length) if previous else float("inf")
        previous = values
        calm = calm + 1 if change <= s.settle_force_change else 0
        if calm >= s.settle_patience:
            place(model, pose, index)  # report the pose the forces belong to
            return Run(values, step, True, 0.0, change)
    place(model, pose, index)
    return Run(values, s.max_steps, False, 0.0, change)


def not_applicable(case: Case) -> Solution:
    """The re-posed solve cannot represent motion or friction (both need velocities)."""
    return Solution(case.name, BACKEND, {}, status="not_applicable",
                    message=f"a {case.kind} case needs velocities; the constraint solve at a "
                            "fixed pose is for statics (use the 'pymunk' backend, which drives it)")


def solve_at_pose(case: Case, settings: SolverSettings = SOLVE) -> Solution:
    """The ``pymunk_solve`` backend: constraint forces at the fixed analytic pose."""
    if case.kind != "static":
        return not_applicable(case)
    start = time.perf_counter()
    singular = singular_solution(case, BACKEND)
    if singular is not None:
        return singular
    model = build_model(case, settings)
    run = iterate_at_pose(model, analytic_pose(case, case.theta12))
    return solution_of(model, run, BACKEND, "constraint_solve", time.perf_counter() - start)
