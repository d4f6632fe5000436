"""Driven sweeps run as one continuous motion: the user's Whitworth quick-return turning at
10 rad/s, a whole turn in 1° steps (360 poses, ``mechcheck sweep --driver 0:360:1``),
through each simulator's ``sweep``, against that simulator's own stepping cost for the same
steps (its C floor, measured in the same run).

The floor: the steps the sweep took, counted in an untimed run of the same (deterministic)
sweep, made again with nothing else in the loop. MuJoCo: one single-threaded
``mujoco.rollout`` of the driven model (its clock and drive) for as many steps, each a
forward pass and an Euler step, as the sweep's are. pymunk: Chipmunk's ``cpSpaceStep`` on
the driven Space, as many times at each time step and iteration count as the sweep stepped
there. The sweep's own work on top (loads, friction, readings, checks, the analytic
seeds) is the ratio. Each timed sweep is of the case read anew from its file, with no
continuation path kept, so nothing an earlier sweep found is reused. Medians over ``--repeats`` with min
and max.

    python benchmarks/bench_sweep_driven.py --repeats 3 [--backend mujoco] [--cpu]

``--cpu`` times with the process's CPU time instead of the wall clock: on a machine shared
with other work the wall clock counts the time the process waited for a core, in the sweep
and in its floor alike but not in the same measure.
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections import Counter
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import mujoco
import numpy as np
import pymunk

from mechcheck import load_cases
from mechcheck.analytic import linkage_kinematics
from mechcheck.analytic.case import Case
from mechcheck.analytic.solution import Solution
from mechcheck.backends import get

#: The clock every time is read from (``--cpu``: the process's CPU time).
CLOCK: list[Callable[[], float]] = [time.perf_counter]
CASES = [Path("compare/cases/users/whitworth.toml"), Path("/work/shared/cases/users/whitworth.toml")]


def whitworth() -> Case:
    path = next(p for p in CASES if p.exists())
    return next(c for c in load_cases(path) if c.name == "whitworth-running")


def sweep(case: Case, grid: np.ndarray, backend: str) -> list[Solution]:
    run = get(backend).sweeper()
    assert run is not None
    solutions: list[Solution] = run(case, grid, backend)
    return solutions


@contextmanager
def counting(backend: str) -> Iterator[Counter[tuple[float, int]]]:
    """The sweep's steps while inside, by (time step, iterations): MuJoCo's Euler steps,
    pymunk's Space steps."""
    counts: Counter[tuple[float, int]] = Counter()
    if backend == "mujoco":
        from mechcheck.sim_models.mujoco import _fast

        euler, compiled = mujoco.mj_Euler, _fast.drive

        def counted_euler(m: Any, d: Any) -> None:
            counts[(float(m.opt.timestep), 0)] += 1
            euler(m, d)

        # The steps are counted in Python: the compiled runs make the same ones, uncounted.
        mujoco.mj_Euler, _fast.drive = counted_euler, lambda *_: False
        try:
            yield counts
        finally:
            mujoco.mj_Euler, _fast.drive = euler, compiled
        return
    step = pymunk.Space.step

    def counted_step(space: pymunk.Space, dt: float) -> None:
        counts[(dt, space.iterations)] += 1
        step(space, dt)

    pymunk.Space.step = counted_step  # type: ignore[method-assign]
    try:
        yield counts
    finally:
        pymunk.Space.step = step  # type: ignore[method-assign]


def mujoco_floor(case: Case, counts: Counter[tuple[float, int]]) -> float:
    """Seconds for one single-threaded rollout of the driven model per time step, as many
    steps as the sweep took at it."""
    from mujoco import rollout

    from mechcheck.sim_models.linkage_motion import prescribed_motion
    from mechcheck.sim_models.mujoco.linkage_dynamics import driven_rigs

    rig = driven_rigs(case, prescribed_motion(case)).base
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    took = 0.0
    for (dt, _), n in counts.items():
        rig.model.opt.timestep = dt
        mujoco.mj_resetData(rig.model, rig.data)
        state = np.zeros(mujoco.mj_stateSize(rig.model, spec))
        mujoco.mj_getState(rig.model, rig.data, state, spec)
        start = CLOCK[0]()
        rollout.rollout(rig.model, rig.data, state[None, :], nstep=n)
        took += CLOCK[0]() - start
    return took


def pymunk_floor(case: Case, counts: Counter[tuple[float, int]]) -> float:
    """Seconds of ``cpSpaceStep`` alone on the driven Space, as many times at each time step
    and iteration count as the sweep stepped there."""
    from dataclasses import replace

    from mechcheck.sim_models.pymunk._fast.bulk import lib
    from mechcheck.sim_models.pymunk.linkage_dynamics import DRIVEN
    from mechcheck.sim_models.pymunk.linkage_model import build_linkage_model

    took = 0.0
    for (dt, iterations), n in counts.items():
        # The driven Space without the run's Python: no loads or friction callbacks.
        settings = replace(DRIVEN, dt=dt, iterations=iterations)
        model = build_linkage_model(case, settings, np.zeros(3 * len(case.linkage.moving_links)),
                                    driven=True)
        model.space.gravity = (0.0, -9.81)  # loaded (see bench_pymunk.c_floor: no subnormals)
        step, space = lib.cpSpaceStep, model.space._space
        start = CLOCK[0]()
        for _ in range(n):
            step(space, dt)
        took += CLOCK[0]() - start
    return took


def spread(values: list[float], digits: int = 2) -> str:
    return (f"{statistics.median(values):.{digits}f} ({min(values):.{digits}f}, "
            f"{max(values):.{digits}f})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--step", type=float, default=1.0, help="grid step, degrees")
    parser.add_argument("--backend", choices=("mujoco", "pymunk"), action="append",
                        help="time this simulator only (repeatable; default: both)")
    parser.add_argument("--cpu", action="store_true",
                        help="time with the process's CPU time (a shared machine's other load "
                             "does not count), not the wall clock")
    args = parser.parse_args()
    if args.cpu:
        CLOCK[0] = time.process_time
    case = whitworth()
    grid = np.radians(np.arange(0.0, 360.0, args.step))
    floors: dict[str, Callable[[Case, Counter[tuple[float, int]]], float]] = {
        "mujoco": mujoco_floor, "pymunk": pymunk_floor}
    floors = {name: f for name, f in floors.items() if name in (args.backend or floors)}
    print(f"Whitworth turning at 10 rad/s, {grid.size} poses; median (min, max) of "
          f"{args.repeats} repeats; {'CPU time' if args.cpu else 'wall clock'}")
    print("| backend | ok | continuous | sweep s | steps | ms/pose | C floor ms/pose | "
          "ratio to floor |")
    print("|---|---|---|---|---|---|---|---|")
    for backend, floor_of in floors.items():
        with counting(backend) as counts:
            solutions = sweep(case, grid, backend)
        ok = sum(s.status == "ok" for s in solutions)
        continuous = sum(str(s.diagnostics.get("sweep_run", "")).startswith("continuous")
                         for s in solutions)
        took, floor = [], []
        for _ in range(args.repeats):
            # Read anew, and no path of its continuation kept: nothing an earlier sweep
            # found is reused (a sweep in a new process).
            fresh = whitworth()
            linkage_kinematics._PATHS.clear()
            start = CLOCK[0]()
            sweep(fresh, grid, backend)
            took.append(CLOCK[0]() - start)
            floor.append(floor_of(case, counts))
        per_pose = [1e3 * t / grid.size for t in took]
        floor_ms = [1e3 * f / grid.size for f in floor]
        ratio = [t / f for t, f in zip(took, floor, strict=True)]
        print(f"| {backend} | {ok} | {continuous} | {spread(took, 1)} | "
              f"{sum(counts.values())} | {spread(per_pose)} | {spread(floor_ms)} | "
              f"{spread(ratio)} |", flush=True)


if __name__ == "__main__":
    main()
