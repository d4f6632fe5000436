"""The member-equilibrium matrix method, vectorised over poses.

For each moving link j = 2, 3, 4 the D'Alembert equilibrium gives three rows
(ΣFx, ΣFy, ΣM about A0). The nine unknowns are::

    x = [F12x, F12y, F23x, F23y, F34x, F34y, J1, J2, T]

with J = (F14x, F14y) for a four-bar, J = (N14, M14) for a slider-crank
(F14 = N14·n + f·u, the friction f along the slide through B), and T the
drive torque on link 2 (T12) or link 4 (T14). F_ij acts *on* j, so it
enters link j's rows with + and link i's rows with − (F_ji = −F_ij).

The system is written K x + b + φ(x) = 0 with b the known loads (external
loads, weights, inertia forces, viscous friction) and φ the Coulomb friction
terms, which depend on |F| and make the problem nonlinear. Without Coulomb
friction x = −K⁻¹ b.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from analytic.case import Case, FourBarGeometry, Load, Mass
from analytic.kinematics import Array, Pose, cross, unit

N_UNKNOWNS = 9
#: Columns of the pin forces F_ij in x, by joint name.
PIN_COLUMNS = {"A0": (0, 1), "A": (2, 3), "B": (4, 5), "B0": (6, 7)}
#: (i, j) of each joint: F_ij is the force by i on j.
JOINT_LINKS = {"A0": (1, 2), "A": (2, 3), "B": (3, 4), "B0": (1, 4), "slide": (1, 4)}

#: Above this condition number (of the dimensionless system, see
#: :func:`condition_number`) a pose is reported ``singular`` and its forces
#: withheld. Reason: a relative change of 1e-8 in the geometry (10 nm on a
#: 1 m link, below any drawing's precision) then changes the forces by order
#: 100 %, and rounding alone (cond × 2.2e-16 ≈ 2e-8) already exceeds the 1e-9
#: agreement the analytic backends are held to.
SINGULAR_CONDITION = 1.0e8


def row(link: int) -> int:
    """First of the three equation rows of a moving link."""
    return 3 * (link - 2)


def slide_frame(case: Case) -> tuple[Array, Array]:
    """(u, n): slide direction and its +90° normal."""
    u = unit(np.array(case.ground_angle))
    return u, np.array([-u[1], u[0]])


def coefficient_matrix(case: Case, pose: Pose) -> Array:
    """K, shape (N, 9, 9): the linear part of the equilibrium equations."""
    n = pose.theta12.shape[0]
    k = np.zeros((n, N_UNKNOWNS, N_UNKNOWNS))
    j = pose.joints

    def put_force(link: int, col: int, point: Array, sign: float) -> None:
        # A force (x, y) in columns col, col+1 acting on `link` at `point`.
        r = row(link)
        k[:, r, col] += sign
        k[:, r + 1, col + 1] += sign
        k[:, r + 2, col] += -sign * point[:, 1]
        k[:, r + 2, col + 1] += sign * point[:, 0]

    put_force(2, 0, j["A0"], +1.0)   # F12 on 2
    put_force(2, 2, j["A"], -1.0)    # F32 = −F23 on 2
    put_force(3, 2, j["A"], +1.0)    # F23 on 3
    put_force(3, 4, j["B"], -1.0)    # F43 on 3
    put_force(4, 4, j["B"], +1.0)    # F34 on 4
    if isinstance(case.geometry, FourBarGeometry):
        put_force(4, 6, j["B0"], +1.0)  # F14 on 4
    else:
        _, nrm = slide_frame(case)
        k[:, 6, 6] = nrm[0]
        k[:, 7, 6] = nrm[1]
        k[:, 8, 6] = cross(j["B"], np.broadcast_to(nrm, j["B"].shape))
        k[:, 8, 7] = 1.0                # M14: the guide's moment on the slider
    k[:, row(case.drive_link) + 2, 8] = 1.0
    return k


def load_vector(pose: Pose, load: Load) -> Array:
    """b contribution (N, 9) of one external load."""
    b = np.zeros((pose.theta12.shape[0], N_UNKNOWNS))
    p, _, _ = pose.point(load.link, load.at)
    f = np.broadcast_to(np.asarray(load.force), p.shape)
    r = row(load.link)
    b[:, r:r + 2] += f
    b[:, r + 2] += cross(p, f) + load.torque
    return b


def weight_vector(pose: Pose, mass: Mass, gravity: tuple[float, float]) -> Array:
    """b contribution of a link's weight m·g at its centre of mass."""
    b = np.zeros((pose.theta12.shape[0], N_UNKNOWNS))
    p, _, _ = pose.point(mass.link, mass.com)
    w = np.broadcast_to(mass.mass * np.asarray(gravity), p.shape)
    r = row(mass.link)
    b[:, r:r + 2] += w
    b[:, r + 2] += cross(p, w)
    return b


def inertia_vector(pose: Pose, mass: Mass) -> Array:
    """b contribution of the D'Alembert inertia force −m·a_G and torque −I_G·α."""
    b = np.zeros((pose.theta12.shape[0], N_UNKNOWNS))
    p, _, acc = pose.point(mass.link, mass.com)
    f = -mass.mass * acc
    r = row(mass.link)
    b[:, r:r + 2] += f
    b[:, r + 2] += cross(p, f) - mass.inertia * pose.links[mass.link].alpha
    return b


def relative_omega(pose: Pose, joint: str) -> Array:
    """ω_j − ω_i of a pin joint (i, j) = JOINT_LINKS[joint]; the ground's ω is 0."""
    i, jj = JOINT_LINKS[joint]
    wi = pose.links[i].omega if i != 1 else 0.0
    return pose.links[jj].omega - wi


def pin_moment_vector(pose: Pose, joint: str, moment_on_j: Array) -> Array:
    """b contribution of a moment acting on link j of a joint and its reaction on i."""
    b = np.zeros((pose.theta12.shape[0], N_UNKNOWNS))
    i, j = JOINT_LINKS[joint]
    b[:, row(j) + 2] += moment_on_j
    if i != 1:
        b[:, row(i) + 2] -= moment_on_j
    return b


def slide_force_vector(case: Case, pose: Pose, force_along_u: Array) -> Array:
    """b contribution of a force along the slide axis acting on the slider at B."""
    u, _ = slide_frame(case)
    b = np.zeros((pose.theta12.shape[0], N_UNKNOWNS))
    f = force_along_u[:, None] * u
    b[:, 6:8] += f
    b[:, 8] += cross(pose.joints["B"], f)
    return b


def viscous_vectors(case: Case, pose: Pose) -> list[Array]:
    """b contributions of the viscous friction terms, one per joint (−c·ω_rel, −c·v)."""
    if case.friction is None:
        return []
    out = []
    for joint, c in case.friction.viscous.items():
        if c == 0.0:
            continue
        if joint == "slide":
            assert pose.s14_dot is not None
            out.append(slide_force_vector(case, pose, -c * pose.s14_dot))
        else:
            out.append(pin_moment_vector(pose, joint, -c * relative_omega(pose, joint)))
    return out


def known_vectors(case: Case, pose: Pose) -> list[tuple[str, Array]]:
    """Every known contribution to b, labelled, one per 'load' (superposition sums these)."""
    parts: list[tuple[str, Array]] = [(f"load[{i}]", load_vector(pose, ld))
                                      for i, ld in enumerate(case.loads)]
    for m in case.masses:
        if case.gravity != (0.0, 0.0):
            parts.append((f"weight{m.link}", weight_vector(pose, m, case.gravity)))
        if not case.motion.is_static:
            parts.append((f"inertia{m.link}", inertia_vector(pose, m)))
    parts += [(f"viscous[{i}]", v) for i, v in enumerate(viscous_vectors(case, pose))]
    return parts


def known_vector(case: Case, pose: Pose) -> Array:
    """b: the sum of every known load contribution, shape (N, 9)."""
    b = np.zeros((pose.theta12.shape[0], N_UNKNOWNS))
    for _, part in known_vectors(case, pose):
        b += part
    return b


def scaling(case: Case) -> tuple[Array, Array]:
    """Row and column scales that make K dimensionless (moments / L, torques × L)."""
    length = case.geometry.scale
    rows = np.ones(N_UNKNOWNS)
    rows[2::3] = 1.0 / length
    cols = np.ones(N_UNKNOWNS)
    cols[8] = length
    if not isinstance(case.geometry, FourBarGeometry):
        cols[7] = length
    return rows, cols


def condition_number(case: Case, k: Array, k_inv: Array) -> Array:
    """1-norm condition number of the dimensionless K, per pose."""
    rows, cols = scaling(case)
    ks = rows[:, None] * k * cols[None, :]
    ks_inv = (1.0 / cols)[:, None] * k_inv * (1.0 / rows)[None, :]
    norm = lambda m: np.abs(m).sum(axis=-2).max(axis=-1)  # noqa: E731 - 1-norm per pose
    return norm(ks) * norm(ks_inv)


@dataclass(frozen=True)
class LinearSystem:
    """K, its inverse and the condition number at N poses."""

    k: Array
    k_inv: Array
    condition: Array


def linear_system(case: Case, pose: Pose) -> LinearSystem:
    """Assemble K and invert it once (superposition reuses the inverse for every load)."""
    k = coefficient_matrix(case, pose)
    finite = np.all(np.isfinite(k), axis=(1, 2))
    k_safe = np.where(finite[:, None, None], k, np.eye(N_UNKNOWNS))
    with np.errstate(all="ignore"):
        try:
            k_inv = np.linalg.inv(k_safe)
        except np.linalg.LinAlgError:
            k_inv = np.linalg.pinv(k_safe)  # exactly singular somewhere: cond → inf below
        cond = condition_number(case, k_safe, k_inv)
    cond = np.where(finite & np.isfinite(cond), cond, np.inf)
    return LinearSystem(k, k_inv, cond)
