"""The public vectorised solve, ``mechcheck.solve_poses``: each pose's verdict and numbers are
those of ``mechcheck.solve`` at that pose, and unusable arguments are refused."""

from __future__ import annotations

import math

import numpy as np
import pytest

import mechcheck
from mechcheck.analytic.presets import redrawn
from mechcheck.tolerance import rule

from .builtin import builtin

#: Two analytic routes to the same pose (one linkage drawn at the first pose and moved, one
#: drawn at the pose itself) agree to rounding amplified by the condition number: the
#: policy's tolerance between analytic backends.
ANALYTIC = rule("superposition", "force", "static").rtol


def test_each_pose_is_the_single_case_solve() -> None:
    """Seed E1 at θ12 = 60° (SEEDS.md E1: T12 = 2.90133 N·m), 180° (its change point) and 250°:
    the table's status and T12 are mechcheck.solve's at each pose."""
    e1 = builtin("seed-E1-as-stated")
    theta = np.radians([60.0, 180.0, 250.0])
    table = mechcheck.solve_poses(e1, theta)
    assert table["driver"].tolist() == theta.tolist()
    assert round(float(table["T12"].iloc[0]), 5) == 2.90133
    for row, t in zip(table.itertuples(), theta, strict=True):
        alone = mechcheck.solve(redrawn(e1, theta12=float(t)))
        assert row.status == alone.status
        if alone.status == "ok":
            assert row.T12 == pytest.approx(alone.values["T12"], rel=ANALYTIC)
        else:
            assert math.isnan(row.T12) and row.message == alone.message


def test_a_linkage_is_swept_by_its_first_driver() -> None:
    """The Watt II six-bar (moving) at its own driver value gives mechcheck.solve's effort,
    and a tenth of a radian on it has one too."""
    watt = builtin("watt-ii-demo")
    value = watt.linkage.drivers[0].value
    table = mechcheck.solve_poses(watt, [value, value + 0.1], condition=False)
    alone = mechcheck.solve(watt)
    effort = f"Q_{watt.linkage.drivers[0].joint}"
    assert table[effort].iloc[0] == pytest.approx(alone.values[effort], rel=ANALYTIC)
    assert "condition_number" not in table.columns
    assert (table["status"] == "ok").all()


@pytest.mark.parametrize(("backend", "values", "says"), [
    ("mujoco", [0.0], "not vectorised"),
    ("analytic", [math.nan], "finite"),
    ("analytic", [1e9], "within"),
])
def test_unusable_arguments_are_refused(backend: str, values: list[float], says: str) -> None:
    """A simulator backend, a value that is not finite and a θ12 beyond the format's bounds
    are refused with a ValueError that says which."""
    with pytest.raises(ValueError, match=says):
        mechcheck.solve_poses(builtin("seed-E1-as-stated"), values, backend)
