"""The prismatic joint (a slide): links[1] carries the point ``at`` along the axis u fixed
in links[0], and neither turns relative to the other.

- Constraint: φ_j − φ_i = 0 and n_i·(p_j(A0) − p_i(A0)) = 0 (n the axis turned +90°); a
  driver adds u_i·(p_j(A0) − p_i(A0)) = q.
- Reaction: a force N along n through ``at`` and a couple M, by links[0] on links[1]; a
  driver's effort is a force along u through ``at``.
- Friction: μ·|N| along the axis opposing the sliding, and a viscous force −c·q̇; both are
  part of the reported force F.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from mechcheck.analytic.joint_kinds.base import JointFrame, JointKind
from mechcheck.analytic.joint_kinds.drawing import JointDrawing, Placement, Slide, grounded, rotated
from mechcheck.analytic.rigid import Array, Constraints, ForceLayout, Motion, dot, perp, rotate
from mechcheck.analytic.values import CaseError, pair

if TYPE_CHECKING:
    from mechcheck.analytic.linalg import Batched
    from mechcheck.analytic.linkage import Joint, JointFriction, Link
    from mechcheck.analytic.linkage_kinematics import LinkagePose
    from mechcheck.analytic.motion_rows import RowPlan


def slot_axis(joint: Joint) -> Array:
    """The joint's sliding direction u at the drawn pose, fixed in links[0]."""
    assert joint.axis is not None   # checked(): every sliding joint has one
    return np.array(joint.axis)


class Prismatic(JointKind):
    name = "prismatic"
    symbol = "P"
    freedoms = 1
    rotates = False
    pins = False
    slides = True
    #: Its sliding link turns about the point on the axis (a pin in a slot), else not (a block).
    turns_on_axis: ClassVar[bool] = False

    def checked(self, joint: Joint, links: Mapping[str, Link], key: str) -> Joint:
        second = links[joint.links[1]]
        if joint.at not in second.points:
            raise CaseError(f"links[1] ({second.name!r}) must carry point {joint.at!r}",
                            key=f"{key}.at")
        if joint.axis is None:
            raise CaseError(f"a {self.name} joint needs its sliding direction", key=f"{key}.axis")
        ax, ay = pair(joint.axis, f"{key}.axis")
        length = math.hypot(ax, ay)
        if length == 0.0:
            raise CaseError("must not be zero", key=f"{key}.axis")
        return type(joint)(joint.name, joint.kind, joint.links, joint.at, (ax / length, ay / length))

    # -- kinematics ---------------------------------------------------------------------
    def constrain(self, c: Constraints, joint: Joint, row: int) -> None:
        c.angle_lock(row, joint)
        c.along(row + 1, joint, perp(slot_axis(joint)))

    def accelerate(self, m: Motion, joint: Joint, out: Array, row: int) -> None:
        out[:, row + 1] = m.along(joint, perp(slot_axis(joint)))

    def row_lengths(self, size: float) -> tuple[float, ...]:
        return (size, 1.0)

    def plan(self, rows: RowPlan, joint: Joint, row: int) -> None:
        rows.angle_lock(row, joint)
        rows.along(row + 1, joint, perp(slot_axis(joint)))

    def plan_drive(self, rows: RowPlan, joint: Joint, row: int) -> None:
        rows.along(row, joint, slot_axis(joint))

    def drive(self, c: Constraints, joint: Joint, row: int) -> None:
        c.along(row, joint, slot_axis(joint))

    def drive_acceleration(self, m: Motion, joint: Joint) -> Array | None:
        return m.along(joint, slot_axis(joint))

    def coordinate(self, pose: LinkagePose, joint: Joint) -> tuple[Array, Array, Array]:
        i, j = joint.links
        a0 = pose.linkage.points[joint.at]
        phi_i, w_i, a_i = pose.angle(i)
        u = rotate(phi_i, slot_axis(joint))
        pj, vj, accj = pose.point(j, a0)
        pi, vi, acci = pose.point(i, a0)
        d, dd, ddd = pj - pi, vj - vi, accj - acci
        du = w_i[:, None] * perp(u)
        ddu = a_i[:, None] * perp(u) - (w_i**2)[:, None] * u
        return (dot(u, d), dot(du, d) + dot(u, dd),
                dot(ddu, d) + 2 * dot(du, dd) + dot(u, ddd))

    def value(self, pose: LinkagePose, joint: Joint) -> Array:
        i, j = joint.links
        a0 = pose.linkage.points[joint.at]
        u = pose.turned(i, slot_axis(joint))
        return dot(u, pose.position(j, a0) - pose.position(i, a0))

    # -- statics --------------------------------------------------------------------------
    def frame(self, pose: LinkagePose, joint: Joint) -> JointFrame:
        point = pose.point(joint.links[1], pose.linkage.points[joint.at])[0]
        u = pose.turned(joint.links[0], slot_axis(joint))
        return JointFrame(point, u, perp(u))

    def react(self, k: Batched, layout: ForceLayout, joint: Joint, frame: JointFrame) -> None:
        assert frame.n is not None
        c0, c1 = layout.joint_columns(joint)
        layout.force_pair(k, joint.links, (c0,), frame.n[None], frame.point)
        for link, sign in ((joint.links[1], 1.0), (joint.links[0], -1.0)):
            layout.couple_on(k, link, c1, sign)

    def reaction_lengths(self, size: float) -> tuple[float, ...]:
        return (1.0, size)

    def exert(self, k: Batched, layout: ForceLayout, col: int, joint: Joint,
              frame: JointFrame) -> None:
        assert frame.u is not None
        layout.force_pair(k, joint.links, (col,), frame.u[None], frame.point)

    def drawing(self, joint: Joint, place: Placement) -> JointDrawing:
        # The axis is fixed in links[0]: it turns with that link.
        assert joint.axis is not None   # checked(): every sliding joint has one
        at = place.point(joint.at)
        axis = rotated(place.turn(joint.links[0]), joint.axis)
        return JointDrawing((Slide(at, axis, self.turns_on_axis, grounded(joint.links)),), at)

    def quantities(self, joint: Joint) -> dict[str, str]:
        return {f"F_{joint.name}_x": "N", f"F_{joint.name}_y": "N", f"M_{joint.name}": "N*m"}

    def reported(self, pose: LinkagePose, joint: Joint, x: Array, along: Array) -> dict[str, Array]:
        return self.slide_force(pose, joint, x, along) | {f"M_{joint.name}": x[:, 1]}

    def slide_force(self, pose: LinkagePose, joint: Joint, x: Array, along: Array) -> dict[str, Array]:
        """The force by links[0] on links[1]: the normal reaction x[:, 0] along n, and along
        u the Coulomb friction ``along`` and the viscous force."""
        frame = pose.frame(joint)
        assert frame.u is not None and frame.n is not None
        f = pose.linkage.friction
        if f is not None and f.viscous.get(joint.name, 0.0):
            along = along - f.viscous[joint.name] * self.coordinate(pose, joint)[1]
        force = x[:, 0][:, None] * frame.n + along[:, None] * frame.u
        return {f"F_{joint.name}_x": force[:, 0], f"F_{joint.name}_y": force[:, 1]}

    # -- friction -------------------------------------------------------------------------
    def coulomb_coefficient(self, friction: JointFriction, joint: Joint) -> float:
        return friction.coefficient(joint.name)

    def coulomb(self, pose: LinkagePose, layout: ForceLayout, joint: Joint, coefficient: float,
                sense: Array, x: Array, phi: Array, dphi: Batched) -> None:
        frame = self.frame(pose, joint)
        assert frame.u is not None
        c0 = layout.joint_columns(joint)[0]
        along = self.sliding_friction(coefficient, sense, x[:, [c0]])
        d_along = -coefficient * sense * np.sign(x[:, c0])
        lever = frame.point[:, 0] * frame.u[:, 1] - frame.point[:, 1] * frame.u[:, 0]
        for link, sign in ((joint.links[1], 1.0), (joint.links[0], -1.0)):
            r = layout.row(link)
            if r < 0:
                continue
            for offset, coef in ((0, frame.u[:, 0]), (1, frame.u[:, 1]), (2, lever)):
                phi[:, r + offset] += sign * coef * along
                dphi.add(r + offset, c0, sign * coef * d_along)

    def sliding_friction(self, coefficient: float, sense: Array, x: Array) -> Array:
        return -coefficient * sense * np.abs(x[:, 0])

    def viscous(self, b: Array, layout: ForceLayout, pose: LinkagePose, joint: Joint,
                c: float) -> None:
        _, rate, _ = self.coordinate(pose, joint)
        frame = self.frame(pose, joint)
        assert frame.u is not None
        force = -c * rate[:, None] * frame.u
        layout.add_force(b, joint.links[1], force, frame.point)
        layout.add_force(b, joint.links[0], -force, frame.point)


PRISMATIC = Prismatic()
