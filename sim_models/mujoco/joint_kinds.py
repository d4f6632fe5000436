"""How the MuJoCo model builds each kind of joint and reads its reaction: the one place a
joint's kind is looked up (:func:`builder_of`). The builder, the index maps, the read-out,
the friction and the driven runs ask a joint's :class:`KindBuild`; none of them asks
which kind a joint is.

A tree joint becomes one or more MuJoCo joints of its child body (:class:`MjJoint`, in
the order MuJoCo applies them). The one named after the joint carries its coordinate q
(``qpos`` = q whichever way the tree runs), so drivers' equalities, dampers, torsional
springs and armature go on it; a pin in a slot adds a hinge for its free turn. A joint
that may close a loop becomes a ``connect`` at its point (:mod:`.linkage_model`). A gear
mesh is never a tree joint: it always closes the loop through its gears' bearings, as a
tendon on its line of action held at constant length (:mod:`.linkage_mesh`).

To add a kind: one :class:`KindBuild` in :data:`BUILDS` (see ``README.md``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import mujoco

from mechcheck.analytic.joint_kinds import GEAR, PIN_IN_SLOT, PRISMATIC, REVOLUTE, JointKind
from mechcheck.analytic.linkage import Joint

HINGE = mujoco.mjtJoint.mjJNT_HINGE
SLIDE = mujoco.mjtJoint.mjJNT_SLIDE


@dataclass(frozen=True)
class MjJoint:
    """One MuJoCo joint of a tree joint's child body. ``coordinate``: its qpos is the
    joint's coordinate q; else it is a hinge whose qpos is the child's free rotation
    relative to the parent (the analytic pose seeds it as such)."""

    name: str
    type: mujoco.mjtJoint
    axis: tuple[float, float, float]
    coordinate: bool

    @property
    def turn(self) -> float:
        """The child's rotation per unit of its qpos (a slide does not turn it)."""
        return self.axis[2] if self.type == HINGE else 0.0


def turn_name(joint: Joint) -> str:
    """The MuJoCo name of the hinge that lets a pin turn in its slot."""
    return f"{joint.name}_turn"


def _hinge(joint: Joint, sign: float) -> tuple[MjJoint, ...]:
    return (MjJoint(joint.name, HINGE, (0.0, 0.0, sign), True),)


def _slide_axis(joint: Joint, sign: float) -> tuple[float, float, float]:
    assert joint.axis is not None  # the kind's check: every sliding joint has one
    return (sign * joint.axis[0], sign * joint.axis[1], 0.0)


def _slide(joint: Joint, sign: float) -> tuple[MjJoint, ...]:
    return (MjJoint(joint.name, SLIDE, _slide_axis(joint, sign), True),)


def _slide_and_turn(joint: Joint, sign: float) -> tuple[MjJoint, ...]:
    """The slot's slide and the pin's hinge at ``at`` (the child's origin). The slot is
    fixed in links[0]: hanging from it (sign +1) the pin's body slides along the parent's
    axis, then turns; hanging from the pin (sign −1) the slotted body turns about the pin,
    then slides along its own axis turned with it, reversed (the pin moves +q along it)."""
    slide = MjJoint(joint.name, SLIDE, _slide_axis(joint, sign), True)
    turn = MjJoint(turn_name(joint), HINGE, (0.0, 0.0, 1.0), False)
    return (slide, turn) if sign > 0.0 else (turn, slide)


def _never_in_the_tree(joint: Joint, sign: float) -> tuple[MjJoint, ...]:
    raise AssertionError(f"joint {joint.name} closes its loop: it has no MuJoCo joint")


@dataclass(frozen=True)
class KindBuild:
    """How MuJoCo builds one kind of joint and reads its reaction.

    - ``closes_loops``: it may close a loop as a ``connect`` at its point (it carries a
      force in any direction there and no couple); else it must be a tree joint, and
      enters the spanning tree first.
    - ``slide_readout``: its reaction is read as a slide's (the child's ``cfrc_int`` plus
      the emulated friction along the axis, less the driver's effort along it), else as a
      pin's (the child's ``cfrc_int`` force alone).
    - ``couple``: it reports a couple ``M_<joint>`` (about ``at``).
    - ``sliding_friction``: its Coulomb friction is μ·|N| along its axis, else the
      friction circle's couple μ·r·|F|.
    - ``joints``: its MuJoCo joints on the child body, given the tree's sign.
    - ``meshes``: it is a gear mesh: never a tree joint, it closes its loop as a tendon on
      the line of action (:mod:`.linkage_mesh`) and reports the tooth force's tangential
      and radial parts besides its x, y.
    """

    kind: JointKind
    closes_loops: bool
    slide_readout: bool
    couple: bool
    sliding_friction: bool
    joints: Callable[[Joint, float], tuple[MjJoint, ...]]
    meshes: bool = False

    def reaction_names(self, joint: Joint) -> list[str]:
        """Its reaction quantities, in the read-out's order."""
        force = [f"F_{joint.name}_x", f"F_{joint.name}_y"]
        parts = [f"F_{joint.name}_t", f"F_{joint.name}_r"] if self.meshes else []
        return ([f"M_{joint.name}"] if self.couple else []) + force + parts

    def coordinate_is_angle(self, joint: Joint) -> bool:
        """Its coordinate (and a driver's target, a damper's rate) is an angle."""
        return next(j for j in self.joints(joint, 1.0) if j.coordinate).type == HINGE

    def turns(self, joint: Joint) -> bool:
        """Its child body can turn relative to its parent."""
        return any(j.turn for j in self.joints(joint, 1.0))


#: Every kind MuJoCo builds, by the kind's name.
BUILDS: dict[str, KindBuild] = {b.kind.name: b for b in (
    KindBuild(REVOLUTE, closes_loops=True, slide_readout=False, couple=False,
              sliding_friction=False, joints=_hinge),
    KindBuild(PRISMATIC, closes_loops=False, slide_readout=True, couple=True,
              sliding_friction=True, joints=_slide),
    KindBuild(PIN_IN_SLOT, closes_loops=False, slide_readout=True, couple=False,
              sliding_friction=True, joints=_slide_and_turn),
    KindBuild(GEAR, closes_loops=False, slide_readout=False, couple=False,
              sliding_friction=False, joints=_never_in_the_tree, meshes=True),
)}


def builder_of(joint: Joint) -> KindBuild:
    """How MuJoCo builds ``joint`` (KeyError for a kind it has no model of: every kind of
    :data:`mechcheck.analytic.joint_kinds.KINDS` has one, ``tests/test_mujoco_pin_in_slot.py``)."""
    return BUILDS[joint.kind.name]
