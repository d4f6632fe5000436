"""The report's seed table (SEEDS.md): every printed answer of a built-in case stands beside a
computed value in its own unit, and every case says what its printed answer is."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from typer.testing import CliRunner

from mechcheck.analytic.joint_kinds import PRISMATIC, REVOLUTE
from mechcheck.backends import REFERENCE
from mechcheck.casefile import builtin_case_files, load_specs
from mechcheck.cli import app
from mechcheck.report import seed_rows
from mechcheck.run import run
from mechcheck.seeds import SeedRow, seed_row, seed_unit

from .builtin import builtin

#: SEEDS.md prints its corrected values to three decimals: half a unit of the last digit.
HALF_3DP = 0.0005


@pytest.fixture(scope="module")
def rows() -> list[SeedRow]:
    specs = [(c, s) for c, s in load_specs(builtin_case_files()) if s.seed is not None]
    result = run([c for c, _ in specs], [REFERENCE])
    return seed_rows(result, {c.name: s for c, s in specs})


def test_every_printed_answer_has_a_computed_value_and_a_note(rows: list[SeedRow]) -> None:
    """No row of the seed table is left without its computed value, and no case without the
    note that says what its printed answer is."""
    assert {r.case for r in rows} >= {"exam-q1-slider-bar", "e1-linkage", "e2-linkage-friction"}
    for r in rows:
        assert r.computed is not None and math.isfinite(r.computed), r
        assert r.deviation is not None, r
        assert r.note.strip(), f"{r.case} has no note"


def test_linkage_rows_carry_their_quantities_units(rows: list[SeedRow]) -> None:
    """A link's rotation is in degrees and a revolute driver's effort in N·m (LINKAGES.md,
    "What comes out"), not N."""
    by_key = {(r.case, r.key): r for r in rows}
    assert by_key[("exam-q1-slider-bar", "phi_bar")].unit == "deg"
    for case in ("e1-linkage", "e1-linkage-seed-sign", "e2-linkage-frictionless",
                 "e2-linkage-friction"):
        assert by_key[(case, "Q_A0")].unit == REVOLUTE.effort_unit == "N*m"


def test_a_prismatic_driver_s_effort_is_in_newtons() -> None:
    """The boom's hydraulic cylinder is a prismatic driver: its effort Q_cyl is a force, N,
    and its joint coordinate a length, m."""
    case = builtin("boom-raise")
    assert case.linkage.joint("cyl").kind is PRISMATIC
    assert seed_unit(case, "Q_cyl") == "N"
    assert seed_unit(case, "q_cyl") == "m"


def test_the_computed_values_are_the_seeds(rows: list[SeedRow]) -> None:
    """Exam Q1: φ = atan(2F/(m g)) with F = 10 N, m = 3 kg, g = 9.81 m/s² (SEEDS.md); E1 and
    E2 as linkages: SEEDS.md's torques to their printed digits."""
    by_key = {(r.case, r.key): r for r in rows}
    phi = math.degrees(math.atan(2.0 * 10.0 / (3.0 * 9.81)))
    assert by_key[("exam-q1-slider-bar", "phi_bar")].computed == pytest.approx(phi, abs=1e-6)
    for case, printed in (("e1-linkage", 2.90133), ("e1-linkage-seed-sign", -2.90133),
                          ("e2-linkage-frictionless", -18.783), ("e2-linkage-friction", -22.897)):
        assert abs(by_key[(case, "Q_A0")].computed - printed) <= HALF_3DP, case


def test_a_joint_coordinate_deviates_by_its_turns_a_rotation_does_not() -> None:
    """Printed 400° against a computed 40°: a joint coordinate is a turn off, a link's
    rotation (a direction) is not off at all."""
    turned = SeedRow("c", "q_A0", 400.0, 40.0, "s", "n", "deg")
    direction = SeedRow("c", "phi_crank", 400.0, 40.0, "s", "n", "deg")
    assert turned.deviation == pytest.approx(-360.0)
    assert direction.deviation == pytest.approx(0.0)


def test_seed_row_reads_a_linkage_key_in_its_unit() -> None:
    """seed_row gives a linkage's printed key its value in table units (degrees for a link's
    rotation) and its unit."""
    from mechcheck import solve

    case = builtin("exam-q1-slider-bar")
    row = seed_row(case, solve(case), "phi_bar", 34.2, "seed 002", "note")
    assert row.unit == "deg"
    assert row.computed == pytest.approx(math.degrees(math.atan(20.0 / (3.0 * 9.81))), abs=1e-6)


def test_a_linkage_printed_key_it_does_not_have_is_refused(tmp_path: Path) -> None:
    """A printed answer naming no quantity of the linkage (a driver on a joint it does not
    drive) is refused in one line naming the key, rather than shown without a value."""
    path = next(p for p in builtin_case_files() if p.name == "exam_q1_slider_bar.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text(path.read_text(encoding="utf-8").replace("printed = { phi_bar = 34.2 }",
                                                             "printed = { Q_A = 1.0 }"))
    result = CliRunner().invoke(app, ["validate", str(bad)])
    lines = result.stderr.strip().splitlines()
    assert result.exit_code == 2 and len(lines) == 1, result.stderr
    assert "key 'seed.printed.Q_A'" in lines[0] and "case 'exam-q1-slider-bar'" in lines[0]
