"""Benchmark: settled static equilibrium per pose over a 360-pose continuation sweep of E1.

Prints Markdown: ms per pose, steps per pose and the worst relative force
error against the analytic backend, for ``pymunk`` (settle) and
``pymunk_solve``. Target: ≤ 2 ms/pose for the settled sweep.

Run: /work/venv/bin/python benchmarks/bench_pymunk.py
"""

from __future__ import annotations

import platform
import time

import numpy as np
import pymunk

from mechcheck.analytic.forces import solve_poses
from mechcheck.analytic.solution import Solution
from mechcheck.casefile import builtin_case_files, load_cases
from mechcheck.sim_models.pymunk import sweep


def worst_error(solutions: list[Solution], reference: dict[str, np.ndarray]) -> float:
    """Largest relative error over the sweep (forces scaled by the pose's largest force)."""
    worst = 0.0
    for k, sol in enumerate(solutions):
        if sol.status != "ok":
            continue
        force_scale = max(abs(reference[q][k]) for q in reference if q.startswith("F"))
        for q, v in sol.values.items():
            if q[0] in "FT":
                scale = force_scale if q[0] == "F" else abs(reference[q][k])
                worst = max(worst, abs(v - reference[q][k]) / max(abs(reference[q][k]), scale))
    return worst


def main() -> None:
    case = next(c for c in load_cases(*builtin_case_files()) if c.name == "seed-E1-as-stated")
    theta = np.radians(np.arange(360.0))
    reference = solve_poses(case, theta).values
    print(f"pymunk {pymunk.version}, Python {platform.python_version()}, {platform.machine()}\n")
    print("| backend | poses | ok | singular | ms/pose | steps/pose | worst rel. error |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for backend in ("pymunk", "pymunk_solve"):
        sweep(case, theta[:10], backend)  # warm-up (imports, layout check)
        start = time.perf_counter()
        sols = sweep(case, theta, backend)
        wall = time.perf_counter() - start
        ok = sum(s.status == "ok" for s in sols)
        singular = sum(s.status == "singular" for s in sols)
        steps = np.mean([s.diagnostics.get("steps", 0) for s in sols if s.status == "ok"])
        print(f"| {backend} | {len(sols)} | {ok} | {singular} | {wall / len(sols) * 1e3:.2f} | "
              f"{steps:.1f} | {worst_error(sols, reference):.1e} |")


if __name__ == "__main__":
    main()
