"""Time the MuJoCo backends over a 360-pose sweep of seed E1 (Söylemez 6.3,
``seed-E1-as-stated`` from the built-in case files) and measure their error.

Errors are measured as the tolerance policy measures them
(:func:`mechcheck.tables.comparison_rows`: each value against the largest
reference value of its kind at that pose), and each pose is judged against its
policy tolerance (static 1e-6; near-singular, condition number > 1e4, 1e-2).

Targets: settled statics ≤ 2 ms/pose, mujoco_solve ≤ 0.2 ms/pose.

A second table follows the near-toggle study (seed E1 at θ12 = 180° − δ): the
settled backend's status, error, steps and passes as the change point nears.
Run: /work/venv/bin/python benchmarks/bench_mujoco.py
"""

import math
import time

import mujoco
import numpy as np

from mechcheck.analytic.forces import solve
from mechcheck.casefile import builtin_case_files, load_cases
from mechcheck.sim_models.mujoco import settle, sweep
from mechcheck.tables import comparison_rows

CASE = "seed-E1-as-stated"
#: The near-toggle study's distances from the change point down to condition number ~5000, degrees.
NEAR_TOGGLE_DELTAS = np.geomspace(30.0, 1e-4, 15)[2:9]


def pose_errors(case, theta, solutions):
    """(worst force/torque relative error, number of poses outside tolerance,
    worst error where the condition number is ≤ 1e4) over the poses simulated."""
    worst = worst_regular = 0.0
    failing = 0
    for t, s in zip(theta, solutions, strict=True):
        if s.status != "ok":
            continue
        at = case.with_(theta12=float(t))
        reference = solve(at)
        rows = [r for r in comparison_rows(at, reference, s) if str(r["quantity"])[0] in "FTM"]
        error = max(float(r["rel_err"]) for r in rows)
        worst = max(worst, error)
        if reference.diagnostics["condition_number"] <= 1e4:
            worst_regular = max(worst_regular, error)
        failing += not all(r["passed"] for r in rows)
    return worst, failing, worst_regular


def main() -> None:
    case = {c.name: c for c in load_cases(*builtin_case_files())}[CASE]
    theta = np.radians(np.arange(360.0))
    print(f"MuJoCo {mujoco.__version__}; {CASE}, 360 poses (1° steps)\n")
    print("| backend | ms/pose | poses ok | singular | not settled | worst rel. error "
          "(cond ≤ 1e4) | outside tolerance | median steps | max steps |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for backend in ("mujoco", "mujoco_solve"):
        start = time.perf_counter()
        sols = sweep(case, theta, backend)
        per_pose = (time.perf_counter() - start) / theta.size * 1e3
        status = [s.status for s in sols]
        steps = [s.diagnostics.get("steps", 0) for s in sols if s.status == "ok"]
        _, failing, worst_regular = pose_errors(case, theta, sols)
        print(f"| {backend} | {per_pose:.3f} | {status.count('ok')} | "
              f"{status.count('singular')} | {status.count('not_settled')} | "
              f"{worst_regular:.2e} | {failing} | {np.median(steps):.0f} | {max(steps)} |")

    print("\n| δ (deg) | condition number | status | rel. error | steps | passes | ms |")
    print("|---:|---:|---|---:|---:|---:|---:|")
    for delta in NEAR_TOGGLE_DELTAS:
        at = case.with_(theta12=math.pi - math.radians(float(delta)))
        start = time.perf_counter()
        sim = settle(at)
        ms = (time.perf_counter() - start) * 1e3
        reference = solve(at)
        error = pose_errors(at, [at.theta12], [sim])[0] if sim.status == "ok" else math.nan
        print(f"| {delta:.4g} | {reference.diagnostics['condition_number']:.0f} | {sim.status} | "
              f"{error:.1e} | {sim.diagnostics['steps']} | {sim.diagnostics['passes']} | {ms:.1f} |")


if __name__ == "__main__":
    main()
