"""Benchmark: settled static equilibrium per pose over 360-pose continuation sweeps.

1. Seed E1 (as its linkage) over a full turn of θ12, as the harness runs it: the pose
   gate first, so the change point is never simulated.
2. The Watt II six-bar (linkage builder; the built-in case with its crank held still)
   over 360 crank angles from 1° after its lower lock to 1° before its upper lock, against
   a simple reference doing the same work without continuation: each pose its own case
   through the backend (fresh Space, analytic gate, priming, settling), on every
   ``--stride``-th pose. Also the share of the analytic gate (poses and verdicts of the
   whole sweep in one vectorised call) in the sweep's time.

Prints Markdown: ms per pose (median over ``--repeats`` with min and max), steps per
pose and the worst relative force error against the analytic backend, for ``pymunk``
(settle) and ``pymunk_solve``; and, measured in the same repeat right after the sweep,
its **C floor**: the same pymunk Space, loaded, stepped pose after pose as many steps as
the sweep's run at that pose took, with nothing but Chipmunk's ``cpSpaceStep`` in the loop
(:func:`c_floor`), and the ratio sweep / floor (median, min, max over the repeats).
Target (issue 13): ratio ≤ 2 for the settled sweeps. With numba installed (the ``fast``
extra) the settled runs are compiled (:mod:`mechcheck.sim_models.pymunk.compiled`); the
row "pymunk, Python loop" is the same sweep with the loop stepped from Python.

Run: /work/venv/bin/python benchmarks/bench_pymunk.py [--repeats 3] [--stride 10]
"""

from __future__ import annotations

import argparse
import math
import platform
import statistics
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import replace

import numpy as np
import pymunk
from pymunk._chipmunk_cffi import lib

from mechcheck import backends as registry, solve_poses
from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage_backends import analytic_results
from mechcheck.analytic.presets import as_linkage
from mechcheck.analytic.solution import Solution
from mechcheck.casefile import builtin_case_files, load_cases
from mechcheck.sim_models.pymunk import _fast as compiled, backend as backends
from mechcheck.sim_models.pymunk.linkage import hold_without_correction
from mechcheck.sim_models.pymunk.linkage_model import build_linkage_model
from mechcheck.sim_models.pymunk.settings import LINKAGE_SETTLE, LINKAGE_SOLVE
from mechcheck.sweep import gated_poses

#: (median, min, max) of a measurement over the repeats.
Stats = tuple[float, float, float]


#: The rows of each table: (label, backend, the settling loop stepped from Python).
ROWS = [("pymunk", "pymunk", False), ("pymunk, Python loop", "pymunk", True),
        ("pymunk_solve", "pymunk_solve", False)]


def sweep(case: Case, grid: np.ndarray, backend: str = "pymunk") -> list[Solution]:
    """The backend's sweep as the harness calls it (a preset as its linkage)."""
    sweeper = registry.get(backend).sweeper()
    assert sweeper is not None
    return sweeper(case, np.asarray(grid, dtype=float), backend)  # type: ignore[no-any-return]


def rows() -> list[tuple[str, str, bool]]:
    """:data:`ROWS`; without numba the plain row is the Python loop already."""
    return ROWS if compiled.available() else [r for r in ROWS if not r[2]]


@contextmanager
def loop(python: bool) -> Iterator[None]:
    """Settle with the Python loop (``python``) or whichever is available."""
    available = compiled.available
    if python:
        compiled.available = lambda: False  # type: ignore[assignment]
    try:
        yield
    finally:
        compiled.available = available


def worst_error(solutions: list[Solution], reference: dict[str, np.ndarray]) -> float:
    """Largest relative error over the sweep (forces scaled by the pose's largest force)."""
    worst = 0.0
    for k, sol in enumerate(solutions):
        if sol.status != "ok":
            continue
        force_scale = max(abs(reference[q][k]) for q in reference if q.startswith("F"))
        for q, v in sol.values.items():
            if q[0] in "FT":
                scale = force_scale if q[0] == "F" else abs(reference[q][k])
                worst = max(worst, abs(v - reference[q][k]) / max(abs(reference[q][k]), scale))
    return worst


def harness_sweep(case: Case, theta: np.ndarray, backend: str) -> tuple[list[Solution], int]:
    """The sweep as the harness runs it: the pose gate (:func:`mechcheck.sweep.gated_poses`),
    then the backend on the poses that have forces; (their solutions, poses gated)."""
    verdicts, _ = gated_poses(case, theta)
    keep = np.array([v == "" for v in verdicts])
    return sweep(case, theta[keep], backend), int((~keep).sum())


def four_bar_sweep(repeats: int) -> None:
    case = next(c for c in load_cases(*builtin_case_files()) if c.name == "seed-E1-as-stated")
    theta = np.radians(np.arange(360.0))
    table = solve_poses(case, theta)
    verdicts, _ = gated_poses(case, theta)
    keep = np.array([x == "" for x in verdicts])
    kept = {k: table[k].to_numpy()[keep] for k in table.columns
            if k not in ("driver", "status", "message", "condition_number")}
    linkage = as_linkage(case)
    print(f"Seed E1, as its linkage, 360 poses, the pose gate included; median of {repeats} "
          "(min, max); C floor: the same Space, loaded, stepped as many steps per pose by "
          "cpSpaceStep alone\n")
    print("| backend | poses | ok | gated (singular) | ms/pose (min, max) | C floor ms/pose "
          "(min, max) | ratio to floor (min, max) | steps/pose | worst rel. error |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for label, backend, python in rows():
        with loop(python):
            sweep(case, theta[:10], backend)  # warm-up (imports, layout check, compiling)
            sols, gated = harness_sweep(case, theta, backend)
            time_ms, floor_ms, ratio = against_floor(
                lambda b=backend: harness_sweep(case, theta, b)[0],  # type: ignore[misc]
                linkage, backend, len(theta), repeats)
        ok = sum(s.status == "ok" for s in sols)
        steps = np.mean([s.diagnostics.get("steps", 0) for s in sols if s.status == "ok"])
        print(f"| {label} | {len(theta)} | {ok} | {gated} | {cell(time_ms)} | {cell(floor_ms)} | "
              f"{cell(ratio, '×')} | {steps:.1f} | {worst_error(sols, kept):.1e} |")


def watt_at_rest() -> Case:
    """The built-in Watt II six-bar with its crank held still (a static case)."""
    case = next(c for c in load_cases(*builtin_case_files()) if c.name == "watt-ii-demo")
    held = tuple(replace(d, velocity=0.0, acceleration=0.0) for d in case.linkage.drivers)
    return case.with_(name="watt-ii-at-rest", geometry=replace(case.linkage, drivers=held))


def lock_to_lock(case: Case, poses: int, margin_deg: float = 1.0) -> np.ndarray:
    """``poses`` crank values (rad from the drawn pose) between the two locks, with margins."""
    far = np.radians([-720.0, 720.0])
    locked = analytic_results(case, far).pose.locked_at * far
    return np.linspace(locked[0] + math.radians(margin_deg), locked[1] - math.radians(margin_deg),
                       poses)


def linkage_error(case: Case, sols: list[Solution], values: np.ndarray) -> float:
    """Worst error of F_ (÷ the pose's largest reaction) and Q_ (÷ that × the size)."""
    reference = analytic_results(case, values).values
    worst = 0.0
    for k, sol in enumerate(sols):
        if sol.status != "ok":
            continue
        scale = max(abs(reference[q][k]) for q in sol.values if q.startswith("F_"))
        for q, v in sol.values.items():
            if q.startswith(("F_", "Q_")):
                size = scale * (case.linkage.scale if q.startswith("Q_") else 1.0)
                worst = max(worst, abs(v - reference[q][k]) / size)
    return worst


def spread(values: list[float]) -> Stats:
    return statistics.median(values), min(values), max(values)


def per_pose(fn: Callable[[], object], poses: int, repeats: int) -> Stats:
    """(median, min, max) ms per pose over the repeats."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append((time.perf_counter() - start) / poses * 1e3)
    return spread(times)


def c_floor(case: Case, backend: str, steps: list[int]) -> float:
    """Seconds to step the backend's Space of the linkage ``case`` ``steps[k]`` times for
    every pose k, with nothing but Chipmunk's ``cpSpaceStep`` in the loop: what the sweep
    would cost if all its Python work (loads, damping, readings, stop rule, verdicts, and
    pymunk's own ``Space.step`` wrapper) were free.

    The Space is loaded, by ``Space.gravity`` (applied inside ``cpSpaceStep``, no Python):
    unloaded, the accumulated impulses of seed E1 decay into subnormal doubles (1e-320),
    and subnormal arithmetic made each step 9.5 µs instead of 6.6 µs: a floor that slow
    flattered the ratio by 1.4×. The solver's work per step (``iterations`` Gauss–Seidel
    passes) does not depend on the load otherwise (Watt six-bar: 10.7 µs either way)."""
    settings = LINKAGE_SETTLE if backend == "pymunk" else LINKAGE_SOLVE
    model = build_linkage_model(case, settings, analytic_results(case).pose.q[0])
    if backend == "pymunk_solve":
        hold_without_correction(model)
    model.space.gravity = (0.0, -9.81)
    step, space, dt = lib.cpSpaceStep, model.space._space, settings.dt
    start = time.perf_counter()
    for n in steps:
        for _ in range(n):
            step(space, dt)
    return time.perf_counter() - start


def against_floor(run: Callable[[], list[Solution]], case: Case, backend: str, poses: int,
                  repeats: int) -> tuple[Stats, Stats, Stats]:
    """ms per pose of ``run`` and of its C floor (:func:`c_floor`, with the steps the run
    took at each pose), each repeat measuring both, and their ratio: (median, min, max)
    of each over the repeats."""
    sweep_ms, floor_ms, ratio = [], [], []
    for _ in range(repeats):
        start = time.perf_counter()
        sols = run()
        took = time.perf_counter() - start
        steps = [int(s.diagnostics["steps"]) for s in sols if "steps" in s.diagnostics]
        floor = c_floor(case, backend, steps)
        sweep_ms.append(took / poses * 1e3)
        floor_ms.append(floor / poses * 1e3)
        ratio.append(took / floor)
    return spread(sweep_ms), spread(floor_ms), spread(ratio)


def cell(stats: Stats, unit: str = "", digits: int = 2) -> str:
    """A table cell: the median, and (min, max)."""
    median, low, high = stats
    return f"{median:.{digits}f}{unit} ({low:.{digits}f}, {high:.{digits}f})"


def one_by_one(case: Case, values: np.ndarray, backend: str) -> list[Solution]:
    """The reference: every pose its own case through the backend, no continuation."""
    run = backends.settle if backend == "pymunk" else backends.solve_at_pose
    driver = case.linkage.drivers[0]
    return [run(case.with_(geometry=replace(case.linkage, drivers=(replace(driver, value=float(v)),))))
            for v in values]


def watt_sweep(repeats: int, stride: int) -> None:
    case = watt_at_rest()
    values = lock_to_lock(case, 360)
    sparse = values[::stride]
    gate = per_pose(lambda: analytic_results(case, values), len(values), repeats)
    print(f"\nWatt II six-bar held, linkage builder, 360 poses lock to lock "
          f"({math.degrees(values[0]):.2f}° … {math.degrees(values[-1]):.2f}° from the drawn pose); "
          f"analytic gate alone {gate[0]:.2f} ms/pose (min {gate[1]:.2f}, max {gate[2]:.2f})\n")
    print("| backend | ok | other verdicts | sweep ms/pose (min, max) | C floor ms/pose (min, max) "
          "| ratio to floor (min, max) | one by one ms/pose (min, max) | sweep speed-up | "
          "steps/pose | worst rel. error |")
    print("|---|---:|---|---:|---:|---:|---:|---:|---:|---:|")
    for label, backend, python in rows():
        with loop(python):
            sweep(case, values[:5], backend)  # warm-up
            sols = sweep(case, values, backend)
            fast, floor_ms, ratio = against_floor(
                lambda b=backend: sweep(case, values, b), case, backend, len(values), repeats)  # type: ignore[misc]
            slow = per_pose(lambda b=backend: one_by_one(case, sparse, b), len(sparse), repeats)  # type: ignore[misc]
        ok = [s for s in sols if s.status == "ok"]
        others = {s.status for s in sols} - {"ok"}
        other = ", ".join(f"{sum(s.status == v for s in sols)} {v}" for v in sorted(others)) or "-"
        steps = np.mean([s.diagnostics["steps"] for s in ok])
        print(f"| {label} | {len(ok)} | {other} | {cell(fast)} | {cell(floor_ms)} | "
              f"{cell(ratio, '×')} | {cell(slow)} | {slow[0] / fast[0]:.1f}× | {steps:.1f} | "
              f"{linkage_error(case, sols, values):.1e} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--stride", type=int, default=10)
    args = parser.parse_args()
    print(f"pymunk {pymunk.version}, Python {platform.python_version()}, {platform.machine()}; "
          f"settling loop {'compiled (numba)' if compiled.available() else 'Python (numba not installed)'}\n")
    four_bar_sweep(args.repeats)
    watt_sweep(args.repeats, args.stride)


if __name__ == "__main__":
    main()
