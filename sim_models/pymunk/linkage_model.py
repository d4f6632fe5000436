"""Linkage → pymunk Space: one builder for any planar linkage (LINKAGES.md).

Frames. Every moving link is one dynamic body whose local coordinates are the
**drawn pose's** global coordinates: a point drawn at P0 on link k is at
R(φ_k)·P0 + t_k, with the body's angle φ_k and position (origin) t_k — exactly
the linkage's own coordinates (:mod:`mechcheck.analytic.linkage_kinematics`). So
every anchor, load point, centre of mass and spring end of the Linkage is used
unchanged, and the ground is the space's static body (its frame is the world).

Joints are pymunk's own constraints, body a = ``links[0]``, body b = ``links[1]``,
so the impulse a constraint accumulates on body b is the force *by* links[0]
*on* links[1] (LINKAGES.md). Which constraints each kind of joint is, how a
driver's lock holds it and where its reaction is read: :mod:`.joint_kinds`, the
one place that knows joint kinds.

Springs are pymunk's own: a :class:`pymunk.DampedSpring` between the two ends
(rest length L0) and a :class:`pymunk.DampedRotarySpring` per torsional spring.
Chipmunk's rotary spring measures the angle of body a relative to body b
(torque on b = k·(φ_a − φ_b − rest)), the opposite of its documented sense, so
its rest angle is −q0 here; both springs' signed ``impulse`` is the impulse they
applied to body b along b − a (linear) or CCW (rotary), so S = −impulse / dt.

Bodies get equal fictitious masses (statics: inertia is irrelevant at rest);
real weights are applied as forces (:mod:`mechcheck.sim_models.pymunk.loads`).
No collision shapes are added, so nothing collides.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import pymunk

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage import Joint, LinearSpring, Link, Linkage
from mechcheck.analytic.linkage_backends import quantity_units
from mechcheck.analytic.linkage_kinematics import Array
from mechcheck.analytic.values import GROUND
from mechcheck.sim_models.inertia import Inertial, real_inertial
from mechcheck.sim_models.pymunk import _fast
from mechcheck.sim_models.pymunk._fast import Bodies, Cell, Plan, impulse_cells
from mechcheck.sim_models.pymunk.gear_mesh import ToothContact
from mechcheck.sim_models.pymunk.joint_kinds import GROOVE_REACH as GROOVE_REACH, along as along, builder
from mechcheck.sim_models.pymunk.loads import LoadTerms, apply_forces
from mechcheck.sim_models.pymunk.members import MemberEnd, build_end, modelled, sliding_ends
from mechcheck.sim_models.pymunk.readout import HeldSlide, Readout
from mechcheck.sim_models.pymunk.settings import SolverSettings

Vec = tuple[float, float]
Spring = pymunk.DampedSpring | pymunk.DampedRotarySpring

#: Smallest radius of gyration of a fictitious body, as a fraction of the linkage's
#: size: a link carrying one point (a slider) still needs a finite moment of inertia.
MIN_RADIUS = 0.25
#: In a driven run, a massless link's fictitious mass as a fraction of the heaviest real
#: mass (1 kg without one). Its inertia forces are removed exactly by extrapolation (with
#: the motion prescribed every reaction is affine in it), so its size only sets how well
#: Chipmunk's Gauss–Seidel converges, which is slowest across large mass ratios: a random
#: six-bar with 1.9 kg and 1.5 kg links was ``not_settled`` after 25 200 steps at 1e-2
#: (MuJoCo's fraction; its solver is direct), took 6 800 at 0.1 and 1 100 at 1.
FICTITIOUS_FRACTION = 1.0
#: In a driven run, the smallest moment of a link about its centre of mass, × m·r² (r the
#: reach of its points from it): below it the link gets that much fictitious moment
#: (removed again). Measured on the random four-bar of :func:`moment_floor`: 1e-2 took
#: 400 iterations and 6 800 steps, 0.1 took 100 and 500.
MOMENT_FLOOR = 0.1


@dataclass
class LinkageModel:
    """A built pymunk linkage and a handle on every constraint that carries a force.

    ``pins`` (revolute joints), ``grooves`` (free sliding joints: prismatic, pin in a
    slot), ``held`` (driven sliding joints: a pivot), ``locks`` (the prismatic joints'
    angle locks), ``drives`` (driven revolute joints), ``springs``; ``radius`` per body
    for speeds; which joint goes in which table is :mod:`.joint_kinds`'.
    For loops that read or write every step: ``scale`` (the linkage's, which
    :attr:`Linkage.scale` computes anew each time), ``radii`` (``radius`` as an array), ``bulk``
    (the bodies in bulk), ``loads`` (the loads' force and torque per body) and ``readout``
    (the reactions as a vector).
    """

    case: Case
    settings: SolverSettings
    space: pymunk.Space
    bodies: dict[str, pymunk.Body]
    pins: dict[str, pymunk.PivotJoint]
    grooves: dict[str, pymunk.GrooveJoint]
    held: dict[str, pymunk.PivotJoint]
    locks: dict[str, pymunk.GearJoint]
    drives: dict[str, pymunk.GearJoint]
    springs: dict[str, Spring]
    radius: dict[str, float]
    meshes: dict[str, ToothContact] = field(default_factory=dict)
    members: dict[str, MemberEnd] = field(default_factory=dict)
    scale: float = field(init=False)
    radii: np.ndarray = field(init=False)
    bulk: Bodies = field(init=False)
    loads: LoadTerms = field(init=False)
    readout: Readout = field(init=False)

    @property
    def linkage(self) -> Linkage:
        return self.case.linkage

    def body(self, link: str) -> pymunk.Body:
        """The link's body; the ground is the space's static body."""
        return self.space.static_body if link == GROUND else self.bodies[link]

    def constraints(self) -> list[pymunk.Constraint]:
        return [*self.pins.values(), *self.grooves.values(), *self.held.values(),
                *self.locks.values(), *self.drives.values(), *self.springs.values(),
                *(mesh.pin for mesh in self.meshes.values()),
                *(c for end in self.members.values() for c in (end.groove, end.spring))]

    @cached_property
    def plan(self) -> Plan:
        """Where the compiled settling loop reads and writes (:mod:`._fast.compiled`)."""
        return _fast.plan(self)


def centroid(linkage: Linkage, link: str) -> Vec:
    """The mean of the link's drawn points: where its fictitious mass sits."""
    xy = np.array([linkage.points[p] for p in _link(linkage, link).points])
    return float(xy[:, 0].mean()), float(xy[:, 1].mean())


def gyration_radius(linkage: Linkage, link: str) -> float:
    """The farthest of the link's points from its centroid, at least MIN_RADIUS × size."""
    return reach(linkage, link, centroid(linkage, link))


def reach(linkage: Linkage, link: str, about: Vec) -> float:
    """The farthest of the link's points from ``about``, at least MIN_RADIUS × size."""
    far = max(math.hypot(linkage.points[p][0] - about[0], linkage.points[p][1] - about[1])
              for p in _link(linkage, link).points)
    return max(far, MIN_RADIUS * linkage.scale)


def _link(linkage: Linkage, name: str) -> Link:
    return next(link for link in linkage.links if link.name == name)


def make_bodies(linkage: Linkage, settings: SolverSettings,
                driven: bool = False) -> dict[str, pymunk.Body]:
    """One dynamic body per moving link. Statics: the fictitious mass at the link's
    centroid, with the moment of a uniform bar of half-length ``gyration_radius``
    (m·r²/3). ``driven``: the link's real inertia (:func:`driven_inertial`)."""
    bodies = {}
    for link in linkage.moving_links:
        if driven:
            mass, moment, cog = driven_inertial(linkage, link, settings)
        else:
            mass = settings.fictitious_mass
            moment, cog = mass * gyration_radius(linkage, link) ** 2 / 3.0, centroid(linkage, link)
        body = pymunk.Body(mass, moment)
        body.center_of_gravity = cog
        bodies[link] = body
    return bodies


def driven_inertial(linkage: Linkage, link: str, settings: SolverSettings
                    ) -> tuple[float, float, Vec]:
    """(mass, moment about the centre of mass, centre of mass) of a link in a driven run.

    A massless link gets :data:`FICTITIOUS_FRACTION` of the heaviest real mass as a bar
    (m·r²/3) at its centroid; a real mass whose moment is below ``MOMENT_FLOOR`` × m·r²
    (a point mass: pymunk needs a positive moment) gets that much more. Both are ×
    ``fictitious_scale``, so a reading removes them by extrapolation to zero
    (:func:`mechcheck.sim_models.convergence.massless_limit`). In a quasi-static run every
    link's inertia is fictitious, real masses' included.
    """
    k, r = settings.fictitious_scale, gyration_radius(linkage, link)
    real = real_inertial(linkage, link)
    if real is None:
        m = k * FICTITIOUS_FRACTION * max((m.mass for m in linkage.masses), default=1.0)
        return m, m * r * r / 3.0, centroid(linkage, link)
    floor = moment_floor(linkage, link, real)
    if settings.quasi_static:
        return k * real.mass, k * max(real.inertia, floor), real.com
    moment = real.inertia + (k * floor if real.inertia < floor else 0.0)
    return real.mass, moment, real.com


def moment_floor(linkage: Linkage, link: str, real: Inertial) -> float:
    """``MOMENT_FLOOR`` × m·r², r the reach of the link's points from its centre of mass:
    a point mass far from its joints (a lever) needs a moment to match, or Gauss–Seidel
    converges slowly (a random four-bar's crank, its point mass 0.5 m off its 0.33 m
    length, was ``not_settled`` with r measured from the link's centroid)."""
    return MOMENT_FLOOR * real.mass * reach(linkage, link, real.com) ** 2


def has_fictitious_inertia(linkage: Linkage, quasi_static: bool = False) -> bool:
    """True when a driven model gives some link inertia the Case does not (a quasi-static
    run: every link's, :func:`driven_inertial`)."""
    if quasi_static:
        return True
    for link in linkage.moving_links:
        real = real_inertial(linkage, link)
        if real is None or real.inertia < moment_floor(linkage, link, real):
            return True
    return False


def move_lock(model: LinkageModel, joint: Joint, value: float) -> None:
    """Move a driven joint's lock to ``value`` (rad or m from the drawn pose): a gear's
    phase, or a held slide's anchor (:mod:`.joint_kinds`)."""
    builder(joint).move_lock(model, joint, value)


def make_joints(model: LinkageModel) -> None:
    """Every joint's constraints, and each driver's lock, added to the model's tables; an
    elastic member's sliding end (:mod:`.members`) in place of its joint's pivot."""
    linkage = model.linkage
    driven = {d.joint: d.value for d in linkage.drivers}
    ends = sliding_ends(linkage) if modelled(linkage) else {}
    assert not isinstance(ends, str), ends
    for joint in linkage.joints:
        if joint.name in ends:
            model.members[joint.name] = build_end(model, ends[joint.name])
        else:
            builder(joint).build(model, joint, driven.get(joint.name))


def make_springs(model: LinkageModel) -> None:
    """A DampedSpring per linear spring, a DampedRotarySpring (rest −q0) per torsional one."""
    linkage = model.linkage
    for spring in linkage.springs:
        if isinstance(spring, LinearSpring):
            (la, pa), (lb, pb) = spring.ends
            model.springs[spring.name] = pymunk.DampedSpring(
                model.body(la), model.body(lb), pa, pb, spring.free_length, spring.stiffness,
                spring.damping)
        else:
            i, j = linkage.joint(spring.joint).links
            model.springs[spring.name] = pymunk.DampedRotarySpring(
                model.body(i), model.body(j), -spring.free_rotation, spring.stiffness,
                spring.damping)


def make_space(settings: SolverSettings) -> pymunk.Space:
    """An empty space without gravity (weights are explicit forces) and without its own
    damping; the run damps velocities itself (:func:`damp`).

    Chipmunk adds a spring's impulse *before* it damps the velocities, so
    ``Space.damping`` scales every spring force (measured: Q of the bonnet 9 % off). And
    even without springs it kept an unloaded near-parallelogram four-bar (random test
    case, condition 92) moving at 0.04 m/s for 20 000 steps, where damping before the
    step settles it in 267.
    """
    space = pymunk.Space()
    space.iterations = int(settings.iterations)
    space.gravity = (0.0, 0.0)
    space.damping = 1.0
    return space


def build_linkage_model(case: Case, settings: SolverSettings, q: Array,
                        driven: bool = False,
                        bodies: dict[str, pymunk.Body] | None = None) -> LinkageModel:
    """The pymunk model of a linkage case, its bodies placed at coordinates q (3n,);
    ``driven``: with the links' real inertia (:func:`make_bodies`); ``bodies``: these
    bodies instead, one per moving link in order (a free run's, :mod:`.trajectory`)."""
    linkage = case.linkage
    space = make_space(settings)
    bodies = make_bodies(linkage, settings, driven) if bodies is None else bodies
    model = LinkageModel(case, settings, space, bodies, {}, {}, {}, {}, {}, {},
                         {link: gyration_radius(linkage, link) for link in bodies})
    make_joints(model)
    make_springs(model)
    space.add(*bodies.values())
    for constraint in model.constraints():
        constraint.error_bias = settings.error_bias
        space.add(constraint)
    model.scale = linkage.scale
    model.radii = np.array(list(model.radius.values()))
    model.bulk = Bodies(space, list(bodies.values()))
    model.loads = LoadTerms([ld for ld in linkage.loads if ld.link != GROUND],
                            [m for m in linkage.masses if m.link != GROUND], linkage.gravity,
                            bodies)
    model.readout = compile_readout(model)
    place(model, q)
    return model


def reaction_names(model: LinkageModel) -> list[str]:
    """Every F_, M_, Q_ and S_ quantity of the linkage, in the order of its joints, then
    drives and springs; a held slide's Q_ comes before its F_."""
    names = []
    for joint in model.linkage.joints:
        names += builder(joint).reaction_names(joint, joint.name in model.held)
    return (names + [f"Q_{name}" for name in model.drives] + [f"S_{name}" for name in model.springs]
            + [f"N_{end.member}" for end in model.members.values()])


def compile_readout(model: LinkageModel) -> Readout:
    """Which accumulated impulse is which quantity (:class:`~.readout.Readout`).

    A constraint's impulse on its body b is the force by ``links[0]`` on ``links[1]``
    (the module docstring): each joint's F as its kind reads it (:mod:`.joint_kinds`: a
    pin's or groove's impulse, a held slide's pivot F + Q), locks' M, drives' Q; a
    spring's S is the negative of its signed impulse.
    """
    linkage = model.linkage
    forces: list[tuple[str, Cell]] = []
    held: list[HeldSlide] = []
    for joint in linkage.joints:
        if joint.name in model.members:   # the groove here; the spring with the springs
            forces += list(zip((f"F_{joint.name}_x", f"F_{joint.name}_y"),
                               model.members[joint.name].cells, strict=True))
            continue
        cells, slide = builder(joint).reaction(model, joint)
        forces += cells
        if slide is not None:
            held.append(slide)
    couples = [(f"M_{name}", impulse_cells(lock)[0]) for name, lock in model.locks.items()]
    couples += [(f"Q_{name}", impulse_cells(gear)[0]) for name, gear in model.drives.items()]
    units = quantity_units(linkage)
    springs = tuple((f"S_{name}", spring, units.get(f"S_{name}") == "N*m")
                    for name, spring in model.springs.items())
    springs += tuple((f"N_{end.member}", end.spring, False) for end in model.members.values())
    return Readout(tuple(reaction_names(model)), model.settings.dt, linkage.scale, tuple(forces),
                   tuple(couples), springs, tuple(held), tuple(model.meshes.values()),
                   tuple(model.members.values()))


def place(model: LinkageModel, q: Array) -> None:
    """Put every body at its coordinates (t_x, t_y, φ) in q (3n,), at rest, no load pending.

    This only seeds (or, in the constraint solve, re-poses) the configuration;
    the forces are still pymunk's.
    """
    stage(model, q)
    model.bulk.repose()


def stage(model: LinkageModel, q: Array, loaded: bool = False) -> None:
    """Ready the bodies' coordinates q (3n,), at rest, for :meth:`~._fast.bulk.Bodies.repose`,
    with the loads at that pose (``loaded``) or none."""
    coords, loads = np.asarray(q, dtype=float).tolist(), model.loads
    none = [0.0] * len(model.bodies)
    model.bulk.stage(coords, loads.forces if loaded else none * 2,
                     loads.torques(coords[2::3]) if loaded else none)


def coordinates(model: LinkageModel) -> Array:
    """The bodies' coordinates q (3n,) in the linkage's layout (moving links in order)."""
    return model.bulk.read()[:, :3].flatten()


def apply_loads(model: LinkageModel) -> None:
    """The linkage's loads and real weights on the moving links, for the next step
    (loads on the ground act on nothing that moves)."""
    linkage = model.linkage
    apply_forces([ld for ld in linkage.loads if ld.link != GROUND],
                 [m for m in linkage.masses if m.link != GROUND], linkage.gravity, model.bodies)


def damp(model: LinkageModel) -> None:
    """Remove kinetic energy before a step: velocities × damping^dt (``Space.damping``'s
    law, applied where it cannot scale the springs' impulses). At rest it does nothing."""
    keep = model.settings.damping ** model.settings.dt
    for body in model.bodies.values():
        body.velocity = body.velocity * keep
        body.angular_velocity = body.angular_velocity * keep
