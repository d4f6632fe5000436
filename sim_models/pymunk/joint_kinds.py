"""How pymunk builds each kind of joint, reads its reaction and applies its friction: the
one place that maps a joint kind (:mod:`mechcheck.analytic.joint_kinds`) to pymunk.

Body a = ``links[0]``, body b = ``links[1]``, so the impulse a constraint accumulates on
body b is the force *by* links[0] *on* links[1] (LINKAGES.md). Each builder puts its
constraints in the :class:`~.linkage_model.LinkageModel`'s tables (``pins``, ``grooves``,
``held``, ``locks``, ``drives``, ``meshes``): the tables, not the builders, fix the order in which the
space solves them, so a kind added here leaves every other linkage's numbers unchanged.

- revolute (:class:`Pin`): a :class:`pymunk.PivotJoint` at the joint's point; a driver on
  it a :class:`pymunk.GearJoint` (ratio 1, phase = the driver's value), whose torque is Q.
  Its friction is a couple.
- prismatic (:class:`Slide` that locks the turning): a :class:`pymunk.GrooveJoint` on
  links[0] along the axis through ``at`` (its impulse is the normal reaction N·n at ``at``)
  plus a GearJoint (ratio 1, phase 0) locking the relative rotation (its torque is M).
- pin_in_slot (:class:`Slide` that turns): the groove alone; the pin turns freely in it,
  so there is no couple to read.
- a driver on a slide: the groove is replaced by a PivotJoint between ``at`` on links[1]
  and the point ``at`` + value·axis of links[0], which holds the slide where the driver
  puts it; its impulse along the axis is Q, across it the reaction N·n.

- gear (:class:`Mesh`): the tooth contact, a :class:`pymunk.PinJoint` laid along the
  line of action through the pitch point before every solve (:mod:`.gear_mesh`); its
  impulse is the whole tooth force F, read along t (F_t) and the separating direction
  (F_r). A mesh takes no driver and no friction; it is refused where the rest of the
  linkage does not hold its centre distance.

A slide's friction is a force along its axis through ``at``, and part of its reported
force F (as in the analytic engine). To add a kind: one builder in :data:`BUILDERS`, under
the kind's name (sim_models/pymunk/README.md).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import TYPE_CHECKING

import pymunk

from mechcheck.analytic.joint_kinds import GEAR, PIN_IN_SLOT, PRISMATIC, REVOLUTE
from mechcheck.analytic.linkage import Joint, JointFriction, Linkage
from mechcheck.sim_models.pymunk._fast import Cell, impulse_cells
from mechcheck.sim_models.pymunk.gear_mesh import ToothContact, centre_distance_held
from mechcheck.sim_models.pymunk.readout import HeldSlide, turned

if TYPE_CHECKING:
    from mechcheck.sim_models.pymunk.linkage_model import LinkageModel

Vec = tuple[float, float]
#: A reaction's impulse cells by quantity name (F_x, F_y of a pin or a free slide).
ForceCells = list[tuple[str, Cell]]

#: A groove reaches this many linkage sizes either side of its point, so its end stops
#: never engage within any pose the linkage can reach.
GROOVE_REACH = 100.0


def along(joint: Joint, point: Vec, distance: float) -> Vec:
    """The point ``distance`` along a sliding joint's drawn axis from ``point``."""
    assert joint.axis is not None
    return point[0] + distance * joint.axis[0], point[1] + distance * joint.axis[1]


def axis_now(model: LinkageModel, joint: Joint) -> Vec:
    """A sliding joint's direction at the current pose (fixed in links[0])."""
    assert joint.axis is not None
    return turned(joint.axis, model.body(joint.links[0]).angle)


def joint_bodies(model: LinkageModel, joint: Joint) -> tuple[pymunk.Body, pymunk.Body]:
    """Bodies a (links[0]) and b (links[1]) of a joint."""
    a, b = (model.body(link) for link in joint.links)
    return a, b


class JointBuilder(ABC):
    """How pymunk holds one kind of joint, reads its reaction and applies its friction."""

    @abstractmethod
    def build(self, model: LinkageModel, joint: Joint, driven: float | None) -> None:
        """Add the joint's constraints to the model's tables; ``driven``: the value of a
        driver on it (rad or m from the drawn pose), held by a lock, or None."""

    @abstractmethod
    def move_lock(self, model: LinkageModel, joint: Joint, value: float) -> None:
        """Move the lock of a driver on it to ``value``."""

    @abstractmethod
    def reaction_names(self, joint: Joint, held: bool) -> list[str]:
        """Its reaction quantities in the readout's order (``held``: a driver's lock holds
        it, and that lock's effort is read with them)."""

    @abstractmethod
    def reaction(self, model: LinkageModel, joint: Joint) -> tuple[ForceCells, HeldSlide | None]:
        """Where its force F is read: impulse cells by name, or a held slide that splits
        its pivot's impulse into Q and F. (Couples are read from the ``locks`` and
        ``drives`` tables.)"""

    @abstractmethod
    def rate(self, model: LinkageModel, joint: Joint) -> float:
        """q̇ from the bodies' velocities."""

    @abstractmethod
    def coulomb(self, model: LinkageModel, joint: Joint, friction: JointFriction,
                fx: float, fy: float) -> float:
        """The size of its Coulomb friction (N·m or N) under the reaction (fx, fy)."""

    @abstractmethod
    def apply_friction(self, model: LinkageModel, joint: Joint, body: pymunk.Body,
                       load: float) -> None:
        """Apply its friction ``load`` (signed, on this body) to ``body``."""

    @abstractmethod
    def sliding(self, model: LinkageModel, joint: Joint, value: float) -> Vec | None:
        """The friction ``value`` as a force that is part of its reported F, or None."""

    def refusal(self, linkage: Linkage, joint: Joint) -> str | None:
        """Why this joint of ``linkage`` cannot be built exactly, or None (the default)."""
        return None


class Pin(JointBuilder):
    """A revolute joint: a pivot; a driver's gear; friction a couple (friction circle)."""

    def build(self, model: LinkageModel, joint: Joint, driven: float | None) -> None:
        a, b = joint_bodies(model, joint)
        at = model.linkage.points[joint.at]
        model.pins[joint.name] = pymunk.PivotJoint(a, b, at, at)
        if driven is not None:
            model.drives[joint.name] = pymunk.GearJoint(a, b, driven, 1.0)

    def move_lock(self, model: LinkageModel, joint: Joint, value: float) -> None:
        model.drives[joint.name].phase = value

    def reaction_names(self, joint: Joint, held: bool) -> list[str]:
        return [f"F_{joint.name}_x", f"F_{joint.name}_y"]

    def reaction(self, model: LinkageModel, joint: Joint) -> tuple[ForceCells, HeldSlide | None]:
        cells = impulse_cells(model.pins[joint.name])
        return list(zip(self.reaction_names(joint, False), cells, strict=True)), None

    def rate(self, model: LinkageModel, joint: Joint) -> float:
        a, b = joint_bodies(model, joint)
        return float(b.angular_velocity - a.angular_velocity)

    def coulomb(self, model: LinkageModel, joint: Joint, friction: JointFriction,
                fx: float, fy: float) -> float:
        arm = friction.coefficient(joint.name) * friction.pin_radius.get(joint.name, 0.0)
        return arm * math.hypot(fx, fy)

    def apply_friction(self, model: LinkageModel, joint: Joint, body: pymunk.Body,
                       load: float) -> None:
        body.torque += load

    def sliding(self, model: LinkageModel, joint: Joint, value: float) -> Vec | None:
        return None


@dataclass(frozen=True)
class Slide(JointBuilder):
    """A joint whose point ``at`` of links[1] slides along an axis fixed in links[0]: a
    groove, or a driver's pivot; with ``locks_turning``, a gear that keeps the two links
    from turning relative to each other (a prismatic joint; its torque is M), else the
    pin turns freely in the groove (a pin in a slot). Friction: a force along the axis
    through ``at``, part of F."""

    locks_turning: bool

    def build(self, model: LinkageModel, joint: Joint, driven: float | None) -> None:
        a, b = joint_bodies(model, joint)
        at = model.linkage.points[joint.at]
        if self.locks_turning:
            model.locks[joint.name] = pymunk.GearJoint(a, b, 0.0, 1.0)
        if driven is not None:
            model.held[joint.name] = pymunk.PivotJoint(a, b, along(joint, at, driven), at)
        else:
            reach = GROOVE_REACH * model.linkage.scale
            model.grooves[joint.name] = pymunk.GrooveJoint(
                a, b, along(joint, at, -reach), along(joint, at, reach), at)

    def move_lock(self, model: LinkageModel, joint: Joint, value: float) -> None:
        model.held[joint.name].anchor_a = along(joint, model.linkage.points[joint.at], value)

    def reaction_names(self, joint: Joint, held: bool) -> list[str]:
        effort = [f"Q_{joint.name}"] if held else []
        couple = [f"M_{joint.name}"] if self.locks_turning else []
        return [*effort, f"F_{joint.name}_x", f"F_{joint.name}_y", *couple]

    def reaction(self, model: LinkageModel, joint: Joint) -> tuple[ForceCells, HeldSlide | None]:
        name = joint.name
        assert joint.axis is not None
        if name in model.held:
            cells = impulse_cells(model.held[name])
            return [], HeldSlide(name, (cells[0], cells[1]), model.body(joint.links[0]), joint.axis)
        return list(zip((f"F_{name}_x", f"F_{name}_y"), impulse_cells(model.grooves[name]),
                        strict=True)), None

    def rate(self, model: LinkageModel, joint: Joint) -> float:
        a, b = joint_bodies(model, joint)
        point = b.local_to_world(model.linkage.points[joint.at])
        relative = b.velocity_at_world_point(point) - a.velocity_at_world_point(point)
        ux, uy = axis_now(model, joint)
        return float(relative.x * ux + relative.y * uy)

    def coulomb(self, model: LinkageModel, joint: Joint, friction: JointFriction,
                fx: float, fy: float) -> float:
        ux, uy = axis_now(model, joint)
        return friction.coefficient(joint.name) * abs(-fx * uy + fy * ux)

    def apply_friction(self, model: LinkageModel, joint: Joint, body: pymunk.Body,
                       load: float) -> None:
        ux, uy = axis_now(model, joint)
        point = model.body(joint.links[1]).local_to_world(model.linkage.points[joint.at])
        body.apply_force_at_world_point((load * ux, load * uy), point)

    def sliding(self, model: LinkageModel, joint: Joint, value: float) -> Vec | None:
        ux, uy = axis_now(model, joint)
        return value * ux, value * uy


class Mesh(JointBuilder):
    """A gear mesh: its tooth contact (:class:`~.gear_mesh.ToothContact`), whose groove's
    impulse is the whole tooth force by links[0] on links[1]."""

    def build(self, model: LinkageModel, joint: Joint, driven: float | None) -> None:
        assert driven is None, "a gear mesh is never driven (Linkage refuses it)"
        a, b = joint_bodies(model, joint)
        model.meshes[joint.name] = ToothContact.build(joint, model.linkage, a, b)

    def move_lock(self, model: LinkageModel, joint: Joint, value: float) -> None:
        raise AssertionError("a gear mesh is never driven (Linkage refuses it)")

    def reaction_names(self, joint: Joint, held: bool) -> list[str]:
        return [f"F_{joint.name}_{part}" for part in ("x", "y", "t", "r")]

    def reaction(self, model: LinkageModel, joint: Joint) -> tuple[ForceCells, HeldSlide | None]:
        # The pin's scalar impulse along the line of action is what a run compares and warm
        # starts; it is no reported quantity (F_x, F_y, F_t, F_r are the Readout's meshes').
        return [(f"F_{joint.name}_w", model.meshes[joint.name].cells[0])], None

    def rate(self, model: LinkageModel, joint: Joint) -> float:
        return model.meshes[joint.name].rate()

    def coulomb(self, model: LinkageModel, joint: Joint, friction: JointFriction,
                fx: float, fy: float) -> float:
        return 0.0   # a mesh has no friction model (the analytic engine's coefficient is 0)

    def apply_friction(self, model: LinkageModel, joint: Joint, body: pymunk.Body,
                       load: float) -> None:
        raise AssertionError("a gear mesh has no friction (its Coulomb term is 0)")

    def sliding(self, model: LinkageModel, joint: Joint, value: float) -> Vec | None:
        return None

    def refusal(self, linkage: Linkage, joint: Joint) -> str | None:
        if centre_distance_held(linkage, joint):
            return None
        return (f"joint {joint.name} is a gear whose centre distance the rest of the linkage "
                "does not hold: the pymunk model's tooth contact acts along the line of action, "
                "which is the rolling constraint only where a frame or a carrier holds the "
                "centres apart; its forces are checked by the analytic backends only")


#: Every kind pymunk builds, by the name a case file gives it (``JointKind.name``).
BUILDERS: dict[str, JointBuilder] = {
    REVOLUTE.name: Pin(),
    PRISMATIC.name: Slide(locks_turning=True),
    PIN_IN_SLOT.name: Slide(locks_turning=False),
    GEAR.name: Mesh(),
}


def builder(joint: Joint) -> JointBuilder:
    """How pymunk builds ``joint`` (by its kind's name)."""
    try:
        return BUILDERS[joint.kind.name]
    except KeyError:
        raise LookupError(f"pymunk builds no {joint.kind.name} joint (joint {joint.name!r}): "
                          "sim_models/pymunk/joint_kinds.py has no builder for that kind") from None
