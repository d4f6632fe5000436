"""End-to-end wall times of the command line, as a user runs it.

Usage:  python benchmarks/bench_pipeline.py [--repeats 3] [--only suite|sweeps]

Each is a fresh process, timed ``--repeats`` times: median, min and max.

1. ``mechcheck run`` — the built-in suite through every backend, with the report;
   its reference, the same solves and comparisons in one process through the Python
   API (``mechcheck.check``), with no report written: the ratio is what the command
   line and the report cost on top.
2. ``mechcheck sweep --fresh`` — the built-in whole-cycle sweeps (seed four-bar,
   seed slider-crank with and without friction, 360 poses each) through every
   backend, with figures and the report; its reference, the same run's own time for
   solving the tasks (the sweep prints it): the ratio is what comparing, drawing and
   reporting add on top of the backends' work.
3. ``mechcheck sweep`` again on the same directory, every part already there (the
   resume path: imports, software versions, reading the parts, comparing, figures,
   report), then the same with ``--no-figures`` (issue 13: "≤ 1 s plus its figures");
   their reference, ``import mechcheck`` and reading the parts with pandas in a fresh
   process. The runs alternate (with figures, without, the reference) so that the
   machine's drift falls on all three alike.
4. ``mechcheck sweep FILE -b analytic`` over 10⁶ poses, written to Parquet.
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import statistics
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


#: The reference for the suite: the same work through the Python API, nothing written.
API_SUITE = ("import mechcheck; from mechcheck.casefile import builtin_case_files; "
             "r = mechcheck.check(mechcheck.load_cases(*builtin_case_files())); "
             "print(len(r.comparison), 'comparisons, exit', r.exit_status)")


#: The resume path's reference: a fresh process that imports mechcheck and reads every part.
READ_PARTS = ("import mechcheck, pandas as pd; r = pd.read_parquet({out!r} + '/results'); "
              "s = pd.read_parquet({out!r} + '/status'); print(len(r), 'rows,', len(s), 'poses')")


def solve_time(line: str) -> float:
    """The time a sweep spent solving its tasks, from its summary line ("…, 37.1 s -> …")."""
    found = re.search(r"reused, ([0-9.]+) s ->", line)
    assert found, line
    return float(found.group(1))


def timed(command: list[str]) -> tuple[float, str]:
    # In an empty directory: ``python -c`` and ``-m`` put theirs first on sys.path, where a
    # stray file (a scratch ``nt.py`` in /tmp once was imported by pathlib) would be timed.
    with tempfile.TemporaryDirectory() as empty:
        start = time.perf_counter()
        done = subprocess.run(command, capture_output=True, text=True, check=False, cwd=empty)
        took = time.perf_counter() - start
    return took, done.stdout.strip().splitlines()[-1]


def repeated(command: list[str], repeats: int) -> tuple[list[float], str]:
    runs = [timed(command) for _ in range(repeats)]
    return [t for t, _ in runs], runs[-1][1]


def spread(times: list[float]) -> str:
    return f"{statistics.median(times):.2f} s (min {min(times):.2f}, max {max(times):.2f})"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--only", choices=["suite", "sweeps"], help="time only these")
    args = parser.parse_args()
    repeats = args.repeats
    cli = [sys.executable, "-m", "mechcheck.cli"]
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, Python "
          f"{platform.python_version()}; median of {repeats}")
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        (out / "e1.toml").write_text(E1)
        if args.only != "sweeps":
            time_suite(cli, out, repeats)
        if args.only != "suite":
            time_sweeps(cli, out, repeats)


def time_suite(cli: list[str], out: Path, repeats: int) -> None:
    suite, last = repeated([*cli, "run", "-q", "--out", str(out / "suite")], repeats)
    reference, ref_last = repeated([sys.executable, "-c", API_SUITE], repeats)
    print(f"built-in suite, every backend, with the report: {spread(suite)}  ({last})")
    print(f"  reference, the same through mechcheck.check, nothing written: "
          f"{spread(reference)}  ({ref_last}); ratio "
          f"{statistics.median(suite) / statistics.median(reference):.2f}")


def time_sweeps(cli: list[str], out: Path, repeats: int) -> None:
    sweep = [*cli, "sweep", "-q", "--out", str(out / "sweep")]
    runs = [timed([*sweep, "--fresh"]) for _ in range(repeats)]
    fresh, solving = [t for t, _ in runs], [solve_time(line) for _, line in runs]
    print(f"built-in sweeps (3 × 360 poses), every backend, with figures and the report: "
          f"{spread(fresh)}  ({runs[-1][1]})")
    print(f"  reference, the same runs' time solving the tasks: {spread(solving)}; "
          f"ratio {statistics.median(fresh) / statistics.median(solving):.2f}")
    read_parts = [sys.executable, "-c", READ_PARTS.format(out=str(out / "sweep"))]
    resumed, bare, reading = [], [], []
    for _ in range(repeats):
        for times, command in ((resumed, sweep), (bare, [*sweep, "--no-figures"]),
                               (reading, read_parts)):
            took, last = timed(command)
            times.append(took)
    print(f"the same sweeps resumed, every part there: {spread(resumed)}")
    print(f"  the same with --no-figures: {spread(bare)}; the figures add "
          f"{statistics.median(resumed) - statistics.median(bare):.2f} s")
    print(f"  reference, import mechcheck and read the parts: {spread(reading)}  ({last}); "
          f"ratio {statistics.median(bare) / statistics.median(reading):.2f} without figures, "
          f"{statistics.median(resumed) / statistics.median(reading):.2f} with them")
    million = ["sweep", str(out / "e1.toml"), "-b", "analytic", "--theta12", "0:360:0.00036",
               "-q", "--fresh", "--out", str(out / "million")]
    times, last = repeated([*cli, *million], repeats)
    print(f"analytic sweep, 10^6 poses to Parquet: {spread(times)}  ({last})")


if __name__ == "__main__":
    main()
