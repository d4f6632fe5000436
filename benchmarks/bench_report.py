"""How the report's build time grows with the number of cases.

Usage:  python benchmarks/bench_report.py [--sizes 500,2000,6000] [--repeats 3]

For each size, N seed-E1 four-bars (θ12 and the rocker load varied) run through
``analytic`` and ``virtual_work`` in process; then the Markdown and HTML report
is rendered, and, as the reference for the same work, the same results are
written as the three CSV tables. Printed: the median (min, max) of each over the
repeats, per case, and the ratio report / tables. A build linear in the number of
cases keeps the per-case time flat as N grows (issue 10: at 6,000 cases the
report took 75 % of the run, with per-case filtering that grew like N²).
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time

from mechcheck.analytic.case import Case, FourBarGeometry, Load
from mechcheck.analytic.presets import preset_case
from mechcheck.report import render
from mechcheck.run import run
from mechcheck.tables import diagnostics_frame, results_frame


def cases(n: int) -> list[Case]:
    """Seed E1's geometry at n crank angles that assemble, with a varying rocker load."""
    geometry = FourBarGeometry(0.14, 0.08, 0.10, 0.12)
    return [preset_case(name=f"e1-{i:05d}", geometry=geometry, theta12=0.2 + 2.5 * i / n,
                 loads=(Load(4, (0.09, 0.0), (100.0 + i % 7, 30.0)),)) for i in range(n)]


def timed(fn: object, *args: object) -> tuple[float, object]:
    start = time.perf_counter()
    out = fn(*args)  # type: ignore[operator]
    return time.perf_counter() - start, out


def summary(times: list[float], n: int) -> str:
    per = [1e3 * t / n for t in times]
    return f"{statistics.median(per):.3f} ({min(per):.3f}–{max(per):.3f})"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="500,2000,6000")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, Python "
          f"{platform.python_version()}; {args.repeats} repeats")
    print("| cases | run ms/case | report ms/case | CSV tables ms/case (reference) | "
          "report / tables | report share of run + report |")
    print("|---:|---:|---:|---:|---:|---:|")
    for n in (int(s) for s in args.sizes.split(",")):
        batch = cases(n)
        runs, reports, tables = [], [], []
        for _ in range(args.repeats):
            t_run, result = timed(run, batch, ["virtual_work"])
            t_report, _ = timed(render, result, {})
            t_tables, _ = timed(lambda r=result: (results_frame(r.solutions).to_csv(),
                                                  r.comparison.to_csv(),
                                                  diagnostics_frame(r.solutions).to_csv()))
            runs.append(t_run)
            reports.append(t_report)
            tables.append(t_tables)
        ratio = statistics.median(reports) / statistics.median(tables)
        share = statistics.median(reports) / (statistics.median(reports) + statistics.median(runs))
        print(f"| {n} | {summary(runs, n)} | {summary(reports, n)} | {summary(tables, n)} | "
              f"{ratio:.1f}× | {100 * share:.0f} % |")


if __name__ == "__main__":
    main()
