"""The pin in a slot (``kind = "pin_in_slot"``, seed 001's Cs joint, Sᵢ = 2) in the analytic
engine: a hand free-body solution of a crank driving a slotted lever; the same joint written
the classical way, a massless block pinned to the crank and sliding in the lever (the
engine's revolute and prismatic joints, whose own checks are independent of this kind),
with and without friction; its mobility; and the file's refusals."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import mechcheck
from mechcheck.analytic.case import Case
from mechcheck.analytic.joint_kinds import PIN_IN_SLOT, PRISMATIC, REVOLUTE
from mechcheck.analytic.linkage import (
    Driver,
    Joint,
    JointFriction,
    LinearSpring,
    Link,
    Linkage,
    LinkMass,
    PointLoad,
)
from mechcheck.analytic.linkage_forces import solve_linkage
from mechcheck.tolerance import rule

#: Two analytic routes agree to the policy's tolerance for the analytic backend.
RTOL = rule("analytic", "force", "static").rtol

#: The crank O2-A turns about O2 = (0, 0.3); its pin A = (0.1, 0.3) slides in the slot of the
#: lever O4-B, pivoted at O4 = (0, 0), along O4→B = (0.2, 0.6); a 100 N load pulls B to −x.
POINTS = {"O2": (0.0, 0.3), "A": (0.1, 0.3), "O4": (0.0, 0.0), "B": (0.2, 0.6)}


def slotted_lever(*, rotation: float = 0.0, velocity: float = 0.0,
                  friction: JointFriction | None = None, sense: int = 0) -> Linkage:
    return Linkage(
        points=POINTS,
        links=(Link("ground", ("O2", "O4")), Link("crank", ("O2", "A")),
               Link("lever", ("O4", "B"))),
        joints=(Joint("O2", REVOLUTE, ("ground", "crank"), "O2"),
                Joint("O4", REVOLUTE, ("ground", "lever"), "O4"),
                Joint("A", PIN_IN_SLOT, ("lever", "crank"), "A", (0.2, 0.6))),
        drivers=(Driver("O2", rotation, velocity, 0.0, sense),),
        loads=(PointLoad("lever", POINTS["B"], (-100.0, 0.0)),),
        friction=friction)


def quick_return(rotation: float = 0.4, velocity: float = 0.0,
                 springs: tuple[LinearSpring, ...] = ()) -> Linkage:
    """A quick-return (shaper) mechanism: the crank O2-A turns about O2 = (0, 0.3); its pin A
    slides in the slot of the lever O4-B (pivot O4 = (0, 0), slot along O4→B); the rod B-C
    drives the ram C along a horizontal slide against a 200 N cutting force; every moving
    link has a mass, under gravity. The pin in the slot closes the loop O2-A-O4."""
    points = {"O2": (0.0, 0.3), "A": (0.1, 0.3), "O4": (0.0, 0.0), "B": (0.2, 0.6),
              "C": (0.5, 0.65)}
    return Linkage(
        points=points,
        links=(Link("ground", ("O2", "O4")), Link("crank", ("O2", "A")),
               Link("lever", ("O4", "B")), Link("rod", ("B", "C")), Link("ram", ("C",))),
        joints=(Joint("O2", REVOLUTE, ("ground", "crank"), "O2"),
                Joint("O4", REVOLUTE, ("ground", "lever"), "O4"),
                Joint("A", PIN_IN_SLOT, ("lever", "crank"), "A", (0.2, 0.6)),
                Joint("B", REVOLUTE, ("lever", "rod"), "B"),
                Joint("C", REVOLUTE, ("rod", "ram"), "C"),
                Joint("slide", PRISMATIC, ("ground", "ram"), "C", (1.0, 0.0))),
        drivers=(Driver("O2", rotation, velocity),),
        loads=(PointLoad("ram", points["C"], (-200.0, 0.0)),),
        masses=(LinkMass("crank", 1.0, (0.05, 0.3), 1e-3), LinkMass("lever", 3.0, (0.1, 0.3), 0.04),
                LinkMass("rod", 1.0, (0.35, 0.625), 8e-3), LinkMass("ram", 2.0, (0.5, 0.65), 1e-3)),
        gravity=(0.0, -9.81),
        springs=springs)


def with_block(linkage: Linkage) -> Linkage:
    """The same mechanism with its pin in a slot written as a massless block: pinned to the
    crank at A (revolute ``A``) and sliding in the lever (prismatic ``A_slide``)."""
    links = (*linkage.links, Link("block", ("A",)))
    joints = (linkage.joints[0], linkage.joints[1],
              Joint("A", REVOLUTE, ("block", "crank"), "A"),
              Joint("A_slide", PRISMATIC, ("lever", "block"), "A", (0.2, 0.6)))
    friction = linkage.friction
    if friction is not None:
        friction = replace(friction,
                           joint_mu={f"{j}_slide": m for j, m in friction.joint_mu.items()},
                           viscous={f"{j}_slide": c for j, c in friction.viscous.items()})
    return replace(linkage, links=links, joints=joints, friction=friction)


def values(linkage: Linkage) -> dict[str, float]:
    results = solve_linkage(linkage)
    out = {q: float(v[0]) for q, v in results.values.items()}
    assert all(math.isfinite(v) for v in out.values())
    return out


def test_a_slotted_lever_has_the_hand_solution() -> None:
    """Lever about O4: the load's moment r_B × F = 0.6·100 = 60 N·m is balanced by the slot's
    force N along the slot normal n = (−3, 1)/√10 at A, N·|O4A| = 60 with |O4A| = √0.1; so
    the crank feels F_A = N n = (−180, 60) N, O4 carries −(F_B + N n) = (−80, 60) N, and
    the crank's drive torque is −r_A × F_A = −(0.1·60) = −6 N·m about O2."""
    v = values(slotted_lever())
    n_mag = 60.0 / math.sqrt(0.1)
    normal = np.array([-3.0, 1.0]) / math.sqrt(10.0)
    # By the lever (links[0]) on the crank (links[1]): N n; the crank pushes the lever with
    # −N n = (180, −60), whose moment about O4 is 0.1·(−60) − 0.3·180 = −60 N·m.
    assert np.allclose(n_mag * normal, [-180.0, 60.0], rtol=1e-15, atol=1e-12)
    expected = {"F_A_x": -180.0, "F_A_y": 60.0, "F_O4_x": -80.0, "F_O4_y": 60.0,
                "F_O2_x": 180.0, "F_O2_y": -60.0, "Q_O2": -6.0}
    assert math.isclose(math.hypot(v["F_A_x"], v["F_A_y"]), n_mag, rel_tol=RTOL)
    for q, want in expected.items():
        assert v[q] == pytest.approx(want, rel=RTOL, abs=RTOL * 100.0), q
    assert "M_A" not in v, "a pin turns freely in its slot: no couple"


def test_it_leaves_two_freedoms() -> None:
    """Gruebler–Kutzbach with Sᵢ = 2: 3·(3 − 1) − (2 + 2 + 1) = 1, and the Jacobian agrees."""
    linkage = slotted_lever()
    assert PIN_IN_SLOT.freedoms == 2 and PIN_IN_SLOT.rows == 1
    assert linkage.gruebler == 1 and linkage.dof == 1 and not linkage.redundant


@pytest.mark.parametrize("rotation", np.radians([-50.0, -10.0, 0.0, 25.0, 60.0]))
@pytest.mark.parametrize("friction", [None, JointFriction(mu=0.0, joint_mu={"A": 0.2}),
                                      JointFriction(mu=0.0, viscous={"A": 3.0})],
                         ids=["frictionless", "coulomb", "viscous"])
def test_it_equals_a_massless_block_in_a_slot(rotation: float,
                                              friction: JointFriction | None) -> None:
    """At poses along the crank's turn, turning at 4 rad/s: every reaction and the drive
    torque equal those of the block written with a revolute and a prismatic joint (the
    block's slide carries the friction μ·|N| and −c·q̇ the slot carries)."""
    linkage = slotted_lever(rotation=float(rotation), velocity=4.0, friction=friction)
    slot, block = values(linkage), values(with_block(linkage))
    scale = max(abs(v) for q, v in block.items() if q.startswith(("F_", "Q_")))
    for q in ("F_O2_x", "F_O2_y", "F_O4_x", "F_O4_y", "Q_O2"):
        assert slot[q] == pytest.approx(block[q], rel=RTOL, abs=RTOL * scale), q
    # The slot's force on the crank is the block's pin force on the crank.
    for axis in ("x", "y"):
        assert slot[f"F_A_{axis}"] == pytest.approx(block[f"F_A_{axis}"], rel=RTOL,
                                                    abs=RTOL * scale)
    assert slot["q_A"] == pytest.approx(block["q_A_slide"], rel=RTOL, abs=1e-12)
    if friction is not None:   # the friction is felt: the comparison is not of two zeros
        bare = values(slotted_lever(rotation=float(rotation), velocity=4.0))
        assert abs(slot["Q_O2"] - bare["Q_O2"]) > 1e-3 * abs(bare["Q_O2"])


def test_the_case_file_takes_it_and_refuses_it_without_an_axis(tmp_path: Path) -> None:
    """``kind = "pin_in_slot"`` reads from a file and solves as built here; without ``axis``
    the file is refused with one line naming the file, the case and the key."""
    text = CASE_FILE
    path = tmp_path / "slot.toml"
    path.write_text(text)
    (case,) = mechcheck.load_cases(path)
    assert isinstance(case, Case)
    assert mechcheck.solve(case).values["Q_O2"] == pytest.approx(-6.0, rel=RTOL)
    path.write_text(text.replace("axis = [0.2, 0.6]\n", ""))
    with pytest.raises(mechcheck.CaseError) as error:
        mechcheck.load_cases(path)
    message = str(error.value)
    assert str(path) in message and "slotted-lever" in message and "joints[2].axis" in message


def test_the_format_reference_example_is_this_case(tmp_path: Path) -> None:
    """The pin-in-slot example in docs/case-files.md reads and gives the hand solution."""
    docs = (Path(__file__).parents[1] / "docs" / "case-files.md").read_text(encoding="utf-8")
    block = docs.split('name = "slotted-lever"', 1)[1].split("```", 1)[0]
    path = tmp_path / "example.toml"
    path.write_text('[[case]]\nname = "slotted-lever"' + block)
    (case,) = mechcheck.load_cases(path)
    v = mechcheck.solve(case).values
    assert (v["F_A_x"], v["F_A_y"], v["Q_O2"]) == pytest.approx((-180.0, 60.0, -6.0), rel=RTOL)


CASE_FILE = """
[[case]]
name = "slotted-lever"
mechanism = "linkage"
[case.points]
O2 = [0.0, 0.3]
A = [0.1, 0.3]
O4 = [0.0, 0.0]
B = [0.2, 0.6]
[[case.links]]
name = "ground"
points = ["O2", "O4"]
[[case.links]]
name = "crank"
points = ["O2", "A"]
[[case.links]]
name = "lever"
points = ["O4", "B"]
[[case.joints]]
name = "O2"
kind = "revolute"
links = ["ground", "crank"]
at = "O2"
[[case.joints]]
name = "O4"
kind = "revolute"
links = ["ground", "lever"]
at = "O4"
[[case.joints]]
name = "A"
kind = "pin_in_slot"
links = ["lever", "crank"]
at = "A"
axis = [0.2, 0.6]
[[case.drivers]]
joint = "O2"
rotation = 0.0
[[case.loads]]
link = "lever"
at = "B"
force = { x = -100.0, y = 0.0 }
"""
