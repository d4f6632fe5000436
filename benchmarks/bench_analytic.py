"""Throughput of the analytic force analysis: one vectorised call vs a per-pose loop.

Usage:  python benchmarks/bench_analytic.py [--poses 1000000] [--loop-poses 2000]

Solves the frictionless seed four-bar (SEEDS.md E1) statics at N input angles
spread over the assemblable range, first in one vectorised call
(:func:`mechcheck.analytic.forces.solve_poses`), then pose by pose through the same
solver in a Python loop, and prints poses/s for both and their ratio: medians over
``--repeats`` with min and max (this machine is shared; a best run is not typical).
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time

import numpy as np

from mechcheck.analytic import forces
from mechcheck.casefile import builtin_case_files, load_cases


def seed_case():  # type: ignore[no-untyped-def]
    return next(c for c in load_cases(*builtin_case_files()) if c.name == "seed-E1-as-stated")


def timings(repeats: int, fn) -> list[float]:  # type: ignore[no-untyped-def]
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return times


def rates(poses: int, times: list[float]) -> tuple[float, float, float]:
    """(median, min, max) poses per second."""
    per = sorted(poses / t for t in times)
    return statistics.median(per), per[0], per[-1]


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
    vector = rates(args.poses, timings(args.repeats, lambda: forces.solve_poses(case, theta)))
    loop_theta = theta[:: max(1, args.poses // args.loop_poses)][: args.loop_poses]
    loop = rates(len(loop_theta), timings(
        args.repeats, lambda: [forces.solve_poses(case, t) for t in loop_theta]))
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}, numpy {np.__version__}; median of {args.repeats}")
    print(f"vectorised: {args.poses} poses, {vector[0]:,.0f} poses/s "
          f"(min {vector[1]:,.0f}, max {vector[2]:,.0f})")
    print(f"loop:       {len(loop_theta)} poses, {loop[0]:,.0f} poses/s "
          f"(min {loop[1]:,.0f}, max {loop[2]:,.0f})")
    print(f"ratio of the medians: {vector[0] / loop[0]:,.0f}x (slowest vectorised over fastest "
          f"loop {vector[1] / loop[2]:,.0f}x, fastest over slowest {vector[2] / loop[1]:,.0f}x)")


if __name__ == "__main__":
    main()
