"""Time and peak memory of the simulator backends against the size of a linkage.

Usage:  python benchmarks/bench_chain_sims.py [--loops 4,16,64] [--repeats 3]
                                              [--backends mujoco,pymunk] [--kinds static,driven]

The linkage is a chain of n seed-E1 four-bar loops (``tests/chains.py``: 2n + 1 moving links,
one degree of freedom, every loop in E1's drawn configuration). "static" is the chain held
at its drawn pose under E1's loads on every loop; "driven" gives its first crank 1 rad/s.
Each run is ``mechcheck run FILE -b BACKEND -q -o DIR`` in a fresh process started in an
empty directory, as a user runs it, so the time includes the start-up and the analytic
reference, and the peak memory is the process's resident peak (``wait4``'s ``ru_maxrss``).

Prints Markdown: per backend and kind, the seconds and the peak MB at each chain length
(median over the repeats, with min and max) and the run's verdict; then, from one length to
the next, the growth of the links, of the time and of the memory above the smallest
chain's peak (linear growth: the memory ratio equals the links' ratio).
"""

from __future__ import annotations

import argparse
import csv
import itertools
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the repository: tests.chains

from tests.chains import four_bar_chain, toml_of


@dataclass(frozen=True)
class Run:
    """One ``mechcheck run`` in a fresh process."""

    seconds: float
    peak_mb: float
    verdict: str


def chain_file(directory: Path, loops: int, kind: str) -> Path:
    """The chain's case file: held still (static) or its first crank at 1 rad/s (driven)."""
    table = four_bar_chain(loops, name=f"chain{loops}-{kind}")
    if kind == "driven":
        table["drivers"][0]["velocity"] = 1.0
    path = directory / f"chain{loops}_{kind}.toml"
    path.write_text(toml_of(table))
    return path


def run_once(case_file: Path, backend: str, workdir: Path) -> Run:
    """``mechcheck run`` of one file through one backend: wall time, peak RSS, verdict."""
    out = workdir / "out"
    command = [sys.executable, "-m", "mechcheck", "run", str(case_file), "-b", backend, "-q",
               "-o", str(out)]
    start = time.perf_counter()
    process = subprocess.Popen(command, cwd=workdir, stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL)
    _, _, usage = os.wait4(process.pid, 0)
    seconds = time.perf_counter() - start
    return Run(seconds, usage.ru_maxrss / 1024.0, verdict(out / "diagnostics.csv", backend))


def verdict(diagnostics: Path, backend: str) -> str:
    """The backend's status in a run's diagnostics ("missing" if the run wrote none)."""
    if not diagnostics.exists():
        return "missing"
    with diagnostics.open() as f:
        statuses = {row["status"] for row in csv.DictReader(f) if row["backend"] == backend}
    return ",".join(sorted(statuses)) or "missing"


def spread(values: list[float], fmt: str = ".3g") -> str:
    return (f"{statistics.median(values):{fmt}} (min {min(values):{fmt}}, "
            f"max {max(values):{fmt}})")


def measure(loops: list[int], backend: str, kind: str, repeats: int,
            root: Path) -> dict[int, list[Run]]:
    """Every chain length's runs, ``repeats`` each, each in an empty directory of its own."""
    runs: dict[int, list[Run]] = {}
    for n in loops:
        case_file = chain_file(root, n, kind)
        runs[n] = []
        for r in range(repeats):
            workdir = root / f"{backend}-{kind}-{n}-{r}"
            workdir.mkdir()
            runs[n].append(run_once(case_file, backend, workdir))
    return runs


def report(runs: dict[int, list[Run]], backend: str, kind: str) -> None:
    print(f"\n### {backend}, {kind}\n")
    print("| loops | moving links | s | peak MB | verdict |")
    print("|---:|---:|---|---|---|")
    for n, rs in runs.items():
        print(f"| {n} | {2 * n + 1} | {spread([r.seconds for r in rs])} | "
              f"{spread([r.peak_mb for r in rs], '.0f')} | "
              f"{', '.join(sorted({r.verdict for r in rs}))} |")
    lengths = list(runs)
    if len(lengths) < 2:
        return
    base = statistics.median(r.peak_mb for r in runs[lengths[0]])
    print("\n| from → to | links × | time × | peak MB above the smallest chain's |")
    print("|---|---:|---:|---|")
    for a, b in itertools.pairwise(lengths):
        time_a = statistics.median(r.seconds for r in runs[a])
        time_b = statistics.median(r.seconds for r in runs[b])
        extra_a = statistics.median(r.peak_mb for r in runs[a]) - base
        extra_b = statistics.median(r.peak_mb for r in runs[b]) - base
        print(f"| {a} → {b} | {(2 * b + 1) / (2 * a + 1):.2f} | {time_b / time_a:.2f} | "
              f"{extra_a:.0f} → {extra_b:.0f} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--loops", default="4,16,64")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--backends", default="mujoco,pymunk")
    parser.add_argument("--kinds", default="static,driven")
    args = parser.parse_args()
    loops = [int(x) for x in args.loops.split(",")]
    print(f"Python {platform.python_version()} on {platform.machine()}, "
          f"{os.cpu_count()} cores; median of {args.repeats} fresh processes per row")
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        for backend in args.backends.split(","):
            for kind in args.kinds.split(","):
                report(measure(loops, backend, kind, args.repeats, root), backend, kind)


if __name__ == "__main__":
    main()
