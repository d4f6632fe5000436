"""The four-bar and the slider-crank as linkages (LINKAGES.md, "The four-bar and
slider-crank as linkages"): the same mechanism, drawn at the case's pose.

Links ``ground``, ``crank``, ``coupler``, ``rocker`` / ``slider``; joints ``A0``
(ground, crank), ``A`` (crank, coupler), ``B`` (coupler, rocker or slider) and ``B0``
(ground, rocker) or ``slide`` (ground, slider, prismatic at B along the slide axis). The
crank's joint A0 is driven with the case's ω and α from the drawn pose (with
``drive_link = 4``, the rocker's joint B0 with the rocker's ω and α at that instant), so the
generic engine solves exactly the case's problem. Legacy quantity names map one to one
(:func:`names_of`).
"""

from __future__ import annotations

import math

from mechcheck.analytic.case import Case, FourBarGeometry, Vec2
from mechcheck.analytic.joint_kinds import PRISMATIC, REVOLUTE
from mechcheck.analytic.kinematics import pose_of
from mechcheck.analytic.linkage import (
    Driver,
    Joint,
    JointFriction,
    Link,
    Linkage,
    LinkMass,
    PointLoad,
)

LINK_NAMES = {2: "crank", 3: "coupler"}

#: Legacy quantity → linkage quantity (forces, torques).
LEGACY_NAMES = {
    "F12_x": "F_A0_x", "F12_y": "F_A0_y", "F23_x": "F_A_x", "F23_y": "F_A_y",
    "F34_x": "F_B_x", "F34_y": "F_B_y", "T12": "Q_A0",
}
FOUR_BAR_NAMES = LEGACY_NAMES | {"F14_x": "F_B0_x", "F14_y": "F_B0_y"}
SLIDER_CRANK_NAMES = LEGACY_NAMES | {"F14_x": "F_slide_x", "F14_y": "F_slide_y",
                                     "M14": "M_slide"}


def names_of(case: Case) -> dict[str, str]:
    """Legacy quantity → linkage quantity for ``case`` (its drive torque included)."""
    names = FOUR_BAR_NAMES if case.mechanism == "four_bar" else SLIDER_CRANK_NAMES
    if case.drive_link == 4:
        names = {k: v for k, v in names.items() if k != "T12"} | {"T14": "Q_B0"}
    return names


def link_name(case: Case, link: int) -> str:
    if link == 4:
        return "rocker" if case.mechanism == "four_bar" else "slider"
    return LINK_NAMES[link]


def linkage_of(case: Case) -> Linkage:
    """The case's mechanism as a linkage drawn at the case's pose, driven at A0, or at B0
    for ``drive_link = 4``.

    LINKAGES.md gives ``drive_link = 4`` no direct spelling because its motion is prescribed
    through link 2; at one instant of a one-freedom linkage that motion is the rocker's
    ω14, α14 (from the crank's, by the velocity and acceleration analysis), so a driver on
    B0 with those rates is the same problem, and the same state at the reading.
    """
    pose = pose_of(case)

    def drawn(link: int, local: Vec2) -> Vec2:
        x, y = pose.point(link, local)[0][0]
        return (float(x), float(y))

    points = {name: (float(p[0][0]), float(p[0][1])) for name, p in pose.joints.items()}
    rocker = link_name(case, 4)
    links = [Link("ground", ("A0", "B0") if "B0" in points else ("A0",)),
             Link("crank", ("A0", "A")), Link("coupler", ("A", "B")),
             Link(rocker, ("B0", "B") if "B0" in points else ("B",))]
    joints = [Joint("A0", REVOLUTE, ("ground", "crank"), "A0"),
              Joint("A", REVOLUTE, ("crank", "coupler"), "A"),
              Joint("B", REVOLUTE, ("coupler", rocker), "B")]
    if isinstance(case.geometry, FourBarGeometry):
        joints.append(Joint("B0", REVOLUTE, ("ground", rocker), "B0"))
    else:
        axis = (math.cos(case.ground_angle), math.sin(case.ground_angle))
        joints.append(Joint("slide", PRISMATIC, ("ground", rocker), "B", axis))
    return Linkage(
        points=points, links=tuple(links), joints=tuple(joints),
        drivers=(_driver_of(case),),
        loads=tuple(PointLoad(link_name(case, ld.link), drawn(ld.link, ld.at), ld.force, ld.torque)
                    for ld in case.loads),
        masses=tuple(LinkMass(link_name(case, m.link), m.mass, drawn(m.link, m.com), m.inertia)
                     for m in case.masses),
        gravity=case.gravity,
        friction=_friction_of(case),
    )


def _driver_of(case: Case) -> Driver:
    sense = case.input_sense if case.has_coulomb_friction and not case.motion.omega else 0
    if case.drive_link == 2:
        return Driver("A0", 0.0, case.motion.omega, case.motion.alpha, sense)
    rocker = pose_of(case).links[4]
    # The rocker's sense of a quasi-static motion: the crank's times dθ14/dθ12.
    ratio = float(pose_of(case, omega=1.0, alpha=0.0).links[4].omega[0])
    return Driver("B0", 0.0, float(rocker.omega[0]), float(rocker.alpha[0]),
                  sense * (1 if ratio > 0 else -1))


def _friction_of(case: Case) -> JointFriction | None:
    f = case.friction
    if f is None:
        return None
    joint_mu = {"slide": f.slide_coefficient()} if case.mechanism == "slider_crank" else {}
    return JointFriction(mu=f.mu, pin_radius=dict(f.pin_radius), joint_mu=joint_mu,
                         viscous=dict(f.viscous))
