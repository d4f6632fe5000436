"""The compiled loops (:mod:`mechcheck.sim_models.pymunk._fast.compiled`, numba: settling, and
the constraint solve's re-posed steps) are the Python loops they replace: the same steps
and the same forces, bit for bit, on every built-in static case, every moving one held
still, whole sweeps of seed E1 and the Watt six-bar, and random linkages; and they read
the bodies' and springs' C structs only where the layout check has verified them."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import pytest
from hypothesis import given

from mechcheck.analytic.case import Case
from mechcheck.analytic.presets import as_linkage
from mechcheck.analytic.solution import Solution
from mechcheck.sim_models.compiled import kernel
from mechcheck.sim_models.pymunk import _fast, backend as pm, linkage as pl
from mechcheck.sim_models.pymunk._fast import layout
from mechcheck.sweep import gated_poses

from .builtin import builtin, builtin_cases
from .harness import sweeper
from .strategies import linkage_tables
from .test_linkage_identities import SETTINGS
from .test_pymunk_linkage import at_rest, loaded_case

pytest.importorskip("numba")

STATIC = sorted(n for n, c in builtin_cases().items()
                if c.kind == "static" and n not in ("locking-fourbar", "fourbar-change-point"))
MOVING = sorted(n for n, c in builtin_cases().items()
                if c.kind != "static" and c.mechanism == "linkage")


def held(name: str) -> Case:
    """A built-in case as a static linkage (a moving one with its drivers held still)."""
    case = builtin(name)
    case = case if case.mechanism == "linkage" else as_linkage(case)
    return case if case.kind == "static" else at_rest(case)


#: The held model's two runs: settling, and the constraint solve at the analytic pose.
BACKENDS = {"pymunk": (pl.settle, "pymunk"), "pymunk_solve": (pl.solve_at_pose, "pymunk_solve")}
#: The backend's sweep as the harness calls it (a preset as its linkage).
backend_sweep = sweeper(pm.sweep, {"pymunk": pm.settle, "pymunk_solve": pm.solve_at_pose}, "pymunk")


@pytest.fixture
def compiled_runs(monkeypatch: pytest.MonkeyPatch) -> Iterator[list[int]]:
    """Counts the runs the compiled loop made (each appends its steps)."""
    runs: list[int] = []
    run = _fast.run

    def counted(*args: Any) -> Any:
        out = run(*args)
        runs.append(out[0])
        return out

    monkeypatch.setattr(_fast, "run", counted)
    yield runs


def both(fn: Callable[[], list[Solution]], monkeypatch: pytest.MonkeyPatch,
         runs: list[int]) -> tuple[list[Solution], list[Solution]]:
    """``fn``'s solutions with the compiled loop (which must have run), then with Python's."""
    fast = fn()
    assert runs, "the compiled loop never ran"
    with monkeypatch.context() as m:
        m.setattr(_fast, "available", lambda: False)
        count = len(runs)
        slow = fn()
        assert len(runs) == count, "the Python loop was asked for and the compiled one ran"
    return fast, slow


def identical(a: float, b: float) -> bool:
    return a == b or (math.isnan(a) and math.isnan(b))


#: The residual velocity is |v| + |ω|·r with |v| from the C library's ``hypot`` in the
#: compiled loop and from CPython's own (a different algorithm) in the Python one: each
#: within an ulp of the exact value, so they may differ by two.
HYPOT_RTOL = 4.0 * float(np.finfo(float).eps)


def assert_same_runs(fast: list[Solution], slow: list[Solution]) -> None:
    """Same verdicts, steps, values and force change to the last bit; residual velocities
    within :data:`HYPOT_RTOL`."""
    assert len(fast) == len(slow)
    for k, (f, s) in enumerate(zip(fast, slow, strict=True)):
        assert (f.status, f.diagnostics.get("steps")) == (s.status, s.diagnostics.get("steps")), k
        assert f.values.keys() == s.values.keys()
        assert all(identical(f.values[q], s.values[q]) for q in f.values), k
        if "force_change" in f.diagnostics:
            assert identical(float(f.diagnostics["force_change"]),
                             float(s.diagnostics["force_change"])), k
            a, b = float(f.diagnostics["residual_velocity"]), float(s.diagnostics["residual_velocity"])
            assert identical(a, b) or math.isclose(a, b, rel_tol=HYPOT_RTOL), k


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("name", STATIC + MOVING)
def test_a_compiled_run_is_the_python_run(name: str, backend: str,
                                           monkeypatch: pytest.MonkeyPatch,
                                           compiled_runs: list[int]) -> None:
    case, solve = held(name), BACKENDS[backend][0]
    assert_same_runs(*both(lambda: [solve(case)], monkeypatch, compiled_runs))


def test_a_run_that_never_settles_ends_alike(monkeypatch: pytest.MonkeyPatch,
                                             compiled_runs: list[int]) -> None:
    """At seed E1's change point (the pose gate bypassed) neither loop settles: the same
    budget spent, the same last change and residual velocity."""
    case = held("fourbar-change-point")
    fast, slow = both(lambda: [pl.settle(case)], monkeypatch, compiled_runs)
    assert fast[0].status == "not_settled"
    assert_same_runs(fast, slow)


def test_whole_sweeps_are_the_python_sweeps(monkeypatch: pytest.MonkeyPatch,
                                            compiled_runs: list[int]) -> None:
    """Seed E1 every 3° as the harness sweeps it (the pose gate first) and the Watt six-bar
    from lock to lock: continuation carries each pose's impulses into the next, so one
    differing bit anywhere would show in every later pose."""
    e1 = builtin("seed-E1-as-stated")
    theta = np.radians(np.arange(0.0, 360.0, 3.0))
    verdicts, _ = gated_poses(e1, theta)
    theta = theta[[v == "" for v in verdicts]]
    watt, crank = held("watt-ii-demo"), np.linspace(-3.95, 1.86, 120)
    for case, values in ((e1, theta), (watt, crank)):
        for backend in BACKENDS:
            fast, slow = both(lambda c=case, v=values, b=backend: backend_sweep(c, v, b),  # type: ignore[misc]
                              monkeypatch, compiled_runs)
            assert sum(s.status == "ok" for s in fast) >= 118
            assert_same_runs(fast, slow)


@SETTINGS
@given(linkage_tables(friction=False, moving=False))
def test_random_linkages_run_alike(table: dict[str, Any]) -> None:
    """Random assemblable four-bars, slider-cranks and six-bars with loads, weights and
    springs (those of ``test_pymunk_linkage``'s settling test)."""
    case = loaded_case(table)
    for solve in (pm.settle, pm.solve_at_pose):
        fast = solve(case)
        with pytest.MonkeyPatch.context() as m:
            m.setattr(_fast, "available", lambda: False)
            slow = solve(case)
        assert_same_runs([fast], [slow])


def test_the_environment_switches_the_compiled_loop_off(monkeypatch: pytest.MonkeyPatch) -> None:
    kernel.cache_clear()
    monkeypatch.setenv("MECHCHECK_PURE_PYTHON", "1")
    assert not _fast.available()
    kernel.cache_clear()
    monkeypatch.delenv("MECHCHECK_PURE_PYTHON")
    assert _fast.available()
    kernel.cache_clear()
    # numba's own switch: its kernels would run as Python, where raw memory access fails.
    monkeypatch.setattr(pytest.importorskip("numba").config, "DISABLE_JIT", True)
    assert not _fast.available()
    kernel.cache_clear()


@pytest.mark.parametrize(("fields", "name"), [(layout.BODY_FIELDS, "w"), (layout.BODY_FIELDS, "f"),
                                              (layout.BODY_FIELDS, "p"),
                                              (layout.BODY_FIELDS, "transform"),
                                              (layout.DAMPED_SPRING_FIELDS, "jAcc"),
                                              (layout.ROTARY_SPRING_FIELDS, "jAcc")])
def test_a_wrong_body_or_spring_offset_fails_the_layout_check(
        fields: dict[str, int], name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """Off by one field, the check raises instead of letting the loop write elsewhere."""
    monkeypatch.setitem(fields, name, fields[name] + 8)
    with pytest.raises(layout.LayoutError):
        layout.check_layout()
