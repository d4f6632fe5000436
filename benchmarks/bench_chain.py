"""How the analytic pose analysis grows with the size of a linkage: a chain of n four-bar
loops (tests/chains.py), static, through the one engine, against a bare sparse solve of
the same member-equilibrium equations timed in the same run.

Usage:  python benchmarks/bench_chain.py [--loops 16 64 256 1000] [--repeats 5] [--friction]

For each n, in a fresh process each repeat (so that memory is that case's alone):

- ``mechcheck``: read and validate the case file, then ``mechcheck.solve(case)`` (pose,
  reactions, drive torque, verdict and the exact condition number);
- ``reference``: the same equilibrium equations assembled straight from the drawing with
  scipy.sparse and solved by ``spsolve``: no validation, no verdict, no condition number,
  the linear algebra's floor;
- with ``--friction``, friction circles (μ = 0.2, r = 5 mm) at the pins of the first
  :data:`FRICTION_LOOPS` loops, a Coulomb case solved by Newton's method; its reference is
  then ``dense``: the same ``mechcheck.solve`` with every matrix held dense (the path every
  Coulomb case took before, and the one small linkages take);
- peak memory of the mechcheck process (``ru_maxrss``) above the interpreter with
  mechcheck, its case-file reader, its engine and scipy imported (imports are not timed).

Printed: medians with min and max over the repeats, the ratio mechcheck / reference, and
the growth exponent between consecutive sizes (1 is linear).
"""

from __future__ import annotations

import argparse
import json
import math
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
#: With ``--friction``: the loops whose pins carry friction circles. Each loop turns slower
#: than the one before, and a pin whose relative motion is below 1e-12 of the driver's
#: has no defined friction sense (``indeterminate``), so friction stays on the first loops.
FRICTION_LOOPS = 16

CHILD = r"""
import json, resource, sys, time
sys.path.insert(0, {tests!r})
import numpy as np
import mechcheck
import mechcheck.casefile, mechcheck.run
import mechcheck.analytic.linkage_forces, mechcheck.analytic.linkage_statics
import scipy.sparse.linalg
from mechcheck.analytic.values import GROUND
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
path, which = sys.argv[1], sys.argv[2]
start = time.perf_counter()
case = mechcheck.load_cases(path)[0]
if which == "dense":
    mechcheck.analytic.linalg.DENSE_COLUMNS = 10**9
if which in ("mechcheck", "dense"):
    solution = mechcheck.solve(case)
    assert solution.status == "ok", solution.message
    value = solution.values["Q_J_O0"]
else:
    from scipy import sparse
    from scipy.sparse.linalg import spsolve
    lk = case.linkage
    row = {{name: 3 * k for k, name in enumerate(lk.moving_links)}}
    r, c, v = [], [], []
    for k, joint in enumerate(lk.joints):
        x, y = lk.points[joint.at]
        for link, sign in ((joint.links[1], 1.0), (joint.links[0], -1.0)):
            if link == GROUND:
                continue
            i = row[link]
            r += [i, i + 2, i + 1, i + 2]
            c += [2 * k, 2 * k, 2 * k + 1, 2 * k + 1]
            v += [sign, -sign * y, sign, sign * x]
    crank = lk.joint(lk.drivers[0].joint).links[1]
    r.append(row[crank] + 2); c.append(2 * len(lk.joints)); v.append(1.0)
    n = 3 * len(lk.moving_links)
    b = np.zeros(n)
    for load in lk.loads:
        i = row[load.link]
        b[i] += load.force[0]; b[i + 1] += load.force[1]
        b[i + 2] += load.at[0] * load.force[1] - load.at[1] * load.force[0]
    x = spsolve(sparse.csc_matrix((v, (r, c)), shape=(n, n)), -b)
    value = float(x[-1])
elapsed = time.perf_counter() - start
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(json.dumps({{"time": elapsed, "memory_kb": peak - base, "value": value}}))
"""


def run(path: Path, which: str) -> dict[str, float]:
    code = CHILD.format(tests=str(HERE.parent / "tests"))
    done = subprocess.run([sys.executable, "-c", code, str(path), which], capture_output=True,
                          text=True, check=True, cwd=tempfile.gettempdir())
    result: dict[str, float] = json.loads(done.stdout.splitlines()[-1])
    return result


def spread(values: list[float], fmt: str = ".3g") -> str:
    return f"{statistics.median(values):{fmt}} (min {min(values):{fmt}}, max {max(values):{fmt}})"


def with_friction(table: dict[str, Any]) -> dict[str, Any]:
    """The chain with friction circles at the pins of its first :data:`FRICTION_LOOPS`
    loops, its driver turning forwards (the sense friction opposes)."""
    pins = {j["name"]: 5.0 for j in table["joints"]
            if int(j["name"].lstrip("J_ABO")) <= FRICTION_LOOPS}
    drivers = [d | {"sense": "increasing"} for d in table["drivers"]]
    return table | {"friction": {"mu": 0.2, "pin_radius": pins}, "drivers": drivers}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--loops", type=int, nargs="+", default=[16, 64, 256, 1000])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--friction", action="store_true",
                        help="Coulomb friction circles, against the dense path")
    args = parser.parse_args()
    sys.path.insert(0, str(HERE.parent / "tests"))
    from chains import four_bar_chain, toml_of

    previous: tuple[int, float, float] | None = None
    with tempfile.TemporaryDirectory() as tmp:
        for loops in args.loops:
            path = Path(tmp) / f"chain{loops}.toml"
            table = four_bar_chain(loops, name=f"chain{loops}")
            if args.friction:
                table = with_friction(table)
            path.write_text(toml_of(table))
            reference = "dense" if args.friction else "reference"
            ours, ref, memory, ref_memory = [], [], [], []
            for _ in range(args.repeats):   # alternating, so that drift hits both alike
                a = run(path, "mechcheck")
                b = run(path, reference)
                assert math.isclose(a["value"], b["value"], rel_tol=1e-9), (a, b)
                ours.append(a["time"])
                ref.append(b["time"])
                memory.append(a["memory_kb"] / 1024)
                ref_memory.append(b["memory_kb"] / 1024)
            ratio = [x / y for x, y in zip(ours, ref, strict=True)]
            t, m = statistics.median(ours), statistics.median(memory)
            growth = ""
            if previous is not None:
                n0, t0, m0 = previous
                k = math.log(loops / n0)
                growth = (f"; growth exponent time {math.log(t / t0) / k:.2f}, "
                          f"memory {math.log(max(m, 1e-3) / max(m0, 1e-3)) / k:.2f}")
            print(f"{loops:5d} loops ({3 * loops + 1} joints): mechcheck {spread(ours)} s, "
                  f"{reference} {spread(ref)} s, ratio {spread(ratio)}; "
                  f"memory {spread(memory)} MB ({reference} {spread(ref_memory)} MB){growth}")
            previous = (loops, t, m)


if __name__ == "__main__":
    main()
