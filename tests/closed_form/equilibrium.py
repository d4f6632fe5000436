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

The fixed loads (external loads and weights) on a link are folded into one resultant
(:class:`~mechcheck.analytic.resultant.Resultant`) before any pose is touched, so a static
case builds one right-hand side from positions alone (:func:`fixed_wrenches`), and
:func:`solve_members` solves it on flat coordinate arrays without forming b or x.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from mechcheck.analytic.case import Case, FourBarGeometry, Mass
from mechcheck.analytic.kinematics import Array, Pose, cross, unit
from mechcheck.analytic.pose import Coordinates, Placement, coordinates
from mechcheck.analytic.resultant import Wrench, resultants
from mechcheck.analytic.values import Vec2

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
    u = unit(np.array(case.preset.ground_angle))
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
    if isinstance(case.preset.geometry, FourBarGeometry):
        put_force(4, 6, j["B0"], +1.0)  # F14 on 4
    else:
        _, nrm = slide_frame(case)
        k[:, 6, 6] = nrm[0]
        k[:, 7, 6] = nrm[1]
        k[:, 8, 6] = cross(j["B"], np.broadcast_to(nrm, j["B"].shape))
        k[:, 8, 7] = 1.0                # M14: the guide's moment on the slider
    k[:, row(case.preset.drive_link) + 2, 8] = 1.0
    return k


#: One fixed load: (link, body-fixed point, global force, pure moment).
FixedLoad = tuple[int, Vec2, Vec2, float]


def fixed_loads(case: Case) -> list[tuple[str, FixedLoad]]:
    """The external loads and the weights m·g at the centres of mass, labelled."""
    out: list[tuple[str, FixedLoad]] = [(f"load[{i}]", (ld.link, ld.at, ld.force, ld.torque))
                                        for i, ld in enumerate(case.preset.loads)]
    if case.gravity != (0.0, 0.0):
        gx, gy = case.gravity
        out += [(f"weight{m.link}", (m.link, m.com, (m.mass * gx, m.mass * gy), 0.0))
                for m in case.preset.masses]
    return out


def fixed_wrenches(case: Case, place: Placement) -> dict[int, Wrench]:
    """Every link's wrench of the fixed loads at each pose: statics' one right-hand side."""
    return {link: r.wrench(place.directions[link])
            for link, r in resultants(ld for _, ld in fixed_loads(case)).items()}


def link_origins(case: Case) -> dict[int, str]:
    """The joint at each moving link's frame origin (CONVENTIONS.md)."""
    return {2: "A0", 3: "A", 4: "B0" if case.mechanism == "four_bar" else "B"}


def wrench_vector(case: Case, pose: Pose, loads: Iterable[FixedLoad]) -> Array:
    """b contribution (N, 9) of fixed loads, folded per link (moments about the global
    origin, as K's rows take them)."""
    b = np.zeros((pose.theta12.shape[0], N_UNKNOWNS))
    origins = link_origins(case)
    for link, res in resultants(loads).items():
        angle = pose.links[link].angle
        fx, fy, moment = res.wrench((np.cos(angle), np.sin(angle)))
        origin = pose.joints[origins[link]]
        r = row(link)
        b[:, r], b[:, r + 1] = fx, fy
        b[:, r + 2] = origin[:, 0] * fy - origin[:, 1] * fx + moment
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
    if case.preset.friction is None:
        return []
    out = []
    for joint, c in case.preset.friction.viscous.items():
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
    parts = [(label, wrench_vector(case, pose, [ld])) for label, ld in fixed_loads(case)]
    if not case.preset.motion.is_static:
        parts += [(f"inertia{m.link}", inertia_vector(pose, m)) for m in case.preset.masses]
    parts += [(f"viscous[{i}]", v) for i, v in enumerate(viscous_vectors(case, pose))]
    return parts


def known_vector(case: Case, pose: Pose) -> Array:
    """b: every known load in one right-hand side, shape (N, 9): the fixed loads folded per
    link, then the pose-dependent inertia and viscous terms."""
    b = wrench_vector(case, pose, (ld for _, ld in fixed_loads(case)))
    if not case.preset.motion.is_static:
        for m in case.preset.masses:
            b += inertia_vector(pose, m)
    for v in viscous_vectors(case, pose):
        b += v
    return b


def levers(case: Case, joints: dict[str, Coordinates]) -> tuple[Coordinates, Coordinates]:
    """The two equations that fix F34 once F23, F14 (or N14) are eliminated, each as
    the vector v of v × F34 = rhs.

    Always: link 3's moment about A, v = A − B. Then link 4's moment about B0 (four-bar,
    drive on 2: B − B0), link 2's moment about A0 (four-bar, drive on 4: A0 − A), or the
    slider's force along the slide (slider-crank: u · F = (−n) × F, v = −n).
    """
    (ax, ay), (bx, by) = joints["A"], joints["B"]
    first = (ax - bx, ay - by)
    if case.mechanism == "slider_crank":
        u, _ = slide_frame(case)
        return first, (float(u[1]), -float(u[0]))
    if case.preset.drive_link == 2:
        b0x, b0y = joints["B0"]
        return first, (bx - b0x, by - b0y)
    a0x, a0y = joints["A0"]
    return first, (a0x - ax, a0y - ay)


def row_condition(v1: Coordinates, v2: Coordinates) -> Array:
    """2-norm condition number of 2×2 matrices with rows along v1 and v2 (or along both
    turned by 90°: the angle between them is the same), scaled to unit length.

    With unit rows at angle γ the singular values are √(1 ± |cos γ|), so the
    condition number is √((1 + |cos γ|)/(1 − |cos γ|)) ≈ 2/γ near γ = 0.
    """
    (x1, y1), (x2, y2) = v1, v2
    with np.errstate(divide="ignore", invalid="ignore"):
        cos = np.abs(x1 * x2 + y1 * y2) / np.sqrt((x1 * x1 + y1 * y1) * (x2 * x2 + y2 * y2))
        cond = np.sqrt((1.0 + cos) / (1.0 - cos))
    return np.where(np.isfinite(cond), cond, np.inf)


def core_condition(case: Case, joints: dict[str, Coordinates]) -> Array:
    """Condition number of the force core (:func:`levers`): large exactly at toggle,
    change and dead points (coupler and rocker, crank and coupler, or rod and
    slide normal aligned), where it bounds how much the forces are amplified."""
    return row_condition(*levers(case, joints))


def kinematic_condition(case: Case, pose: Pose) -> Array:
    """Condition number of the velocity equations, which fix ω3, ω4 (or ṡ) from ω2.

    Their columns are e3⊥ and e4⊥ (four-bar) or e3⊥ and the slide direction u
    (slider-crank), at the angle of e3 and e4 (or of e3 and n): singular when coupler and
    rocker align, or the rod stands perpendicular to the slide. (A 2×2 matrix and its
    transpose share their condition number, so the columns are passed as rows.) With the
    drive on link 4 the force core stays regular there, but the velocities, and with
    them inertia forces and friction senses, do not.
    """
    e3 = unit(pose.theta13)
    if case.mechanism == "four_bar":
        e4 = unit(pose.theta14)
        return row_condition((e3[:, 0], e3[:, 1]), (e4[:, 0], e4[:, 1]))
    _, nrm = slide_frame(case)
    return row_condition((e3[:, 0], e3[:, 1]), (float(nrm[0]), float(nrm[1])))


def condition(case: Case, pose: Pose) -> Array:
    """The condition number a force analysis reports: the force core's, and the
    velocity equations' too when velocities enter (motion or friction)."""
    cond = core_condition(case, coordinates(pose.joints))
    if not case.preset.motion.is_static or case.has_friction:
        cond = np.maximum(cond, kinematic_condition(case, pose))
    return cond


def solve_members(case: Case, joints: dict[str, Coordinates],
                  wrenches: dict[int, Wrench]) -> list[Array]:
    """Solve the member equations without friction by block elimination, elementwise over
    poses, on flat coordinates: the nine unknowns of x, in order.

    ``wrenches`` are the known loads on each link (moments about its frame's origin; a
    link without loads may be missing). This is the member-equilibrium matrix method
    solved in the seed's order: link 3's force balance gives F23 = F34 − F3, link 4's gives
    F14 (or the slide's normal N14), two moment (or slide) equations form a 2×2 system for
    F34 (:func:`levers`), and the remaining rows give F12, M14 and the drive torque
    explicitly. It costs O(1) array operations per pose instead of a 9×9 factorisation;
    :func:`coefficient_matrix` gives the same equations whole (used with friction, and in
    tests to cross-check).
    """
    f2x, f2y, m2 = wrenches.get(2, (0.0, 0.0, 0.0))
    f3x, f3y, m3 = wrenches.get(3, (0.0, 0.0, 0.0))
    f4x, f4y, m4 = wrenches.get(4, (0.0, 0.0, 0.0))
    (ax, ay), (bx, by) = joints["A"], joints["B"]
    (v1x, v1y), (v2x, v2y) = levers(case, joints)
    if case.mechanism == "slider_crank":
        u, nrm = slide_frame(case)
        rhs2: Array | float = -(f4x * u[0] + f4y * u[1])
    elif case.preset.drive_link == 2:
        rhs2 = -m4
    else:
        rhs2 = (v2x * f3y - v2y * f3x) - m2
    # A near-singular draw overflows here; its condition number rejects it in the strategy.
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        det = v1x * v2y - v1y * v2x
        f34x = (v2x * -m3 - v1x * rhs2) / det
        f34y = (v2y * -m3 - v1y * rhs2) / det
    f23x, f23y = f34x - f3x, f34y - f3y
    f12x, f12y = f23x - f2x, f23y - f2y
    j2: Array | float
    if case.mechanism == "slider_crank":
        # N14 balances the slider across the slide; F34 and F14 act through B, the
        # slider's origin, so the guide's moment M14 balances the loads' alone.
        j1 = -((f34x + f4x) * nrm[0] + (f34y + f4y) * nrm[1])
        j2 = -m4 if isinstance(m4, np.ndarray) else np.full(np.shape(f34x), -m4)
    else:
        j1, j2 = -f34x - f4x, -f34y - f4y
    if case.preset.drive_link == 2:  # crank about A0, the ground frame's origin
        torque = ax * f23y - ay * f23x - m2
    else:  # rocker about B0: (B − B0) × F34 + m4 + T = 0
        b0x, b0y = joints["B0"]
        torque = -((bx - b0x) * f34y - (by - b0y) * f34x) - m4
    return [f12x, f12y, f23x, f23y, f34x, f34y, j1, j2, torque]


def eliminate(case: Case, pose: Pose, b: Array) -> Array:
    """:func:`solve_members` for a right-hand side b (N, 9) whose moments are about the
    global origin (the matrix form's): x, shape (N, 9)."""
    joints = coordinates(pose.joints)
    wrenches: dict[int, Wrench] = {}
    for link, origin in link_origins(case).items():
        r = row(link)
        ox, oy = joints[origin]
        fx, fy = b[:, r], b[:, r + 1]
        wrenches[link] = (fx, fy, b[:, r + 2] - (ox * fy - oy * fx))
    return np.stack(solve_members(case, joints, wrenches), axis=1)
