"""MuJoCo's compiled per-pose loops (:mod:`mechcheck.sim_models.mujoco._fast.exact_kernel`:
``mujoco_solve``'s batch and the settled sweep's reads) against the Python loops: the same
MuJoCo functions on the same MjData, so the same numbers to the last bit; the Python loops
wherever the compiled ones cannot run; and models kept from one sweep to the next give the
numbers of models built anew. A continuous driven sweep's runs
(:mod:`~mechcheck.sim_models.mujoco._fast.drive_kernel`) likewise."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest

from mechcheck.analytic.presets import as_linkage
from mechcheck.analytic.solution import Solution
from mechcheck.sim_models.mujoco import _fast, backend as _mujoco, batch_settle, linkage_dynamics
from mechcheck.sweep import gated_poses

from .builtin import builtin, builtin_cases
from .harness import sweeper
from .test_driven_sweep import whitworth
from .test_pymunk_linkage import at_rest

#: The backend's functions as the harness calls them (a preset as its linkage).
sweep = sweeper(_mujoco.sweep, {"mujoco": _mujoco.settle, "mujoco_solve": _mujoco.solve_at_pose},
                "mujoco")

pytest.importorskip("numba")

#: Built-in linkages whose driver sweeps ±0.1 (rad or m) stay exact solves (no friction,
#: no free coordinates), and the presets' θ12 sweeps.
LINKAGES = sorted(n for n, c in builtin_cases().items()
                  if c.mechanism == "linkage" and not c.has_friction
                  and n not in ("bonnet-hold", "bonnet-free", "exam-q1-slider-bar"))


def grid(name: str) -> np.ndarray:
    case = builtin(name)
    if case.mechanism == "linkage":
        return np.linspace(-0.1, 0.1, 25)
    theta = np.radians(np.arange(0.0, 360.0, 7.0))
    verdicts, _ = gated_poses(case, theta)
    return theta[[v == "" for v in verdicts]]


def counted(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """Records each compiled loop that runs."""
    ran: list[str] = []
    loop = _fast.loops()
    assert loop is not None, "numba is installed: the loops compile"
    for name in ("load_points", "equations", "post", "reads"):
        original = getattr(loop, name)

        def wrapper(*args: object, _f: Callable[..., None] = original, _n: str = name) -> None:
            ran.append(_n)
            _f(*args)

        monkeypatch.setattr(loop, name, wrapper)
    return ran


def identical(a: list[Solution], b: list[Solution]) -> bool:
    return len(a) == len(b) and all(
        x.status == y.status and x.values.keys() == y.values.keys()
        and all(x.values[q] == y.values[q] or (math.isnan(x.values[q]) and math.isnan(y.values[q]))
                for q in x.values)
        for x, y in zip(a, b, strict=True))


@pytest.mark.parametrize("name", [*LINKAGES, "seed-E1-as-stated", "seed-E2-frictionless"])
def test_the_compiled_loops_give_the_python_loops_numbers(name: str,
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    case, values = builtin(name), grid(name)
    ran = counted(monkeypatch)
    fast = sweep(case, values, "mujoco_solve")
    assert {"load_points", "equations", "post"} <= set(ran)
    with monkeypatch.context() as m:
        m.setattr(_fast, "loops", lambda: None)
        count = len(ran)
        slow = sweep(case, values, "mujoco_solve")
        assert len(ran) == count
    assert sum(s.status == "ok" for s in fast) >= 10
    assert identical(fast, slow)


def test_an_arena_laid_out_elsewhere_falls_back_to_python(monkeypatch: pytest.MonkeyPatch) -> None:
    """If a forward pass put the constraint arrays elsewhere, the Python loops redo the work:
    the same numbers as without the compiled loops."""
    case, values = builtin("seed-E1-as-stated"), grid("seed-E1-as-stated")
    expected = sweep(case, values, "mujoco_solve")

    def moved(*args: object) -> None:
        raise _fast.ArenaMoved("test")

    monkeypatch.setattr(_fast, "check_arena", moved)
    assert identical(sweep(case, values, "mujoco_solve"), expected)


def settled_sweep(name: str) -> list[Solution]:
    """The built-in case's settled sweep, a moving linkage's with its drivers held."""
    case = builtin(name)
    case = at_rest(case) if case.mechanism == "linkage" and case.kind != "static" else case
    values = np.linspace(-0.5, 0.5, 41) if case.mechanism == "linkage" else grid(name)
    return sweep(case, values, "mujoco")


def assert_same_settling(a: list[Solution], b: list[Solution]) -> None:
    """Same verdicts, steps and numbers, to the last bit."""
    assert [s.diagnostics.get("steps") for s in a] == [s.diagnostics.get("steps") for s in b]
    assert identical(a, b)


@pytest.mark.parametrize("name", ["seed-E1-as-stated", "watt-ii-demo"])
def test_settled_reads_compiled_are_the_python_reads(name: str,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    """A settled sweep, batched: the pass-end reads compiled and in Python, every pose's
    steps and numbers alike (each pose's next pass starts from what its read carried, so one
    differing bit would change what follows)."""
    ran = counted(monkeypatch)
    fast = settled_sweep(name)
    assert ran.count("reads") >= 2  # one per round of passes (the first is in Python)
    with monkeypatch.context() as m:
        m.setattr(_fast, "loops", lambda: None)
        slow = settled_sweep(name)
    assert sum(s.status == "ok" for s in fast) >= 30
    assert_same_settling(fast, slow)


def test_kept_settling_models_give_the_numbers_of_new_ones() -> None:
    """The second settled sweep of a Case reuses the first's rig, model copies and rollout
    data (:func:`~mechcheck.sim_models.mujoco.batch_settle.kept_models`): the same steps
    and numbers as a sweep with models built anew, and the same models again."""
    batch_settle.kept_models.cache_clear()
    first = settled_sweep("seed-E1-as-stated")
    kept = batch_settle.kept_models.cache_info().currsize
    again = settled_sweep("seed-E1-as-stated")
    assert batch_settle.kept_models.cache_info().currsize == kept > 0
    assert batch_settle.kept_models.cache_info().hits >= kept
    batch_settle.kept_models.cache_clear()
    assert_same_settling(first, again)
    assert_same_settling(again, settled_sweep("seed-E1-as-stated"))


def test_copies_refreshed_in_place_give_the_numbers_of_new_copies(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """A settled sweep after another of a linkage of the same sizes (seed E1 drawn at
    another pose: another Case, another rig) steps the copies that sweep left, refreshed in
    place (:func:`~mechcheck.sim_models.mujoco._fast.model_copies`): the same
    numbers as with new copies."""
    e1 = builtin("seed-E1-as-stated")
    theta = grid("seed-E1-as-stated")
    _fast.COPIES.clear()
    sweep(e1, theta, "mujoco")
    ((_, kept),) = _fast.COPIES.values()
    before = [id(m) for m in kept]
    in_place = sweep(e1, theta[3:], "mujoco")  # drawn at its own first pose
    assert [id(m) for m in kept[:len(before)]] == before and len(_fast.COPIES) == 1
    monkeypatch.setattr(_fast, "copy_model", lambda: None)
    batch_settle.kept_models.cache_clear()
    assert_same_settling(in_place, sweep(e1, theta[3:], "mujoco"))


@pytest.mark.parametrize("name", ["seed-E1-as-stated", "watt-ii-demo"])
def test_compiled_passes_settle_as_the_rollouts_do(name: str,
                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    """The settled sweep's passes stepped in numba (:mod:`._fast.step_kernel`) against MuJoCo's
    rollouts, 16 steps a call: every pose stops at the same step of the same pass with the
    same rule and reads the same numbers, to the last bit. The kernel zeroes the warm start
    where each rollout would begin: with the rollouts cut otherwise (a trial that stepped
    small waves longer), this test failed, E1's poses reading up to 2e-13 apart and one
    stopping by another rule."""
    calls: list[int] = []
    model = batch_settle.sensing_rig(as_linkage(builtin("seed-E1-as-stated"))).model
    assert _fast.compiled_passes(model) is not None, "numba: the passes compile"
    original = _fast.step_passes

    def counting(*args: object) -> None:
        calls.append(1)
        original(*args)  # type: ignore[arg-type]

    with monkeypatch.context() as m:
        m.setattr(_fast, "step_passes", counting)
        compiled = settled_sweep(name)
    assert len(calls) >= 4
    with monkeypatch.context() as m:
        m.setattr(_fast, "compiled_passes", lambda model: None)
        batch_settle.kept_models.cache_clear()
        rolled = settled_sweep(name)
    assert sum(s.status == "ok" for s in compiled) >= 30
    for key in ("passes", "stop_rule"):
        assert [s.diagnostics.get(key) for s in compiled] == [s.diagnostics.get(key) for s in rolled]
    assert_same_settling(compiled, rolled)


def test_compiled_passes_run_out_of_budget_as_the_rollouts_do(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """Seed E1 within 0.02° of its change point: poses whose passes run out of their step
    budgets (96 000 steps in 15 passes, `not_settled`; 19 623 in 3) and one that settles
    late (20 267 in 8) take the same steps, passes, verdicts and numbers compiled and
    through the rollouts: the budget's last reading is where both end a pass."""
    e1 = builtin("seed-E1-as-stated")
    theta = np.radians(180.0 - np.array([0.0097, 0.006, 0.02]))
    compiled = sweep(e1, theta, "mujoco")
    assert [s.status for s in compiled] == ["not_settled", "not_settled", "ok"]
    with monkeypatch.context() as m:
        m.setattr(_fast, "compiled_passes", lambda model: None)
        batch_settle.kept_models.cache_clear()
        rolled = sweep(e1, theta, "mujoco")
    assert [s.diagnostics.get("passes") for s in compiled] == \
        [s.diagnostics.get("passes") for s in rolled]
    assert [s.message for s in compiled] == [s.message for s in rolled]
    assert_same_settling(compiled, rolled)


def test_a_continuous_driven_sweep_compiled_reads_the_python_loops_numbers(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The user's Whitworth quick-return (a massless block: two models and their massless
    limit; a cutting force off the ram's centre, weights), its crank turning at 10 rad/s
    through a whole turn in 30° steps, one continuous run: each model's run
    compiled (:mod:`._fast.drive_kernel`), in the Python loop of the same MuJoCo calls, and
    in the lockstep loop that applies the loads as the general path does
    (:meth:`~mechcheck.sim_models.mujoco.linkage_loads.RigLoads.wrenches`, a kinematics pass
    before each forward pass) give every pose the same steps and numbers, to the last bit."""
    case, turn = whitworth(), np.radians(np.arange(0.0, 360.0, 30.0))
    ran: list[bool] = []
    original = _fast.drive

    def recorded(*args: object) -> bool:
        ran.append(original(*args))  # type: ignore[arg-type]
        return ran[-1]

    with monkeypatch.context() as m:
        m.setattr(_fast, "drive", recorded)
        compiled = sweep(case, turn, "mujoco")
    assert ran and all(ran), "numba: every model's run compiled"
    with monkeypatch.context() as m:
        m.setattr(_fast, "drive", lambda *_: False)
        stepped = sweep(case, turn, "mujoco")
    with monkeypatch.context() as m:
        m.setattr(linkage_dynamics, "plain", lambda rig: False)
        general = sweep(case, turn, "mujoco")
    continuous = [s for s in compiled if str(s.diagnostics.get("sweep_run")).startswith("continuous")]
    assert len(continuous) == 12 and all(s.status == "ok" for s in continuous)
    for other in (stepped, general):
        assert [s.diagnostics.get("steps") for s in compiled] == \
            [s.diagnostics.get("steps") for s in other]
        assert identical(compiled, other)
