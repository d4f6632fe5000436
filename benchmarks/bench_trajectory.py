"""The analytic trajectory reference's cost per right-hand-side evaluation on Andrews'
squeezing mechanism, against the test set's equations written by hand in numpy
(``reference_andrews.py``), timed in the same run.

Usage:  python benchmarks/bench_trajectory.py [--repeats 5] [--calls 2000] [--cpu]

1. The hand right-hand side alone: one call at the published state at 0.03 s (a 13 × 13
   solve for q̈ and λ), µs per call.
2. The hand equations integrated by ``scipy.integrate.solve_ivp`` from the consistent start to
   0.03 s, with the method and rtol the reference reports in its ``settings`` (DOP853 at
   1e-12 while it is not there): the run's time over its evaluations, µs per evaluation, and
   its error against the published angles (so both sides are seen to do the same work).
3. ``mechcheck.analytic.trajectory.simulate`` on ``compare/cases/trajectories/andrews.toml``:
   its time over ``Trajectory.steps`` (the right-hand-side evaluations it reports), µs per
   evaluation, and its ratio to 2 (the target: within 3×); and its first run in the
   process, which also loads the compiled right-hand side from numba's cache (or compiles
   it, the first time after an install or a change of ``analytic/_fast/``). With numba
   absent or ``MECHCHECK_PURE_PYTHON=1``, the numpy path's figures.

Medians over the repeats, with min and max; ``--cpu``: in the process's CPU time instead of
the wall clock (a machine shared with other work).
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import reference_andrews as andrews
from bench_linkage import spread
from scipy.integrate import solve_ivp

import mechcheck
from mechcheck.analytic._fast import kernel
from mechcheck.analytic._fast.motion import KERNEL
from mechcheck.analytic.case import Case
from mechcheck.analytic.trajectory import simulate
from mechcheck.casefile import load_cases

CASE = Path(mechcheck.__file__).parent / "cases" / "trajectories" / "andrews.toml"
#: The clock every figure is read on (``--cpu``: time.process_time).
clock = time.perf_counter


def per_call(fn: Callable[[], object], calls: int, repeats: int) -> list[float]:
    """Seconds per call of ``fn``, once per repeat (each repeat ``calls`` calls)."""
    fn()    # warm-up
    out = []
    for _ in range(repeats):
        start = clock()
        for _ in range(calls):
            fn()
        out.append((clock() - start) / calls)
    return out


def hand_run(method: str, rtol: float) -> tuple[float, int, float]:
    """The hand equations integrated to 0.03 s: seconds, evaluations, worst relative error of
    the angles against the published state."""
    start_state = np.concatenate([andrews.Q0, np.zeros(7)])
    start = clock()
    solution = solve_ivp(andrews.rhs, (0.0, andrews.T_END), start_state, method=method,
                         rtol=rtol, atol=rtol)
    elapsed = clock() - start
    error = np.max(np.abs(solution.y[:7, -1] - andrews.Q_END) / np.abs(andrews.Q_END))
    return elapsed, int(solution.nfev), float(error)


def engine_run(case: Case) -> tuple[float, int, dict[str, object]] | None:
    """One run of the reference: (seconds, evaluations, settings); None while it is a stub."""
    start = clock()
    try:
        (run,) = simulate(case)
    except NotImplementedError:
        return None
    return clock() - start, run.steps, dict(run.settings)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--calls", type=int, default=2000)
    parser.add_argument("--cpu", action="store_true", help="time in the process's CPU time")
    args = parser.parse_args()
    global clock
    clock = time.process_time if args.cpu else time.perf_counter
    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"numpy {np.__version__}, {args.repeats} repeats, {'CPU time' if args.cpu else 'wall clock'}")

    state = np.concatenate([andrews.Q_END, andrews.QD_END])
    hand_rhs = per_call(lambda: andrews.rhs(andrews.T_END, state), args.calls, args.repeats)
    print(f"1. hand right-hand side alone: {spread(hand_rhs, scale=1e6)} µs per call")

    (case,) = load_cases(CASE)
    warm = engine_run(case)     # the first in the process: it warms the caches up
    settings = warm[2] if warm else {}
    method, rtol = str(settings.get("method", "DOP853")), float(str(settings.get("rtol", 1e-12)))
    # each repeat runs both, one after the other, so that a ratio compares runs made under
    # the same load of a shared machine
    pairs = [(engine_run(case), hand_run(method, rtol)) for _ in range(args.repeats)]
    hand = [h for _, h in pairs]
    hand_per_eval = [1e6 * t / n for t, n, _ in hand]
    print(f"2. hand equations, solve_ivp {method} rtol {rtol:g}: {hand[0][1]} evaluations, "
          f"{spread(hand_per_eval)} µs per evaluation (whole run {spread([t for t, _, _ in hand])} s; "
          f"angles within {hand[0][2]:.2g} of the published state)")
    engine = [e for e, _ in pairs if e is not None]
    if warm is None:
        print("3. mechcheck's analytic trajectory reference: not available yet "
              "(mechcheck.analytic.trajectory.simulate is a stub)")
        return
    engine_per_eval = [1e6 * t / max(n, 1) for t, n, _ in engine]
    ratios = [e / h for e, h in zip(engine_per_eval, hand_per_eval, strict=True)]
    print(f"3. mechcheck's reference ({settings}): {engine[0][1]} evaluations, "
          f"{spread(engine_per_eval)} µs per evaluation (whole run "
          f"{spread([t for t, _, _ in engine])} s); over the hand equations': "
          f"{spread(ratios, fmt='.2f')} (target ≤ 3)")
    path = "compiled (numba)" if kernel(KERNEL) is not None else "numpy (no numba, or switched off)"
    print(f"   right-hand side: {path}; first run in this process {warm[0]:.3g} s, "
          f"{warm[0] - float(np.median([t for t, _, _ in engine])):.3g} s over a later one")


if __name__ == "__main__":
    main()
