"""The gear mesh in pymunk: the tooth contact of an involute pair, a pin joint along the
line of action re-laid through the pitch point before every solve (:class:`ToothContact`).

Why not a :class:`pymunk.GearJoint`. A GearJoint holds ``ratio·φ_b − φ_a = phase`` in
absolute angles; the mesh rolls relative to the line of centres,
σa·ra·(φ_a − θ) − σb·rb·(φ_b − θ) = 0 (:mod:`mechcheck.analytic.joint_kinds.gear`), which
is that only while the line does not turn. On a planetary train the line turns with the
carrier: the constraint ties three bodies (sun, planet, carrier), a GearJoint ties two,
and a GearJoint between each gear and the carrier would hold each gear's turning relative
to the carrier fixed instead of tying the two gears together. A GearJoint also acts on
the bodies' angles alone, so the tooth force would miss the bearings and the carrier.

What is built instead is what involute teeth are: a frictionless contact at the pitch
point P whose normal is the line of action. The rolling constraint at the velocity level
is (v_b(P) − v_a(P))·t = 0 for the material points of both gears at P (t = e turned +90°,
e = unit Pa→Pb): v(P)·t = v_centre·t + σ·r·ω on each gear, and the difference is
D·θ̇ − (σa·ra·ω_a − σb·rb·ω_b), minus the analytic constraint's rate. Along e the relative
velocity at P is ρ̇, the rate of the centre distance, which the rest of the linkage holds
(the bearings on a frame or a carrier; :func:`centre_distance_held`, refused by name where
it does not). So a constraint on (v_b(P) − v_a(P))·w with w = t + s·tan α·n (n the
separating direction on gear b, s = ±1 the flank in contact) is the rolling constraint,
and its force, along w, is the analytic tooth force F_t·t + tan α·|F_t|·n when s =
sign(F_t): the tangential and the radial part are one constraint impulse, of one solve.

That constraint is a :class:`pymunk.PinJoint` from a point of gear a on the line of action,
a lever L behind P, to the point P of gear b: it holds the distance between them along
their line (w), and a point of a rigid body anywhere on that line moves along it as P
does. Its impulse is a scalar along its direction, applied at the anchors, so the tooth
force reaches both centres' bearings (and a carrier) as the teeth exert it. (A groove
would do the same with its normal along w, but Chipmunk solves a groove as a 2-D pivot and
then drops the part along the groove, which converges to the constraint only where the
relative velocity along the groove is zero: measured on the external pair, it corrects
the rolled arc's drift 2.6× over in a step, an oscillation that grows.) Chipmunk fixes
the anchors in their bodies and the pitch point moves through both as they turn, so the
pre-solve callback (which Chipmunk calls after it has moved the bodies and before it
solves) lays the pin along the line of action through the pitch point of the pose the
step solves at, every step:
the constraint is exact at every step's pose, in the Python and in the compiled loop
alike (the callback runs inside ``cpSpaceStep``). The flank s is the sign of F_t in the
pin's own last impulse (measured; s = +1 before the first); where the torque reverses,
the one step on the other flank reads a radial part of the wrong sign, which the next
step's flank corrects. The rolled arc's own error Φ (integration drift) is set off across
the line at P, so the pin's error correction rolls Φ back as a pivot's closes a gap.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pymunk
from scipy.linalg import null_space

from mechcheck.analytic.joint_kinds import GearMesh
from mechcheck.analytic.linkage import Joint, Linkage
from mechcheck.analytic.linkage_kinematics import constraint_system
from mechcheck.analytic.rigid import Layout
from mechcheck.sim_models.pymunk._fast import Cell, direction_cells, impulse_cells, read

Vec = tuple[float, float]

#: The pin's lever L behind the pitch point, × the larger pitch radius: any length gives the
#: same constraint; one of the linkage's own keeps the pin's arithmetic at its scale.
LEVER = 1.0
#: The centre distance counts as held when the motions the other joints allow change it by
#: no more than this, relative (rounding of the Jacobian's null space).
HELD_RTOL = 1e-9


def unit(x: float, y: float) -> Vec:
    size = math.hypot(x, y)
    return x / size, y / size


@dataclass
class ToothContact:
    """A gear joint's tooth contact: the ``pin`` from body a (links[0]) to body b
    (links[1]), laid along the line of action through the pitch point by :meth:`lay`
    before every solve, and read back as the tooth force and its parts."""

    name: str
    mesh: GearMesh
    pin: pymunk.PinJoint
    local: tuple[Vec, Vec]  # the centres in their bodies (the drawing's coordinates)
    lever: float
    cells: list[Cell] = field(init=False)      # the pin's impulse, along its direction
    direction: list[Cell] = field(init=False)  # that direction n (of the last step)

    def __post_init__(self) -> None:
        self.cells = impulse_cells(self.pin)
        self.direction = direction_cells(self.pin)
        self.pin.pre_solve = self.pre_solve

    @classmethod
    def build(cls, joint: Joint, linkage: Linkage, a: pymunk.Body, b: pymunk.Body) -> ToothContact:
        mesh = joint.mesh
        assert mesh is not None   # the analytic engine's check: every gear joint has one
        local = tuple(linkage.points[c] for c in mesh.centres)
        lever = LEVER * max(mesh.pitch_radii)
        pin = pymunk.PinJoint(a, b, (local[0][0] - lever, local[0][1]), local[0])
        pin.distance = lever
        contact = cls(joint.name, mesh, pin, (local[0], local[1]), lever)
        contact.lay()
        return contact

    # -- the geometry now -------------------------------------------------------------------
    def centres(self) -> tuple[pymunk.Vec2d, pymunk.Vec2d]:
        """Both centres in the world, from their bodies (local coordinates are the drawing's)."""
        return self.pin.a.local_to_world(self.local[0]), self.pin.b.local_to_world(self.local[1])

    def line(self) -> tuple[pymunk.Vec2d, Vec, float]:
        """(Pa, e, Δθ): centre a, the unit e from Pa to Pb and how far that line has turned
        from the drawing (±π)."""
        pa, pb = self.centres()
        dx, dy = pb.x - pa.x, pb.y - pa.y
        (xa, ya), (xb, yb) = self.local
        d0x, d0y = xb - xa, yb - ya   # the line in the drawing: Δθ is measured from it
        return pa, unit(dx, dy), math.atan2(d0x * dy - d0y * dx, d0x * dx + d0y * dy)

    def rolled(self, turn: float) -> float:
        """Φ = σa·ra·(φ_a − Δθ) − σb·rb·(φ_b − Δθ), on the branch nearest zero (the analytic
        constraint, whose Δθ counts no whole turns)."""
        (sa, sb), (ra, rb) = self.mesh.signs, self.mesh.pitch_radii
        span = self.mesh.centre_distance
        raw = sa * ra * (self.pin.a.angle - turn) - sb * rb * (self.pin.b.angle - turn)
        return math.remainder(raw, span * math.tau) if math.isfinite(raw) else math.nan

    def force(self) -> Vec:
        """The pin's last impulse as a vector on gear b (the tooth force × dt)."""
        (j,), (nx, ny) = read(self.cells), read(self.direction)
        return j * nx, j * ny

    def flank(self, t: Vec) -> float:
        """s: the sign of F_t in the pin's last impulse (+1 before there is one)."""
        jx, jy = self.force()
        return -1.0 if jx * t[0] + jy * t[1] < 0.0 else 1.0

    # -- laid before every solve --------------------------------------------------------------
    def pre_solve(self, constraint: pymunk.Constraint, space: pymunk.Space) -> None:
        self.lay()

    def lay(self) -> None:
        """The pin along the line of action w, from the point L behind the pitch point P on
        gear a to P on gear b, that end set off by −Φ·t (so the pin's error correction rolls
        Φ back to zero). A pose that is not finite is left as it is: the run that reached
        it reports it (an exception here would be swallowed by the C callback)."""
        pa, (ex, ey), turn = self.line()
        phi = self.rolled(turn)
        if not (math.isfinite(pa.x) and math.isfinite(pa.y) and math.isfinite(phi)):
            return
        t = (-ey, ex)
        sa, ra = self.mesh.signs[0], self.mesh.pitch_radii[0]
        px, py = pa.x + sa * ra * ex, pa.y + sa * ra * ey
        lean = self.flank(t) * math.tan(self.mesh.pressure_angle) * self.mesh.separating
        wx, wy = unit(t[0] + lean * ex, t[1] + lean * ey)   # the line of action
        self.pin.anchor_a = self.pin.a.world_to_local((px - self.lever * wx, py - self.lever * wy))
        self.pin.anchor_b = self.pin.b.world_to_local((px - phi * t[0], py - phi * t[1]))

    # -- read back ----------------------------------------------------------------------------
    def reactions(self, dt: float) -> dict[str, float]:
        """F_x, F_y (the tooth force by gear a on gear b), F_t and F_r (its parts along t
        and along the separating direction, at the pose now) of the last step."""
        jx, jy = self.force()
        fx, fy = jx / dt, jy / dt
        _, (ex, ey), _ = self.line()
        sep = self.mesh.separating
        f = f"F_{self.name}"
        return {f"{f}_x": fx, f"{f}_y": fy, f"{f}_t": -ey * fx + ex * fy,
                f"{f}_r": sep * (ex * fx + ey * fy)}

    def rate(self) -> float:
        """q̇ = σa·ra·(ω_a − θ̇), θ̇ = t·(v_Pb − v_Pa)/ρ from the bodies' velocities."""
        pa, pb = self.centres()
        body_a, body_b = self.pin.a, self.pin.b
        va, vb = body_a.velocity_at_world_point(pa), body_b.velocity_at_world_point(pb)
        dx, dy = pb.x - pa.x, pb.y - pa.y
        theta_dot = (dx * (vb.y - va.y) - dy * (vb.x - va.x)) / (dx * dx + dy * dy)
        return self.mesh.signs[0] * self.mesh.pitch_radii[0] * (body_a.angular_velocity - theta_dot)


def centre_distance_held(linkage: Linkage, joint: Joint) -> bool:
    """Whether the linkage's other joints hold the mesh's centre distance (at the drawn
    pose): the gradient of |Pb − Pa| is orthogonal to every motion they allow. The
    analytic mesh assumes it (its pitch point and rate use D); a frame or a carrier that
    both gears turn on holds it."""
    layout = Layout(linkage)
    q = np.zeros((1, layout.size))
    _, jac = constraint_system(linkage, q, np.zeros((1, len(linkage.drivers))), drivers=False)
    rows = jac.dense()[0]
    first = 0
    for other in linkage.joints:
        if other.name == joint.name:
            break
        first += other.kind.rows
    others = np.delete(rows, range(first, first + joint.kind.rows), axis=0)
    grad = distance_gradient(linkage, joint, layout)
    lengths = np.tile([1.0, 1.0, linkage.scale], layout.size // 3)  # φ columns as lengths
    free = null_space(others / lengths)
    if free.size == 0:
        return True
    return float(np.abs((grad / lengths) @ free).max()) <= HELD_RTOL * float(np.linalg.norm(grad / lengths))


def distance_gradient(linkage: Linkage, joint: Joint, layout: Layout) -> np.ndarray:
    """∂|Pb − Pa|/∂q at the drawn pose (q = 0: ∂P/∂φ = P turned +90°)."""
    mesh = joint.mesh
    assert mesh is not None
    (xa, ya), (xb, yb) = (linkage.points[c] for c in mesh.centres)
    ex, ey = unit(xb - xa, yb - ya)
    grad = np.zeros(layout.size)
    for link, (x, y), sign in ((joint.links[0], (xa, ya), -1.0), (joint.links[1], (xb, yb), 1.0)):
        k = layout.index(link)
        if k >= 0:
            grad[k:k + 3] += sign * np.array([ex, ey, -ex * y + ey * x])
    return grad
