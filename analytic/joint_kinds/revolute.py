"""The revolute joint (a pin): its two links hold a point together and turn freely about it.

- Constraint: p_i(P0) − p_j(P0) = 0, two rows; a driver adds φ_j − φ_i = q.
- Reaction: the force (Fx, Fy) by links[0] on links[1] at the pin; a driver's effort is a
  couple on links[1].
- Friction: the friction circle, a moment μ·r·|F| opposing the relative rotation (only
  at a pin with a radius r), and a viscous moment −c·q̇.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from mechcheck.analytic.joint_kinds.base import JointFrame, JointKind
from mechcheck.analytic.joint_kinds.drawing import JointDrawing, Pin, Placement
from mechcheck.analytic.rigid import Array, Constraints, ForceLayout, Motion, unit_axes
from mechcheck.analytic.values import CaseError

if TYPE_CHECKING:
    from mechcheck.analytic.linalg import Batched
    from mechcheck.analytic.linkage import Joint, JointFriction, Link
    from mechcheck.analytic.linkage_kinematics import LinkagePose
    from mechcheck.analytic.motion_rows import RowPlan


class Revolute(JointKind):
    name = "revolute"
    symbol = "R"
    freedoms = 1
    rotates = True
    pins = True

    def checked(self, joint: Joint, links: Mapping[str, Link], key: str) -> Joint:
        if joint.axis is not None:
            raise CaseError("a revolute joint has no axis: only a prismatic joint slides along one",
                            key=f"{key}.axis")
        if any(joint.at not in links[name].points for name in joint.links):
            raise CaseError(f"both links must carry point {joint.at!r} (a revolute joint "
                            "pins them there)", key=f"{key}.at")
        return joint

    # -- kinematics ---------------------------------------------------------------------
    def constrain(self, c: Constraints, joint: Joint, row: int) -> None:
        c.coincide(row, joint)

    def accelerate(self, m: Motion, joint: Joint, out: Array, row: int) -> None:
        i, j = joint.links
        p0 = np.array(m.linkage.points[joint.at])
        out[:, row:row + 2] = (-(m.spin(i) ** 2)[:, None] * m.rotated(i, p0)
                               + (m.spin(j) ** 2)[:, None] * m.rotated(j, p0))

    def row_lengths(self, size: float) -> tuple[float, ...]:
        return (1.0, 1.0)

    def plan(self, rows: RowPlan, joint: Joint, row: int) -> None:
        rows.coincide(row, joint)

    def plan_drive(self, rows: RowPlan, joint: Joint, row: int) -> None:
        rows.angle_lock(row, joint)

    def drive(self, c: Constraints, joint: Joint, row: int) -> None:
        c.angle_lock(row, joint)

    def drive_acceleration(self, m: Motion, joint: Joint) -> Array | None:
        return None

    def coordinate(self, pose: LinkagePose, joint: Joint) -> tuple[Array, Array, Array]:
        i, j = joint.links
        (pi, wi, ai), (pj, wj, aj) = pose.angle(i), pose.angle(j)
        return pj - pi, wj - wi, aj - ai

    def value(self, pose: LinkagePose, joint: Joint) -> Array:
        i, j = joint.links
        return pose.link_state(j, pose.q)[1] - pose.link_state(i, pose.q)[1]

    # -- statics --------------------------------------------------------------------------
    def frame(self, pose: LinkagePose, joint: Joint) -> JointFrame:
        return JointFrame(pose.point(joint.links[1], pose.linkage.points[joint.at])[0], None, None)

    def react(self, k: Batched, layout: ForceLayout, joint: Joint, frame: JointFrame) -> None:
        layout.force_pair(k, joint.links, layout.joint_columns(joint),
                          unit_axes(frame.point.shape[0]), frame.point)

    def react_all(self, k: Batched, layout: ForceLayout, joints: Sequence[Joint],
                  frames: Sequence[JointFrame]) -> None:
        points = np.array([frame.point for frame in frames])   # np.stack's copy, in a fifth
        layout.force_pairs(k, [j.links for j in joints], [layout.joint_columns(j) for j in joints],
                           unit_axes(points.shape[1]), points)

    def reaction_lengths(self, size: float) -> tuple[float, ...]:
        return (1.0, 1.0)

    def exert(self, k: Batched, layout: ForceLayout, col: int, joint: Joint,
              frame: JointFrame) -> None:
        layout.couple_on(k, joint.links[1], col, 1.0)
        layout.couple_on(k, joint.links[0], col, -1.0)

    def drawing(self, joint: Joint, place: Placement) -> JointDrawing:
        at = place.point(joint.at)
        return JointDrawing((Pin(at),), at)

    def quantities(self, joint: Joint) -> dict[str, str]:
        return {f"F_{joint.name}_x": "N", f"F_{joint.name}_y": "N"}

    def reported(self, pose: LinkagePose, joint: Joint, x: Array, along: Array) -> dict[str, Array]:
        return {f"F_{joint.name}_x": x[:, 0], f"F_{joint.name}_y": x[:, 1]}

    # -- friction -------------------------------------------------------------------------
    def coulomb_coefficient(self, friction: JointFriction, joint: Joint) -> float:
        return friction.coefficient(joint.name) * friction.pin_radius.get(joint.name, 0.0)

    def coulomb(self, pose: LinkagePose, layout: ForceLayout, joint: Joint, coefficient: float,
                sense: Array, x: Array, phi: Array, dphi: Batched) -> None:
        c0, c1 = layout.joint_columns(joint)
        mag = np.hypot(x[:, c0], x[:, c1])
        safe = np.where(mag > 0.0, mag, 1.0)
        moment = -coefficient * sense * mag
        grad = (-coefficient * sense)[:, None] * (x[:, [c0, c1]] / safe[:, None])
        for link, sign in ((joint.links[1], 1.0), (joint.links[0], -1.0)):
            r = layout.row(link)
            if r < 0:
                continue
            phi[:, r + 2] += sign * moment
            dphi.add(r + 2, c0, sign * grad[:, 0])
            dphi.add(r + 2, c1, sign * grad[:, 1])

    def sliding_friction(self, coefficient: float, sense: Array, x: Array) -> Array:
        return np.zeros(x.shape[0])

    def viscous(self, b: Array, layout: ForceLayout, pose: LinkagePose, joint: Joint,
                c: float) -> None:
        _, rate, _ = self.coordinate(pose, joint)
        layout.add_couple(b, joint.links[1], -c * rate)
        layout.add_couple(b, joint.links[0], c * rate)


REVOLUTE = Revolute()
