"""Throughput of the analytic force analysis: one vectorised call vs a per-pose loop.

Usage:  python benchmarks/bench_analytic.py [--poses 1000000] [--loop-poses 2000]

Solves the frictionless seed four-bar (SEEDS.md E1) statics at N input angles
spread over the assemblable range, first in one vectorised call
(:func:`mechcheck.analytic.forces.solve_poses`), then pose by pose through the same
solver in a Python loop, and prints poses/s for both and their ratio.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import numpy as np

from mechcheck.analytic import forces
from mechcheck.casefile import builtin_case_files, load_cases


def seed_case():  # type: ignore[no-untyped-def]
    return next(c for c in load_cases(*builtin_case_files()) if c.name == "seed-E1-as-stated")


def best_of(repeats: int, fn) -> float:  # type: ignore[no-untyped-def]
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--poses", type=int, default=1_000_000)
    parser.add_argument("--loop-poses", type=int, default=2_000)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    case = seed_case()
    # The seed four-bar is a Grashof change-point linkage: avoid the singular
    # pose θ12 = 180° itself so every pose is an ordinary one.
    theta = np.linspace(-np.pi + 1e-3, np.pi - 1e-3, args.poses)
    vector = best_of(args.repeats, lambda: forces.solve_poses(case, theta))
    loop_theta = theta[:: max(1, args.poses // args.loop_poses)][: args.loop_poses]
    loop = best_of(args.repeats, lambda: [forces.solve_poses(case, t) for t in loop_theta])
    vec_rate = args.poses / vector
    loop_rate = len(loop_theta) / loop
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}, numpy {np.__version__}")
    print(f"vectorised: {args.poses} poses in {vector:.3f} s = {vec_rate:,.0f} poses/s")
    print(f"loop:       {len(loop_theta)} poses in {loop:.3f} s = {loop_rate:,.0f} poses/s")
    print(f"ratio: {vec_rate / loop_rate:,.0f}x")


if __name__ == "__main__":
    main()
