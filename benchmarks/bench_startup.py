"""Start-up time of the command line, against a bare interpreter timed in the same run.

Usage:  python benchmarks/bench_startup.py [--repeats N]

Each command runs N times in a fresh process (after one unmeasured warm-up that
fills the OS file cache); the table gives the median with min and max, and the
ratio of medians to ``python -c pass``. Target (issue 9): ``mechcheck --help``
≤ 0.25 s median. ``--help`` and ``backends`` import neither pandas, matplotlib,
mujoco nor pymunk; ``run`` needs them all, and is shown for scale.
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
from pathlib import Path

MECHCHECK = str(Path(sys.executable).with_name("mechcheck"))
COMMANDS = {
    "python -c pass (reference)": [sys.executable, "-c", "pass"],
    "python -c 'import mechcheck'": [sys.executable, "-c", "import mechcheck"],
    "mechcheck --help": [MECHCHECK, "--help"],
    "mechcheck backends": [MECHCHECK, "backends"],
    "mechcheck theory grashof ...": [MECHCHECK, "theory", "grashof", "--ground", "250", "--crank",
                                     "100", "--coupler", "220", "--rocker", "150"],
}
TARGET_S = {"mechcheck --help": 0.25}


def wall_times(command: list[str], repeats: int, cwd: str) -> list[float]:
    subprocess.run(command, capture_output=True, check=True, cwd=cwd)  # warm-up, not measured
    out = []
    for _ in range(repeats):
        start = time.perf_counter()
        subprocess.run(command, capture_output=True, check=True, cwd=cwd)
        out.append(time.perf_counter() - start)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=21)
    repeats = parser.parse_args().repeats
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, Python "
          f"{platform.python_version()}; {repeats} runs each, fresh processes")
    print("| command | median s | min s | max s | median / python -c pass | target |")
    print("|---|---:|---:|---:|---:|---|")
    reference = None
    # Each process starts in an empty directory: ``python -c`` puts its directory first on
    # sys.path, where a stray file (a scratch ``nt.py`` in /tmp once was imported by
    # pathlib) would be timed too.
    with tempfile.TemporaryDirectory() as empty:
        rows = {label: wall_times(command, repeats, empty) for label, command in COMMANDS.items()}
    for label, times in rows.items():
        median = statistics.median(times)
        reference = reference or median
        target = TARGET_S.get(label)
        verdict = "" if target is None else f"≤ {target} s: {'met' if median <= target else 'MISSED'}"
        print(f"| {label} | {median:.3f} | {min(times):.3f} | {max(times):.3f} | "
              f"{median / reference:.1f}× | {verdict} |")


if __name__ == "__main__":
    main()
