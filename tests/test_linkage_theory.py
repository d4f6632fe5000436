"""`mechcheck theory case` on linkages, and the engine's mobility and verdicts on an
over-constrained linkage: each fact checked by hand."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from typer.testing import CliRunner

from mechcheck import load_cases, solve
from mechcheck.analytic import theory
from mechcheck.cli import app

LINKAGES = Path(__file__).resolve().parents[1] / "compare" / "cases" / "linkages"

TRIPLE_PARALLELOGRAM = """
[[case]]
name = "triple-parallelogram"
mechanism = "linkage"
length_unit = "mm"
[case.points]
O1 = [0.0, 0.0]
O2 = [100.0, 0.0]
O3 = [200.0, 0.0]
A1 = [30.0, 80.0]
A2 = [130.0, 80.0]
A3 = [230.0, 80.0]
[[case.links]]
name = "ground"
points = ["O1", "O2", "O3"]
[[case.links]]
name = "c1"
points = ["O1", "A1"]
[[case.links]]
name = "c2"
points = ["O2", "A2"]
[[case.links]]
name = "c3"
points = ["O3", "A3"]
[[case.links]]
name = "coupler"
points = ["A1", "A2", "A3"]
""" + "".join(f"""[[case.joints]]
name = "{n}"
kind = "revolute"
links = ["{a}", "{b}"]
at = "{n}"
""" for n, a, b in (("O1", "ground", "c1"), ("O2", "ground", "c2"), ("O3", "ground", "c3"),
                    ("A1", "c1", "coupler"), ("A2", "c2", "coupler"), ("A3", "c3", "coupler"))
) + """[[case.drivers]]
joint = "O1"
rotation = 25.0
"""


def test_a_non_grashof_crank_locks_both_ways_where_the_loop_stretches() -> None:
    """The locking four-bar (a1..a4 = 100, 80, 60, 70 mm, drawn at θ12 = 30°) locks where
    |A O4| = a3 + a4: cos θ12 = (a1² + a2² − 130²)/(2 a1 a2), θ12 = ±91.790785°, i.e. at
    rotations +61.790785° and −121.790785° of O2 from the drawn pose."""
    case = load_cases(LINKAGES / "locking_fourbar.toml")[0]
    limit = math.degrees(math.acos((100**2 + 80**2 - 130**2) / (2 * 100 * 80)))
    (r,) = theory.driver_ranges(case.linkage)
    assert r.high is not None and r.low is not None
    assert math.degrees(r.high) == pytest.approx(limit - 30.0, abs=1e-6)
    assert math.degrees(r.low) == pytest.approx(-limit - 30.0, abs=1e-6)


def test_theory_case_prints_mobility_ranges_and_mechanical_advantage() -> None:
    """For the Watt II example: links, joints, both mobility counts, the driver's range, and
    the load's mechanical advantage |F|/|Q| with Q the driver effort of the load alone."""
    path = LINKAGES / "watt_ii_sixbar.toml"
    result = CliRunner().invoke(app, ["theory", "case", str(path)])
    assert result.exit_code == 0, result.output
    out = result.output
    assert "links: 6" in out and "joints: 7 (7 revolute)" in out
    assert "Gruebler–Kutzbach 3(n − 1) − Σ(3 − Sᵢ) = 1" in out and "drawn pose: 1" in out
    assert "driver O2:" in out and "mechanical advantage (load on output): 100 N" in out
    q = solve(load_cases(path)[0]).values["Q_O2"]  # the load is the case's only force
    assert f"{100 / abs(q):.6g}" in out


def test_an_over_constrained_linkage_says_so_and_withholds_forces(tmp_path: Path) -> None:
    """Three equal parallel cranks under one coupler: Gruebler–Kutzbach gives 3·4 − 2·6 = 0,
    the rank of the constraint Jacobian 1 (the constraints are dependent); the reactions
    are not unique (indeterminate), the coupler still translates without turning."""
    path = tmp_path / "tp.toml"
    path.write_text(TRIPLE_PARALLELOGRAM)
    case = load_cases(path)[0]
    assert case.linkage.gruebler == 0 and case.linkage.dof == 1 and case.linkage.redundant
    solution = solve(case)
    assert solution.status == "indeterminate"
    assert solution.values["phi_coupler"] == pytest.approx(0.0, abs=1e-12)
    assert not any(q.startswith("F_") for q in solution.values)
    out = CliRunner().invoke(app, ["theory", "case", str(path)]).output
    assert "(they differ: redundant constraints or a singular drawing)" in out
