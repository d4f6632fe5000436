"""The kinds of joint a linkage may hold, one module each, and their registry.

A kind is a value with behaviour (:class:`~.base.JointKind`): the engine, the checks and
the simulators ask a joint's kind what to do and never compare kind names. To add a kind,
follow the recipe in ``analytic/README.md``.
"""

from __future__ import annotations

from mechcheck.analytic.joint_kinds.base import JointFrame, JointKind
from mechcheck.analytic.joint_kinds.gear import GEAR, GearMesh
from mechcheck.analytic.joint_kinds.pin_in_slot import PIN_IN_SLOT
from mechcheck.analytic.joint_kinds.prismatic import PRISMATIC
from mechcheck.analytic.joint_kinds.revolute import REVOLUTE

#: Every kind, by the name a case file gives it.
KINDS: dict[str, JointKind] = {kind.name: kind for kind in (REVOLUTE, PRISMATIC, PIN_IN_SLOT, GEAR)}


def kind_named(name: str) -> JointKind:
    """The kind a case file names (KeyError for an unknown name)."""
    return KINDS[name]


__all__ = [
    "GEAR",
    "KINDS",
    "PIN_IN_SLOT",
    "PRISMATIC",
    "REVOLUTE",
    "GearMesh",
    "JointFrame",
    "JointKind",
    "kind_named",
]
