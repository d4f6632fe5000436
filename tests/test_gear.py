"""The gear mesh (``kind = "gear"``, seed 001's G, Sᵢ = 2) in the analytic engine, against
hand solutions: an external pair and an internal pair (the tooth force's tangential part
from the gears' moment balances, its radial part tan α·|F_t| pushing the gears apart
whichever way the torque goes, the bearings carrying both); a planetary train against
Willis' formula over two carrier turns, its drive torque against the output torque times
the ratio; its mobility; and the file's refusals."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import mechcheck
from mechcheck.analytic.joint_kinds import GEAR, REVOLUTE, GearMesh
from mechcheck.analytic.linkage import Driver, Joint, Link, Linkage, PointLoad
from mechcheck.analytic.linkage_forces import solve_linkage
from mechcheck.analytic.values import CaseError
from mechcheck.tolerance import rule

#: Two analytic routes agree to the policy's tolerance for the analytic backend.
RTOL = rule("analytic", "force", "static").rtol
TAN20 = math.tan(math.radians(20.0))


def values(linkage: Linkage) -> dict[str, float]:
    out = {q: float(v[0]) for q, v in solve_linkage(linkage).values.items()}
    assert all(math.isfinite(v) for v in out.values()), out
    return out


def pair(torque: float, *, internal: bool = False, rotation: float = 0.5) -> Linkage:
    """A pinion (ra = 50 mm, centre Pa) driven at Pa, meshing with a wheel (rb = 100 mm,
    centre Pb on the x axis: 150 mm away, or 50 mm for an internal ring), which carries
    ``torque`` (N·m, CCW)."""
    ra, rb = 0.05, 0.10
    distance = rb - ra if internal else ra + rb
    return Linkage(
        points={"Pa": (0.0, 0.0), "Pb": (distance, 0.0)},
        links=(Link("ground", ("Pa", "Pb")), Link("pinion", ("Pa",)), Link("wheel", ("Pb",))),
        joints=(Joint("Pa", REVOLUTE, ("ground", "pinion"), "Pa"),
                Joint("Pb", REVOLUTE, ("ground", "wheel"), "Pb"),
                Joint("mesh", GEAR, ("pinion", "wheel"), "Pa",
                      mesh=GearMesh(("Pa", "Pb"), (ra, rb), math.radians(20.0), internal))),
        drivers=(Driver("Pa", rotation),),
        loads=(PointLoad("wheel", (distance, 0.0), (0.0, 0.0), torque),))


def pair_by_hand(torque: float) -> dict[str, float]:
    """The external pair's hand solution (see the test below): the wheel about Pb gives
    F_t = T/rb, the pinion about Pa Q = T·ra/rb, the radial part tan 20°·|F_t| along +e."""
    f_t = torque / 0.10
    radial = TAN20 * abs(f_t)
    return {"F_mesh_t": f_t, "F_mesh_r": radial, "F_mesh_x": radial, "F_mesh_y": f_t,
            "F_Pb_x": -radial, "F_Pb_y": -f_t, "F_Pa_x": radial, "F_Pa_y": f_t,
            "Q_Pa": torque * 0.05 / 0.10}


@pytest.mark.parametrize("torque", [10.0, -10.0])
def test_an_external_pair_has_the_hand_solution(torque: float) -> None:
    """e = +x (Pa→Pb), t = +y, pitch point P = Pa + ra·e. The wheel about Pb: the tooth
    force's tangential part F_t·t at P (lever −rb·e) gives −rb·F_t, so F_t = T/rb; the
    pinion about Pa: Q − ra·F_t = 0, Q = T·ra/rb; the radial part tan20°·|F_t| pushes the
    wheel along +e whatever the sign of T; each bearing carries the tooth force back."""
    v = values(pair(torque))
    for q, want in pair_by_hand(torque).items():
        assert v[q] == pytest.approx(want, rel=RTOL, abs=RTOL * 100.0), q
    # The wheel turns the other way, by the ratio of the radii.
    assert v["phi_wheel"] == pytest.approx(-0.5 * 0.05 / 0.10, rel=1e-12)


@pytest.mark.parametrize("torque", [10.0, -10.0])
def test_an_internal_pair_has_the_hand_solution(torque: float) -> None:
    """A pinion inside a ring (rb = 100 mm) 50 mm away: P = Pa − ra·e = Pb − rb·e. The ring
    about Pb: lever −rb·e, so F_t = T/rb again; the pinion about Pa: lever −ra·e under
    −F_t·t gives +ra·F_t, so Q = −T·ra/rb; the radial part pushes the ring outward, along
    −e; pinion and ring turn the same way."""
    v = values(pair(torque, internal=True))
    f_t = torque / 0.10
    radial = TAN20 * abs(f_t)
    expected = {"F_mesh_t": f_t, "F_mesh_r": radial, "F_mesh_x": -radial, "F_mesh_y": f_t,
                "Q_Pa": -torque * 0.05 / 0.10}
    for q, want in expected.items():
        assert v[q] == pytest.approx(want, rel=RTOL, abs=RTOL * 100.0), q
    assert v["phi_wheel"] == pytest.approx(0.5 * 0.05 / 0.10, rel=1e-12)


SUN, RING = 0.03, 0.09
PLANET = (RING - SUN) / 2


def planetary(carrier: float, velocity: float = 1.0) -> Linkage:
    """Sun and carrier turn about O; the planet, pinned to the carrier at C, meshes with the
    sun and with a fixed ring (internal). The carrier is driven; the sun carries 2 N·m."""
    return Linkage(
        points={"O": (0.0, 0.0), "C": (SUN + PLANET, 0.0)},
        links=(Link("ground", ("O",)), Link("sun", ("O",)), Link("arm", ("O", "C")),
               Link("planet", ("C",))),
        joints=(Joint("O_sun", REVOLUTE, ("ground", "sun"), "O"),
                Joint("O_arm", REVOLUTE, ("ground", "arm"), "O"),
                Joint("C", REVOLUTE, ("arm", "planet"), "C"),
                Joint("sp", GEAR, ("sun", "planet"), "O", mesh=GearMesh(("O", "C"), (SUN, PLANET))),
                Joint("pr", GEAR, ("planet", "ground"), "C",
                      mesh=GearMesh(("C", "O"), (PLANET, RING), internal=True))),
        drivers=(Driver("O_arm", carrier, velocity),),
        loads=(PointLoad("sun", (0.0, 0.0), (0.0, 0.0), 2.0),))


@pytest.mark.parametrize("carrier_deg", [0.0, 100.0, 200.0, 370.0, 725.0])
def test_a_planetary_train_follows_willis_and_balances_power(carrier_deg: float) -> None:
    """Ring fixed: ω_sun = ω_arm·(1 + R/S) = 4 ω_arm (Willis), over two carrier turns; the
    drive torque balances the sun's torque times that ratio, Q = −2·4 = −8 N·m, to 1e-12; the
    sun's tooth force is T/S."""
    carrier = math.radians(carrier_deg)
    v = values(planetary(carrier))
    ratio = 1.0 + RING / SUN
    assert v["phi_sun"] == pytest.approx(carrier * ratio, rel=1e-12, abs=1e-12)
    assert v["Q_O_arm"] == pytest.approx(-2.0 * ratio, rel=1e-12)
    assert v["F_sp_t"] == pytest.approx(2.0 / SUN, rel=1e-12)


def test_mobility_counts_a_mesh_as_two_freedoms() -> None:
    """Gruebler–Kutzbach: the pair 3·2 − (2 + 2 + 1) = 1 (the seed's gear pair, 3 links,
    2R 1G, S = 1); the planetary train 3·3 − (3·2 + 2·1) = 1; the Jacobian agrees."""
    assert pair(1.0).gruebler == pair(1.0).dof == 1
    assert planetary(0.0).gruebler == planetary(0.0).dof == 1
    assert GEAR.freedoms == 2 and not GEAR.drivable


def test_superposition_refuses_and_virtual_work_agrees() -> None:
    """Superposition cannot add the radial parts; the power equation gives the hand Q."""
    case = mechcheck.analytic.case.Case("pair", pair(10.0))
    assert mechcheck.solve(case, "superposition").status == "not_applicable"
    assert mechcheck.solve(case, "virtual_work").values["Q_Pa"] == pytest.approx(5.0, rel=RTOL)


GEAR_FILE = """
[[case]]
name = "gear-pair"
mechanism = "linkage"
length_unit = "mm"
[case.points]
Pa = [0.0, 0.0]
Pb = [150.0, 0.0]
[[case.links]]
name = "ground"
points = ["Pa", "Pb"]
[[case.links]]
name = "pinion"
points = ["Pa"]
[[case.links]]
name = "wheel"
points = ["Pb"]
[[case.joints]]
name = "Pa"
kind = "revolute"
links = ["ground", "pinion"]
at = "Pa"
[[case.joints]]
name = "Pb"
kind = "revolute"
links = ["ground", "wheel"]
at = "Pb"
[[case.joints]]
name = "mesh"
kind = "gear"
links = ["pinion", "wheel"]
centres = ["Pa", "Pb"]
pitch_radii = [50.0, 100.0]
[[case.drivers]]
joint = "Pa"
rotation = 30.0
[[case.loads]]
link = "wheel"
at = "Pb"
torque = 10.0
"""


def test_the_case_file_reads_a_gear_pair(tmp_path: Path) -> None:
    """The file's pair (pressure angle 20° by default) solves as built above."""
    path = tmp_path / "gears.toml"
    path.write_text(GEAR_FILE)
    (case,) = mechcheck.load_cases(path)
    v = mechcheck.solve(case).values
    assert (v["Q_Pa"], v["F_mesh_t"], v["F_mesh_r"]) == pytest.approx((5.0, 100.0, 100.0 * TAN20),
                                                                        rel=RTOL)


@pytest.mark.parametrize(("change", "key", "fragment"), [
    (("pitch_radii = [50.0, 100.0]", "pitch_radii = [50.0, 90.0]"), "joints[2].pitch_radii",
     "centre distance 150 mm is not ra + rb = 140 mm"),
    (("pitch_radii = [50.0, 100.0]", "pitch_radii = [50.0, 100.0]\ninternal = true"),
     "joints[2].pitch_radii", "is not |ra − rb|"),
    (("pitch_radii = [50.0, 100.0]", "pitch_radii = [50.0, 100.0]\npressure_angle = 50.0"),
     "joints[2].pressure_angle", "[0°, 45°)"),
    (("centres = [\"Pa\", \"Pb\"]", "centres = [\"Pb\", \"Pa\"]"), "joints[2].centres",
     "must carry its gear's centre"),
    (("centres = [\"Pa\", \"Pb\"]\n", ""), "joints[2].centres", "needs it"),
    (("links = [\"pinion\", \"wheel\"]\n", "links = [\"pinion\", \"wheel\"]\nat = \"Pa\"\n"),
     "joints[2].at", "has no 'at'"),
    (("kind = \"revolute\"\nlinks = [\"ground\", \"wheel\"]\nat = \"Pb\"",
      "kind = \"revolute\"\nlinks = [\"ground\", \"wheel\"]\nat = \"Pb\"\npitch_radii = [1.0, 2.0]"),
     "joints[1].pitch_radii", "only a gear joint"),
    (("joint = \"Pa\"", "joint = \"mesh\""), "drivers[0].joint", "cannot be driven"),
    (("torque = 10.0", "torque = 10.0\n[case.friction]\nviscous = { mesh = 1.0 }"),
     "friction.viscous.mesh", "no friction model"),
])
def test_the_case_file_refuses_what_a_mesh_cannot_be(tmp_path: Path, change: tuple[str, str],
                                                     key: str, fragment: str) -> None:
    """Each refusal is one CaseError naming the file, the case and the key."""
    old, new = change
    assert old in GEAR_FILE
    path = tmp_path / "gears.toml"
    path.write_text(GEAR_FILE.replace(old, new, 1))
    with pytest.raises(CaseError) as error:
        mechcheck.load_cases(path)
    message = str(error.value)
    assert str(path) in message and "gear-pair" in message, message
    assert f"key '{key}'" in message and fragment in message, message


def test_a_carrier_turning_past_half_a_turn_keeps_the_gears_on_their_branch() -> None:
    """The line of centres turns with the carrier through ±180° and on: the sun's angle stays
    the Willis multiple of the carrier's at every pose of a batch (no 2π slip)."""
    carrier = np.radians(np.linspace(0.0, 720.0, 73))
    results = solve_linkage(planetary(0.0), carrier[:, None])
    assert np.allclose(results.values["phi_sun"], carrier * (1.0 + RING / SUN), rtol=1e-12,
                       atol=1e-9)
