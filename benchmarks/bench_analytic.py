"""Throughput of the analytic force analysis against a straight-line numpy reference timed in
the same run, and against a per-pose loop.

Usage:  python benchmarks/bench_analytic.py [--poses 1000000] [--loop-poses 2000] [--repeats 5]

For the frictionless seed four-bar (SEEDS.md E1) and the seed slider-crank without friction
(E2), statics at N input angles spread over the assemblable range:

1. the library, the one engine in one vectorised call: the ``analytic`` backend's sweep (the
   preset drawn as its linkage, solved by the Assur plan, read under the preset's names), and
   the public :func:`mechcheck.solve_poses` without condition numbers (the same, with the
   pose gate and verdicts, as a table);
2. the reference, ``reference_presets.py``: the same outputs (pose angles, reactions, drive
   torque, condition number, forces withheld where singular) as deliberately simple
   straight-line numpy. Its answers are checked against the library's first (the tolerance
   policy's 1e-9 for two analytic routes). Target: library/reference ≥ 0.8.
3. the four-bar pose by pose through the library in a Python loop.

Each repeat times library and reference back to back; printed are poses/s and the ratio
library/reference per repeat: medians over the repeats with min and max (this machine is
shared; a best run is not typical).
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time
from collections.abc import Callable

import numpy as np
import reference_presets as reference

import mechcheck
from mechcheck import backends as registry
from mechcheck.analytic.case import Case
from mechcheck.casefile import builtin_case_files, load_cases
from mechcheck.tolerance import NEAR_SINGULAR_CONDITION, rule

CASES = ("seed-E1-as-stated", "seed-E2-frictionless")


def builtin(name: str) -> Case:
    return next(c for c in load_cases(*builtin_case_files()) if c.name == name)


def reference_for(case: Case) -> Callable[[np.ndarray], dict[str, np.ndarray]]:
    statics = reference.fourbar_statics if case.mechanism == "four_bar" \
        else reference.slidercrank_statics

    def run(theta: np.ndarray) -> dict[str, np.ndarray]:
        with np.errstate(invalid="ignore", divide="ignore"):  # as the library: NaN, no warning
            return statics(case, theta)
    return run


def engine(case: Case, theta: np.ndarray) -> dict[str, np.ndarray]:
    """The ``analytic`` backend's vectorised sweep: each quantity's column."""
    sweep = registry.get(registry.REFERENCE).sweeper()
    assert sweep is not None
    values: dict[str, np.ndarray] = sweep(case, theta).values
    return values


def timed(fn: Callable[[], object]) -> float:
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def spread(values: list[float]) -> tuple[float, float, float]:
    """(median, min, max)."""
    return statistics.median(values), min(values), max(values)


def check_agreement(case: Case, theta: np.ndarray) -> float:
    """The library's worst error against the reference at the ordinary poses; fails the run
    beyond the policy's tolerance for two analytic routes."""
    ref = reference_for(case)(theta)
    got = engine(case, theta)
    worst = reference.worst_error(case, ref, got, ref["condition"] <= NEAR_SINGULAR_CONDITION)
    assert worst <= rule("analytic", "force", "static").rtol, (case.name, worst)
    return worst


def compare(case: Case, theta: np.ndarray, repeats: int) -> None:
    """Library and reference back to back, ``repeats`` times, after one warm-up each."""
    n = theta.shape[0]
    run_reference = reference_for(case)
    worst = check_agreement(case, theta)
    lib, table, ref, ratio, table_ratio = [], [], [], [], []
    for _ in range(repeats):
        t_lib = timed(lambda: engine(case, theta))
        t_table = timed(lambda: mechcheck.solve_poses(case, theta, condition=False))
        t_ref = timed(lambda: run_reference(theta))
        lib.append(n / t_lib)
        table.append(n / t_table)
        ref.append(n / t_ref)
        ratio.append(t_ref / t_lib)
        table_ratio.append(t_ref / t_table)
    print(f"{case.name}: {n} poses, worst error against the reference {worst:.1e}")
    for label, values in (("  engine     ", lib), ("  solve_poses", table), ("  reference  ", ref)):
        med, lo, hi = spread(values)
        print(f"{label} {med / 1e6:6.2f} M poses/s (min {lo / 1e6:.2f}, max {hi / 1e6:.2f})")
    for label, values in (("engine", ratio), ("solve_poses", table_ratio)):
        med, lo, hi = spread(values)
        print(f"  {label}/reference {med:.2f} (min {lo:.2f}, max {hi:.2f})  target >= 0.8")


def compare_loop(case: Case, theta: np.ndarray, loop_poses: int, repeats: int) -> None:
    """The vectorised call against the same solver pose by pose in a Python loop."""
    loop_theta = theta[:: max(1, theta.shape[0] // loop_poses)][:loop_poses]
    vector = [theta.shape[0] / timed(lambda: engine(case, theta)) for _ in range(repeats)]
    loop = [loop_theta.shape[0] / timed(lambda: [engine(case, np.array([t])) for t in loop_theta])
            for _ in range(repeats)]
    (v, v_lo, v_hi), (lp, lp_lo, lp_hi) = spread(vector), spread(loop)
    print(f"{case.name}, vectorised {v:,.0f} poses/s (min {v_lo:,.0f}, max {v_hi:,.0f}); "
          f"loop of {loop_theta.shape[0]} poses {lp:,.0f} poses/s (min {lp_lo:,.0f}, "
          f"max {lp_hi:,.0f}): {v / lp:,.0f}x (slowest over fastest {v_lo / lp_hi:,.0f}x)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--poses", type=int, default=1_000_000)
    parser.add_argument("--loop-poses", type=int, default=2_000)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}, numpy {np.__version__}; median of {args.repeats}")
    # The seed four-bar is a Grashof change-point linkage: avoid the singular pose
    # θ12 = 180° itself so every pose is an ordinary one.
    theta = np.linspace(-np.pi + 1e-3, np.pi - 1e-3, args.poses)
    cases = [builtin(name) for name in CASES]
    for case in cases:
        compare(case, theta, args.repeats)
    compare_loop(cases[0], theta, args.loop_poses, args.repeats)


if __name__ == "__main__":
    main()
