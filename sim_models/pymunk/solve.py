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
from mechcheck.sim_models.pymunk.readout import reactions
from mechcheck.sim_models.pymunk.settings import SOLVE, SolverSettings
from mechcheck.sim_models.pymunk.settle import Reading, Run, run_until_settled, solution_of

BACKEND = "pymunk_solve"


def iterate_at_pose(model: Model, pose: Pose, index: int = 0,
                    settings: SolverSettings | None = None) -> Run:
    """Re-pose and step until the impulses stop changing (``settle_force_change``)."""
    s = settings or model.settings

    def step() -> Reading:
        place(model, pose, index)
        apply_loads(model)
        model.space.step(s.dt)
        return reactions(model), 0.0

    run = run_until_settled(step, s, model.case.geometry.scale)
    place(model, pose, index)  # report the pose the forces belong to
    return run


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
    model = build_model(case, settings)
    run = iterate_at_pose(model, analytic_pose(case, case.theta12))
    return solution_of(model, run, BACKEND, "constraint_solve", time.perf_counter() - start)
