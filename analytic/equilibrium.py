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

import numpy as np

from mechcheck.analytic.case import Case, FourBarGeometry, Load, Mass
from mechcheck.analytic.kinematics import Array, Pose, cross, unit

N_UNKNOWNS = 9
#: Columns of the pin forces F_ij in x, by joint name.
PIN_COLUMNS = {"A0": (0, 1), "A": (2, 3), "B": (4, 5), "B0": (6, 7)}
#: (i, j) of each joint: F_ij is the force by i on j.
JOINT_LINKS = {"A0": (1, 2), "A": (2, 3), "B": (3, 4), "B0": (1, 4), "slide": (1, 4)}

#: Above this condition number (of the dimensionless 2×2 core, see
#: :func:`core_condition`) a pose is reported ``singular`` and its forces
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


def _rows(case: Case, pose: Pose) -> tuple[Array, Array]:
    """The two equations that fix F34 once F23, F14 (or N14) are eliminated.

    Each row r stands for the equation r · F34 = rhs. Always: link 3's moment
    about A, (A − B)⊥ · F34. Then link 4's moment about B0 (four-bar, drive on
    2: (B − B0)⊥), link 2's moment about A0 (four-bar, drive on 4:
    (A0 − A)⊥), or the slider's force along the slide (slider-crank: u).
    """
    j = pose.joints
    first = perp_of(j["A"] - j["B"])
    if case.mechanism == "slider_crank":
        u, _ = slide_frame(case)
        second = np.broadcast_to(u, first.shape)
    elif case.drive_link == 2:
        second = perp_of(j["B"] - j["B0"])
    else:
        second = perp_of(j["A0"] - j["A"])
    return first, second


def perp_of(v: Array) -> Array:
    """The row of cross(v, F) = v_x F_y − v_y F_x as a vector acting on F: (−v_y, v_x)."""
    return np.stack([-v[..., 1], v[..., 0]], axis=-1)


def row_condition(r1: Array, r2: Array) -> Array:
    """2-norm condition number of 2×2 matrices [r1; r2] with rows scaled to unit length.

    With unit rows at angle γ the singular values are √(1 ± |cos γ|), so the
    condition number is √((1 + |cos γ|)/(1 − |cos γ|)) ≈ 2/γ near γ = 0.
    """
    with np.errstate(divide="ignore", invalid="ignore"):
        cos = np.abs(np.einsum("ij,ij->i", r1, r2)) / (
            np.linalg.norm(r1, axis=1) * np.linalg.norm(r2, axis=1))
        cond = np.sqrt((1.0 + cos) / (1.0 - cos))
    return np.where(np.isfinite(cond), cond, np.inf)


def core_condition(case: Case, pose: Pose) -> Array:
    """Condition number of the force core (:func:`_rows`): large exactly at toggle,
    change and dead points (coupler and rocker, crank and coupler, or rod and
    slide normal aligned), where it bounds how much the forces are amplified."""
    return row_condition(*_rows(case, pose))


def kinematic_condition(case: Case, pose: Pose) -> Array:
    """Condition number of the velocity equations, which fix ω3, ω4 (or ṡ) from ω2.

    Their columns are e3⊥ and e4⊥ (four-bar) or e3⊥ and the slide direction u
    (slider-crank): singular when coupler and rocker align, or the rod stands
    perpendicular to the slide. (A 2×2 matrix and its transpose share their
    condition number, so the columns are passed as rows.) With the drive on
    link 4 the force core stays regular there, but the velocities, and with
    them inertia forces and friction senses, do not.
    """
    e3 = unit(pose.theta13)
    if case.mechanism == "four_bar":
        return row_condition(perp_of(e3), perp_of(unit(pose.theta14)))
    u, _ = slide_frame(case)
    return row_condition(perp_of(e3), np.broadcast_to(u, e3.shape))


def condition(case: Case, pose: Pose) -> Array:
    """The condition number a force analysis reports: the force core's, and the
    velocity equations' too when velocities enter (motion or friction)."""
    cond = core_condition(case, pose)
    if not case.motion.is_static or case.has_friction:
        cond = np.maximum(cond, kinematic_condition(case, pose))
    return cond


def eliminate(case: Case, pose: Pose, b: Array) -> Array:
    """Solve K x + b = 0 without friction by block elimination, elementwise over poses.

    This is the member-equilibrium matrix method solved in the seed's order:
    link 3's force balance gives F23 = F34 − b3, link 4's gives F14 (or the
    slide's normal N14), two moment (or slide) equations form a 2×2 system
    for F34 (:func:`_rows`), and the remaining rows give F12, M14 and the
    drive torque explicitly. It costs O(1) array operations per pose instead
    of a 9×9 factorisation; :func:`coefficient_matrix` gives the same
    equations whole (used with friction, and in tests to cross-check).
    """
    j = pose.joints
    b2f, b2m = b[:, 0:2], b[:, 2]
    b3f, b3m = b[:, 3:5], b[:, 5]
    b4f, b4m = b[:, 6:8], b[:, 8]
    r1, r2 = _rows(case, pose)
    rhs1 = cross(j["A"], b3f) - b3m
    if case.mechanism == "slider_crank":
        u, _ = slide_frame(case)
        rhs2 = -(b4f @ u)
    elif case.drive_link == 2:
        rhs2 = cross(j["B0"], b4f) - b4m
    else:
        rhs2 = cross(j["A0"], b2f) - b2m + cross(j["A0"] - j["A"], b3f)
    det = r1[:, 0] * r2[:, 1] - r1[:, 1] * r2[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        f34 = np.stack([(rhs1 * r2[:, 1] - rhs2 * r1[:, 1]) / det,
                        (r1[:, 0] * rhs2 - r2[:, 0] * rhs1) / det], axis=-1)
    f23 = f34 - b3f
    f12 = f23 - b2f
    x = np.empty((b.shape[0], N_UNKNOWNS))
    x[:, 0:2], x[:, 2:4], x[:, 4:6] = f12, f23, f34
    if case.mechanism == "slider_crank":
        _, nrm = slide_frame(case)
        normal = -((f34 + b4f) @ nrm)
        x[:, 6] = normal
        x[:, 7] = -cross(j["B"], f34) - normal * cross(j["B"], np.broadcast_to(nrm, f34.shape)) \
            - b4m
    else:
        x[:, 6:8] = -f34 - b4f
    if case.drive_link == 2:
        x[:, 8] = -(cross(j["A0"], f12) - cross(j["A"], f23) + b2m)
    else:
        x[:, 8] = -(cross(j["B"], f34) + cross(j["B0"], x[:, 6:8]) + b4m)
    return x
