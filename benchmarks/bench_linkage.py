"""The generic linkage engine's speed, against the four-bar's closed-form fast path timed in
the same run.

Usage:  python benchmarks/bench_linkage.py [--poses 1000000] [--repeats 5]

1. Statics of the built-in Watt II six-bar over N crank angles (±30° about the drawn pose)
   in one vectorised call (the Assur-group path: closed-form dyads, group-by-group
   elimination), and the seed four-bar's closed form over N angles: poses/s of each and
   their ratio per repeat. (Issue 11's target: ≥ 10⁶ six-bar poses/s on one core.) Then the
   seed four-bar and the seed slider-crank (E2) as linkage cases through ``analytic_results``
   over N crank angles (a whole turn): poses/s of each and the slider-crank's rate over
   the four-bar's (target: within 2×).
2. The seed four-bar through the generic engine (its preset) against its closed form, one
   pose at a time as a backend runs it: the ratio (target: within 5×).
3. ``mechcheck run --backend analytic`` on the built-in suite, linkages included
   (target: under 2 s).

Medians over the repeats, with min and max.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable

import numpy as np

from mechcheck import load_cases
from mechcheck.analytic.linkage_backends import analytic_results
from mechcheck.analytic.linkage_forces import solve_linkage
from mechcheck.analytic.presets import as_linkage
from mechcheck.casefile import builtin_case_files


def timed(fn: Callable[[], object], repeats: int) -> list[float]:
    fn()  # warm-up
    out = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        out.append(time.perf_counter() - start)
    return out


def spread(times: list[float], scale: float = 1.0, fmt: str = ".3g") -> str:
    values = [scale * t for t in times]
    return (f"{statistics.median(values):{fmt}} (min {min(values):{fmt}}, "
            f"max {max(values):{fmt}})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--poses", type=int, default=1_000_000)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    n, repeats = args.poses, args.repeats
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, Python "
          f"{platform.python_version()}; {repeats} repeats")
    cases = {c.name: c for c in load_cases(*builtin_case_files())}
    watt = cases["watt-ii-demo"].linkage
    e1 = cases["seed-E1-as-stated"]
    crank = np.radians(np.linspace(-30.0, 30.0, n))[:, None]
    six = timed(lambda: solve_linkage(watt, crank, np.zeros(1), np.zeros(1)), repeats)
    preset = e1.linkage
    four = timed(lambda: solve_linkage(preset, crank, np.zeros(1), np.zeros(1)), repeats)
    rate_six = [n / t for t in six]
    rate_four = [n / t for t in four]
    ratio = [s / f for s, f in zip(rate_six, rate_four, strict=True)]
    print(f"1. Watt II six-bar statics, {n} poses: {spread(rate_six, fmt='.3g')} poses/s; "
          f"seed four-bar: {spread(rate_four, fmt='.3g')} poses/s; six-bar/four-bar "
          f"rate {spread(ratio, fmt='.2f')}")
    turn = np.radians(np.linspace(-180.0, 180.0, n))
    e2 = as_linkage(cases["seed-E2-frictionless"])
    e1_case = as_linkage(e1)
    slider = [n / t for t in timed(lambda: analytic_results(e2, turn), repeats)]
    fourbar = [n / t for t in timed(lambda: analytic_results(e1_case, turn), repeats)]
    print(f"   through analytic_results, a whole turn: seed four-bar {spread(fourbar, fmt='.3g')} "
          f"poses/s; seed slider-crank {spread(slider, fmt='.3g')} poses/s; four-bar/slider-crank "
          f"rate {spread([f / s for f, s in zip(fourbar, slider, strict=True)], fmt='.2f')}")
    one = timed(lambda: solve_linkage(preset), repeats * 20)
    print(f"2. seed four-bar, one pose: {spread(one, 1e3)} ms")
    with tempfile.TemporaryDirectory() as tmp:
        run = timed(lambda: subprocess.run(
            [sys.executable, "-m", "mechcheck", "run", "-q", "-b", "analytic", "--out", tmp],
            check=True, capture_output=True), repeats)
    print(f"3. mechcheck run --backend analytic, built-in suite ({len(cases)} cases): "
          f"{spread(run)} s")


if __name__ == "__main__":
    main()
