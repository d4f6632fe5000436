"""Every case's analytic answers, saved before a speed change and compared after: a change
that only spares work must leave them the same to the bit.

Usage:  python benchmarks/compare_answers.py save before.pkl
        python benchmarks/compare_answers.py compare before.pkl

The answers: every case of ``compare/cases`` but the trajectories, and the user mechanisms (``bench_exudyn``'s
cases), through ``analytic``, ``superposition`` and ``virtual_work``, each solved on a
Linkage built anew (a first call) and again on the case's own (status, message, every value
and the condition number); and ``solve_poses`` of every linkage with a driver at seven
values of it (±30° or ±10 mm). ``compare`` prints the differing values (at most 30) and
their count; its exit status is 1 where any differs.
"""

from __future__ import annotations

import argparse
import math
import pickle
import sys
from pathlib import Path
from typing import Any

import numpy as np
from bench_exudyn import all_cases, fresh

import mechcheck
from mechcheck.analytic.case import Case

CASES = Path(__file__).resolve().parent.parent / "compare" / "cases"
BACKENDS = ("analytic", "superposition", "virtual_work")
SHOWN = 30


def every_case() -> list[Case]:
    """Every case file's cases but the trajectory ones (no pose to solve), then the user
    mechanisms."""
    cases = [c for f in sorted(CASES.rglob("*.toml")) for c in mechcheck.load_cases(f)]
    return [c for c in cases if c.simulation is None] + all_cases()


def solved(case: Case, backend: str) -> object:
    try:
        s = mechcheck.solve(case, backend)
    except Exception as error:    # a refusal is an answer too
        return repr(error)
    return (s.status, s.message, dict(s.values), s.diagnostics.get("condition_number"))


def swept(case: Case) -> object:
    rotates = case.linkage.joint(case.linkage.drivers[0].joint).kind.rotates
    grid = np.radians(np.linspace(-30, 30, 7)) if rotates else np.linspace(-0.01, 0.01, 7)
    try:
        return mechcheck.solve_poses(case, grid).to_dict("list")
    except Exception as error:
        return repr(error)


def answers() -> dict[tuple[object, ...], object]:
    out: dict[tuple[object, ...], object] = {}
    for i, case in enumerate(every_case()):
        for backend in BACKENDS:
            new = case if case.is_preset else fresh(case)
            out[i, case.name, backend, "first"] = solved(new, backend)
            out[i, case.name, backend, "again"] = solved(case, backend)
        if not case.is_preset and case.linkage.drivers:
            out[i, case.name, "solve_poses"] = swept(case)
    return out


def differences(old: Any, new: Any, where: str = "") -> list[str]:
    """Where ``new`` differs from ``old``: a float that is not the same number (NaN equals
    NaN), anything else that is not equal, or a different shape."""
    if isinstance(old, dict) and isinstance(new, dict):
        if set(old) != set(new):
            return [f"{where}: keys {sorted(map(str, set(old) ^ set(new)))}"]
        return [d for k in old for d in differences(old[k], new[k], f"{where}/{k}")]
    if isinstance(old, (list, tuple)) and isinstance(new, (list, tuple)):
        if len(old) != len(new):
            return [f"{where}: length {len(old)} → {len(new)}"]
        pairs = enumerate(zip(old, new, strict=True))
        return [d for k, (a, b) in pairs for d in differences(a, b, f"{where}[{k}]")]
    if isinstance(old, float) and isinstance(new, float):
        same = old == new or (math.isnan(old) and math.isnan(new))
        return [] if same else [f"{where}: {old!r} → {new!r}"]
    return [] if old == new else [f"{where}: {old!r:.80} → {new!r:.80}"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("action", choices=("save", "compare"))
    parser.add_argument("file", type=Path)
    args = parser.parse_args()
    found = answers()
    if args.action == "save":
        args.file.write_bytes(pickle.dumps(found))
        print(f"{len(found)} answer sets saved to {args.file}")
        return
    diff = differences(pickle.loads(args.file.read_bytes()), found)
    for line in diff[:SHOWN]:
        print(line)
    print(f"{len(found)} answer sets; {len(diff)} values differ")
    sys.exit(1 if diff else 0)


if __name__ == "__main__":
    main()
