"""The links' mass matrix and the forces on them at one state, in the links' own
coordinates (t_x, t_y, φ per moving link), over all links, masses, loads and springs at
once: the terms of the trajectory reference's equations of motion (:mod:`.linkage_dynamics`)
𝕄(q)·q̈ = F(q, q̇) + Jᵀλ.

Each link's masses make one rigid body (their total mass, centre and inertia about it);
with r = R(φ)·c0 its centre's offset from the link's origin, T = ½m|ṫ + ω·perp(r)|² + ½Iω²
gives the 3 × 3 block [[m, 0, −m·r_y], [0, m, m·r_x], [−m·r_y, m·r_x, I + m|r|²]] and the
velocity term m·ω²·r on t (Lagrange's equations). A force f at a point r from the link's
origin is (f, r × f) in these coordinates, a couple (0, 0, M); a joint's torsion spring,
damper or viscous friction acts along its coordinate's gradient (its driver row D):
−(k·(q − q0) + c·q̇)·Dᵀ. The power of each force is F·q̇, which the energy balance
integrates: the loads' as work, the dampers' as what is dissipated.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mechcheck.analytic.linkage import LinearSpring, Linkage, TorsionSpring
from mechcheck.analytic.linkage_loads import MEETING
from mechcheck.analytic.motion_rows import Rows, coordinate_rows
from mechcheck.analytic.rigid import Array, kept


@dataclass(frozen=True)
class Forces:
    """The generalised forces at one state (3n,): weights and springs' stiffness
    (``conservative``), the point loads (``loads``), dampers and viscous friction
    (``dissipative``), and the velocity terms of the mass matrix (``inertial``)."""

    conservative: Array
    loads: Array
    dissipative: Array
    inertial: Array

    @property
    def total(self) -> Array:
        return self.conservative + self.loads + self.dissipative + self.inertial


@dataclass(frozen=True)
class Terms:
    """A linkage's masses, loads and springs as arrays (:func:`terms`)."""

    links: int
    mass: Array
    com_x: Array
    com_y: Array
    inertia: Array
    gravity: Array
    load_links: Array
    load_x: Array
    load_y: Array
    load_force: Array
    load_torque: Array
    load_index: Array
    spring_stiffness: Array
    spring_length: Array
    spring_damping: Array
    spring_index: Array
    spring_ends: Array
    spring_drawn: Array
    meeting: float
    coordinates: Rows | None
    coordinate_stiffness: Array
    coordinate_free: Array
    coordinate_damping: Array

    def mass_times(self, cos: Array, sin: Array, v: Array) -> Array:
        """𝕄·v for v (3n, k), the links' turns given (cos, sin of each link's φ, the
        ground's last)."""
        n = self.links
        rx, ry = self._centres(cos, sin)
        m = self.mass
        vt = v.reshape(n, 3, -1)
        out = np.empty_like(vt)
        mx, my = (m * rx)[:, None], (m * ry)[:, None]
        out[:, 0] = m[:, None] * vt[:, 0] - my * vt[:, 2]
        out[:, 1] = m[:, None] * vt[:, 1] + mx * vt[:, 2]
        out[:, 2] = (-my * vt[:, 0] + mx * vt[:, 1]
                     + (self.inertia + m * (rx * rx + ry * ry))[:, None] * vt[:, 2])
        return out.reshape(v.shape)

    def _centres(self, cos: Array, sin: Array) -> tuple[Array, Array]:
        c, s = cos[:self.links], sin[:self.links]
        return c * self.com_x - s * self.com_y, s * self.com_x + c * self.com_y

    def forces(self, q: Array, qdot: Array, cos: Array, sin: Array) -> Forces:
        """The generalised forces at q, q̇ (each (3n,))."""
        size = 3 * self.links
        rx, ry = self._centres(cos, sin)
        omega = qdot[2::3]
        wx, wy = self.mass * self.gravity[0], self.mass * self.gravity[1]
        conservative = np.empty(size)
        conservative[0::3], conservative[1::3], conservative[2::3] = wx, wy, rx * wy - ry * wx
        inertial = np.zeros(size)
        spin = self.mass * omega * omega
        inertial[0::3], inertial[1::3] = spin * rx, spin * ry
        loads = self._loads(cos, sin) if self.load_links.size else np.zeros(size)
        dissipative = np.zeros(size)
        if self.spring_stiffness.size:
            elastic, damping = self._springs(q, qdot, cos, sin)
            conservative += elastic
            dissipative += damping
        flat = [conservative, loads, dissipative]
        if self.coordinates is not None:
            self._add_coordinates(flat, q, qdot)
        return Forces(flat[0], flat[1], flat[2], inertial)

    def _summed(self, index: Array, values: Array) -> Array:
        """Values summed into the coordinates at ``index`` (the ground's dropped), (3n,)."""
        summed = np.bincount(index, values, minlength=3 * self.links + 3)
        return np.asarray(summed[:3 * self.links], dtype=np.float64)

    def _loads(self, cos: Array, sin: Array) -> Array:
        k = self.load_links
        c, s = cos[k], sin[k]
        rx = c * self.load_x - s * self.load_y
        ry = s * self.load_x + c * self.load_y
        f = self.load_force
        moment = rx * f[:, 1] - ry * f[:, 0] + self.load_torque
        return self._summed(self.load_index, np.concatenate([f[:, 0], f[:, 1], moment]))

    def _springs(self, q: Array, qdot: Array, cos: Array, sin: Array) -> tuple[Array, Array]:
        """Linear springs: tension k(L − L0) and c·L̇ along the line between their ends, a
        toward b (the elastic and the damping parts)."""
        links, drawn = self.spring_ends, self.spring_drawn      # every a end, then every b end
        c, s = cos[links], sin[links]
        rx = c * drawn[:, 0] - s * drawn[:, 1]
        ry = s * drawn[:, 0] + c * drawn[:, 1]
        k = self.spring_stiffness.size
        at = 3 * links
        qe, qde = np.append(q, _GROUND), np.append(qdot, _GROUND)
        omega = qde[at + 2]
        dx = np.diff((qe[at] + rx).reshape(2, k), axis=0)[0]
        dy = np.diff((qe[at + 1] + ry).reshape(2, k), axis=0)[0]
        vx = np.diff((qde[at] - omega * ry).reshape(2, k), axis=0)[0]
        vy = np.diff((qde[at + 1] + omega * rx).reshape(2, k), axis=0)[0]
        length = np.hypot(dx, dy)
        meets = length <= self.meeting
        safe = np.where(meets, 1.0, length)
        ux, uy = np.where(meets, 0.0, dx / safe), np.where(meets, 0.0, dy / safe)
        both = np.array([self.spring_stiffness * (length - self.spring_length),
                         self.spring_damping * (ux * vx + uy * vy)])
        fx, fy = both * ux, both * uy                 # (2, k): on end a; the reverse on b
        sign = np.repeat([1.0, -1.0], k)
        fx2, fy2 = np.tile(fx, 2) * sign, np.tile(fy, 2) * sign
        values = np.concatenate([fx2, fy2, rx * fy2 - ry * fx2], axis=1)
        return self._summed(self.spring_index, values[0]), self._summed(self.spring_index, values[1])

    def _add_coordinates(self, flat: list[Array], q: Array, qdot: Array) -> None:
        """Torsion springs, their dampers and viscous joints: −(k(q − q0) + c·q̇)·Dᵀ."""
        assert self.coordinates is not None
        rows = self.coordinates
        state = rows.at(q)
        gradient = rows.dense(state)
        rate = gradient @ qdot
        flat[0] = flat[0] - gradient.T @ (self.coordinate_stiffness * state.phi
                                          - self.coordinate_free)
        flat[2] = flat[2] - gradient.T @ (self.coordinate_damping * rate)


def terms(linkage: Linkage) -> Terms:
    """The linkage's :class:`Terms`, kept with it."""
    return kept(linkage, "motion terms", lambda: _terms(linkage))


def _terms(linkage: Linkage) -> Terms:
    n = len(linkage.moving_links)
    named, table = _coordinate_table(linkage)
    return Terms(n, *_bodies(linkage), np.array(linkage.gravity, dtype=float),
                 *_point_loads(linkage), *_linear_springs(linkage), MEETING * linkage.scale,
                 coordinate_rows(linkage, named) if named else None,
                 table[:, 0].copy(), table[:, 1].copy(), table[:, 2].copy())


def _link(linkage: Linkage, name: str) -> int:
    """The link's number (the ground: the count of moving links)."""
    return linkage.link_number.get(name, len(linkage.moving_links))


def _bodies(linkage: Linkage) -> tuple[Array, Array, Array, Array]:
    """Each moving link's masses as one rigid body: its mass, centre (x, y, in the link)
    and inertia about the centre."""
    n = len(linkage.moving_links)
    mass, first, second = np.zeros(n), np.zeros((n, 2)), np.zeros(n)
    for m in linkage.masses:     # Σm, Σm·c, Σ(I + m|c|²)
        k = linkage.link_number[m.link]
        mass[k] += m.mass
        first[k] += m.mass * np.array(m.com)
        second[k] += m.inertia + m.mass * float(np.dot(m.com, m.com))
    has = mass > 0.0
    com = np.where(has[:, None], first / np.where(has, mass, 1.0)[:, None], 0.0)
    inertia = second - mass * (com * com).sum(axis=1)
    return mass, com[:, 0].copy(), com[:, 1].copy(), inertia


def _point_loads(linkage: Linkage) -> tuple[Array, Array, Array, Array, Array, Array]:
    """The point loads: links, points (x, y), forces, couples, where they add up."""
    loads = linkage.loads
    links = [_link(linkage, ld.link) for ld in loads]
    return (np.array(links, dtype=np.intp),
            np.array([ld.at[0] for ld in loads]), np.array([ld.at[1] for ld in loads]),
            np.array([ld.force for ld in loads], dtype=float).reshape(-1, 2),
            np.array([ld.torque for ld in loads], dtype=float), _flat_index(links))


def _linear_springs(linkage: Linkage) -> tuple[Array, Array, Array, Array, Array, Array]:
    """The linear springs: stiffness, free length, damping, where their ends add up, and
    every end (a ends, then b ends): its link and its point."""
    linear = [s for s in linkage.springs if isinstance(s, LinearSpring)]
    a = [_link(linkage, s.ends[0][0]) for s in linear]
    b = [_link(linkage, s.ends[1][0]) for s in linear]
    points = [np.array([s.ends[e][1] for s in linear], dtype=float).reshape(-1, 2) for e in (0, 1)]
    return (np.array([s.stiffness for s in linear]), np.array([s.free_length for s in linear]),
            np.array([s.damping for s in linear]), _flat_index(a + b),
            np.array(a + b, dtype=np.intp), np.concatenate(points).reshape(-1, 2))


def _coordinate_table(linkage: Linkage) -> tuple[tuple[str, ...], Array]:
    """The joints whose coordinate carries a torsion spring, a damper or viscous friction,
    and (k, k·q0, c) of each."""
    joints: dict[str, list[float]] = {}
    for s in linkage.springs:
        if isinstance(s, TorsionSpring):
            entry = joints.setdefault(s.joint, [0.0, 0.0, 0.0])
            entry[0] += s.stiffness
            entry[1] += s.stiffness * s.free_rotation
            entry[2] += s.damping
    if linkage.friction is not None:
        for name, c in linkage.friction.viscous.items():
            joints.setdefault(name, [0.0, 0.0, 0.0])[2] += c
    named = tuple(joints)
    return named, np.array([joints[j] for j in named]).reshape(-1, 3)


def _flat_index(*links: list[int]) -> Array:
    """The coordinates (t_x of each, then t_y, then φ) of each list of links, one after
    the other: where :meth:`Terms._summed` adds values given in that order."""
    parts = [3 * np.array(k, dtype=np.intp) + c for k in links for c in range(3)]
    return np.concatenate(parts) if parts else np.zeros(0, dtype=np.intp)


_GROUND = np.zeros(3)
