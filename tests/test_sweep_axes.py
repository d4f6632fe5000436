"""A sweep's axis as the user gave it: a linkage's first driver by name and in its case
file's unit; poses counted once; unsettled poses not compared; the progress estimate
weighed by each backend's measured cost per pose."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from mechcheck import load_cases
from mechcheck.analytic.case import Case
from mechcheck.sweep import check_driver_grid, driver_axis, grid_si, plan
from mechcheck.sweep_run import Remaining, failed_poses, ok_rows
from tests.builtin import builtin

USERS = Path(__file__).resolve().parents[1] / "compare" / "cases" / "users"


def user_case(file: str, name: str) -> Case:
    return next(c for c in load_cases(USERS / file) if c.name == name)


def test_the_axis_names_the_driver_and_its_unit() -> None:
    scissor = user_case("scissor_lift.toml", "scissor-lift-hold")
    whitworth = user_case("whitworth.toml", "whitworth-static")
    assert driver_axis(scissor, "m") == "displacement of cyl, m"
    assert driver_axis(whitworth, "deg") == "rotation of O2, deg"
    assert driver_axis(builtin("seed-E1-as-stated"), "deg") == "θ12, deg"


def test_a_sliding_driver_is_swept_in_its_files_length_unit() -> None:
    scissor = user_case("scissor_lift.toml", "scissor-lift-hold")
    metres = plan([scissor], [], np.array([0.0]), np.array([0.01, 0.02]),
                  {scissor.name: "m"})
    assert {t.unit for t in metres} == {"m"}
    # 0.01 m and 10 mm are the same 0.01 m to the engine.
    assert grid_si(scissor, np.array([0.01]), "m") == pytest.approx([0.01])
    assert grid_si(scissor, np.array([10.0]), "mm") == pytest.approx([0.01])
    # A turning driver is in degrees whatever the file's length unit.
    whitworth = user_case("whitworth.toml", "whitworth-static")
    assert {t.unit for t in plan([whitworth], [], np.array([0.0]), np.array([90.0]),
                                 {whitworth.name: "mm"})} == {"deg"}


def test_a_travel_beyond_the_bound_is_refused_in_the_files_unit() -> None:
    scissor = user_case("scissor_lift.toml", "scissor-lift-hold")
    with pytest.raises(ValueError, match=r"displacement of 290 m of cyl .*length_unit"):
        check_driver_grid(scissor, np.array([-60.0, 290.0]), "--driver", "m")


def comparison(rows: list[tuple[str, float, str, bool]]) -> pd.DataFrame:
    return pd.DataFrame(rows, columns=["backend", "theta12", "quantity", "passed"]).assign(
        case="c")


def test_a_pose_counts_once_however_many_of_its_quantities_failed() -> None:
    table = comparison([("pymunk", 10.0, "x_P3", False), ("pymunk", 10.0, "y_P3", False),
                        ("pymunk", 10.0, "F_E_x", False), ("pymunk", 15.0, "F_E_x", False),
                        ("mujoco", 10.0, "F_E_x", False), ("pymunk", 20.0, "F_E_x", True)])
    assert failed_poses(table) == 3   # pymunk at 10 and 15, mujoco at 10


def test_a_pose_without_forces_is_not_compared_position_by_position() -> None:
    rows = pd.DataFrame({"theta12": [0.0, 0.0, 5.0, 5.0], "quantity": ["y_P3", "F_E_x"] * 2,
                         "value": [0.1, 2.0, -0.139, np.nan]})
    status = pd.DataFrame({"theta12": [0.0, 5.0], "status": ["ok", "not_settled"]})
    kept = ok_rows(rows, status)
    assert kept["theta12"].tolist() == [0.0, 0.0]


def status_part(costs: list[float]) -> bytes:
    buffer = io.BytesIO()
    pd.DataFrame({"wall_time_s": costs}).to_parquet(buffer, index=False)
    return buffer.getvalue()


def test_the_estimate_weighs_each_backend_by_its_measured_cost() -> None:
    """Two backends, two tasks each: once one task of each has reported its poses' cost,
    what is left is the other two tasks' poses at those costs, over the workers."""
    case = builtin("seed-E1-as-stated")
    tasks = plan([case], ["pymunk"], np.arange(0.0, 120.0, 1.0))   # 2 chunks of 60 each
    slow = [t for t in tasks if t.backend == "pymunk"]
    fast = [t for t in tasks if t.backend == "analytic"]
    left = Remaining(tasks, workers=2)
    assert left.seconds() is None
    left.finished(slow[0], status_part([2.0] * len(slow[0].theta12_deg)))
    # Not yet measured: the analytic poses are priced at the dearest cost known (2 s).
    assert left.seconds() == pytest.approx((60 * 2.0 + 120 * 2.0) / 2)
    left.finished(fast[0], status_part([1e-4] * len(fast[0].theta12_deg)))
    assert left.seconds() == pytest.approx(60 * 2.0 / 2)
    assert left.backend() == "pymunk"
