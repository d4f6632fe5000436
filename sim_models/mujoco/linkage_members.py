"""Elastic members of a redundant linkage in the MuJoCo model.

Where a linkage's joints are redundant, its members' stretch decides the reactions
(``axial_stiffness``, E·A). Each such member is two bodies: the link's own body, which
hangs from the member's tree joint at its *near* end, and a *far* body on a slide along
the member's axis that carries the other end (every site, closure and child body at
that point). No joint stiffness: an explicit spring of E·A/L ~ 1e8–1e11 N/m is unstable
at a settling time step. The member's length is held by a tendon equality between a site
at each end, made soft with a negative ``solref`` = (−s, −b): MuJoCo's constraint solver
then gives, at rest, the force s/((1 − d)·w)·(L − L₀), w the tendon's inverse weight
``tendon_invweight0`` and d the impedance (dmin = dmax), solved implicitly (the stretch
mode is as if its mass were m/(1 − d)). ``s`` is set after compiling, once w is known
(:func:`set_member_stiffness`), so the force is E·A/L per metre of stretch. The member's
tension N is minus that equality's force (efc_force), which is ∫N dx/L, less what that
exceeds the mean of the tensions just inside the two ends by where the member carries loads
of its own away from its middle (:func:`stretch_excess_along`): the mean is its
``N_<link>``.

Only redundant linkages are split: elsewhere statics alone decides the forces, and the
model stays as it is.
"""

from __future__ import annotations

from collections.abc import Mapping

import mujoco
import numpy as np

from mechcheck.analytic.linkage import Link, Linkage
from mechcheck.analytic.linkage_elastic import stretch_excess

#: Impedance of a member's equality (MuJoCo's largest, mjMAXIMP): the stretch mode moves
#: as if its mass were 1/(1 − d) = 1e4 times larger, which keeps it stable at the
#: settling time step even at E·A/L ~ 1e11 N/m.
MEMBER_IMPEDANCE = 0.9999
#: solimp of a member's equality: d at every stretch.
MEMBER_SOLIMP = (MEMBER_IMPEDANCE, MEMBER_IMPEDANCE, 0.001, 0.5, 2.0)
#: The stretch mode's damping ratio (critical: it settles without ringing).
MEMBER_DAMPING_RATIO = 1.0
#: ω·dt of a member's stretch mode on its far body (:func:`far_mass`): well inside Euler's
#: stable range, and no slower than it needs to be.
STRETCH_STEP_PHASE = 0.3


def far_mass(member: Link, length: float, timestep: float) -> float:
    """The far body's mass (kg): the stretch mode, a spring of E·A/L on a mass m/(1 − d),
    turns by :data:`STRETCH_STEP_PHASE` per step. Heavier is as stable but noisier: the
    constraint's damping, ~2·√(k·m/(1 − d)), multiplies the velocities' rounding into its
    force."""
    assert member.axial_stiffness is not None
    stiffness = member.axial_stiffness / length
    return stiffness * (1.0 - MEMBER_IMPEDANCE) * (timestep / STRETCH_STEP_PHASE) ** 2


def split_members(linkage: Linkage) -> tuple[Link, ...]:
    """The members built as two bodies: the elastic links of a redundant linkage."""
    return linkage.elastic_links if linkage.redundant else ()


def stretch_excess_along(linkage: Linkage, member: Link) -> float:
    """What the member's equality force (∫N dx/L) exceeds its ``N_<link>`` by, along its
    drawn axis (:func:`mechcheck.analytic.linkage_elastic.stretch_excess`; the axis turns by
    the strain, which moves this by that fraction of it)."""
    a, b = (np.asarray(linkage.points[p]) for p in member.points)
    return float((b - a) @ stretch_excess(linkage, member)) / float(np.hypot(*(b - a)))


def far_body_name(link: str) -> str:
    return f"link_{link}_far"


def stretch_name(link: str) -> str:
    """The slide joint between a member's two bodies, and its tendon and equality."""
    return f"stretch_{link}"


def end_sites(link: str) -> tuple[str, str]:
    """The member's tendon sites: near end (on the link's body), far end (far body)."""
    return f"{link}_near_end", f"{link}_far_end"


def far_point(member: Link, near: str) -> str:
    """The member's point that is not ``near`` (its tree joint's point)."""
    return member.points[1] if member.points[0] == near else member.points[0]


def member_ends(member: Link, near: str, points: Mapping[str, tuple[float, float]]
                ) -> tuple[tuple[float, float], tuple[float, float]]:
    """The drawn near and far ends of a member whose tree joint is at ``near``."""
    return points[near], points[far_point(member, near)]


def far_site(site: str) -> str:
    """The far body's twin of a load's site on a split member (:func:`far_share`)."""
    return f"{site}_far"


def far_share(near: tuple[float, float], far: tuple[float, float],
              at: tuple[float, float]) -> float:
    """The part of a load at ``at`` on a split member that its far body takes: t, the
    load's place from the near end to the far end (0 to 1); the near body takes 1 − t.
    Then the spring between them carries the far end's tension plus t times the load's
    axial part, and stretches as the whole member does under a load at t
    (∫N dx/(E·A)); at t = ½, as a weight at the middle, it carries the mean of the end
    tensions, which is the member's N."""
    d = np.subtract(far, near)
    t = float(np.dot(np.subtract(at, near), d) / np.dot(d, d))
    return min(max(t, 0.0), 1.0)


def add_far_body(body: mujoco.MjsBody, member: Link, near: tuple[float, float],
                 far: tuple[float, float], origin: tuple[float, float], timestep: float,
                 armature: float) -> mujoco.MjsBody:
    """The member's far body (:func:`far_mass`) on a slide along the member, from ``near``
    to ``far`` (drawn points), with its frame on the link's body (``origin``), and the two
    end sites."""
    d = np.subtract(far, near)
    length = float(np.hypot(*d))
    u = d / length
    mass = far_mass(member, length, timestep)
    at = [far[0] - origin[0], far[1] - origin[1], 0.0]
    child = body.add_body(name=far_body_name(member.name), pos=[0.0, 0.0, 0.0], mass=mass,
                          ipos=at, inertia=[mass, mass, mass], explicitinertial=True)
    child.add_joint(name=stretch_name(member.name), type=mujoco.mjtJoint.mjJNT_SLIDE,
                    axis=[float(u[0]), float(u[1]), 0.0], armature=armature)
    near_site, far_site = end_sites(member.name)
    body.add_site(name=near_site, pos=[near[0] - origin[0], near[1] - origin[1], 0.0])
    child.add_site(name=far_site, pos=at)
    return child


def add_member_equality(spec: mujoco.MjSpec, member: Link) -> None:
    """The tendon between the member's end sites, held at its drawn length by a soft
    tendon equality (its stiffness is set after compiling, :func:`set_member_stiffness`)."""
    tendon = spec.add_tendon(name=stretch_name(member.name))
    for site in end_sites(member.name):
        tendon.wrap_site(site)
    spec.add_equality(name=stretch_name(member.name), type=mujoco.mjtEq.mjEQ_TENDON,
                      objtype=mujoco.mjtObj.mjOBJ_TENDON, name1=stretch_name(member.name),
                      solref=[-1.0, -1.0], solimp=list(MEMBER_SOLIMP))


def member_solref(model: mujoco.MjModel, member: Link, tendon: int) -> tuple[float, float]:
    """(−s, −b) that make the member's equality a spring of E·A/L (N/m) at rest, and
    critically damped in MuJoCo's stretch dynamics (r̈ = −s·r − b·ṙ at d → 1)."""
    assert member.axial_stiffness is not None
    length = float(model.tendon_length0[tendon])
    weight = float(model.tendon_invweight0[tendon])
    s = member.axial_stiffness / length * (1.0 - MEMBER_IMPEDANCE) * weight
    return -s, -2.0 * MEMBER_DAMPING_RATIO * float(np.sqrt(s))


def set_member_stiffness(model: mujoco.MjModel, members: tuple[Link, ...]) -> list[int]:
    """Set each member equality's solref (:func:`member_solref`); their equality ids."""
    ids = []
    for member in members:
        name = stretch_name(member.name)
        eq = int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_EQUALITY, name))
        tendon = int(mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TENDON, name))
        model.eq_solref[eq] = member_solref(model, member, tendon)
        ids.append(eq)
    return ids


