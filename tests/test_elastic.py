"""Statically indeterminate structures with elastic members (``axial_stiffness``, seed 001's
S = −1) in the analytic engine, against the seed's own method written in the test: the
displacement method (node displacement u from K_node·u = P with K_node = Σ (E·A/L)·e·eᵀ,
each member's force (E·A/L)·e·u), and the identities it must keep (the supports balance
the loads; a member's stretch is N·L/(E·A)); and the verdicts where stiffness does not
decide the forces."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import mechcheck
from mechcheck.analytic.case import Case
from mechcheck.analytic.joint_kinds import REVOLUTE
from mechcheck.analytic.linkage import Joint, Link, Linkage, LinkMass, PointLoad
from mechcheck.analytic.values import CaseError
from mechcheck.tolerance import rule

RTOL = rule("analytic", "force", "static").rtol

#: Wall points and the node, metres; each bar's E·A (N).
WALL = {"A": (0.0, 0.0), "B": (0.0, 0.8), "C": (0.0, 2.0), "E": (0.3, -0.4)}
NODE = (1.2, 0.9)
LOAD = (250.0, -1000.0)


def bars(stiffness: dict[str, float | None]) -> Linkage:
    """Bars from wall points to one node D, pinned at both ends, loaded at D: with three or
    four bars, redundant once or twice (S = −1, −2)."""
    names = list(stiffness)
    links = [Link("ground", tuple(names))]
    links += [Link(f"bar{w}", (w, "D"), stiffness[w]) for w in names]
    joints = [Joint(w, REVOLUTE, ("ground", f"bar{w}"), w) for w in names]
    joints += [Joint(f"D{w}", REVOLUTE, (f"bar{names[0]}", f"bar{w}"), "D") for w in names[1:]]
    return Linkage(points={**{w: WALL[w] for w in names}, "D": NODE}, links=tuple(links),
                   joints=tuple(joints),
                   loads=(PointLoad(f"bar{names[0]}", NODE, LOAD),))


def displacement_method(stiffness: dict[str, float],
                        load: tuple[float, float] = LOAD) -> dict[str, float]:
    """The seed's method: the node's displacement from the bars' stiffnesses under the node's
    ``load``, then each bar's tension (E·A/L)·e·u, e the unit vector from the wall to the
    node."""
    k_node = np.zeros((2, 2))
    units = {}
    for w, ea in stiffness.items():
        d = np.subtract(NODE, WALL[w])
        length = float(np.hypot(*d))
        e = d / length
        units[w] = (e, ea / length)
        k_node += ea / length * np.outer(e, e)
    u = np.linalg.solve(k_node, load)
    return {w: k * float(e @ u) for w, (e, k) in units.items()}


def solved(linkage: Linkage) -> mechcheck.Solution:
    return mechcheck.solve(Case("bars", linkage))


def along_bar(w: str, t: float) -> tuple[float, float]:
    """The point a fraction t of the way along bar ``w`` from the wall to the node."""
    (ax, ay), (dx, dy) = WALL[w], NODE
    return ax + t * (dx - ax), ay + t * (dy - ay)


def loaded_bar_method(stiffness: dict[str, float], w: str, t: float,
                      force: tuple[float, float]) -> dict[str, float]:
    """The displacement method with a force on bar ``w`` a fraction t along it from the wall:
    by the lever rule t·F bears on the node (the rest on the wall), so the node moves by
    K u = LOAD + t·F and each bar stretches by e·u. The loaded bar's tension is N₁ on the wall
    side of the force and N₁ − F·e beyond it, so its stretch is ∫N dx/(E·A) with ∫N dx/L =
    N₁ − (1 − t)·F·e, and its N, the mean of its end tensions, N₁ − ½·F·e, is (E·A/L)·e·u −
    (t − ½)·F·e."""
    out = displacement_method(stiffness, (LOAD[0] + t * force[0], LOAD[1] + t * force[1]))
    d = np.subtract(NODE, WALL[w])
    e = d / np.hypot(*d)
    out[w] -= (t - 0.5) * float(e @ np.asarray(force))
    return out


@pytest.mark.parametrize("stiffness", [
    {"A": 2.0e7, "B": 1.0e7, "C": 3.0e7},
    {"A": 1.0e7, "B": 5.0e7, "C": 1.0e7, "E": 2.0e7},
], ids=["three-bars", "four-bars"])
def test_redundant_bars_share_the_load_as_the_displacement_method_says(
        stiffness: dict[str, float]) -> None:
    """Each bar's tension N_<bar> equals the displacement method's; the wall's reactions
    balance the load to 1e-12; the largest strain is max |N|/(E·A)."""
    linkage = bars(dict(stiffness))
    assert linkage.gruebler == 2 - len(stiffness) and linkage.redundant   # 3m − 2(2m − 1)
    solution = solved(linkage)
    assert solution.status == "ok", solution.message
    expected = displacement_method(stiffness)
    v = solution.values
    for w, tension in expected.items():
        assert v[f"N_bar{w}"] == pytest.approx(tension, rel=RTOL, abs=RTOL * 1000.0), w
    # The wall's reactions act on the bars (by the ground, links[0]): they balance the load.
    fx = sum(v[f"F_{w}_x"] for w in stiffness)
    fy = sum(v[f"F_{w}_y"] for w in stiffness)
    assert abs(fx + LOAD[0]) <= 1e-12 * 1000.0 and abs(fy + LOAD[1]) <= 1e-12 * 1000.0
    strain = max(abs(expected[w]) / stiffness[w] for w in stiffness)
    assert solution.diagnostics["max_strain"] == pytest.approx(strain, rel=1e-9)


@pytest.mark.parametrize("t", [0.25, 0.5, 0.8])
@pytest.mark.parametrize("as_weight", [True, False], ids=["weight", "point-load"])
def test_a_bar_loaded_between_its_ends_stretches_by_its_whole_tension(t: float,
                                                                     as_weight: bool) -> None:
    """A 300 N force on bar B (along the bar, mostly: it changes its tension most), as a
    point load or as the weight of a 30.58 kg bar with its centre of mass there, a fraction t
    along it: every N_<bar> is the displacement method's with the force's lever-rule share
    at the node (:func:`loaded_bar_method`)."""
    force = (300.0, 0.0) if not as_weight else (0.0, -300.0)
    stiffness = {"A": 2.0e7, "B": 1.0e7, "C": 3.0e7}
    linkage = bars(dict(stiffness))
    at = along_bar("B", t)
    if as_weight:
        linkage = replace(linkage, gravity=(0.0, -9.81),
                          masses=(LinkMass("barB", 300.0 / 9.81, at, 0.0),))
    else:
        linkage = replace(linkage, loads=(*linkage.loads, PointLoad("barB", at, force)))
    solution = solved(linkage)
    assert solution.status == "ok", solution.message
    for w, tension in loaded_bar_method(stiffness, "B", t, force).items():
        assert solution.values[f"N_bar{w}"] == pytest.approx(tension, rel=RTOL,
                                                             abs=RTOL * 1000.0), w


def test_rigid_bars_take_everything_from_an_elastic_one() -> None:
    """One elastic bar beside two rigid ones: the rigid pair is infinitely stiff, so the
    elastic bar carries nothing and the rigid pair carries the load as a determinate truss."""
    v = solved(bars({"A": None, "B": 1.0e7, "C": None})).values
    assert abs(v["N_barB"]) <= RTOL * 1000.0
    alone = solved(bars({"A": None, "C": None})).values   # the determinate pair
    for q in ("F_A_x", "F_A_y", "F_C_x", "F_C_y"):
        assert v[q] == pytest.approx(alone[q], rel=RTOL, abs=RTOL * 1000.0), q


def test_stiffness_that_does_not_decide_the_forces_is_said() -> None:
    """Rigid redundant bars: ``indeterminate``, suggesting axial_stiffness; four bars with one
    elastic: a self-stress through the three rigid ones remains, still ``indeterminate``."""
    rigid = solved(bars({"A": None, "B": None, "C": None}))
    assert rigid.status == "indeterminate" and "axial_stiffness" in rigid.message
    partly = solved(bars({"A": None, "B": 1.0e7, "C": None, "E": None}))
    assert partly.status == "indeterminate" and "rigid members only" in partly.message


def test_a_determinate_linkage_reports_its_members_forces() -> None:
    """Two elastic bars (S = 0): the forces are statics' alone, whatever the stiffness."""
    one = solved(bars({"A": 1.0e7, "C": 4.0e7})).values
    other = solved(bars({"A": 3.0e9, "C": 1.0e5})).values
    for q in ("N_barA", "N_barC", "F_A_x", "F_C_y"):
        assert one[q] == pytest.approx(other[q], rel=RTOL), q


FILE = """
[[case]]
name = "three-bars"
mechanism = "linkage"
[case.points]
A = [0.0, 0.0]
B = [0.0, 1.0]
C = [0.0, 2.0]
D = [1.0, 1.0]
[[case.links]]
name = "ground"
points = ["A", "B", "C"]
[[case.links]]
name = "ad"
points = ["A", "D"]
axial_stiffness = 1.0e7
[[case.links]]
name = "bd"
points = ["B", "D"]
axial_stiffness = 1.0e7
[[case.links]]
name = "cd"
points = ["C", "D"]
axial_stiffness = 1.0e7
[[case.joints]]
name = "A"
kind = "revolute"
links = ["ground", "ad"]
at = "A"
[[case.joints]]
name = "B"
kind = "revolute"
links = ["ground", "bd"]
at = "B"
[[case.joints]]
name = "C"
kind = "revolute"
links = ["ground", "cd"]
at = "C"
[[case.joints]]
name = "D1"
kind = "revolute"
links = ["ad", "bd"]
at = "D"
[[case.joints]]
name = "D2"
kind = "revolute"
links = ["bd", "cd"]
at = "D"
[[case.loads]]
link = "bd"
at = "D"
force = { x = 0.0, y = -1000.0 }
"""


def test_the_case_file_reads_elastic_members(tmp_path: Path) -> None:
    """The symmetric three-bar truss: the horizontal bar carries nothing, the others
    ±1000/√2 N (the lower one in compression)."""
    path = tmp_path / "bars.toml"
    path.write_text(FILE)
    (case,) = mechcheck.load_cases(path)
    v = mechcheck.solve(case).values
    half = 1000.0 / math.sqrt(2.0)
    assert (v["N_ad"], v["N_bd"], v["N_cd"]) == pytest.approx((-half, 0.0, half), rel=RTOL,
                                                              abs=RTOL * 1000.0)


@pytest.mark.parametrize(("old", "new", "key"), [
    ('name = "ad"\npoints = ["A", "D"]\naxial_stiffness = 1.0e7',
     'name = "ad"\npoints = ["A", "D"]\naxial_stiffness = 0.0', "links[1].axial_stiffness"),
    ('name = "ground"\npoints = ["A", "B", "C"]',
     'name = "ground"\npoints = ["A", "B", "C"]\naxial_stiffness = 1.0e7',
     "links[0].axial_stiffness"),
    ('name = "ad"\npoints = ["A", "D"]', 'name = "ad"\npoints = ["A", "D", "B"]',
     "links[1].axial_stiffness"),
])
def test_the_case_file_refuses_a_member_that_cannot_stretch(tmp_path: Path, old: str, new: str,
                                                             key: str) -> None:
    """E·A ≤ 0, the ground, or a link of three points: one line naming the key."""
    assert old in FILE
    path = tmp_path / "bars.toml"
    path.write_text(FILE.replace(old, new, 1))
    with pytest.raises(CaseError) as error:
        mechcheck.load_cases(path)
    assert f"key '{key}'" in str(error.value) and "three-bars" in str(error.value)
