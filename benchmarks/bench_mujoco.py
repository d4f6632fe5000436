"""Time the MuJoCo backends over a 360-pose sweep of seed E1 (Söylemez 6.3,
``seed-E1-as-stated`` from the built-in case files) and measure their error.

Errors are measured as the tolerance policy measures them
(:func:`mechcheck.tables.comparison_rows`: each value against the largest
reference value of its kind at that pose), and each pose is judged against its
policy tolerance (static 1e-6; near-singular, condition number > 1e4, 1e-2).

Each backend's time is printed beside a reference measured in the same run, and their
ratio (issue 13): for settled statics the C floor, the steps the sweep's poses settled in
(summed over their passes) stepped by a single-threaded ``mujoco.rollout`` of the same
model with nothing else done; for ``mujoco_solve`` one bare ``mj_forward`` per pose.
Settled statics also get issue 13's own floor ("42 steps × 3.5 µs"): the steps each pose
takes settled alone (the single-pose backend, nothing carried from a neighbour), stepped
the same way; the sweep's continuation makes its own floor the lower, stricter one.
Both backends keep the models they build for a linkage for the next sweep of the same one
(and the settled sweep its model copies for a linkage of the same sizes): each is timed
both ways, the "built" rows as a sweep run once in a fresh process. Where numba compiles
the per-pose loops, rows with Python's loops are timed too. Each row is timed with the
earlier rows' objects frozen out of the garbage collector.
Targets: settled ≤ 2× the C floor; ``mujoco_solve`` ≤ 20 µs/pose.

A second table times a linkage sweep (issue 12): the Watt II six-bar held statically
(``watt-ii-demo`` with its driver at rest) at 360 crank angles over −170°…100° (where it
assembles from the drawn pose), through both backends, with the analytic pose analysis
done once beforehand (not timed). The settled sweep is stepped in batches
(:func:`mechcheck.sim_models.mujoco.linkage.settled_sweep`), continued from settled
neighbours; a row gives it with every pose settled from nothing carried.
Medians over ``LINKAGE_REPEATS`` repeats, with min and max.

A last table follows the near-toggle study (seed E1 at θ12 = 180° − δ): the
settled backend's status, error, steps and passes as the change point nears, and its time
per pose against the C floor of as many steps (``--near-toggle``: that table alone).

Run: /work/venv/bin/python benchmarks/bench_mujoco.py [--linkage | --near-toggle]
"""

import contextlib
import dataclasses
import gc
import math
import statistics
import sys
import time

import mujoco
import numpy as np

from mechcheck import backends as registry, solve
from mechcheck.analytic.case import Case
from mechcheck.analytic.presets import as_linkage, redrawn
from mechcheck.analytic.solution import Solution
from mechcheck.casefile import builtin_case_files, load_cases
from mechcheck.sweep import gated_poses
from mechcheck.tables import comparison_rows

CASE = "seed-E1-as-stated"
LINKAGE = "watt-ii-demo"
LINKAGE_REPEATS = 5
#: The near-toggle study's distances from the change point, degrees: its grid from condition
#: number 24 to 13 100 (5.0°…0.009°), with 0.0119°, 0.0115°, 0.011°, 0.0105° and 0.01°
#: (condition numbers 9 970 to 11 900, all settled since plain passes that contract
#: steadily are extrapolated) and 0.0097° (12 200, the first that does not).
NEAR_TOGGLE_DELTAS = np.sort(np.r_[np.geomspace(30.0, 1e-4, 15)[2:10],
                                   0.0119, 0.0115, 0.011, 0.0105, 0.01, 0.0097])[::-1]
NEAR_TOGGLE_REPEATS = 3


#: (row label, backend). Both keep their models for the next sweep of the same linkage
#: (:func:`mechcheck.sim_models.mujoco.linkage.sweep_rig`,
#: :func:`mechcheck.sim_models.mujoco.batch_settle.kept_models`) and the settled
#: sweep's model copies for models of the same sizes
#: (:func:`mechcheck.sim_models.mujoco.batch_settle.model_copies`): timed with them kept
#: from the warm-up run, and with them all built anew in every repeat (a sweep run once in
#: a fresh process).
RUNS = (("mujoco", "mujoco"), (COLD_SETTLED := "mujoco, models built", "mujoco"),
        ("mujoco_solve", "mujoco_solve"), (COLD := "mujoco_solve, model built", "mujoco_solve"))


#: A row timing the settled sweep stepped by MuJoCo's rollouts, 16 steps a call, where
#: numba compiles the passes (:mod:`mechcheck.sim_models.mujoco._fast.step_kernel`): the same
#: sweep, the same steps; the difference is the steps past each stop and the Python
#: between rollouts.
ROLLOUTS = "rollouts, passes not compiled"
#: Rows with the per-pose loops in Python where numba compiles them
#: (:mod:`mechcheck.sim_models.mujoco._fast`: the settled reads, the exact solve).
PYTHON_LOOPS = "Python per-pose loops"


#: The backends' functions as the harness calls them (a preset as its linkage).
settle = registry.get("mujoco").solver()


def sweep(case: Case, grid: np.ndarray, backend: str = "mujoco") -> list[Solution]:
    sweeper = registry.get(backend).sweeper()
    assert sweeper is not None
    return sweeper(case, np.asarray(grid, dtype=float), backend)  # type: ignore[no-any-return]


def compiled_rules() -> bool:
    from mechcheck.sim_models.compiled import kernel
    from mechcheck.sim_models.mujoco._fast import STOP_KERNEL

    return kernel(STOP_KERNEL) is not None


def runs():
    """:data:`RUNS`, with the settled sweep again through MuJoCo's rollouts and both again
    with Python's per-pose loops, if numba compiled them."""
    if not compiled_rules():
        return RUNS
    return (RUNS[0], (f"mujoco, {ROLLOUTS}", "mujoco"), (f"mujoco, {PYTHON_LOOPS}", "mujoco"),
            *RUNS[1:3], (f"mujoco_solve, {PYTHON_LOOPS}", "mujoco_solve"), *RUNS[3:])


@contextlib.contextmanager
def stop_rules(label):
    """Within: the batched settling stepped by rollouts, or the per-pose loops Python's, if
    ``label`` names them."""
    from mechcheck.sim_models.mujoco import _fast

    passes, loops = _fast.compiled_passes, _fast.loops
    if ROLLOUTS in label:
        _fast.compiled_passes = lambda model: None
    if PYTHON_LOOPS in label:
        _fast.loops = lambda: None
    try:
        yield
    finally:
        _fast.compiled_passes, _fast.loops = passes, loops


def forget_rigs(label):
    """Before a repeat of the run ``label``: the kept models forgotten if it builds them."""
    from mechcheck.sim_models.mujoco._fast import COPIES
    from mechcheck.sim_models.mujoco.batch_settle import kept_models
    from mechcheck.sim_models.mujoco.linkage import sweep_rig

    if label in (COLD, COLD_SETTLED):  # as in a fresh process
        sweep_rig.cache_clear()
        kept_models.cache_clear()
        COPIES.clear()


def timed(label, backend, sweep_once):
    """ms per pose of ``sweep_once()`` (360 poses) over the repeats, after one untimed run
    (imports; numba's compiled stop rules, if installed, compiled or loaded); ``mujoco_solve``
    with its models kept then finds them in every repeat."""
    with stop_rules(label):
        sweep_once()
        # The earlier rows' objects (their Solutions, kept models) out of the collector's
        # sight: a full collection scanning them landed in one row's repeats or another's.
        gc.collect()
        gc.freeze()
        times = []
        for _ in range(LINKAGE_REPEATS):
            forget_rigs(label)
            start = time.perf_counter()
            out = sweep_once()
            times.append((time.perf_counter() - start) / 360 * 1e3)
        gc.unfreeze()
    return times, out


def pose_errors(case, theta, solutions):
    """(worst force/torque relative error, number of poses outside tolerance,
    worst error where the condition number is ≤ 1e4) over the poses simulated."""
    worst = worst_regular = 0.0
    failing = 0
    for t, s in zip(theta, solutions, strict=True):
        if s.status != "ok":
            continue
        at = redrawn(case, theta12=float(t))
        reference = solve(at)
        rows = [r for r in comparison_rows(at, reference, s) if str(r["quantity"])[0] in "FTM"]
        error = max(float(r["rel_err"]) for r in rows)
        worst = max(worst, error)
        if reference.diagnostics["condition_number"] <= 1e4:
            worst_regular = max(worst_regular, error)
        failing += not all(r["passed"] for r in rows)
    return worst, failing, worst_regular


def harness_sweep(case, theta, backend):
    """The sweep as the harness runs it: the pose gate (:func:`mechcheck.sweep.gated_poses`),
    then the backend on the poses that have forces; (solutions, their θ12, poses gated)."""
    verdicts, _ = gated_poses(case, theta)
    keep = np.array([v == "" for v in verdicts])
    return sweep(case, theta[keep], backend), theta[keep], int((~keep).sum())


def main() -> None:
    case = {c.name: c for c in load_cases(*builtin_case_files())}[CASE]
    theta = np.radians(np.arange(360.0))
    print(f"MuJoCo {mujoco.__version__}; {CASE}, 360 poses (1° steps), the pose gate included; "
          f"median of {LINKAGE_REPEATS}\n")
    print("| backend | ms/pose | reference ms/pose | ratio | floor alone ms/pose | ratio | "
          "poses ok | gated (singular) | not settled | worst rel. error (cond ≤ 1e4) | "
          "outside tolerance | median steps | max steps |")
    print("|---|---|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|")
    linkage = as_linkage(case)
    for label, backend in runs():
        times, (sols, kept, gated) = timed(label, backend,
                                           lambda b=backend: harness_sweep(case, theta, b))
        status = [s.status for s in sols]
        steps = [s.diagnostics.get("steps", 0) for s in sols if s.status == "ok"]
        reference = (c_floor(linkage, steps, LINKAGE_REPEATS) if backend == "mujoco"
                     else forward_floor(linkage, LINKAGE_REPEATS))
        if backend == "mujoco":  # issue 13's floor: the steps of each pose settled alone
            alone = [settle(redrawn(case, theta12=float(t))).diagnostics["steps"] for t in kept]
            floor_alone = c_floor(linkage, alone, LINKAGE_REPEATS)
            alone_cells = f"{spread(floor_alone, '.4f')} | {ratio(times, floor_alone)}"
        else:
            alone_cells = "— | —"
        _, failing, worst_regular = pose_errors(case, kept, sols)
        print(f"| {label} | {spread(times, digits(backend))} | {spread(reference, '.4f')} | "
              f"{ratio(times, reference)} | {alone_cells} | {status.count('ok')} | "
              f"{gated} | {status.count('not_settled')} | "
              f"{worst_regular:.2e} | {failing} | {np.median(steps):.0f} | {max(steps)} |")

    linkage_sweep_table({c.name: c for c in load_cases(*builtin_case_files())})

    near_toggle_table(case)


def near_toggle_table(case) -> None:
    """Settled statics of one pose at each of NEAR_TOGGLE_DELTAS (the single-pose path,
    as the study runs it): status, error, steps, passes, and ms against the C floor of as
    many steps, medians over NEAR_TOGGLE_REPEATS."""
    print(f"\nNear the change point, one pose at a time; median of {NEAR_TOGGLE_REPEATS}\n")
    print("| δ (deg) | condition number | status | rel. error | steps | passes | ms | "
          "C floor ms | ratio |")
    print("|---:|---:|---|---:|---:|---:|---:|---:|---:|")
    for delta in NEAR_TOGGLE_DELTAS:
        at = redrawn(case, theta12=math.pi - math.radians(float(delta)))
        times = []
        for _ in range(NEAR_TOGGLE_REPEATS):
            start = time.perf_counter()
            sim = settle(at)
            times.append((time.perf_counter() - start) * 1e3)
        steps = sim.diagnostics["steps"]
        floor = c_floor(as_linkage(at), [steps], NEAR_TOGGLE_REPEATS, poses=1)
        reference = solve(at)
        error = pose_errors(at, [at.preset.theta12], [sim])[0] if sim.status == "ok" else math.nan
        print(f"| {delta:.4g} | {reference.diagnostics['condition_number']:.0f} | {sim.status} | "
              f"{error:.1e} | {steps} | {sim.diagnostics['passes']} | {spread(times, '.1f')} | "
              f"{spread(floor, '.1f')} | {ratio(times, floor)} |")


def static_watt(cases):
    """The Watt II six-bar of the built-in cases with its driver at rest."""
    case = cases[LINKAGE]
    held = tuple(dataclasses.replace(d, velocity=0.0, acceleration=0.0)
                 for d in case.linkage.drivers)
    return dataclasses.replace(case, name="watt-ii-static",
                               geometry=dataclasses.replace(case.linkage, drivers=held))


def linkage_errors(case, results, solutions):
    """Worst relative error (tolerance policy's measure) and poses outside tolerance."""
    from mechcheck.analytic.linkage_backends import solution_from

    worst, failing = 0.0, 0
    for i, s in enumerate(solutions):
        if s.status != "ok":
            continue
        reference = solution_from(case, "analytic", results, method="analytic", elapsed=0.0,
                                  index=i)
        rows = comparison_rows(case, reference, s)
        worst = max(worst, max(float(r["rel_err"]) for r in rows))
        failing += not all(r["passed"] for r in rows)
    return worst, failing


def c_floor(case, steps, repeats, poses=360):
    """ms per pose of stepping a sweep's ``steps`` (each pose's total; ``poses`` of them)
    with nothing but MuJoCo: one single-threaded rollout of the static model from the drawn
    pose at rest, as many steps in all; times over ``repeats``."""
    import copy

    from mujoco import rollout

    from mechcheck.sim_models.mujoco.linkage_rig import LinkageRig

    rig = LinkageRig(case)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.zeros(mujoco.mj_stateSize(rig.model, spec))
    mujoco.mj_getState(rig.model, rig.data, state, spec)
    per = max(1, round(sum(steps) / poses))
    models = [copy.copy(rig.model) for _ in range(poses)]
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        rollout.rollout(models, [mujoco.MjData(rig.model)], np.tile(state, (poses, 1)), nstep=per)
        times.append((time.perf_counter() - start) / poses * 1e3)
    return times


def forward_floor(case, repeats):
    """ms per pose of one bare ``mj_forward`` (a Python loop of 360), over ``repeats``."""
    from mechcheck.sim_models.mujoco.linkage import exact_linkage_rig

    rig = exact_linkage_rig(case)
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(360):
            mujoco.mj_forward(rig.model, rig.data)
        times.append((time.perf_counter() - start) / 360 * 1e3)
    return times


def ratio(figure, reference):
    """Median, min and max of figure/reference over paired repeats."""
    return spread([f / r for f, r in zip(figure, reference, strict=True)], ".2f")


def digits(backend):
    """ms per pose to the µs for ``mujoco_solve`` (its target is 0.020 ms)."""
    return ".4f" if backend == "mujoco_solve" else ".3f"


def spread(values, fmt=".3f"):
    return f"{statistics.median(values):{fmt}} (min {min(values):{fmt}}, max {max(values):{fmt}})"


def linkage_sweep_table(cases) -> None:
    from mechcheck.analytic.linkage_backends import analytic_results
    from mechcheck.sim_models.mujoco.linkage import sweep_linkage

    case = static_watt(cases)
    first = np.radians(np.linspace(-170.0, 100.0, 360))
    results = analytic_results(case, first)
    print(f"\n{LINKAGE} held statically, 360 poses over −170°…100°; {LINKAGE_REPEATS} repeats\n")
    print("| backend | ms/pose | reference ms/pose | ratio | floor alone ms/pose | ratio | "
          "poses ok | worst rel. error | outside tolerance | median steps | max steps |")
    print("|---|---|---|---|---|---|---:|---:|---:|---:|---:|")
    continued = ["mujoco (continued)",
                 *([f"mujoco (continued), {ROLLOUTS}"] if compiled_rules() else [])]
    table = {"mujoco (each pose alone)": ("mujoco", False),
             **{label: ("mujoco", True) for label in continued},
             **{label: (backend, True) for label, backend in RUNS[1:]}}
    floor_alone: list[float] = []
    rows = {}
    for label, (backend, continuation) in table.items():
        times, sols = timed(label, backend, lambda b=backend, c=continuation: sweep_linkage(
            case, first, b, results, continuation=c))
        worst, failing = linkage_errors(case, results, sols)
        steps = [s.diagnostics.get("steps", 0) for s in sols if s.status == "ok"]
        reference = (c_floor(case, steps, LINKAGE_REPEATS) if backend == "mujoco"
                     else forward_floor(case, LINKAGE_REPEATS))
        if not continuation and backend == "mujoco":
            floor_alone = reference
        alone_cells = (f"{spread(floor_alone, '.4f')} | {ratio(times, floor_alone)}"
                       if backend == "mujoco" else "— | —")
        ok = sum(s.status == "ok" for s in sols)
        rows[label] = (f"| {label} | {spread(times, digits(backend))} | "
                       f"{spread(reference, '.4f')} | "
                       f"{ratio(times, reference)} | {alone_cells} | {ok} | {worst:.2e} | "
                       f"{failing} | {np.median(steps):.0f} | {max(steps)} |")
    for label in (*continued, "mujoco (each pose alone)", *dict(RUNS[1:])):
        print(rows[label])


if __name__ == "__main__":
    if "--linkage" in sys.argv:  # the linkage table alone
        linkage_sweep_table({c.name: c for c in load_cases(*builtin_case_files())})
    elif "--near-toggle" in sys.argv:  # the near-toggle table alone
        near_toggle_table({c.name: c for c in load_cases(*builtin_case_files())}[CASE])
    else:
        main()
