"""Edges of the simulator backends: an unloaded linkage at rest, a driven run thrown onto
another assembly, and what a long linkage costs in memory."""

from __future__ import annotations

import math
import tracemalloc
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from mechcheck import load_cases
from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage_backends import solve
from mechcheck.analytic.solution import FORCE_FLOOR_N
from mechcheck.casefile import parse_cases
from mechcheck.sim_models import linkage_motion
from mechcheck.sim_models.linkage_motion import driven_motion, lead_limit
from mechcheck.sim_models.mujoco import backend as mj
from mechcheck.sim_models.mujoco._fast import first_stops
from mechcheck.sim_models.mujoco.batch_settle import RULES
from mechcheck.sim_models.mujoco.linkage import sweep_linkage
from mechcheck.sim_models.mujoco.settle import FLOOR_WINDOW, WOBBLE_RTOL, DecayWatch
from mechcheck.sim_models.pymunk import backend as pm, linkage_dynamics as pld
from mechcheck.sim_models.pymunk.settings import LINKAGE_SETTLE
from mechcheck.sim_models.pymunk.settle import run_until_settled
from mechcheck.testing import assert_solution_close

from .builtin import builtin
from .chains import four_bar_chain, toml_of
from .mujoco_twins import StepWatch, vectorised_stops

FORCES = ("F_", "Q_")


def unloaded_e1(scale: float) -> Case:
    """Seed E1's four-bar drawn ``scale`` times its size, no load, no gravity, a 1 kg
    coupler mass: nothing for any joint to hold."""
    table = four_bar_chain(1, scale=scale, name=f"e1-unloaded-x{scale:g}")
    table["loads"] = []
    table["masses"] = [{"link": "coupler1", "mass": 1.0, "com": "C1", "inertia": 0.001}]
    return parse_cases({"case": [table]}, "e1_unloaded.toml")[0][0]


def largest_force(values: dict[str, float], length: float) -> float:
    """The largest reaction or drive effort of a reading, torques over ``length`` (N)."""
    return max(abs(v) / (length if q.startswith("Q_") else 1.0)
               for q, v in values.items() if q.startswith(FORCES))


@pytest.mark.parametrize("scale", [1.0, 2.0, 4.0, 8.0])
def test_an_unloaded_four_bar_settles_to_zero_forces_in_mujoco(tmp_path: Path, scale: float) -> None:
    """With no load and no gravity nothing is held, so every reaction and the drive torque
    are zero (by hand); MuJoCo settles to that within the policy's tightest static error of
    the 0.01 N force floor, alone and in a batched sweep, at E1's size and up to eight times
    it (at 4× and 8× its joints came to rest at 1e-19 m/s on forces that hop on a rounding
    floor of ~1e-9 N, and no stop rule fired: not_settled)."""
    case = unloaded_e1(scale)
    length = case.linkage.scale
    allowed = 1e-6 * FORCE_FLOOR_N
    alone = mj.settle(case)
    assert alone.status == "ok", alone.message
    assert largest_force(alone.values, length) <= allowed
    swept = sweep_linkage(case, np.radians([0.0, 5.0, 10.0, 15.0, 20.0, 25.0]), "mujoco")
    for solution in swept:
        assert solution.status == "ok", solution.message
        assert largest_force(solution.values, length) <= allowed


def test_an_unloaded_four_bar_settles_to_zero_forces_in_pymunk(tmp_path: Path) -> None:
    """The same unloaded four-bar at four times E1's size in pymunk: zero forces (by hand)
    within the same 1e-8 N."""
    case = unloaded_e1(4.0)
    solution = pm.settle(case)
    assert solution.status == "ok", solution.message
    assert largest_force(solution.values, case.linkage.scale) <= 1e-6 * FORCE_FLOOR_N


def alternation(amplitude: float, readings: int = 40, width: int = 3) -> np.ndarray:
    """Forces hopping between +amplitude and −amplitude from one reading to the next (N)."""
    signs = np.where(np.arange(readings) % 2 == 0, 1.0, -1.0)
    return signs[:, None] * np.full((readings, width), amplitude)


def stops_of(forces: np.ndarray, rounding: float) -> dict[str, tuple[int, str]]:
    """The first reading at which each implementation of the stop rule says settled, and the
    rule: the single pose's, the batch's (compiled where installed), and their twins, one
    step at a time and in numpy."""
    out = {}
    for name, watch in (("single", DecayWatch(rounding)), ("twin", StepWatch(rounding))):
        out[name] = next(((i, watch.rule) for i, f in enumerate(forces) if watch.settled(f)),
                         (-1, ""))
    history = np.full((1, FLOOR_WINDOW - 1, forces.shape[1]), np.nan)
    speed = np.zeros((1, forces.shape[0]))
    for name, stops in (("numpy", vectorised_stops), ("batch", first_stops)):
        first, rule = stops(history, forces[None], speed, rounding)
        out[name] = (int(first[0]), RULES[rule[0]] if first[0] >= 0 else "")
    return out


def test_the_floor_rule_accepts_a_rounding_alternation_in_every_implementation() -> None:
    """Forces alternating by ±5e-9 N about zero (a spread of 1e-8 N, ten times the floor
    rule's 1e-7 of the 0.01 N force floor) sit on a model's rounding floor of 2e-8 N: every
    implementation of the stop rule says "floor" at the first reading whose window of
    FLOOR_WINDOW readings is complete (index 31), and none fires without that floor."""
    forces = alternation(5e-9)
    assert 2 * 5e-9 > WOBBLE_RTOL * FORCE_FLOOR_N  # the relative rule alone rejects it
    assert set(stops_of(forces, 2e-8).values()) == {(FLOOR_WINDOW - 1, "floor")}
    assert set(stops_of(forces, 0.0).values()) == {(-1, "")}


def crank_shaper_at(tmp_path: Path, rotation: float) -> Case:
    """The built-in crank shaper with its crank turned ``rotation`` degrees from the drawing
    (the file's is 60°)."""
    text = Path(builtin("crank-shaper").source).read_text()
    assert "rotation = 60.0" in text
    path = tmp_path / "shaper.toml"
    path.write_text(text.replace("rotation = 60.0", f"rotation = {rotation!r}"))
    return load_cases(path)[0]


def test_a_driven_run_thrown_onto_the_other_assembly_reads_no_forces(tmp_path: Path) -> None:
    """The crank shaper turned 160°, driven for 200 steps with 100 Gauss–Seidel iterations
    a step, lands on the other assembly of its output dyad: the ram's pin C on the other
    side of B along the horizontal guide, so the ram lies 2·(B_x − C_x) = −0.1603 m from
    the prescribed pose (by hand, from the analytic B and C). Such a run reads no forces, so
    the backend tries more iterations; at 1600 it stays on its assembly and reads forces."""
    case = crank_shaper_at(tmp_path, 160.0)
    motion = driven_motion(case, pld.QUASI_STATIC_OMEGA)
    prescribed = solve(case).values
    thrown = pld.read_drive(case, motion, 200, 1e-4, 100)
    assert thrown.values["x_T"] - prescribed["x_T"] == pytest.approx(
        2.0 * (prescribed["x_B"] - prescribed["x_C"]), abs=1e-5)
    forces = [v for q, v in thrown.values.items() if q.startswith(FORCES)]
    assert forces and all(math.isnan(v) for v in forces)
    held = pld.read_drive(case, motion, 100, 1e-4, 1600)
    assert held.drift <= 1e-3 * case.linkage.scale
    assert all(math.isfinite(v) for q, v in held.values.items() if q.startswith(FORCES))


def test_a_driven_run_that_no_solver_setting_holds_says_so(tmp_path: Path,
                                                           monkeypatch: pytest.MonkeyPatch) -> None:
    """Allowed only 100 iterations a step, the crank shaper turned 160° leaves its assembly
    at every lead-in: no forces, and a verdict that names the assembly and the iterations."""
    monkeypatch.setattr(pld, "ITERATIONS", (100,))
    solution = pm.settle(crank_shaper_at(tmp_path, 160.0))
    assert solution.status == "not_settled"
    assert "left the assembly" in solution.message and "100 iterations" in solution.message
    assert not any(q.startswith(FORCES) for q in solution.values)


def test_a_held_pymunk_run_keeps_two_windows_of_readings_not_every_step() -> None:
    """A run watched over a slow window remembers as many readings as its rule looks back:
    with ρ = 0.999 the window is 0.01/(1 − ρ) = 10 steps, so 20 readings of 1000 impulses,
    160 kB, where 5000 steps of them would be 40 MB."""
    rng = np.random.default_rng(0)
    settings = replace(LINKAGE_SETTLE, max_steps=5000)

    def step() -> tuple[list[float], object]:
        return rng.standard_normal(1000).tolist(), lambda: 0.0  # never calm: runs to the end

    tracemalloc.start()
    run = run_until_settled(step, settings, 1.0, dict, slowest=lambda: 0.999)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert not run.settled and run.steps == 5000
    assert peak < 4e6


def test_the_lead_in_limit_analyses_each_pose_once_in_bounded_chunks(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """A lead-in doubling from 100 to 400 steps on the same clock ticks ends at the same
    instant: its limit analyses the 401 ticks once each (100 + 1, then 100 and 200 more),
    never more than LEAD_CHUNK poses at a time."""
    case = builtin("e1-linkage-driven-from-90")
    sizes: list[int] = []
    analyse = linkage_motion.solve_linkage

    def counted(linkage: object, values: np.ndarray, *rest: object) -> object:
        sizes.append(len(values))
        return analyse(linkage, values, *rest)

    monkeypatch.setattr(linkage_motion, "solve_linkage", counted)
    motion = driven_motion(case, pld.QUASI_STATIC_OMEGA)
    limit = lead_limit(case, motion, math.inf)
    assert [limit(steps, 1e-4) for steps in (100, 200, 400)] == ["", "", ""]
    assert sum(sizes) == 401 and max(sizes) <= linkage_motion.LEAD_CHUNK


@pytest.mark.slow
def test_a_64_loop_chain_held_in_pymunk_gives_a_right_number_or_none(tmp_path: Path) -> None:
    """Open limit: held at its drawing, a chain of 64 four-bars (129 links, condition number
    1.1e3) is primed in pymunk with the settings for a pose next to a change point, and its
    settling flies apart (metres off the held pose) within its budget: the verdict is then
    not_settled with no number, never a wrong one; MuJoCo settles it."""
    path = tmp_path / "chain64.toml"
    path.write_text(toml_of(four_bar_chain(64)))
    case = load_cases(path)[0]
    solution = pm.settle(case)
    if solution.status == "ok":
        assert_solution_close(case, solution, complete=True)
    else:
        assert solution.status == "not_settled" and solution.message
        assert not any(q.startswith(FORCES) for q in solution.values)
    assert_solution_close(case, mj.settle(case), complete=True)


def test_an_unloaded_sweep_reads_nothing_beyond_the_models_rounding(tmp_path: Path) -> None:
    """The counterbalanced bonnet (0.6 m) stripped of its loads, springs and masses, swept in
    MuJoCo: every force it reads is within its model's rounding floor 4·m·ε·X/dt² of the
    analytic zero. (Judged against the policy's 0.01 N force floor some of these readings,
    1e-7 N, fail the comparison: docs/limitations.md, "Unloaded linkages read rounding".)"""
    import tomllib

    from mechcheck.sim_models.mujoco.linkage_rig import LinkageRig
    from mechcheck.sweep import LocalExecutor, plan, run_sweep

    table = tomllib.loads((Path(__file__).parents[1] / "compare" / "cases" / "linkages"
                           / "bonnet_counterbalanced.toml").read_text())["case"][0]
    for key in ("loads", "springs", "masses", "seed"):
        table.pop(key, None)
    table.update(gravity=[0.0, 0.0], name="bonnet-unloaded")
    case = parse_cases({"case": [table]}, "bonnet.toml")[0][0]
    floor = LinkageRig(case).rounding
    grid = np.array([-10.0, 0.0, 10.0])
    outcome = run_sweep(plan([case], ["mujoco"], grid, grid), tmp_path, LocalExecutor())
    results = outcome.read()
    forces = results[(results["backend"] == "mujoco")
                     & results["quantity"].astype(str).str.startswith(FORCES)]
    assert len(forces) and floor < 1e-6
    assert forces["value"].abs().max() <= floor
