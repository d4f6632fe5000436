"""The generic linkage engine against the independent reference (tests/linkage_reference.py:
maximal coordinates, arclength continuation, Lagrange multipliers; no shared code) on every
hand-written linkage case file in tests/linkages/."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import pytest

from mechcheck.analytic.case import Case
from mechcheck.casefile import load_file

from . import linkage_reference as ref

#: The built-in linkages (compare/cases/linkages/, shipped with the package).
LINKAGES = Path(__file__).resolve().parents[1] / "compare" / "cases" / "linkages"
FILES = sorted(LINKAGES.glob("*.toml"))
CASES = [(path, table) for path in FILES
         for table in tomllib.loads(path.read_text(encoding="utf-8"))["case"]]
#: Two methods for the same rigid-body equations: rounding only (the policy's 1e-9).
RTOL = 1e-9


def assert_agree(case: Case, table: dict[str, object]) -> None:
    """The engine's analytic Solution and the reference's: same verdict, and every quantity
    within 1e-9 of its kind's scale (forces: the largest reaction; torques: the largest
    torque or reaction × the linkage's size; positions: the size; angles: 1 rad, modulo a
    turn)."""
    from mechcheck.analytic.linkage_backends import solve

    mine = solve(case)
    theirs = ref.solve(table)
    assert mine.status == theirs.status, (mine.message, theirs.message)
    if mine.status != "ok":
        return
    size = case.linkage.scale
    force = max([abs(v) for q, v in theirs.values.items()
                 if q.startswith("F_") or (q[:2] in ("Q_", "S_") and mine.unit(q) == "N")]
                + [1e-2])
    torque = max([abs(v) for q, v in theirs.values.items() if mine.unit(q) == "N*m"]
                 + [force * size])
    assert set(mine.values) == set(theirs.values)
    for q, expected in theirs.values.items():
        got, unit = mine.values[q], mine.unit(q)
        if unit == "deg":
            assert abs(math.remainder(got - expected, math.tau)) <= RTOL, q
        else:
            scale = {"N": force, "N*m": torque, "m": size}[unit]
            assert abs(got - expected) <= RTOL * scale, (q, got, expected)
    if "stable" in theirs.diagnostics:
        assert mine.diagnostics["stable"] == ("yes" if theirs.diagnostics["stable"] else "no")


@pytest.mark.parametrize(("path", "table"), CASES, ids=[t["name"] for _, t in CASES])
def test_engine_equals_the_independent_reference(path: Path, table: dict[str, object]) -> None:
    """On every built-in linkage: the same verdict and the same numbers (1e-9)."""
    case = next(c for c, _ in load_file(path) if c.name == table["name"])
    assert_agree(case, table)
