"""The independent reference (tests/linkage_reference.py) on the pin in a slot (seed 001's Cs):
the slotted lever of tests/test_pin_in_slot.py against its hand solution, driven at the
crank and driven along the slot; its mobility; and, in motion and with friction, against
the same mechanism written the classical way in the reference itself (a massless block
pinned to the crank and sliding in the lever: revolute and prismatic rows, whose own checks
are in tests/test_linkage_reference.py)."""

from __future__ import annotations

import copy
import math
from typing import Any

import numpy as np
import pytest

from . import linkage_reference as ref

#: Two routes to the same rigid-body equations (hand or block against slot): rounding only,
#: the 1e-9 of tests/test_linkage_against_reference.py.
RTOL = 1e-9
ROOT10 = math.sqrt(10.0)

#: The crank O2-A turns about O2 = (0, 0.3); its pin A = (0.1, 0.3) slides in the slot of the
#: lever O4-B, pivoted at O4 = (0, 0), along O4→B = (0.2, 0.6); a 100 N load pulls B to −x.
SLOTTED_LEVER: dict[str, Any] = {
    "name": "slotted-lever", "mechanism": "linkage",
    "points": {"O2": [0.0, 0.3], "A": [0.1, 0.3], "O4": [0.0, 0.0], "B": [0.2, 0.6]},
    "links": [{"name": "ground", "points": ["O2", "O4"]},
              {"name": "crank", "points": ["O2", "A"]},
              {"name": "lever", "points": ["O4", "B"]}],
    "joints": [{"name": "O2", "kind": "revolute", "links": ["ground", "crank"], "at": "O2"},
               {"name": "O4", "kind": "revolute", "links": ["ground", "lever"], "at": "O4"},
               {"name": "A", "kind": "pin_in_slot", "links": ["lever", "crank"], "at": "A",
                "axis": [0.2, 0.6]}],
    "drivers": [{"joint": "O2", "rotation": 0.0}],
    "loads": [{"link": "lever", "at": "B", "force": {"x": -100.0, "y": 0.0}}],
}


def lever(**driver: Any) -> dict[str, Any]:
    case = copy.deepcopy(SLOTTED_LEVER)
    if driver:
        case["drivers"] = [driver]
    return case


def assert_values(values: dict[str, float], expected: dict[str, float]) -> None:
    scale = max(abs(v) for v in expected.values())
    for q, want in expected.items():
        assert abs(values[q] - want) <= RTOL * scale, (q, values[q], want)


def test_driven_at_the_crank_it_has_the_hand_solution() -> None:
    """tests/test_pin_in_slot.py's hand solution: the lever's moment about O4, 0.6·100 =
    60 N·m, is balanced by the slot's force N along n = (−3, 1)/√10 at A, N = 60/√0.1;
    the crank feels N·n = (−180, 60) N, O4 carries (−80, 60) N and the drive torque is
    −(0.1·60) = −6 N·m. A pin turns in its slot: no couple is reported."""
    result = ref.solve(lever())
    assert result.status == "ok", result.message
    assert_values(result.values, {"F_A_x": -180.0, "F_A_y": 60.0, "F_O4_x": -80.0,
                                  "F_O4_y": 60.0, "F_O2_x": 180.0, "F_O2_y": -60.0,
                                  "Q_O2": -6.0})
    assert "M_A" not in result.values


def test_driven_along_the_slot_it_has_the_hand_solution() -> None:
    """The driver is the pin's travel along the slot, its effort Q a force Q·u on the crank
    at A (u = (1, 3)/√10), −Q·u on the lever. The lever: A lies on the slot's line through
    O4, so Q·u has no moment about O4 and N = 60√10 N as before, N·n = (−180, 60) N. The
    crank about O2 (A − O2 = (0.1, 0)): 0.1·(N n_y + Q u_y) = 0, Q = −N/3 = −20√10 N. The
    crank's sum of forces gives O2 = −(N n + Q u) = (200, 0) N, the lever's
    O4 = N n + Q u − (−100, 0) = (−100, 0) N."""
    result = ref.solve(lever(joint="A", displacement=0.0))
    assert result.status == "ok", result.message
    assert_values(result.values, {"F_A_x": -180.0, "F_A_y": 60.0, "Q_A": -20.0 * ROOT10,
                                  "F_O2_x": 200.0, "F_O2_y": 0.0, "F_O4_x": -100.0,
                                  "F_O4_y": 0.0})


def test_it_leaves_two_freedoms() -> None:
    """Gruebler–Kutzbach with Sᵢ = 2: 3·(3 − 1) − (2 + 2 + 1) = 1; the Jacobian agrees."""
    mob = ref.mobility(ref.parse_case(lever()))
    assert (mob.gruebler, mob.dof, mob.redundant_joints) == (1, 1, [])


def with_block(case: dict[str, Any]) -> dict[str, Any]:
    """The same mechanism with a massless block pinned to the crank at A (revolute ``A``)
    and sliding in the lever (prismatic ``A_slide``); friction moves to the slide."""
    out = copy.deepcopy(case)
    out["links"].append({"name": "block", "points": ["A"]})
    out["joints"][2:] = [{"name": "A", "kind": "revolute", "links": ["block", "crank"], "at": "A"},
                         {"name": "A_slide", "kind": "prismatic", "links": ["lever", "block"],
                          "at": "A", "axis": [0.2, 0.6]}]
    friction = out.get("friction")
    for table in ("joint_mu", "viscous"):
        if friction and table in friction:
            friction[table] = {"A_slide": friction[table]["A"]}
    return out


def moving(rotation: float, friction: dict[str, Any] | None) -> dict[str, Any]:
    """The slotted lever turned by ``rotation`` degrees at 4 rad/s and −7 rad/s², with
    masses on the crank and the lever, under gravity."""
    case = lever(joint="O2", rotation=rotation, velocity=4.0, acceleration=-7.0)
    case["gravity"] = [0.0, -9.81]
    case["masses"] = [{"link": "crank", "mass": 0.4, "com": [0.05, 0.3], "inertia": 2e-4},
                      {"link": "lever", "mass": 1.5, "com": [0.1, 0.3], "inertia": 0.03}]
    if friction is not None:
        case["friction"] = friction
    return case


@pytest.mark.parametrize("rotation", [-50.0, -10.0, 25.0, 60.0])
@pytest.mark.parametrize("friction", [None, {"joint_mu": {"A": 0.2}}, {"viscous": {"A": 3.0}}],
                         ids=["frictionless", "coulomb", "viscous"])
def test_in_motion_it_equals_a_massless_block(rotation: float,
                                             friction: dict[str, Any] | None) -> None:
    """Every reaction, the drive torque and the pin's travel equal the block's: the slot's
    force on the crank is the block's pin force on the crank."""
    case = moving(rotation, friction)
    slot, block = ref.solve(case), ref.solve(with_block(case))
    assert slot.status == block.status == "ok", (slot.message, block.message)
    scale = max(abs(v) for q, v in block.values.items() if q.startswith(("F_", "Q_")))
    for q in ("F_O2_x", "F_O2_y", "F_O4_x", "F_O4_y", "F_A_x", "F_A_y", "Q_O2"):
        assert abs(slot.values[q] - block.values[q]) <= RTOL * scale, q
    assert abs(slot.values["q_A"] - block.values["q_A_slide"]) <= 1e-12
    if friction is not None:   # the friction is felt: the comparison is not of two zeros
        bare = ref.solve(moving(rotation, None)).values["Q_O2"]
        assert abs(slot.values["Q_O2"] - bare) > 1e-3 * abs(bare)


def test_its_refusals() -> None:
    """Without an axis, or with links[1] not carrying the pin."""
    case = lever()
    del case["joints"][2]["axis"]
    with pytest.raises(ref.LinkageInputError, match="axis"):
        ref.solve(case)
    case = lever()
    case["joints"][2]["links"] = ["crank", "lever"]
    with pytest.raises(ref.LinkageInputError, match="pin_in_slot joint must carry"):
        ref.solve(case)


def test_the_slot_turns_with_its_link() -> None:
    """Driven along the slot by 50 mm, the pin A stays on the lever's line O4→B (the slot is
    fixed in the lever) and at 0.1 m from O2 (the crank is rigid)."""
    result = ref.solve(lever(joint="A", displacement=0.05))
    assert result.status == "ok", result.message
    v = result.values
    a = np.array([v["x_A"], v["y_A"]])
    b = np.array([v["x_B"], v["y_B"]])
    assert abs(a[0] * b[1] - a[1] * b[0]) <= 1e-12
    assert abs(math.hypot(a[0] - 0.0, a[1] - 0.3) - 0.1) <= 1e-12
    assert abs(v["q_A"] - 0.05) <= 1e-12
