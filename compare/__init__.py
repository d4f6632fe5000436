"""mechcheck: the force analysis of planar mechanisms, checked against MuJoCo and pymunk.

The public Python API is these few names (README, "Python API"):

- :func:`load_cases`: the validated Cases of case files (none: the built-in suite);
- :func:`solve`: one Case through one backend, a :class:`Solution`;
- :func:`solve_poses`: one Case at many values of its driver in one vectorised call, a table;
- :func:`check`: Cases through backends, compared with ``analytic`` under the
  tolerance policy: a :class:`RunResult` with ``exit_status`` and ``comparison``;
- :func:`simulate`: trajectory Cases (``[case.simulate]``) through the backends that
  simulate, each run compared with ``analytic`` over time: a :class:`SimulateResult`;
- :func:`available_backends`: the backends this installation can run;
- :func:`mechcheck.testing.assert_solution_close`, for a project's own tests.

Everything else (``mechcheck.analytic``, ``mechcheck.sim_models``, the tables,
reports and CLI) is importable but may change between versions.

Examples
--------
>>> import mechcheck
>>> e1 = next(c for c in mechcheck.load_cases() if c.name == "seed-E1-as-stated")
>>> round(mechcheck.solve(e1).values["T12"], 5)
2.90133
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from mechcheck.analytic.solution import Solution
from mechcheck.analytic.values import CaseError
from mechcheck.verdicts import DEFAULT_FAIL_ON

if TYPE_CHECKING:
    import pandas as pd
    from numpy.typing import ArrayLike

    from mechcheck.analytic.case import Case
    from mechcheck.run import RunResult
    from mechcheck.simulate_run import SimulateResult

__all__ = ["Case", "CaseError", "RunResult", "SimulateResult", "Solution", "available_backends",
           "check", "load_cases", "simulate", "solve", "solve_poses"]


def load_cases(*paths: str | Path) -> list[Case]:
    """The Cases of case files (TOML), validated, in file order; no path: the built-in suite.

    A file that cannot be used raises :class:`CaseError`, whose message names the
    file, the case and the key (the same line ``mechcheck run`` prints).
    """
    from mechcheck.casefile import builtin_case_files, load_cases as load

    return load(*(paths or builtin_case_files()))


def solve(case: Case, backend: str = "analytic") -> Solution:
    """``case`` through one backend (see :func:`available_backends`); SI values, angles in
    radians. Behind the pose gate, as in ``mechcheck run``: where the analytic pose analysis
    finds no unique forces, the backend is not called and reports that verdict. A
    trajectory case (``[case.simulate]``) raises :class:`CaseError`: :func:`simulate` runs it."""
    from mechcheck.casefile import check_case_kind
    from mechcheck.run import solve_gated

    check_case_kind(case, trajectory=False)
    return solve_gated(backend, case)


def solve_poses(case: Case, driver_values: ArrayLike, backend: str = "analytic", *,
                condition: bool = True) -> pd.DataFrame:
    """``case`` at many poses in one vectorised call: a table, one row per pose.

    ``driver_values`` (SI) are the values of the case's driver: for a linkage, its first
    driver's rotation (rad) or travel (m) from the drawn pose, the others at their own
    values; for a four-bar or slider-crank, θ12 (rad). ``backend`` is one of the vectorised
    ones (``analytic``, ``superposition``, ``virtual_work``). Columns: ``driver``, ``status``,
    ``message``, ``condition_number``, then every quantity in SI (radians), a force NaN
    where the pose has a verdict. Each pose's verdict and numbers are those ``mechcheck
    sweep`` writes for it, behind the same pose gate. ``condition=False`` leaves out the
    condition numbers, an SVD per pose that costs about as much as the rest (the verdicts
    do not need them: near a toggle they are computed anyway).
    """
    import numpy as np
    import pandas as pd

    from mechcheck import backends as registry
    from mechcheck.casefile import check_case_kind
    from mechcheck.sweep import check_driver_grid, check_theta12_grid, vector_poses

    check_case_kind(case, trajectory=False)   # a trajectory has no poses to solve
    grid = np.asarray(driver_values, dtype=float).ravel()
    if not registry.get(backend).vectorised:
        vectorised = [n for n, b in registry.REGISTRY.items() if b.vectorised]
        raise ValueError(f"solve_poses: backend {backend!r} is not vectorised; use one of "
                         f"{', '.join(vectorised)} (or `mechcheck sweep` for a simulator)")
    if not np.isfinite(grid).all():
        raise ValueError("solve_poses: driver_values must be finite")
    if case.is_preset:
        check_theta12_grid(case, grid)
    else:
        rotates = case.linkage.drivers and case.linkage.joint(
            case.linkage.drivers[0].joint).kind.rotates
        check_driver_grid(case, np.degrees(grid) if rotates else grid * 1000.0, "driver_values")
    poses = vector_poses(case, backend, grid)
    if poses is None:
        raise ValueError(f"solve_poses: backend {backend!r} does not apply to case "
                         f"{case.name!r} (its method refuses Coulomb friction)")
    columns: dict[str, Any] = {"driver": grid, "status": poses.statuses.astype(str),
                               "message": poses.messages.astype(str)}
    if condition:
        columns["condition_number"] = poses.condition
    return pd.DataFrame(columns | poses.values)


def check(cases: Sequence[Case], backends: Sequence[str] | None = None, *,
          fail_on: Sequence[str] = DEFAULT_FAIL_ON) -> RunResult:
    """Every Case through every backend, compared with ``analytic`` as ``mechcheck run`` does.

    ``backends`` defaults to every available one. The result's ``exit_status`` is
    0 when everything agrees and 1 otherwise; ``comparison`` is the comparison
    table as a DataFrame, in table units (degrees), one row per quantity.
    """
    from mechcheck import backends as registry
    from mechcheck.casefile import check_case_kind
    from mechcheck.run import run

    for case in cases:
        check_case_kind(case, trajectory=False)
    names = registry.available() if backends is None else list(backends)
    return run(cases, names, fail_on=fail_on)


def simulate(cases: Sequence[Case] | None = None, backends: Sequence[str] | None = None, *,
             fail_on: Sequence[str] = DEFAULT_FAIL_ON) -> SimulateResult:
    """Trajectory Cases through every backend, as ``mechcheck simulate`` runs them; no cases:
    the built-in trajectory cases.

    Each backend that simulates runs each case (a simulator once per setting of its ladder),
    and each run is compared with ``analytic`` over time; the others report
    ``not_applicable``. The result is :func:`check`'s with the runs: ``exit_status``,
    ``comparison`` (one row per simulator and quantity: its finest run's worst error over
    time, and the reference's energy check), ``rungs`` (one row per run: settings, error,
    wall time, steps), ``trajectories`` (each run, by case and backend) and ``table()``
    (every run's quantities at every output time). A case without ``[case.simulate]``
    raises :class:`CaseError`.
    """
    from mechcheck import backends as registry
    from mechcheck.casefile import builtin_trajectory_files, check_case_kind, load_cases as load
    from mechcheck.simulate_run import simulate as run_all

    chosen = list(cases) if cases is not None else load(*builtin_trajectory_files())
    for case in chosen:
        check_case_kind(case, trajectory=True)
    names = registry.available() if backends is None else list(backends)
    return run_all(chosen, names, fail_on=fail_on)


def available_backends() -> list[str]:
    """The backends whose simulator is installed here (``analytic`` first)."""
    from mechcheck import backends as registry

    return registry.available()


def __getattr__(name: str) -> object:
    # Case (numpy), RunResult and SimulateResult (pandas) are imported only when asked for, so that
    # `import mechcheck`, `mechcheck --help` and the pytest plugin stay light.
    if name == "Case":
        from mechcheck.analytic.case import Case

        return Case
    if name == "RunResult":
        from mechcheck.run import RunResult

        return RunResult
    if name == "SimulateResult":
        from mechcheck.simulate_run import SimulateResult

        return SimulateResult
    raise AttributeError(f"module 'mechcheck' has no attribute {name!r}")
