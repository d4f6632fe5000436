"""Pure builder: any :class:`~mechcheck.analytic.linkage.Linkage` → ``MjSpec`` (issue 12).

The joint graph (links are nodes, joints edges) is cut to a spanning tree rooted at the
ground (:func:`spanning_tree`). Each link is a body; each tree joint is the MuJoCo joints
of its child body that :mod:`.joint_kinds` gives its kind (a hinge, a slide, or for a pin
in a slot a slide and a hinge); every joint left out of the tree closes a loop and must be
revolute: it becomes a ``connect`` equality between two sites at its point (sites, because
a body-anchored connect takes its second anchor from ``qpos0``). A loop with no revolute
joint cannot be closed that way and is refused (:class:`Unbuildable`). A gear mesh never
enters the tree: it closes the loop through its gears' bearings as a tendon on its line of
action held by a tendon equality (:mod:`.linkage_mesh`); a gear held by meshes alone is
refused.

Frames: every body is built with the orientation of the world and its origin at the point
of its tree joint in the drawn pose, so ``qpos = 0`` is the drawn pose. A tree joint's
axis is +z (hinge) or +u (slide) when its parent is the joint's ``links[0]``, and reversed
when the tree runs the other way, so that each joint's ``qpos`` is its LINKAGES.md
coordinate q whichever way the tree runs, and a generalised force on it is its effort
(a driver's Q, a torsional spring's −S); a pin's free turn in its slot is about +z.

- drivers: a joint equality on the driven tree joint (held at ``eq_data[id, 0]``);
- linear springs: spatial tendons between two sites, with MuJoCo's stiffness and spring
  length (and damping): the spring force is MuJoCo's passive force;
- torsional springs: the hinge's stiffness with ``springref`` = the free rotation;
- elastic members of a redundant linkage: two bodies on a slide, held at the member's
  length by a soft tendon equality of E·A/L (:mod:`.linkage_members`);
- loads and weights: ``xfrc_applied`` at sites, computed each step (:mod:`.linkage_rig`);
  MuJoCo's gravity is off, so statics may use fictitious masses (as :mod:`.model`).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterator
from dataclasses import dataclass, field

import mujoco
import numpy as np

from mechcheck.analytic.linkage import Joint, LinearSpring, Link, Linkage, TorsionSpring
from mechcheck.analytic.values import GROUND
from mechcheck.sim_models.inertia import Inertial, link_extent, real_inertial
from mechcheck.sim_models.linkage_motion import unmodelled
from mechcheck.sim_models.mujoco import mjwarnings  # noqa: F401  (MuJoCo warnings into Python before any model)
from mechcheck.sim_models.mujoco.joint_kinds import BUILDS, builder_of
from mechcheck.sim_models.mujoco.linkage_members import (
    add_far_body,
    add_member_equality,
    far_point,
    far_site,
    split_members,
)
from mechcheck.sim_models.mujoco.linkage_mesh import drawn_sites, site_names, tendon_name
from mechcheck.sim_models.mujoco.model import (
    CLOCK_ARMATURE,
    DRIVE_ARMATURE_INERTIA,
    SETTLE_MASS,
    SOLVER_TOLERANCE,
    STATIC,
    Settings,
)


class Unbuildable(ValueError):
    """The linkage has no MuJoCo model in this builder; the message says why."""


@dataclass(frozen=True)
class TreeJoint:
    """A joint of the spanning tree: ``child`` hangs from ``parent`` through it;
    ``sign`` is +1 when the parent is the joint's ``links[0]``, else −1."""

    joint: Joint
    parent: str
    child: str
    sign: float


@dataclass(frozen=True)
class LinkageTree:
    """The spanning tree (parents before children) and the loop-closing joints."""

    tree: tuple[TreeJoint, ...]
    closures: tuple[Joint, ...]
    #: Gear meshes: each closes its loop as a tendon on its line of action (:mod:`.linkage_mesh`).
    meshes: tuple[Joint, ...] = ()

    def parent_joint(self, link: str) -> TreeJoint:
        return next(t for t in self.tree if t.child == link)



def _priority(linkage: Linkage, joint: Joint) -> int:
    """Order in which joints enter the tree: joints that cannot close a loop first
    (prismatic joints, pins in slots: a loop can only be closed at a revolute joint,
    :mod:`.joint_kinds`), then driven joints (a joint equality needs a MuJoCo
    joint), then joints with a torsional spring (joint stiffness), then the rest."""
    if not builder_of(joint).closes_loops:
        return 0
    if any(d.joint == joint.name for d in linkage.drivers):
        return 1
    if _torsion(linkage, joint)[0] or joint_damping(linkage, joint):
        return 2
    return 3


def spanning_tree(linkage: Linkage) -> LinkageTree:
    """Kruskal's spanning tree in :func:`_priority` order, then oriented from the ground.

    Raises :class:`Unbuildable` for a loop without a revolute joint, and for a driver or a
    torsional spring on a joint that must close a loop (a damper there is emulated).
    """
    why = unmodelled(linkage, BUILDS, "MuJoCo", stretches=True)
    if why is not None:
        raise Unbuildable(why)
    meshes = tuple(j for j in linkage.joints if builder_of(j).meshes)
    order = sorted((j for j in linkage.joints if j not in meshes),
                   key=lambda j: _priority(linkage, j))
    root = {link.name: link.name for link in linkage.links}

    def find(n: str) -> str:
        while root[n] != n:
            root[n] = root[root[n]]
            n = root[n]
        return n

    chosen: list[Joint] = []
    closures: list[Joint] = []
    for joint in order:
        a, b = (find(n) for n in joint.links)
        if a != b:
            root[a] = b
            chosen.append(joint)
            continue
        why = _closure_refusal(linkage, chosen, joint)
        if why is not None:
            raise Unbuildable(why)
        closures.append(joint)
    tree = LinkageTree(_oriented(chosen), tuple(j for j in linkage.joints if j in closures), meshes)
    why = _unborne(linkage, tree)
    if why is not None:
        raise Unbuildable(why)
    return tree


def _unborne(linkage: Linkage, tree: LinkageTree) -> str | None:
    """Why a link is not in the tree: it hangs on gear meshes alone (a mesh is never a tree
    joint: it closes the loop through the bearings that carry its gears)."""
    reached = {GROUND} | {t.child for t in tree.tree}
    loose = [link for link in linkage.moving_links if link not in reached]
    if not loose:
        return None
    return (f"link {loose[0]} is held by gear meshes alone: the MuJoCo model carries every gear "
            "on a joint of its own (a bearing) and closes the loop through it with the mesh")


def _closure_refusal(linkage: Linkage, chosen: list[Joint], joint: Joint) -> str | None:
    """Why ``joint`` cannot close the loop it makes with the tree joints ``chosen``, or None.
    Only a joint that carries a force in every direction at a point and no couple closes
    a loop (a connect); a damper there is a couple from the joint's rate
    (LinkageRig.apply_loads), but a driver or a torsional spring needs a MuJoCo joint."""
    if not builder_of(joint).closes_loops:
        loop = [*_path(chosen, *joint.links), joint.name]
        return (f"the loop through joints {', '.join(loop)} has no revolute joint: the MuJoCo "
                "model closes every loop with a connect at a revolute joint")
    if _priority(linkage, joint) == 1 or _torsion(linkage, joint)[0]:
        what = "driver" if _priority(linkage, joint) == 1 else "torsional spring"
        # Joints enter the tree in _priority order: the loop's tree joints cannot close it
        # or are driven (or carry a torsional spring).
        names = set(_path(chosen, *joint.links))
        kinds = sorted({j.kind.name for j in chosen
                        if j.name in names and not builder_of(j).closes_loops})
        return (f"the {what} at joint {joint.name} is on a joint that closes a loop of "
                f"{', '.join(kinds) or 'prismatic'} and driven joints: the MuJoCo model holds it only on "
                "a tree joint")
    return None


def _breadth_first(joints: list[Joint], start: str) -> Iterator[tuple[str, Joint, str]]:
    """(link, joint, other) for each link ``other`` first reached through ``joint`` from
    ``link``, breadth-first from ``start`` over ``joints`` in their order."""
    reached = {start}
    queue = deque([start])
    while queue:
        link = queue.popleft()
        for j in joints:
            if link in j.links:
                other = j.links[1] if j.links[0] == link else j.links[0]
                if other not in reached:
                    reached.add(other)
                    queue.append(other)
                    yield link, j, other


def _path(joints: list[Joint], start: str, goal: str) -> list[str]:
    """Names of the joints on the path from ``start`` to ``goal`` through ``joints``."""
    came: dict[str, tuple[str, str] | None] = {start: None}
    for link, j, other in _breadth_first(joints, start):
        came[other] = (link, j.name)
    names: list[str] = []
    step = came.get(goal)
    while step is not None:
        names.append(step[1])
        step = came[step[0]]
    return names[::-1]


def _oriented(joints: list[Joint]) -> tuple[TreeJoint, ...]:
    """The tree joints breadth-first from the ground, each with its parent and child."""
    return tuple(TreeJoint(j, link, other, 1.0 if j.links[0] == link else -1.0)
                 for link, j, other in _breadth_first(joints, GROUND))


# -- inertia ----------------------------------------------------------------------------

def centroid(linkage: Linkage, link: str) -> tuple[float, float]:
    xy = np.array([linkage.points[p] for p in next(k for k in linkage.links
                                                   if k.name == link).points])
    return float(xy[:, 0].mean()), float(xy[:, 1].mean())


def model_inertial(linkage: Linkage, link: str, settings: Settings) -> Inertial:
    """What the model gives a link: :data:`~.model.SETTLE_MASS` for statics; else its
    real mass, a fictitious one if massless (removed after compiling for the exact solve,
    :func:`use_real_inertia`), and a floor inertia for a point mass (MuJoCo refuses zero)."""
    length = link_extent(linkage, link)
    if settings.masses == "settle":
        m = settings.fictitious_scale * SETTLE_MASS
        return Inertial(m, centroid(linkage, link), m * length**2 / 12.0)
    real = real_inertial(linkage, link)
    if real is None:
        reference = max((m.mass for m in linkage.masses), default=1.0)
        m = settings.fictitious_scale * settings.fictitious_fraction * reference
        return Inertial(m, centroid(linkage, link), m * length**2 / 12.0)
    floor = settings.inertia_floor * real.mass * length**2
    return real if real.inertia >= floor else Inertial(real.mass, real.com,
                                                       real.inertia + floor)


# -- the spec ---------------------------------------------------------------------------

@dataclass
class Bodies:
    """The spec's bodies: each link's, and each split member's far body with its far end
    (:mod:`.linkage_members`), which carries everything at that point."""

    links: dict[str, mujoco.MjsBody]
    far: dict[str, tuple[tuple[float, float], mujoco.MjsBody]] = field(default_factory=dict)

    def at(self, link: str, p: tuple[float, float]) -> mujoco.MjsBody:
        """The body of ``link`` that carries the drawn point ``p``."""
        end = self.far.get(link)
        if end is not None and np.allclose(end[0], p, rtol=0.0, atol=1e-12 * max(1.0, *np.abs(p))):
            return end[1]
        return self.links[link]


def body_name(link: str) -> str:
    return f"link_{link}"


def origin_of(tree: LinkageTree, linkage: Linkage, link: str) -> tuple[float, float]:
    """A body's origin: its tree joint's point in the drawn pose (the world's: 0, 0)."""
    if link == GROUND:
        return (0.0, 0.0)
    return linkage.points[tree.parent_joint(link).joint.at]


def local(tree: LinkageTree, linkage: Linkage, link: str, p: tuple[float, float]) -> list[float]:
    """A drawn point in ``link``'s body frame (bodies are aligned with the world)."""
    o = origin_of(tree, linkage, link)
    return [p[0] - o[0], p[1] - o[1], 0.0]


def build_spec(name: str, linkage: Linkage, settings: Settings = STATIC) -> mujoco.MjSpec:
    """The MuJoCo model of ``linkage`` as an MjSpec (pure: a new spec every call).

    Raises :class:`Unbuildable` (see :func:`spanning_tree`).
    """
    tree = spanning_tree(linkage)
    spec = mujoco.MjSpec()
    spec.modelname = name
    spec.compiler.degree = False
    _options(spec, settings)
    bodies = Bodies({GROUND: spec.worldbody})
    members = {m.name: m for m in split_members(linkage)}
    for t in tree.tree:
        at = linkage.points[t.joint.at]
        body = bodies.links[t.child] = _add_body(bodies.at(t.parent, at), tree, linkage, t, settings)
        if t.child in members:
            bodies.far[t.child] = _add_far(body, tree, linkage, members[t.child], t, settings)
    _add_point_sites(bodies, tree, linkage)
    _add_load_sites(bodies, tree, linkage)
    for joint in tree.closures:
        _add_closure(spec, bodies, tree, linkage, joint, settings)
    for joint in tree.meshes:
        _add_mesh(spec, bodies, tree, linkage, joint, settings)
    for spring in linkage.springs:
        _add_spring(spec, bodies, tree, linkage, spring)
    for member in members.values():
        add_member_equality(spec, member)
    if settings.clock:
        _add_clock(spec)
    for driver in linkage.drivers:
        # Held: q = value. Driven: q = value + v·t + a·t²/2 of the clock's angle t
        # (:func:`_add_clock`), so the prescribed motion is exact at every step.
        spec.add_equality(name=f"drive_{driver.joint}", type=mujoco.mjtEq.mjEQ_JOINT,
                          name1=driver.joint, name2=CLOCK if settings.clock else "",
                          data=[driver.value] + [0.0] * 11,
                          solref=list(settings.solref), solimp=list(settings.solimp))
    return spec


#: The clock hinge of a driven run: it turns at 1 rad/s, so its angle is the time t
#: (0 at the instant read), and every driver's equality is a polynomial in it.
CLOCK = "clock"


def _add_clock(spec: mujoco.MjSpec) -> None:
    """A separate grounded body with the clock hinge: an armature of
    :data:`~.model.CLOCK_ARMATURE` makes the drivers' reactions change its unit speed by
    ~1e-8 rad/s²."""
    body = spec.worldbody.add_body(name=CLOCK, mass=1.0, inertia=[1.0, 1.0, 1.0],
                                   explicitinertial=True)
    body.add_joint(name=CLOCK, type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0.0, 0.0, 1.0],
                   armature=CLOCK_ARMATURE)


def drive_armature(linkage: Linkage, joint: Joint, settings: Settings) -> float:
    """The extra armature of a driven joint in a driven run (see
    :data:`~.model.DRIVE_ARMATURE_INERTIA`): of the order of the real links' inertia
    (hinge, kg·m²) or mass (slide, kg); subtracted exactly from the driver's effort."""
    if not settings.drive_armature or not any(d.joint == joint.name for d in linkage.drivers):
        return 0.0
    reference = max((m.mass for m in linkage.masses), default=1.0)
    lever = linkage.scale**2 if builder_of(joint).coordinate_is_angle(joint) else 1.0
    return DRIVE_ARMATURE_INERTIA * reference * lever


def _options(spec: mujoco.MjSpec, settings: Settings) -> None:
    """The model's options."""
    opt = spec.option
    opt.timestep = settings.timestep
    opt.gravity = [0.0, 0.0, 0.0]  # weights are loads on the real masses only
    opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)  # links overlap in the plane
    opt.jacobian = int(mujoco.mjtJacobian.mjJAC_DENSE)  # efc_J read as a dense matrix
    opt.integrator = int(mujoco.mjtIntegrator.mjINT_EULER)
    # Newton's default tolerance (1e-8) stops with a residual acceleration that makes the
    # heavy links creep: the forces then drift by ~1e-8 per step and never settle. The
    # tolerance is relative to the whole problem, which the 1e9 clock armature dominates:
    # 1e-12 still left 7e-5 N·m of step-to-step noise in a clock-driven torque, 1e-16
    # leaves 2e-9 (measured on the four-bar). Newton still stops after one iteration (the
    # problem is quadratic).
    opt.tolerance = SOLVER_TOLERANCE


def _add_body(parent: mujoco.MjsBody, tree: LinkageTree, linkage: Linkage, t: TreeJoint,
              settings: Settings) -> mujoco.MjsBody:
    """The child link of tree joint ``t`` with its hinge or slide."""
    inertial = model_inertial(linkage, t.child, settings)
    origin = origin_of(tree, linkage, t.child)
    parent_origin = origin_of(tree, linkage, t.parent)
    izz = inertial.inertia
    body = parent.add_body(
        name=body_name(t.child), pos=[origin[0] - parent_origin[0], origin[1] - parent_origin[1], 0.0],
        mass=inertial.mass, ipos=local(tree, linkage, t.child, inertial.com),
        # Only Izz matters for hinges about z; Ixx = Iyy = Izz passes MuJoCo's triangle check.
        inertia=[izz, izz, izz], explicitinertial=True)
    joint = t.joint
    for mj in builder_of(joint).joints(joint, t.sign):
        if mj.coordinate:  # the joint's driver, springs, dampers and armature act on q
            stiffness, springref = _torsion(linkage, joint)
            body.add_joint(name=mj.name, type=mj.type, axis=list(mj.axis),
                           armature=settings.armature + drive_armature(linkage, joint, settings),
                           stiffness=[stiffness, 0.0, 0.0], springref=springref,
                           damping=[joint_damping(linkage, joint), 0.0, 0.0])
        else:  # a free turn: only the armature every joint has (the exact solve's M)
            body.add_joint(name=mj.name, type=mj.type, axis=list(mj.axis),
                           armature=settings.armature)
    return body


def _add_far(body: mujoco.MjsBody, tree: LinkageTree, linkage: Linkage, member: Link,
             t: TreeJoint, settings: Settings) -> tuple[tuple[float, float], mujoco.MjsBody]:
    """A split member's far body (:func:`.linkage_members.add_far_body`) and its far end."""
    near = linkage.points[t.joint.at]
    far = linkage.points[far_point(member, t.joint.at)]
    return far, add_far_body(body, member, near, far, origin_of(tree, linkage, member.name),
                             settings.timestep, settings.armature)


def _torsion(linkage: Linkage, joint: Joint) -> tuple[float, float]:
    """(stiffness, free rotation) of the torsional springs at a joint (they add up)."""
    springs = [s for s in linkage.springs if isinstance(s, TorsionSpring) and s.joint == joint.name]
    k = sum(s.stiffness for s in springs)
    if k == 0.0:
        return 0.0, 0.0
    return k, sum(s.stiffness * s.free_rotation for s in springs) / k


def joint_damping(linkage: Linkage, joint: Joint) -> float:
    """Joint damping: the torsional springs' and the friction table's viscous terms."""
    damping = sum(s.damping for s in linkage.springs
                  if isinstance(s, TorsionSpring) and s.joint == joint.name)
    if linkage.friction is not None:
        damping += linkage.friction.viscous.get(joint.name, 0.0)
    return damping


def _carrier(linkage: Linkage, point: str) -> str:
    """The link a point is reported on (the first that carries it, as the analytic side)."""
    return next(link.name for link in linkage.links if point in link.points)


def _add_point_sites(bodies: Bodies, tree: LinkageTree,
                     linkage: Linkage) -> None:
    """A site at every named point, on the link it is reported on: x_, y_ are read there."""
    for name, p in linkage.points.items():
        link = _carrier(linkage, name)
        bodies.at(link, p).add_site(name=f"point_{name}", pos=local(tree, linkage, link, p))


def _add_load_sites(bodies: Bodies, tree: LinkageTree,
                    linkage: Linkage) -> None:
    """A site at every load point and centre of mass (where weights act), and on a split
    member its twin on the far body (:func:`.linkage_members.far_share`)."""
    places = [(f"load{i}", load.link, load.at) for i, load in enumerate(linkage.loads)]
    places += [(f"weight{i}", m.link, m.com) for i, m in enumerate(linkage.masses)]
    for name, link, p in places:
        pos = local(tree, linkage, link, p)
        bodies.links[link].add_site(name=name, pos=pos)
        if link in bodies.far:
            bodies.far[link][1].add_site(name=far_site(name), pos=pos)


def closure_sites(joint: Joint) -> tuple[str, str]:
    """The connect's two sites: the first on ``links[1]``, whose body receives the
    connect force with a + sign, so the equality force is F_<joint> (by links[0] on
    links[1])."""
    return f"{joint.name}_on_{joint.links[1]}", f"{joint.name}_on_{joint.links[0]}"


def _add_closure(spec: mujoco.MjSpec, bodies: Bodies, tree: LinkageTree,
                 linkage: Linkage, joint: Joint, settings: Settings) -> None:
    p = linkage.points[joint.at]
    first, second = closure_sites(joint)
    for site, link in ((first, joint.links[1]), (second, joint.links[0])):
        bodies.at(link, p).add_site(name=site, pos=local(tree, linkage, link, p))
    spec.add_equality(name=f"loop_{joint.name}", type=mujoco.mjtEq.mjEQ_CONNECT,
                      objtype=mujoco.mjtObj.mjOBJ_SITE, name1=first, name2=second,
                      solref=list(settings.solref), solimp=list(settings.solimp))


def _add_mesh(spec: mujoco.MjSpec, bodies: Bodies, tree: LinkageTree,
              linkage: Linkage, joint: Joint, settings: Settings) -> None:
    """A gear mesh: a straight tendon from a site on gear a to one on gear b along the line
    of action, held at its length by a tendon equality (:mod:`.linkage_mesh`)."""
    tendon = spec.add_tendon(name=tendon_name(joint))
    for site, link, p in zip(site_names(joint), joint.links, drawn_sites(linkage, joint), strict=True):
        bodies.at(link, p).add_site(name=site, pos=local(tree, linkage, link, p))
        tendon.wrap_site(site)
    spec.add_equality(name=tendon_name(joint), type=mujoco.mjtEq.mjEQ_TENDON,
                      objtype=mujoco.mjtObj.mjOBJ_TENDON, name1=tendon_name(joint),
                      solref=list(settings.solref), solimp=list(settings.solimp))


def _add_spring(spec: mujoco.MjSpec, bodies: Bodies, tree: LinkageTree,
                linkage: Linkage, spring: LinearSpring | TorsionSpring) -> None:
    """A linear spring as a spatial tendon between two sites (torsional: joint stiffness)."""
    if isinstance(spring, TorsionSpring):
        return
    tendon = spec.add_tendon(name=f"spring_{spring.name}", stiffness=[spring.stiffness, 0.0, 0.0],
                             springlength=[spring.free_length, spring.free_length],
                             damping=[spring.damping, 0.0, 0.0])
    for k, (link, p) in enumerate(spring.ends):
        site = f"{spring.name}_end{k}"
        bodies.at(link, p).add_site(name=site, pos=local(tree, linkage, link, p))
        tendon.wrap_site(site)


def model_xml(name: str, linkage: Linkage, settings: Settings = STATIC) -> str:
    """The model as MJCF text (committed as golden files for review)."""
    return str(build_spec(name, linkage, settings).to_xml())
