"""One verdict everywhere: a pose gets the same verdict, reason and numbers from `sweep` as
from `run`, and neither says ``ok`` where the forces are not unique or not finite."""

from __future__ import annotations

import copy
import math
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st
from typer.testing import CliRunner

from mechcheck import solve
from mechcheck.casefile import parse_cases
from mechcheck.cli import app
from mechcheck.run import solve_gated
from mechcheck.sweep import LocalExecutor, plan, run_sweep
from tests.chains import four_bar_chain, toml_of
from tests.strategies import linkage_tables

#: The analytic family's tolerance (compare/tolerance.py): the same equations, only rounding
#: separates a pose solved among others from the same pose solved alone.
RTOL = 1e-9
BACKENDS = ["analytic", "superposition", "virtual_work"]


def case_of(table: dict[str, Any]) -> Any:
    return parse_cases({"case": [table]}, "case.toml")[0][0]


def swept(tmp_path: Path, case: Any, grid: np.ndarray, backends: list[str]) -> tuple[pd.DataFrame,
                                                                                     pd.DataFrame]:
    """A sweep of the first driver over ``grid`` (file units), run in this process."""
    outcome = run_sweep(plan([case], backends, grid, grid), tmp_path, LocalExecutor())
    return outcome.read(), outcome.read(kind="status")


def at_value(table: dict[str, Any], value: float) -> Any:
    """The case with its first driver at ``value`` (degrees): what `run` solves for that pose."""
    moved = copy.deepcopy(table)
    moved["drivers"][0]["rotation"] = value
    return case_of(moved)


def assert_pose_matches(results: pd.DataFrame, status: pd.DataFrame, backend: str, value: float,
                        alone: Any) -> None:
    """The swept pose ``value`` of ``backend`` carries ``alone``'s verdict, reason and numbers."""
    mine = status[(status["backend"] == backend) & (status["theta12"] == value)]
    assert mine["status"].tolist() == [alone.status], (backend, value, alone.message)
    assert mine["message"].tolist() == [alone.message]
    rows = results[(results["backend"] == backend) & (results["theta12"] == value)]
    got = dict(zip(rows["quantity"].astype(str), rows["value"], strict=True))
    want = alone.in_table_units()
    assert set(got) == set(want), (backend, value, set(got) ^ set(want))
    forces = max((abs(v) for q, v in want.items() if q.startswith(("F_", "S_"))), default=1.0)
    for name, v in want.items():
        scale = 360.0 if alone.units.get(name) == "deg" else max(forces, abs(v), 1.0)
        assert got[name] == pytest.approx(v, abs=RTOL * scale), (backend, value, name)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                  HealthCheck.function_scoped_fixture])
@given(table=linkage_tables(friction=False), values=st.lists(
    st.floats(-200.0, 200.0).map(lambda v: round(v, 3)), min_size=1, max_size=4, unique=True))
def test_a_swept_pose_is_the_pose_run_alone(tmp_path_factory: pytest.TempPathFactory,
                                            table: dict[str, Any], values: list[float]) -> None:
    """Random linkages swept over random driver values (locked, singular and ordinary poses
    alike) through the analytic backends: at every pose the sweep's verdict, message and
    numbers are those of `run` on the case with its driver at that value."""
    case = case_of(table)
    grid = np.array(sorted(values))
    results, status = swept(tmp_path_factory.mktemp("sweep"), case, grid, BACKENDS)
    for value in grid:
        alone_case = at_value(table, float(value))
        reference = solve_gated("analytic", alone_case)
        for backend in BACKENDS:
            assert_pose_matches(results, status, backend, float(value),
                                solve_gated(backend, alone_case, reference))


REDUNDANT_PIN = {"name": "J_A1_again", "kind": "revolute", "links": ["crank", "coupler1"],
                 "at": "A1"}


def test_a_redundant_pin_is_indeterminate_in_a_sweep_as_in_a_run(tmp_path: Path) -> None:
    """Seed E1's four-bar with a second pin at A: its reactions are not unique (rank 8 < 10),
    so `run` and every pose of `sweep` say ``indeterminate`` and give no force at all (no
    50/50 split of the pin force)."""
    table = four_bar_chain(1)
    table["joints"].append(REDUNDANT_PIN)
    case = case_of(table)
    alone = solve(case)
    assert alone.status == "indeterminate" and "rank 8 < 10" in alone.message
    results, status = swept(tmp_path, case, np.array([0.0, 10.0, 20.0]), BACKENDS)
    assert set(status["status"]) == {"indeterminate"}
    assert not results["quantity"].astype(str).str.match(r"(F|Q)_").any()


def test_a_triangle_of_slides_is_indeterminate(tmp_path: Path) -> None:
    """Three links joined in a triangle by prismatic joints, one of them on the ground: their
    relative rotations are locked three times over (φ_b − φ_a, φ_c − φ_b, φ_a − φ_c add to 0),
    so one constraint is redundant at every pose: ``indeterminate`` in `run` and `sweep`."""
    table = {
        "name": "slide-triangle", "mechanism": "linkage",
        "points": {"O": [0.0, 0.0], "P": [1.0, 0.0], "Q": [0.5, 0.8]},
        "links": [{"name": "ground", "points": ["O"]}, {"name": "a", "points": ["P"]},
                  {"name": "b", "points": ["Q"]}],
        "joints": [
            {"name": "s1", "kind": "prismatic", "links": ["ground", "a"], "at": "P", "axis": [1, 0]},
            {"name": "s2", "kind": "prismatic", "links": ["a", "b"], "at": "Q", "axis": [0, 1]},
            {"name": "s3", "kind": "prismatic", "links": ["ground", "b"], "at": "Q", "axis": [1, 1]},
        ],
        "drivers": [{"joint": "s1", "displacement": 0.0}],
        "loads": [{"link": "b", "at": "Q", "force": {"x": 0.0, "y": -10.0}}],
    }
    case = case_of(table)
    assert solve(case).status == "indeterminate"
    _, status = swept(tmp_path, case, np.array([0.0, 10.0]), ["analytic"])
    assert set(status["status"]) == {"indeterminate"}


def test_forces_that_are_not_finite_are_an_error_in_a_sweep_as_in_a_run(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A spring whose force comes out NaN beyond 15° of the crank (injected): `run` gives the
    ``error`` verdict naming S_k; `sweep` gives the same verdict and message at those poses,
    keeps no number there, and exits 1 (error fails a run by default)."""
    import mechcheck.analytic.linkage_forces as forces

    real = forces.spring_force

    def broken(pose: Any, spring: Any) -> Any:
        out = np.array(real(pose, spring), dtype=float)
        turned = np.abs(pose.drivers[:, 0]) > math.radians(15.0)
        return np.where(turned, np.nan, out)

    monkeypatch.setattr(forces, "spring_force", broken)
    table = four_bar_chain(1)
    table["springs"] = [{"name": "k", "ends": [["ground", "O1"], ["coupler1", "C1"]],
                         "stiffness": 100.0, "free_length": 100.0}]
    # A moving case takes the general path, where spring_force is computed.
    table["drivers"][0].update(velocity=1.0)
    path = tmp_path / "spring.toml"
    path.write_text(toml_of(table))
    run_result = CliRunner().invoke(app, ["run", str(path), "-q", "-b", "analytic",
                                          "--out", str(tmp_path / "run")])
    at_30 = solve(at_value(table, 30.0))
    assert at_30.status == "error" and "S_k" in at_30.message
    out = tmp_path / "sweep"
    result = CliRunner().invoke(app, ["sweep", str(path), "-q", "--workers", "0", "-b", "analytic",
                                      "--driver", "0:40:10", "--out", str(out)])
    assert result.exit_code == 1, result.output
    status = pd.read_parquet(out / "status")
    assert status.set_index("theta12")["status"].to_dict() == {0.0: "ok", 10.0: "ok",
                                                               20.0: "error", 30.0: "error"}
    assert status.loc[status["theta12"] == 30.0, "message"].iloc[0] == at_30.message
    results = pd.read_parquet(out / "results")
    assert not (results["theta12"] >= 20.0).any()
    assert run_result.exit_code == 0   # the case's own pose (0°) is fine


FLAT_FOUR_BAR = {
    "name": "flat", "mechanism": "linkage",
    "points": {"O": [0.0, 0.0], "A": [1.0, 0.0], "B": [4.0, 0.0], "Q": [3.0, 0.0], "C": [2.0, 0.0]},
    "links": [{"name": "ground", "points": ["O", "Q"]}, {"name": "crank", "points": ["O", "A"]},
              {"name": "coupler", "points": ["A", "B", "C"]}, {"name": "rocker", "points": ["Q", "B"]}],
    "joints": [{"name": n, "kind": "revolute", "links": links, "at": n} for n, links in
               (("O", ["ground", "crank"]), ("A", ["crank", "coupler"]),
                ("B", ["coupler", "rocker"]), ("Q", ["ground", "rocker"]))],
    "drivers": [{"joint": "O", "rotation": 0.0}],
    "loads": [{"link": "coupler", "at": "C", "force": {"x": 0.0, "y": -10.0}}],
}


def test_a_four_bar_drawn_flat_is_singular_in_both_formats() -> None:
    """A four-bar (a1..a4 = 3, 1, 3, 1 m) drawn flat is at a change point: the linkage format
    says ``singular`` like the four-bar format at θ12 = 0 (not a free coordinate: one degree
    of freedom, counted a little way along its motion), and driven away from the flat
    drawing it is still ``singular``, since the drawing does not say which branch it takes."""
    flat = case_of(FLAT_FOUR_BAR)
    assert flat.linkage.dof == 1 and not flat.linkage.redundant
    assert flat.linkage.drawn_at_change_point
    assert solve(flat).status == "singular"
    turned = copy.deepcopy(FLAT_FOUR_BAR)
    turned["drivers"][0]["rotation"] = 30.0
    driven = solve(case_of(turned))
    assert driven.status == "singular" and "branch" in driven.message
    four_bar = parse_cases({"case": [{
        "name": "flat-fb", "mechanism": "four_bar", "theta12": 0.0,
        "geometry": {"a1": 3.0, "a2": 1.0, "a3": 3.0, "a4": 1.0},
        "loads": [{"link": 3, "at": [1.0, 0.0], "force": {"x": 0.0, "y": -10.0}}]}]}, "x.toml")
    assert solve(four_bar[0][0]).status == "singular"
