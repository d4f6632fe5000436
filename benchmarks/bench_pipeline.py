"""End-to-end wall times of the command line, as a user runs it.

Usage:  python benchmarks/bench_pipeline.py

1. ``mechcheck run`` — the built-in suite through every backend, with the report.
2. ``mechcheck sweep --fresh`` — the built-in whole-cycle sweeps (seed four-bar,
   seed slider-crank with and without friction, 360 poses each) through every
   backend, with figures and the report.
3. ``mechcheck sweep FILE -b analytic`` over 10⁶ poses, written to Parquet.
"""

from __future__ import annotations

import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

E1 = """
[[case]]
name = "seed-E1"
mechanism = "four_bar"
length_unit = "mm"
theta12 = 60.0
[case.geometry]
a1 = 140.0
a2 = 80.0
a3 = 100.0
a4 = 120.0
[[case.loads]]
link = 3
at = [42.5, 55.62148865321747]
force = { magnitude = 50.0, angle = 50.0 }
[[case.loads]]
link = 4
at = [90.0, 0.0]
force = { magnitude = 100.0, angle = 20.0 }
"""


def timed(args: list[str]) -> tuple[float, str]:
    start = time.perf_counter()
    done = subprocess.run([sys.executable, "-m", "mechcheck.cli", *args], capture_output=True,
                          text=True, check=False)
    return time.perf_counter() - start, done.stdout.strip().splitlines()[-1]


def main() -> None:
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, Python "
          f"{platform.python_version()}")
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        (out / "e1.toml").write_text(E1)
        for label, args in (
            ("built-in suite, every backend", ["run", "-q", "--out", str(out / "suite")]),
            ("built-in sweeps (3 × 360 poses), every backend",
             ["sweep", "-q", "--fresh", "--out", str(out / "sweep")]),
            ("analytic sweep, 10^6 poses to Parquet",
             ["sweep", str(out / "e1.toml"), "-b", "analytic", "--theta12", "0:360:0.00036",
              "-q", "--fresh", "--out", str(out / "million")]),
        ):
            seconds, last = timed(args)
            print(f"{label}: {seconds:.1f} s  ({last})")


if __name__ == "__main__":
    main()
