"""The pin in a slot (seed 001's Cs, "kamalı silindir": a keyed cylinder in a slot): the
point ``at`` of links[1] stays on the slot's line, the line through ``at`` along the axis u
fixed in links[0], and slides along it and turns freely in it (Sᵢ = 2).

- Constraint: n_i·(p_j(A0) − p_i(A0)) = 0, one row (n the axis turned +90°); a driver adds
  u_i·(p_j(A0) − p_i(A0)) = q, the travel along the slot.
- Reaction: a force N along n through ``at``, by links[0] on links[1]; no couple, since
  the pin turns freely. A driver's effort is a force along u through ``at``.
- Friction: as on a slide, μ·|N| along the slot opposing the sliding, and a viscous force
  −c·q̇; both are part of the reported force F.

It is a prismatic joint without the row that stops the turning, and without the couple
that row's reaction is: everything else (the slide's coordinate, frame, driver, friction)
is the prismatic joint's.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from mechcheck.analytic.joint_kinds.base import JointFrame
from mechcheck.analytic.joint_kinds.prismatic import Prismatic, slot_axis
from mechcheck.analytic.rigid import Array, Constraints, ForceLayout, Motion, perp

if TYPE_CHECKING:
    from mechcheck.analytic.linalg import Batched
    from mechcheck.analytic.linkage import Joint
    from mechcheck.analytic.linkage_kinematics import LinkagePose
    from mechcheck.analytic.motion_rows import RowPlan


class PinInSlot(Prismatic):
    name = "pin_in_slot"
    symbol = "Cs"
    freedoms = 2
    rotates = False
    pins = False
    turns_on_axis = True

    # -- kinematics ---------------------------------------------------------------------
    def constrain(self, c: Constraints, joint: Joint, row: int) -> None:
        c.along(row, joint, perp(slot_axis(joint)))

    def accelerate(self, m: Motion, joint: Joint, out: Array, row: int) -> None:
        out[:, row] = m.along(joint, perp(slot_axis(joint)))

    def row_lengths(self, size: float) -> tuple[float, ...]:
        return (1.0,)

    def plan(self, rows: RowPlan, joint: Joint, row: int) -> None:
        rows.along(row, joint, perp(slot_axis(joint)))

    # -- statics --------------------------------------------------------------------------
    def react(self, k: Batched, layout: ForceLayout, joint: Joint, frame: JointFrame) -> None:
        assert frame.n is not None
        (c0,) = layout.joint_columns(joint)
        layout.force_pair(k, joint.links, (c0,), frame.n[None], frame.point)

    def reaction_lengths(self, size: float) -> tuple[float, ...]:
        return (1.0,)

    def quantities(self, joint: Joint) -> dict[str, str]:
        return {f"F_{joint.name}_x": "N", f"F_{joint.name}_y": "N"}

    def reported(self, pose: LinkagePose, joint: Joint, x: Array, along: Array) -> dict[str, Array]:
        return self.slide_force(pose, joint, x, along)


PIN_IN_SLOT = PinInSlot()
