"""Time the MuJoCo backends over a 360-pose sweep of seed E1 (Söylemez 6.3).

Targets: settled statics ≤ 2 ms/pose, mujoco_solve ≤ 0.2 ms/pose.
Run: /work/venv/bin/python benchmarks/bench_mujoco.py
"""

import time

import mujoco
import numpy as np

from analytic.forces import solve_poses
from sim_models.mujoco import sweep
from sim_models.mujoco.seeds import fourbar_e1


def worst_relative_error(solutions: list, reference, kinds: str = "FT") -> float:
    """Largest |sim − ref| / max(|ref|, largest |ref| of that kind at the pose)."""
    worst = 0.0
    for i, s in enumerate(solutions):
        if s.status != "ok":
            continue
        for kind in kinds:
            names = [q for q in s.values if q.startswith(kind)]
            scale = max(abs(reference.values[q][i]) for q in names)
            for q in names:
                ref = reference.values[q][i]
                worst = max(worst, abs(s.values[q] - ref) / max(abs(ref), scale))
    return worst


def main() -> None:
    case = fourbar_e1()
    theta = np.radians(np.arange(360.0))
    reference = solve_poses(case, theta)
    print(f"MuJoCo {mujoco.__version__}; seed E1 four-bar, 360 poses (1° steps)\n")
    print("| backend | ms/pose | poses ok | singular | not settled | worst rel. error | "
          "median steps |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    for backend in ("mujoco", "mujoco_solve"):
        start = time.perf_counter()
        sols = sweep(case, theta, backend)
        per_pose = (time.perf_counter() - start) / theta.size * 1e3
        status = [s.status for s in sols]
        steps = [s.diagnostics.get("steps", 0) for s in sols if s.status == "ok"]
        print(f"| {backend} | {per_pose:.3f} | {status.count('ok')} | "
              f"{status.count('singular')} | {status.count('not_settled')} | "
              f"{worst_relative_error(sols, reference):.2e} | {np.median(steps):.0f} |")


if __name__ == "__main__":
    main()
