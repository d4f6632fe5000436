"""The seed 001 mobility catalogue as case files (compare/cases/catalogue/): each file has the
seed's printed link and joint counts and mobility S (written here from the seed's table),
by Gruebler–Kutzbach and by the rank of the constraint Jacobian, in the engine and (for the
rows without gears) in the independent reference (tests/linkage_reference.py); each file of
revolute, prismatic and pin-in-slot joints has the reference's analytic solution (the gear
rows and the elastic structure have theirs checked in tests/test_catalogue_gears.py); and
the truss, a structure, balances its loads at its supports and carries the
member force a hand calculation by the method of joints gives."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import mechcheck
from mechcheck.analytic.case import Case
from mechcheck.analytic.joint_kinds import KINDS

from . import linkage_reference as ref
from .test_linkage_against_reference import RTOL

CATALOGUE = Path(__file__).resolve().parents[1] / "compare" / "cases" / "catalogue"

#: The seed's rows (SEEDS.md, seed 001): u (links, ground included), joints by kind, printed
#: S. Cs is the pin in a slot, G a gear mesh.
PRINTED = {
    "shaper": (5, {"revolute": 3, "prismatic": 2, "pin_in_slot": 1}, 1),
    "garage_door": (6, {"revolute": 7}, 1),
    "seven_link": (7, {"revolute": 8}, 2),
    "excavator_bucket": (10, {"revolute": 12, "prismatic": 1}, 1),
    "truss": (9, {"revolute": 12}, 0),
    "gear_pair": (3, {"revolute": 2, "gear": 1}, 1),
    "mixed": (9, {"revolute": 8, "prismatic": 2, "gear": 2}, 2),
    "over_constrained": (6, {"revolute": 8}, -1),
}
#: The Sᵢ of the seed: R, P = 1; Cs, G = 2.
SEED_FREEDOMS = {"revolute": 1, "prismatic": 1, "pin_in_slot": 2, "gear": 2}
#: The rows whose mobility the independent reference counts: it has no gear mesh.
REFERENCE_MOBILITY = sorted(stem for stem, (_, joints, _) in PRINTED.items() if "gear" not in joints)
#: The rows it also solves: it has no elastic member either.
REFERENCE_ROWS = [stem for stem in REFERENCE_MOBILITY if stem != "over_constrained"]


def table_of(stem: str) -> dict[str, Any]:
    (table,) = tomllib.loads((CATALOGUE / f"{stem}.toml").read_text(encoding="utf-8"))["case"]
    return dict(table)


def rigid(table: dict[str, Any]) -> dict[str, Any]:
    """The table without its members' axial stiffness, which the reference does not read and
    the mobility does not depend on."""
    links = [{k: v for k, v in link.items() if k != "axial_stiffness"} for link in table["links"]]
    return {**table, "links": links}


def case_of(stem: str) -> Case:
    (case,) = mechcheck.load_cases(CATALOGUE / f"{stem}.toml")
    assert isinstance(case, Case)
    return case


def test_the_folder_holds_the_planar_rows_it_can() -> None:
    """One file per planar seed row beyond the three already built in (four-bar,
    slider-crank, five-bar): no more, no fewer."""
    assert sorted(p.stem for p in CATALOGUE.glob("*.toml")) == sorted(PRINTED)


@pytest.mark.parametrize("stem", sorted(PRINTED))
def test_counts_and_mobility_are_the_seeds(stem: str) -> None:
    """u and the joints by kind are the seed's; S = 3(u − m − 1) + ΣSᵢ with the seed's Sᵢ
    and the engine's Gruebler count equal the printed S. The rank of J says the same in its
    own terms: 3(n − 1) − rank J counts the freedoms the linkage moves with, and the rows
    beyond rank J its redundant constraints, so a mechanism (S ≥ 0) has S freedoms and none
    redundant, and the structure of S = −1 none and one redundant (S = freedoms − redundant
    rows). The reference (for the rows it reads) counts the same."""
    u, joints, printed = PRINTED[stem]
    linkage = case_of(stem).linkage
    assert len(linkage.links) == u
    kinds = {name: sum(1 for j in linkage.joints if j.kind is kind) for name, kind in KINDS.items()}
    assert {k: n for k, n in kinds.items() if n} == joints
    m = sum(joints.values())
    assert 3 * (u - m - 1) + sum(n * SEED_FREEDOMS[k] for k, n in joints.items()) == printed
    freedoms, redundant = max(printed, 0), max(-printed, 0)
    assert linkage.gruebler == printed
    assert (linkage.dof, linkage.constraint_rows - linkage.joint_rank) == (freedoms, redundant)
    if stem in REFERENCE_MOBILITY:
        mob = ref.mobility(ref.parse_case(rigid(table_of(stem))))
        assert (mob.gruebler, mob.dof, bool(mob.redundant_joints)) == (printed, freedoms, bool(redundant))
    assert len(linkage.drivers) == freedoms, "every freedom driven: the case is a machine at rest"


@pytest.mark.parametrize("stem", REFERENCE_ROWS)
def test_the_engine_equals_the_independent_reference(stem: str) -> None:
    """``mechcheck.solve`` and the reference: both ``ok``, the same quantities, every reaction,
    effort and position within the oracle tests' 1e-9 of its kind's scale (forces: the
    largest force; torques: the largest torque or force × the linkage's size)."""
    case = case_of(stem)
    mine, theirs = mechcheck.solve(case), ref.solve(table_of(stem))
    assert mine.status == theirs.status == "ok", (mine.message, theirs.message)
    assert set(mine.values) == set(theirs.values)
    size = case.linkage.scale
    force = max(abs(v) for q, v in theirs.values.items() if mine.unit(q) == "N")
    torque = max([abs(v) for q, v in theirs.values.items() if mine.unit(q) == "N*m"]
                 + [force * size])
    for q, expected in theirs.values.items():
        got, unit = float(mine.values[q]), mine.unit(q)
        if unit == "deg":
            assert abs(math.remainder(got - expected, math.tau)) <= RTOL, q
        else:
            assert abs(got - expected) <= RTOL * {"N": force, "N*m": torque, "m": size}[unit], \
                (q, got, expected)


# -- the truss: a structure solved by statics alone ----------------------------------------
G = 9.81
#: The drawing (mm) and the bars' masses (kg), as written in truss.toml.
NODES = {"N4": (1200.0, 1350.0), "N5": (2400.0, 500.0), "N6": (2600.0, 1200.0)}
BAR_MASS = {"bar46": 8.45, "bar56": 4.37}
HOIST = np.array([0.0, -4000.0])


def test_the_truss_file_is_the_drawing_of_the_hand_calculation() -> None:
    table = table_of("truss")
    for node, xy in NODES.items():
        assert tuple(table["points"][node]) == xy
    masses = {m["link"]: m["mass"] for m in table["masses"]}
    assert {k: masses[k] for k in BAR_MASS} == BAR_MASS
    (load,) = table["loads"]
    assert (load["link"], load["at"], load["force"]) == ("bar56", "N6", {"x": 0.0, "y": -4000.0})
    assert "drivers" not in table


def test_the_truss_supports_balance_its_loads() -> None:
    """The wall's reactions at N1 and N2 (by the ground on the bars) balance the hoist load
    and every bar's weight, forces and moments about N1, to 1e-12 of the total load."""
    table = table_of("truss")
    values = mechcheck.solve(case_of("truss")).values
    supports = [j for j in table["joints"] if j["links"][0] == "ground"]
    assert [j["name"] for j in supports] == ["N1_g_13", "N2_g_23", "N2_g_24"]
    forces: list[tuple[np.ndarray, np.ndarray]] = [
        (1e-3 * np.array(table["points"][j["at"]]),
         np.array([values[f"F_{j['name']}_x"], values[f"F_{j['name']}_y"]])) for j in supports]
    forces.append((1e-3 * np.array(table["points"]["N6"]), HOIST))
    forces += [(1e-3 * np.array(m["com"]), np.array([0.0, -G * m["mass"]])) for m in table["masses"]]
    total_load = abs(HOIST[1]) + G * sum(m["mass"] for m in table["masses"])
    net = sum(f for _, f in forces)
    moment = sum(r[0] * f[1] - r[1] * f[0] for r, f in forces)
    assert np.all(np.abs(net) <= 1e-12 * total_load), net
    assert abs(moment) <= 1e-12 * total_load * 2.6, moment   # 2.6 m: the truss's reach


def test_the_truss_tip_member_force_by_the_method_of_joints() -> None:
    """Node N6 joins bar46 and bar56 only. A pinned bar's weight loads each of its end nodes
    with half of it, so the node balance is t46·e64 + t56·e65 + P + (W46 + W56)/2 = 0, with
    e64 = (N4 − N6)/|N4 − N6| = (−1400, 150)/1408.01, e65 = (N5 − N6)/|N5 − N6| =
    (−200, −700)/728.01 and t the tensions; Cramer's rule:
    t46 = (b_x e65_y − b_y e65_x)/det, t56 = (e64_x b_y − e64_y b_x)/det,
    det = e64_x e65_y − e64_y e65_x, b = −(P + (W46 + W56)/2).
    The joint N6 reports the force of bar46 on bar56: the bar's axial pull t46·e64 plus the
    half weight W46/2 it passes on."""
    n4, n5, n6 = (np.array(NODES[k]) for k in ("N4", "N5", "N6"))
    e64 = (n4 - n6) / np.hypot(*(n4 - n6))
    e65 = (n5 - n6) / np.hypot(*(n5 - n6))
    w46, w56 = (np.array([0.0, -G * BAR_MASS[b]]) for b in ("bar46", "bar56"))
    b = -(HOIST + 0.5 * (w46 + w56))
    det = e64[0] * e65[1] - e64[1] * e65[0]
    t46 = (b[0] * e65[1] - b[1] * e65[0]) / det
    t56 = (e64[0] * b[1] - e64[1] * b[0]) / det
    assert t46 > 0.0 > t56, "the top chord pulls, the tip strut pushes"
    expected = t46 * e64 + 0.5 * w46
    values = mechcheck.solve(case_of("truss")).values
    got = np.array([values["F_N6_46_56_x"], values["F_N6_46_56_y"]])
    assert np.all(np.abs(got - expected) <= RTOL * abs(t56)), (got, expected)


# -- `mechcheck theory catalogue` ------------------------------------------------------------
#: The seed's printed S of every row, and where the command takes each row's mobility from.
CATALOGUE_ROWS = {
    "slider-crank": (1, "file cases/linkages/seed_e2_slider_crank.toml"),
    "four-bar": (1, "file cases/linkages/seed_e1_fourbar.toml"),
    "shaper (kurs)": (1, "file cases/catalogue/shaper.toml"),
    "five-bar": (2, "file cases/linkages/five_bar_two_drivers.toml"),
    "seven-link": (2, "file cases/catalogue/seven_link.toml"),
    "garage door": (1, "file cases/catalogue/garage_door.toml"),
    "wave-maker": (2, "table, spatial"),
    "wave-maker, one S keyed": (1, "table, spatial"),
    "gear pair": (1, "file cases/catalogue/gear_pair.toml"),
    "excavator bucket": (1, "file cases/catalogue/excavator_bucket.toml"),
    "mixed": (2, "file cases/catalogue/mixed.toml"),
    "self-closing hinge": (1, "table, spatial"),
    "truss": (0, "file cases/catalogue/truss.toml"),
    "over-constrained": (-1, "file cases/catalogue/over_constrained.toml"),
}


def mobility_lines(output: str) -> dict[str, str]:
    """The command's mobility lines by row name (the name fills columns 10–36)."""
    return {line[10:36].strip(): line for line in output.splitlines()
            if line.startswith("mobility  ")}


def test_the_catalogue_command_takes_planar_rows_from_their_files() -> None:
    """Every row with its source; a row with a file shows S by Gruebler–Kutzbach, the
    printed S, and by the rank of J: the printed S for a mechanism, and for the structure
    of S = −1 no freedom and one redundant row; a table row, S from the table's counts;
    exit 0."""
    from typer.testing import CliRunner

    from mechcheck.cli import app

    result = CliRunner().invoke(app, ["theory", "catalogue"])
    assert result.exit_code == 0, result.output
    lines = mobility_lines(result.output)
    assert set(lines) == set(CATALOGUE_ROWS)
    for name, (printed, source) in CATALOGUE_ROWS.items():
        line = lines[name]
        assert line.endswith(f"(printed {printed:2d})  {source}"), line
        if source.startswith("file") and printed < 0:
            assert f"S = {printed:2d} Gruebler,  0 rank J, {-printed} redundant " in line, line
        elif source.startswith("file"):
            assert f"S = {printed:2d} Gruebler, {printed:2d} rank J " in line, line
        else:
            assert f"S = {printed:2d} " in line and "rank" not in line, line


def test_the_catalogue_command_fails_on_a_file_that_is_not_the_row(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """A row whose file has other links or joints (the garage door's file for the truss's
    row: 6 links, 7 R, S = 1) disagrees: the line says what the file has, exit 1."""
    from typer.testing import CliRunner

    from mechcheck import theory_cli
    from mechcheck.cli import app

    files = {**theory_cli.CATALOGUE_FILES, "truss": "catalogue/garage_door.toml"}
    monkeypatch.setattr(theory_cli, "CATALOGUE_FILES", files)
    result = CliRunner().invoke(app, ["theory", "catalogue"])
    assert result.exit_code == 1
    line = mobility_lines(result.output)["truss"]
    assert "S =  1 Gruebler,  1 rank J (printed  0)" in line and "(which has u=6, 7R)" in line
