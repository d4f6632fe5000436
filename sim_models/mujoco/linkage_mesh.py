"""The gear mesh in MuJoCo: a spatial tendon on the line of action, held at constant length
by a tendon equality.

The tooth force of involute gears acts along the line of action: through the pitch point P,
at the pressure angle α to the common tangent t (``mechcheck.analytic.joint_kinds.gear``).
Its direction on gear b is d = s·cos α·t + sin α·n, with n the separating direction (along
e = Pa→Pb on an external gear b, along −e on a ring or a pinion in a ring) and s = ±1 the
side, which follows the sense of the transmitted torque. The model is a straight tendon
between a site on gear a at P − ℓ·d and a site on gear b at P + ℓ·d (ℓ the centre
distance), and a tendon equality that holds its length:

- its Jacobian is d·(∂X_b/∂q − ∂X_a/∂q): a rigid body's velocity projected on a line is the
  same at every point of the line, so this is the relative speed of the two gears along
  the line of action at their contact point — the involute mesh's kinematics, exactly, at
  every pose where the sites lie on the current line (below). With the centre distance
  held by the bearings it is cos α times the pitch circles' rolling;
- its force f acts along d on the site of gear b (f > 0 pushes the sites apart: gear a
  pushes gear b) and opposite on gear a, so the bearings carrying the gears feel its
  radial part; MuJoCo's ``mj_rnePostConstraint`` puts a spatial tendon's force at its
  sites into ``cfrc_ext`` (measured: a tendon equality's force and the hinge reaction it
  loads agree to 1e-15), so every reaction read from ``cfrc_int`` carries it.

The sites are fixed in their gears, which turn, so the line of action moves off them: before
every forward pass (with the loads, :meth:`.linkage_loads.RigLoads.apply_loads`) they are
put back on the current line, from MuJoCo's own body frames, and the equality's offset is
moved so that its violation (MuJoCo's integral of the rolling error) is unchanged; where a
state is set from outside (a seed) the mesh is held where it is (violation 0).

The side: a tooth pushes, so f ≥ 0 on the right side. The model starts on s = +1 and,
where MuJoCo's own tendon force comes out pulling (its radial part F_r < 0), is put on the
other side and solved again (:func:`wrong_sides`). With α = 0 both sides are one line and
nothing is flipped.

Reported: ``F_<j>_x``, ``F_<j>_y`` = f·u (u the unit vector between MuJoCo's two sites),
``F_<j>_t`` = F·t, ``F_<j>_r`` = F·n, t and n from MuJoCo's centres; ``q_<j>`` =
σa·ra·(φa − Δθ), φa MuJoCo's rotation of gear a and Δθ the turn of its line of centres.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import TypeVar

import mujoco
import numpy as np
from numpy.typing import NDArray

from mechcheck.analytic.joint_kinds import GearMesh
from mechcheck.analytic.linkage import Joint, Linkage

Array = NDArray[np.float64]
R = TypeVar("R")


def mesh_of(joint: Joint) -> GearMesh:
    assert joint.mesh is not None  # the kind's check: every gear joint has one
    return joint.mesh


def site_names(joint: Joint) -> tuple[str, str]:
    """The tendon's two sites: on links[0] (gear a), then on links[1] (gear b)."""
    return f"{joint.name}_on_{joint.links[0]}", f"{joint.name}_on_{joint.links[1]}"


def tendon_name(joint: Joint) -> str:
    return f"mesh_{joint.name}"


def perp(v: Array) -> Array:
    """v turned +90° (…, 2)."""
    return np.stack([-v[..., 1], v[..., 0]], axis=-1)


@dataclass(frozen=True)
class Line:
    """The line of action of N states (each (N, 2)): the pitch point, the tooth force's
    direction on gear b, the common tangent t and the separating direction n."""

    pitch: Array
    d: Array
    t: Array
    n: Array


def line_of_action(pa: Array, pb: Array, mesh: GearMesh, side: float) -> Line:
    """The line of action of gears centred at ``pa`` and ``pb`` (N, 2) on ``side``."""
    span = pb - pa
    e = span / np.hypot(span[:, 0], span[:, 1])[:, None]
    t = perp(e)
    n = mesh.separating * e
    alpha = mesh.pressure_angle
    d = side * math.cos(alpha) * t + math.sin(alpha) * n
    return Line(pa + mesh.signs[0] * mesh.pitch_radii[0] * e, d, t, n)


def drawn_sites(linkage: Linkage, joint: Joint) -> tuple[tuple[float, float], tuple[float, float]]:
    """Where the tendon's sites are drawn (side +1): on gear a and on gear b."""
    mesh = mesh_of(joint)
    pa, pb = (np.array([linkage.points[c]]) for c in mesh.centres)
    line = line_of_action(pa, pb, mesh, 1.0)
    arm = mesh.centre_distance
    a, b = line.pitch - arm * line.d, line.pitch + arm * line.d
    return (float(a[0, 0]), float(a[0, 1])), (float(b[0, 0]), float(b[0, 1]))


def turn_of_line(drawn: Array, span: Array) -> Array:
    """Δθ: how far the line of centres ``span`` (N, 2) has turned from ``drawn`` (2,),
    wrapped to ±π (as the analytic coordinate)."""
    return np.arctan2(drawn[0] * span[:, 1] - drawn[1] * span[:, 0],
                      drawn[0] * span[:, 0] + drawn[1] * span[:, 1])


@dataclass
class MeshLine:
    """One gear mesh in a compiled model: where its parts are, and its side (±1)."""

    joint: Joint
    equality: int
    tendon: int
    sites: tuple[int, int]
    bodies: tuple[int, int]
    #: Each centre in its gear's body frame (3,).
    centres: tuple[Array, Array]
    drawn_span: Array
    side: float = 1.0

    @property
    def mesh(self) -> GearMesh:
        return mesh_of(self.joint)

    def centre_positions(self, xpos: Array, xmat: Array) -> tuple[Array, Array]:
        """(N, 2) each: both centres in N states' body frames (xpos (N, nbody, 3), xmat
        (N, nbody, 9))."""
        out = []
        for body, local in zip(self.bodies, self.centres, strict=True):
            rot = xmat[:, body].reshape(-1, 3, 3)
            out.append((xpos[:, body] + rot @ local)[:, :2])
        return out[0], out[1]

    def line(self, xpos: Array, xmat: Array) -> Line:
        pa, pb = self.centre_positions(xpos, xmat)
        return line_of_action(pa, pb, self.mesh, self.side)

    def aim(self, m: mujoco.MjModel, d: mujoco.MjData, hold: bool) -> None:
        """Put the sites on the current line of action (after MuJoCo's kinematics), and
        keep the equality's violation (``hold``: make it 0, the mesh held where it is)."""
        line = self.line(d.xpos[None], d.xmat[None])
        arm = self.mesh.centre_distance
        targets = (line.pitch[0] - arm * line.d[0], line.pitch[0] + arm * line.d[0])
        before = self.length(d.site_xpos)
        for site, body, target in zip(self.sites, self.bodies, targets, strict=True):
            world = np.array([target[0], target[1], 0.0]) - d.xpos[body]
            m.site_pos[site] = d.xmat[body].reshape(3, 3).T @ world
        after = 2.0 * arm
        violation = 0.0 if hold else before - m.tendon_length0[self.tendon] - m.eq_data[self.equality, 0]
        m.eq_data[self.equality, 0] = after - m.tendon_length0[self.tendon] - violation

    def length(self, site_xpos: Array) -> float:
        """The tendon's length between its sites where MuJoCo's kinematics put them."""
        a, b = (site_xpos[s] for s in self.sites)
        return float(np.linalg.norm(b - a))

    def flip(self) -> None:
        self.side = -self.side

    def force(self, f: Array, site_xpos: Array) -> Array:
        """(N, 2): the tooth force on gear b of N states: the tendon force f (N,) along
        the unit vector from MuJoCo's site on gear a to its site on gear b."""
        u = site_xpos[:, self.sites[1], :2] - site_xpos[:, self.sites[0], :2]
        return f[:, None] * u / np.hypot(u[:, 0], u[:, 1])[:, None]

    def readings(self, f: Array, s_xpos: Array, xpos: Array, xmat: Array,
                 phi_a: Array) -> dict[str, Array]:
        """The mesh's quantities of N states: the tooth force F, its parts along t and n,
        and q (the arc rolled on gear a)."""
        name = self.joint.name
        force = self.force(f, s_xpos)
        pa, pb = self.centre_positions(xpos, xmat)
        line = line_of_action(pa, pb, self.mesh, self.side)
        k = self.mesh.signs[0] * self.mesh.pitch_radii[0]
        return {f"F_{name}_x": force[:, 0], f"F_{name}_y": force[:, 1],
                f"F_{name}_t": (force * line.t).sum(axis=1),
                f"F_{name}_r": (force * line.n).sum(axis=1),
                f"q_{name}": k * (phi_a - turn_of_line(self.drawn_span, pb - pa))}


def wrong_sides(meshes: Iterable[MeshLine], values: Mapping[str, float]) -> list[MeshLine]:
    """The meshes whose tendon MuJoCo found pulling (radial part < 0: the tooth would pull
    the gears together), on a line of action with two sides (α > 0)."""
    return [mesh for mesh in meshes
            if mesh.mesh.pressure_angle > 0.0 and values.get(f"F_{mesh.joint.name}_r", 0.0) < 0.0]


def pushing(meshes: Sequence[Sequence[MeshLine]], run: Callable[[], R],
            values_of: Callable[[R], Mapping[str, float]]) -> R:
    """``run()``, and where a mesh's tendon came out pulling, again with that mesh on the
    other side of its line of action (in every model of ``meshes``: one list per model)."""
    result = run()
    wrong = {mesh.joint.name for mesh in wrong_sides(meshes[0], values_of(result))} if meshes else set()
    if not wrong:
        return result
    for model in meshes:
        for mesh in model:
            if mesh.joint.name in wrong:
                mesh.flip()
    return run()
