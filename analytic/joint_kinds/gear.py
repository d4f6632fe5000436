"""The gear mesh (seed 001's G, "dişli"): two gears whose pitch circles roll on each other
without slipping, relative to whatever carries their centres (planetary trains included).
It removes one freedom (Sᵢ = 2).

Its geometry is a :class:`GearMesh` on the joint: gear a turns about its centre Pa (a point
of links[0]), gear b about Pb (a point of links[1]), pitch radii ra and rb, the pressure
angle α and whether the pair is internal (one gear a ring whose teeth face inward). With
e = (Pb − Pa)/|Pb − Pa| and t = e turned +90°, the pitch point P lies on the line of
centres at P = Pa + σa·ra·e = Pb + σb·rb·e (external: σa = +1, σb = −1; internal, a ring
b: σa = σb = −1; internal, a ring a: σa = σb = +1), and the drawn centre distance is
D = σa·ra − σb·rb.

- Constraint: the pitch points move together along t, σa·ra·ω_a − σb·rb·ω_b = D·θ̇ (θ the
  direction of Pa→Pb), written in positions as
  Φ = σa·ra·(φ_a − Δθ) − σb·rb·(φ_b − Δθ) = 0, φ and Δθ measured from the drawn pose.
- Reaction: the tooth force by gear a on gear b at P, along the line of action: its
  tangential part F_t·t (the one unknown) and its radial part tan α·|F_t|, which pushes the
  gears apart (along e on an external gear b, along −e on a ring or on a pinion in a ring)
  whichever way the torque goes. The radial part follows |F_t|: like Coulomb friction it is
  solved by Newton's method on the equilibrium equations.
- Reported: ``F_<joint>_x``, ``F_<joint>_y`` (the whole tooth force on links[1]),
  ``F_<joint>_t`` (along t) and ``F_<joint>_r`` (the radial part, ≥ 0); ``q_<joint>`` is
  the arc rolled on gear a's pitch circle, σa·ra·(φ_a − Δθ).
- A mesh has no friction model and takes no driver: its gears are driven at their bearings.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from mechcheck.analytic.joint_kinds.base import JointFrame, JointKind
from mechcheck.analytic.joint_kinds.drawing import JointDrawing, PitchCircle, Placement
from mechcheck.analytic.rigid import Array, Constraints, ForceLayout, Motion, cross, dot, perp
from mechcheck.analytic.values import CaseError, length_text

if TYPE_CHECKING:
    from mechcheck.analytic.linalg import Batched
    from mechcheck.analytic.linkage import Joint, JointFriction, Link
    from mechcheck.analytic.linkage_kinematics import LinkagePose

#: How far the drawn centre distance may be from ra + rb (or |ra − rb|), relative to it:
#: a drawing in millimetres to four decimals.
CENTRE_DISTANCE_RTOL = 1e-6
#: The pressure angle lies in [0°, 45°): standard gears use 14.5° to 25°.
MAX_PRESSURE_ANGLE = math.radians(45.0)


@dataclass(frozen=True)
class GearMesh:
    """A gear pair's geometry: centres (point names: Pa on links[0], Pb on links[1]), pitch
    radii (m), pressure angle (rad) and whether it is internal."""

    centres: tuple[str, str]
    pitch_radii: tuple[float, float]
    pressure_angle: float = math.radians(20.0)
    internal: bool = False

    @property
    def signs(self) -> tuple[float, float]:
        """(σa, σb): where the pitch point lies from each centre along e."""
        if not self.internal:
            return 1.0, -1.0
        ring_is_b = self.pitch_radii[1] > self.pitch_radii[0]
        return (-1.0, -1.0) if ring_is_b else (1.0, 1.0)

    @property
    def centre_distance(self) -> float:
        sa, sb = self.signs
        return sa * self.pitch_radii[0] - sb * self.pitch_radii[1]

    @property
    def separating(self) -> float:
        """The radial part's direction on gear b, along e (+1) or −e (−1)."""
        return -1.0 if self.internal else 1.0


def mesh_of(joint: Joint) -> GearMesh:
    assert joint.mesh is not None   # checked(): every gear joint has one
    return joint.mesh


@dataclass(frozen=True)
class _Centres:
    """Both centres now: positions, ∂/∂φ of each, and e, t, ρ = |Pb − Pa|."""

    pa: Array
    dpa: Array
    pb: Array
    dpb: Array

    @property
    def d(self) -> Array:
        return self.pb - self.pa

    @property
    def rho(self) -> Array:
        return np.hypot(self.d[:, 0], self.d[:, 1])

    @property
    def e(self) -> Array:
        return self.d / self.rho[:, None]


class Gear(JointKind):
    name = "gear"
    symbol = "G"
    freedoms = 2
    rotates = False
    pins = False
    drivable = False
    sketchable = False
    frictional = False

    def checked(self, joint: Joint, links: Mapping[str, Link], key: str) -> Joint:
        mesh = joint.mesh
        if mesh is None:
            raise CaseError("a gear mesh needs its centres and pitch_radii", key=f"{key}.centres")
        if joint.axis is not None:
            raise CaseError("a gear mesh has no axis", key=f"{key}.axis")
        for i, (centre, link) in enumerate(zip(mesh.centres, joint.links, strict=True)):
            if centre not in links[link].points:
                raise CaseError(f"links[{i}] ({link!r}) must carry its gear's centre {centre!r}",
                                key=f"{key}.centres")
        ra, rb = mesh.pitch_radii
        if not (ra > 0.0 and rb > 0.0 and math.isfinite(ra) and math.isfinite(rb)):
            raise CaseError("must both be > 0", key=f"{key}.pitch_radii")
        if mesh.internal and ra == rb:
            raise CaseError("an internal pair needs a ring larger than its pinion",
                            key=f"{key}.pitch_radii")
        if not 0.0 <= mesh.pressure_angle < MAX_PRESSURE_ANGLE:
            raise CaseError(f"must lie in [0°, 45°), got {math.degrees(mesh.pressure_angle):g}°",
                            key=f"{key}.pressure_angle")
        return joint

    def check_drawing(self, joint: Joint, points: Mapping[str, tuple[float, float]],
                      key: str) -> None:
        """The drawn centre distance must be ra + rb (external) or |ra − rb| (internal)."""
        mesh = mesh_of(joint)
        (xa, ya), (xb, yb) = (points[c] for c in mesh.centres)
        drawn, wanted = math.hypot(xb - xa, yb - ya), mesh.centre_distance
        if abs(drawn - wanted) > CENTRE_DISTANCE_RTOL * wanted:
            rule = "|ra − rb|" if mesh.internal else "ra + rb"
            raise CaseError(f"the drawn centre distance {length_text(drawn)} is not {rule} = "
                            f"{length_text(wanted)}", key=f"{key}.pitch_radii")

    # -- geometry now ---------------------------------------------------------------------
    def _centres(self, c: Constraints, joint: Joint) -> _Centres:
        a, b = joint.links
        ca, cb = mesh_of(joint).centres
        pa, dpa = c.point(a, np.array(c.linkage.points[ca]))
        pb, dpb = c.point(b, np.array(c.linkage.points[cb]))
        return _Centres(pa, dpa, pb, dpb)

    def _turn_of_line(self, linkage_points: Mapping[str, tuple[float, float]], joint: Joint,
                      d: Array) -> Array:
        """Δθ: how far the line Pa→Pb has turned from the drawing (wrapped to ±π)."""
        ca, cb = mesh_of(joint).centres
        d0 = np.subtract(linkage_points[cb], linkage_points[ca])
        return np.arctan2(d0[0] * d[:, 1] - d0[1] * d[:, 0], d0[0] * d[:, 0] + d0[1] * d[:, 1])

    def _rolled(self, phi_a: Array, phi_b: Array, turn: Array, mesh: GearMesh) -> Array:
        """Φ with Δθ taken on the branch nearest the gears' own rotations: φ counts whole
        turns, Δθ from positions does not."""
        sa, sb = mesh.signs
        ra, rb = mesh.pitch_radii
        span = mesh.centre_distance
        raw = sa * ra * phi_a - sb * rb * phi_b - span * turn
        return raw - span * math.tau * np.round(raw / (span * math.tau))

    # -- kinematics ---------------------------------------------------------------------
    def constrain(self, c: Constraints, joint: Joint, row: int) -> None:
        mesh = mesh_of(joint)
        a, b = joint.links
        sa, sb = mesh.signs
        ra, rb = mesh.pitch_radii
        span = mesh.centre_distance
        g = self._centres(c, joint)
        turn = self._turn_of_line(c.linkage.points, joint, g.d)
        c.phi[:, row] += self._rolled(c.angle(a), c.angle(b), turn, mesh)
        # ∂Δθ = t·(∂Pb − ∂Pa)/ρ, and Φ carries −D·Δθ.
        lever = span / g.rho
        t = perp(g.e)
        c.put(row, a, lever[:, None] * t, sa * ra + lever * dot(t, g.dpa))
        c.put(row, b, -lever[:, None] * t, -sb * rb - lever * dot(t, g.dpb))

    def accelerate(self, m: Motion, joint: Joint, out: Array, row: int) -> None:
        mesh = mesh_of(joint)
        a, b = joint.links
        ca, cb = (np.array(m.linkage.points[p]) for p in mesh.centres)
        d = m.position(b, cb) - m.position(a, ca)
        rho = np.hypot(d[:, 0], d[:, 1])
        e = d / rho[:, None]
        t = perp(e)
        dd = m.velocity(b, cb) - m.velocity(a, ca)
        centripetal = (-(m.spin(b) ** 2)[:, None] * m.rotated(b, cb)
                       + (m.spin(a) ** 2)[:, None] * m.rotated(a, ca))
        rho_dot, theta_dot = dot(e, dd), dot(t, dd) / rho
        out[:, row] = -mesh.centre_distance * (dot(t, centripetal) - 2.0 * rho_dot * theta_dot) / rho

    def row_lengths(self, size: float) -> tuple[float, ...]:
        return (1.0,)

    def drive(self, c: Constraints, joint: Joint, row: int) -> None:
        raise AssertionError("a gear mesh is never driven (Linkage refuses it)")

    def drive_acceleration(self, m: Motion, joint: Joint) -> Array | None:
        raise AssertionError("a gear mesh is never driven (Linkage refuses it)")

    def coordinate(self, pose: LinkagePose, joint: Joint) -> tuple[Array, Array, Array]:
        mesh = mesh_of(joint)
        a = joint.links[0]
        ca, cb = (pose.linkage.points[p] for p in mesh.centres)
        pa, va, aa = pose.point(a, ca)
        pb, vb, ab = pose.point(joint.links[1], cb)
        d, dd, ddd = pb - pa, vb - va, ab - aa
        rho = np.hypot(d[:, 0], d[:, 1])
        e = d / rho[:, None]
        t = perp(e)
        theta_dot = dot(t, dd) / rho
        rho_dot = dot(e, dd)
        theta_ddot = (dot(t, ddd) - 2.0 * rho_dot * theta_dot) / rho
        turn = self._turn_of_line(pose.linkage.points, joint, d)
        phi, omega, alpha = pose.angle(a)
        k = mesh.signs[0] * mesh.pitch_radii[0]
        return k * (phi - turn), k * (omega - theta_dot), k * (alpha - theta_ddot)

    # -- statics --------------------------------------------------------------------------
    def frame(self, pose: LinkagePose, joint: Joint) -> JointFrame:
        """At the pitch point: u = t (the tangential part's direction), n the separating
        direction on gear b."""
        mesh = mesh_of(joint)
        ca, cb = (pose.linkage.points[p] for p in mesh.centres)
        pa = pose.point(joint.links[0], ca)[0]
        d = pose.point(joint.links[1], cb)[0] - pa
        e = d / np.hypot(d[:, 0], d[:, 1])[:, None]
        pitch = pa + mesh.signs[0] * mesh.pitch_radii[0] * e
        return JointFrame(pitch, perp(e), mesh.separating * e)

    def react(self, k: Batched, layout: ForceLayout, joint: Joint, frame: JointFrame) -> None:
        assert frame.u is not None
        (col,) = layout.joint_columns(joint)
        layout.force_pair(k, joint.links, (col,), frame.u[None], frame.point)

    def reaction_lengths(self, size: float) -> tuple[float, ...]:
        return (1.0,)

    def exert(self, k: Batched, layout: ForceLayout, col: int, joint: Joint,
              frame: JointFrame) -> None:
        raise AssertionError("a gear mesh is never driven (Linkage refuses it)")

    def drawing(self, joint: Joint, place: Placement) -> JointDrawing:
        """Both pitch circles; the tooth force acts at the pitch point Pa + σa·ra·e."""
        mesh = mesh_of(joint)
        (xa, ya), (xb, yb) = (place.point(c) for c in mesh.centres)
        rho = math.hypot(xb - xa, yb - ya)
        reach = mesh.signs[0] * mesh.pitch_radii[0] / rho
        circles = tuple(PitchCircle(place.point(c), r)
                        for c, r in zip(mesh.centres, mesh.pitch_radii, strict=True))
        return JointDrawing(circles, (xa + reach * (xb - xa), ya + reach * (yb - ya)))

    def quantities(self, joint: Joint) -> dict[str, str]:
        return {f"F_{joint.name}_{part}": "N" for part in ("x", "y", "t", "r")}

    def reported(self, pose: LinkagePose, joint: Joint, x: Array, along: Array) -> dict[str, Array]:
        frame = self.frame(pose, joint)
        assert frame.u is not None and frame.n is not None
        tangential = x[:, 0]
        radial = math.tan(mesh_of(joint).pressure_angle) * np.abs(tangential)
        force = tangential[:, None] * frame.u + radial[:, None] * frame.n
        return {f"F_{joint.name}_x": force[:, 0], f"F_{joint.name}_y": force[:, 1],
                f"F_{joint.name}_t": tangential, f"F_{joint.name}_r": radial}

    # -- the radial part: nonlinear, as Coulomb friction is ---------------------------------
    def nonlinear_coefficient(self, joint: Joint) -> float:
        return math.tan(mesh_of(joint).pressure_angle)

    def coulomb_coefficient(self, friction: JointFriction, joint: Joint) -> float:
        return 0.0

    def coulomb(self, pose: LinkagePose, layout: ForceLayout, joint: Joint, coefficient: float,
                sense: Array, x: Array, phi: Array, dphi: Batched) -> None:
        """The radial part tan α·|F_t| along n at the pitch point, on gear b and back on a."""
        frame = self.frame(pose, joint)
        assert frame.n is not None
        (col,) = layout.joint_columns(joint)
        size = coefficient * np.abs(x[:, col])
        slope = coefficient * np.sign(x[:, col])
        moment = cross(frame.point, frame.n)
        for link, sign in ((joint.links[1], 1.0), (joint.links[0], -1.0)):
            r = layout.row(link)
            if r < 0:
                continue
            for offset, arm in ((0, frame.n[:, 0]), (1, frame.n[:, 1]), (2, moment)):
                phi[:, r + offset] += sign * arm * size
                dphi.add(r + offset, col, sign * arm * slope)

    def sliding_friction(self, coefficient: float, sense: Array, x: Array) -> Array:
        return np.zeros(x.shape[0])

    def viscous(self, b: Array, layout: ForceLayout, pose: LinkagePose, joint: Joint,
                c: float) -> None:
        raise AssertionError("a gear mesh has no viscous term (Linkage refuses it)")


GEAR = Gear()
