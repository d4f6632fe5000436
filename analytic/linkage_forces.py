"""The member-equilibrium matrix method for any :class:`~mechcheck.analytic.linkage.Linkage`,
vectorised over poses.

Each moving link gives three D'Alembert equilibrium rows (ΣFx, ΣFy, ΣM about the global
origin). The unknowns are, joint by joint in the file's order, the reaction of the joint
— revolute: (Fx, Fy), the force by links[0] on links[1]; prismatic: (N, M), the force
N along the normal n (fixed in links[0]) at ``at`` and the couple M on links[1] — and then
each driver's effort Q (revolute: a couple on links[1]; prismatic: a force along the
axis through ``at``). What acts on links[1] acts reversed on links[0]. The system is

    K x + b + φ(x) = 0

with b every known force (loads, weights, D'Alembert inertia, springs, viscous terms)
and φ the Coulomb terms (friction circle μ·r·|F| at pins with a radius, μ·|N| along
prismatic joints), which depend on the unknowns; without them x = −K⁻¹ b. With a
square, regular K (as many drivers as degrees of freedom, no redundant constraint),
this is exactly the seed's method: three equations per member, solved at once.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property, partial

import numpy as np
from numpy.typing import NDArray

from mechcheck.analytic import _fast, linalg
from mechcheck.analytic.linalg import Batched
from mechcheck.analytic.linkage import Joint, LinearSpring, Linkage
from mechcheck.analytic.linkage_elastic import axial_forces, compatible_forces
from mechcheck.analytic.linkage_equilibrium import equilibrium_poses
from mechcheck.analytic.linkage_kinematics import (
    Array,
    LinkagePose,
    solve_batched,
    solve_pose,
)
from mechcheck.analytic.linkage_loads import known_vector, spring_force, undirected_springs
from mechcheck.analytic.rigid import force_layout, joints_by_kind

#: Above this condition number of the scaled equilibrium matrix the pose is singular and
#: its forces withheld (the same line as the closed-form presets, for the same reason).
SINGULAR_CONDITION = 1.0e8
#: Coulomb friction: Newton's convergence (relative to the largest unknown) and budget.
FRICTION_RTOL = 1e-13
FRICTION_ITERATIONS = 50
#: ... or, on a large linkage whose rounding (condition number × ε) is above FRICTION_RTOL,
#: a step that has stopped shrinking (at least half the one before: no longer Newton's
#: quadratic descent but rounding) below this fraction of the largest unknown, 1e-2 of
#: the analytic backends' tolerance.
FRICTION_ROUNDING = 1e-11
#: A joint whose relative speed is below this fraction of the pose's speed scale counts
#: as not moving: its Coulomb friction may take any value there (``indeterminate``).
REVERSAL_RTOL = 1e-12
#: The margin for the rounding of :func:`condition_bound` where it decides a verdict: its
#: inverse is accurate to about (columns × condition number × ε), 2.3e-7 of itself for 21
#: columns at 10⁸; a pose within this of the threshold gets its exact condition number.
INVERSE_ROUNDING = 1e-6


def coefficient_matrix(pose: LinkagePose) -> Array:
    """K (N, 3n, unknowns): how each unknown enters each link's equilibrium."""
    return coefficient_entries(pose).dense()


def coefficient_entries(pose: LinkagePose) -> Batched:
    """K as entries (:class:`~.linalg.Batched`): each joint's reactions as its kind puts them
    in, then each driver's effort, a few entries per joint whatever the linkage's size."""
    linkage = pose.linkage
    layout = force_layout(linkage)
    k = Batched(layout.rows, layout.columns, pose.q.shape[0])
    frames = {j.name: pose.frame(j) for j in linkage.joints}
    for kind, joints in joints_by_kind(linkage):
        kind.react_all(k, layout, joints, [frames[j.name] for j in joints])
    for index, driver in enumerate(linkage.drivers):
        joint = linkage.joint(driver.joint)
        joint.kind.exert(k, layout, layout.driver_column(index), joint, frames[joint.name])
    return k


@dataclass(frozen=True)
class CoulombTerm:
    """One term of the reactions that follows the size of its joint's unknowns: Coulomb
    friction at a pin (moment arm μ·r) or a slide (μ), with the sense of its relative
    motion per pose (+1, −1, or 0 where the motion reverses); or a gear's radial part
    (tan α; ``friction`` False, its sense unused)."""

    joint: Joint
    coefficient: float
    sense: Array
    friction: bool = True


def coulomb_terms(pose: LinkagePose) -> list[CoulombTerm]:
    """The nonlinear terms: each gear's radial part, and the Coulomb terms with the senses
    of the joints' relative motion: from the drivers' velocities, or, for a driver at rest,
    from its quasi-static ``sense``."""
    linkage = pose.linkage
    ones = np.ones(pose.q.shape[0])
    terms = [CoulombTerm(j, j.kind.nonlinear_coefficient(j), ones, friction=False)
             for j in linkage.joints if j.kind.nonlinear_coefficient(j) > 0.0]
    f = linkage.friction
    if f is None or not linkage.has_coulomb_friction:
        return terms
    senses = np.array([d.velocity if d.velocity else float(d.sense) for d in linkage.drivers])
    moving = solve_pose(linkage, pose.drivers, senses, np.zeros_like(senses))
    for joint in linkage.joints:
        coefficient = joint.kind.coulomb_coefficient(f, joint)
        if coefficient <= 0.0:
            continue
        _, rate, _ = moving.joint_coordinate(joint)
        # The pose's speed scale as an angular speed: a link's |ṫ| / size or |ω|.
        spin = np.abs(moving.qdot).copy()
        spin[:, 0::3] /= linkage.scale
        spin[:, 1::3] /= linkage.scale
        speed = spin.max(axis=1) * linkage.scale / joint.kind.length(linkage.scale)
        sense = np.where(np.abs(rate) > REVERSAL_RTOL * speed, np.sign(rate), 0.0)
        terms.append(CoulombTerm(joint, coefficient, sense))
    return terms


def friction_residual(pose: LinkagePose, terms: list[CoulombTerm],
                      x: Array) -> tuple[Array, Batched]:
    """φ(x) (N, 3n) and the entries of ∂φ/∂x (3n × unknowns) of the Coulomb terms, each as
    its joint's kind applies it."""
    layout = force_layout(pose.linkage)
    n = x.shape[0]
    phi = np.zeros((n, layout.rows))
    dphi = Batched(layout.rows, layout.columns, n)
    for t in terms:
        t.joint.kind.coulomb(pose, layout, t.joint, t.coefficient, t.sense, x, phi, dphi)
    return phi, dphi


def solve_with_friction(pose: LinkagePose, k: Batched, b: Array, x: Array,
                        terms: list[CoulombTerm]) -> tuple[Array, NDArray[np.bool_]]:
    """Newton's method on K x + b + φ(x) = 0 from the frictionless x; (x, converged).
    A small K is solved densely over all poses at once, a large one as a sparse matrix per
    pose (:mod:`.linalg`), so memory grows with the entries, not with their square."""
    dense = k.dense() if k.small else None
    converged = np.zeros(x.shape[0], dtype=bool)
    previous = np.full(x.shape[0], np.inf)
    for _ in range(FRICTION_ITERATIONS):
        phi, dphi = friction_residual(pose, terms, x)
        if dense is not None:
            residual = np.einsum("nij,nj->ni", dense, x) + b + phi
            step = solve_batched(dense + dphi.dense(), residual)
        else:
            with np.errstate(all="ignore"):   # poses that do not assemble stay NaN
                step = linalg.solve(k.plus(dphi), k.times(x) + b + phi)
        x = x - step
        size = np.maximum(np.abs(x).max(axis=1), 1e-300)
        length = np.abs(step).max(axis=1)
        converged = (length <= FRICTION_RTOL * size) \
            | ((length >= 0.5 * previous) & (length <= FRICTION_ROUNDING * size))
        previous = length
        if converged.all():
            break
    return x, converged


def friction_loop_gain(pose: LinkagePose, k: Batched, x: Array,
                       terms: list[CoulombTerm]) -> Array:
    """Per pose, the gain of the loop that takes the Coulomb terms from the last reactions,
    as both simulators do step by step: the spectral radius of K⁻¹·∂φ/∂x at the solution.

    Above 1 that loop cannot settle: a joint held inside its friction angle self-locks (a
    slide whose rod makes φ with its axis, μ·|tan φ| ≥ 1). A term at exactly zero force is
    taken at the side of positive force: |N|'s slope is ±1 on either, and the gain's
    size the same."""
    if k.rows != k.cols:
        return np.full(x.shape[0], np.nan)
    probe = np.where(x == 0.0, np.finfo(float).tiny, x)
    return linalg.spectral_radius(k, friction_residual(pose, terms, probe)[1])


def condition(pose: LinkagePose, k: Batched | Array) -> Array:
    """2-norm condition number of K made dimensionless: moments made forces (moment rows ÷ L,
    couple unknowns × L, L the linkage's size), then each link's two force rows scaled
    together and its moment row alone to unit length. So the number does not change when the
    drawing is moved, turned (rows scaled one by one would mix differently once turned) or
    drawn in another size."""
    linkage = pose.linkage
    entries = k if isinstance(k, Batched) else Batched.from_dense(k)
    if 0 in (entries.rows, entries.cols):
        return np.ones(entries.poses)
    layout = force_layout(linkage)
    cols = layout.unknown_lengths
    rows = layout.row_scales
    if entries.small and entries.distinct:
        return _condition_small(entries, rows, cols)
    first = entries.scaled(np.broadcast_to(rows, (entries.poses, rows.size)), cols)
    # A pose that does not assemble has no matrix: its condition is infinite by definition
    # (its entries are not finite, and linalg.condition says so).
    return linalg.condition(first.scaled(_unit_rows(first.row_norms()), np.ones(layout.columns)))


def _unit_rows(norms: Array) -> Array:
    """The row scales that make each link's two force rows together, and its moment row,
    of unit length (1 for a row of zeros); ``norms`` (N, rows), overwritten."""
    pair = np.sqrt(0.5 * (norms[:, 0::3] ** 2 + norms[:, 1::3] ** 2))
    norms[:, 0::3] = pair
    norms[:, 1::3] = pair
    return np.asarray(1.0 / np.where(norms > 0.0, norms, 1.0), dtype=np.float64)   # 1/1 is 1


def _condition_small(entries: Batched, rows: Array, cols: Array) -> Array:
    """:func:`condition` of a small K with at most one entry per place, scaled as a dense
    matrix."""
    return linalg.condition_of_dense(_scaled_small(entries, rows, cols))


def _scaled_small(entries: Batched, rows: Array, cols: Array) -> Array:
    """The scaled K of :func:`condition` (N, rows, columns), for a small K with at most one
    entry per place: each entry goes through the same products as :meth:`.Batched.scaled`
    (so the same number), in a few calls rather than a few per entry (one pose pays for
    calls)."""
    first = entries.dense() * rows[:, None] * cols
    # The rows' 2-norms, as np.linalg.norm(first, axis=2) sums them, without its wrapper.
    unit = _unit_rows(np.sqrt(np.add.reduce(first * first, axis=2)))
    return np.asarray(np.where(entries.pattern, first * unit[:, :, None], 0.0),  # × 1: the columns
                      dtype=np.float64)


def condition_bound(pose: LinkagePose, k: Batched) -> Array:
    """An upper bound of :func:`condition` per pose, ‖S‖_F·‖S⁻¹‖_F of the scaled matrix S
    (σ_max ≤ ‖S‖_F and 1/σ_min ≤ ‖S⁻¹‖_F), an inverse instead of an SVD; inf where it
    is not computed (a K that is not small and square) or S is singular."""
    if not (k.small and k.distinct and k.rows == k.cols) or k.rows == 0:
        return np.full(k.poses, np.inf)
    layout = force_layout(pose.linkage)
    scaled = _scaled_small(k, layout.row_scales, layout.unknown_lengths)
    bound = np.full(k.poses, np.inf)
    finite = np.isfinite(scaled).all(axis=(1, 2))
    some = scaled if finite.all() else scaled[finite]
    with np.errstate(all="ignore"):
        inverse = _fast.inverse(some)
        if inverse is None:
            try:
                inverse = np.asarray(np.linalg.inv(some), dtype=np.float64)
            except np.linalg.LinAlgError:   # a singular pose: its exact condition number decides
                return bound
        bound[finite] = np.sqrt(np.square(some).sum(axis=(1, 2))
                                * np.square(inverse).sum(axis=(1, 2)))
    return np.where(np.isnan(bound), np.inf, bound)


@dataclass(frozen=True)
class LinkageResults:
    """Every output quantity (LINKAGES.md names; SI, radians) at N poses, the condition
    number (computed when first asked for), which poses it puts above
    :data:`SINGULAR_CONDITION`, Newton's convergence, and per pose why forces are withheld
    (empty string: they are not)."""

    pose: LinkagePose
    values: dict[str, Array]
    condition_of: Callable[[], Array]
    ill_conditioned: NDArray[np.bool_]
    converged: NDArray[np.bool_]
    reversing: NDArray[np.str_]
    #: Free coordinates only: 1 where the equilibrium pose is stable, 0 where not.
    stable: Array | None = None
    #: Linear springs whose ends meet while they carry a tension (:func:`undirected_springs`).
    undirected: NDArray[np.str_] | None = None
    #: With Coulomb friction: the gain of its explicit loop (:func:`friction_loop_gain`),
    #: computed when first asked for (only a simulator's verdict reads it).
    friction_gain_of: Callable[[], Array] | None = None
    #: Redundant joints: where the reactions are not decided (all poses of a rigid linkage;
    #: with elastic members, where they do not decide them, :mod:`.linkage_elastic`).
    undecided: NDArray[np.bool_] | None = None

    @cached_property
    def friction_gain(self) -> Array | None:
        return None if self.friction_gain_of is None else self.friction_gain_of()

    @cached_property
    def condition(self) -> Array:
        """The condition number of the scaled equilibrium matrix per pose (:func:`condition`)."""
        return self.condition_of()

    def head(self, n: int) -> LinkageResults:
        """The first ``n`` poses' results."""
        return self.take(slice(None, n))

    def take(self, which: slice | NDArray[np.intp]) -> LinkageResults:
        """The results of the poses ``which`` (a slice or indices), in that order (each
        pose's condition number is its own: computed for all, if asked for, and cut)."""
        return LinkageResults(self.pose.take(which), {k: v[which] for k, v in self.values.items()},
                              lambda: self.condition[which], self.ill_conditioned[which],
                              self.converged[which], self.reversing[which],
                              None if self.stable is None else self.stable[which],
                              None if self.undirected is None else self.undirected[which],
                              None if self.friction_gain_of is None
                              else lambda: np.asarray(self.friction_gain)[which],
                              None if self.undecided is None else self.undecided[which])

    @property
    def singular(self) -> NDArray[np.bool_]:
        return self.ill_conditioned & self.pose.assembled

    @property
    def indeterminate(self) -> NDArray[np.bool_]:
        """Friction reversing, or a spring's tension without a line of action."""
        if self.undirected is None:
            return self.reversing != ""
        return (self.reversing != "") | (self.undirected != "")

    @property
    def assembled(self) -> NDArray[np.bool_]:
        return self.pose.assembled

    @property
    def withheld(self) -> NDArray[np.bool_]:
        """Poses without forces: unassembled, singular, friction reversing or not converged."""
        return ~self.assembled | self.singular | self.indeterminate | ~self.converged


def pose_quantities(pose: LinkagePose) -> dict[str, Array]:
    """x_/y_ of every point, phi_ of every moving link, q_ of every joint."""
    linkage = pose.linkage
    out: dict[str, Array] = {}
    carriers = linkage.carriers
    drawn_at = pose.drawn_positions()
    if drawn_at is not None:    # a few poses at rest: every point moved in one operation
        moved = drawn_at + linkage.offset
        for i, name in enumerate(linkage.points):
            out[f"x_{name}"] = moved[:, i, 0]
            out[f"y_{name}"] = moved[:, i, 1]
    for name, drawn in () if drawn_at is not None else linkage.points.items():
        position = pose.position(carriers[name], drawn)
        out[f"x_{name}"] = position[:, 0] + linkage.offset[0]
        out[f"y_{name}"] = position[:, 1] + linkage.offset[1]
    for link in linkage.moving_links:
        out[f"phi_{link}"] = pose.link_state(link, pose.q)[1]
    for joint in linkage.joints:
        out[f"q_{joint.name}"] = joint.kind.value(pose, joint)
    return out


def force_quantities(pose: LinkagePose, x: Array, terms: list[CoulombTerm]) -> dict[str, Array]:
    """Each joint's reactions as its kind reports them (a slide's force with its friction
    along the axis), Q_<joint> and S_<spring>, from the unknowns x."""
    linkage = pose.linkage
    layout = force_layout(linkage)
    coulomb = {t.joint.name: t for t in terms}
    out: dict[str, Array] = {}
    still = np.zeros(x.shape[0])    # no friction along a joint: read, never written
    still.flags.writeable = False
    for joint in linkage.joints:
        first = layout.joint_columns(joint)[0]
        own = x[:, first:first + joint.kind.rows]   # its columns, one after another
        along = still
        if joint.name in coulomb:   # the friction force along its axis (0 at a pin)
            t = coulomb[joint.name]
            along = joint.kind.sliding_friction(t.coefficient, t.sense, own)
        out |= joint.kind.reported(pose, joint, own, along)
    for index, driver in enumerate(linkage.drivers):
        out[f"Q_{driver.joint}"] = x[:, layout.driver_column(index)]
    for spring in linkage.springs:
        out[f"S_{spring.name}"] = spring_force(pose, spring)
    return out


def solve_linkage(linkage: Linkage, values: Array | None = None,
                  velocities: Array | None = None,
                  accelerations: Array | None = None) -> LinkageResults:
    """The force analysis of ``linkage`` at each row of driver values (default: its own).

    Poses that lock have NaN everything; singular poses, and friction poses whose Newton
    iteration did not converge or whose friction reverses, have NaN forces.
    """
    free = linkage.dof - len(linkage.drivers)
    if free == 0 and linkage.assur_plan is not None and not linkage.has_coulomb_friction \
            and _at_rest(linkage, velocities, accelerations):
        return _static_by_groups(linkage, values)
    stable = None
    if free > 0:
        pose, stable = equilibrium_poses(linkage, values)
    else:
        pose = solve_pose(linkage, values, velocities, accelerations)
    entries = coefficient_entries(pose)
    b = known_vector(pose)
    # The verdicts from a cheap bound of the condition number where it decides, as for an
    # Assur linkage; the exact numbers computed when read.
    exact = _ExactCondition(pose, entries)
    singular = _singular_by_bound(pose, condition_bound(pose, entries), exact,
                                  INVERSE_ROUNDING) | ~pose.assembled
    with np.errstate(all="ignore"):
        x = linalg.solve(entries, -b)
    terms = coulomb_terms(pose)
    converged = np.ones(x.shape[0], dtype=bool)
    reversing = np.zeros(x.shape[0], dtype="<U1")   # "" at every pose
    gain: Callable[[], Array] | None = None
    if terms:
        x, converged, reversing, gain = _with_nonlinear_terms(pose, entries, b, x, terms)
    undirected = undirected_springs(pose)
    undecided = None
    extra: dict[str, Array] = {}
    if linkage.redundant:
        undecided = np.ones(x.shape[0], dtype=bool)
        if linkage.elastic_links and not terms:
            k = entries.dense()
            x, undecided = compatible_forces(pose, k, b)
    if linkage.elastic_links:
        extra = axial_forces(pose, entries.dense(), x)
    withheld = singular | (undirected != "") | linkage.drawn_at_change_point   # not unique, no branch
    if terms:
        withheld |= ~converged | (reversing != "")
    if undecided is not None:
        withheld |= undecided
    x[withheld] = np.nan
    for name in extra:
        extra[name][withheld] = np.nan
    if stable is not None:  # an equilibrium not found is no pose to report forces at
        converged = converged & np.isfinite(stable)
    return LinkageResults(pose, pose_quantities(pose) | force_quantities(pose, x, terms) | extra,
                          exact.all, singular, converged, reversing, stable, undirected, gain,
                          undecided)


def _with_nonlinear_terms(pose: LinkagePose, entries: Batched, b: Array, x: Array,
                          terms: list[CoulombTerm]) -> tuple[Array, NDArray[np.bool_],
                                                             NDArray[np.str_],
                                                             Callable[[], Array] | None]:
    """The unknowns with the Coulomb terms and gears' radial parts (:func:`solve_with_friction`
    from the linear solution x), whether Newton converged, the joints whose friction reverses
    at each pose ("" where none), and the friction loop's gain when first asked for."""
    x, converged = solve_with_friction(pose, entries, b, x, terms)
    friction = [t for t in terms if t.friction]
    gain = partial(friction_loop_gain, pose, entries, x.copy(), friction) if friction else None
    reversing = np.full(x.shape[0], "", dtype=object)
    for t in terms:
        stops = t.sense == 0.0
        reversing[stops] = np.where(reversing[stops] == "", t.joint.name,
                                    reversing[stops] + ", " + t.joint.name)
    return x, converged, reversing.astype(str), gain


def _at_rest(linkage: Linkage, velocities: Array | None, accelerations: Array | None) -> bool:
    """Every driver's velocity and acceleration zero: a static case."""
    if velocities is None and accelerations is None:    # the case's own: no arrays needed
        return not any(d.velocity or d.acceleration for d in linkage.drivers)
    own = [(d.velocity, d.acceleration) for d in linkage.drivers]
    v = np.asarray([v for v, _ in own] if velocities is None else velocities, dtype=float)
    a = np.asarray([a for _, a in own] if accelerations is None else accelerations, dtype=float)
    return not (np.any(v) or np.any(a))


def _static_by_groups(linkage: Linkage, values: Array | None) -> LinkageResults:
    """A static case of a linkage with an Assur plan: :mod:`.linkage_statics`, group by
    group; the condition number computed densely only if asked for."""
    from mechcheck.analytic.linkage_statics import static_results

    assert linkage.assur_plan is not None
    vals = np.array([[d.value for d in linkage.drivers]]) if values is None \
        else np.atleast_2d(np.asarray(values, dtype=float)).reshape(-1, len(linkage.drivers))
    # The bound decides most poses' verdicts without their exact condition numbers, which
    # are computed only if read (a Solution's diagnostics read them lazily).
    found = static_results(linkage.assur_plan, vals)
    pose = found.pose
    exact = _ExactCondition(pose)
    singular = _singular_by_bound(pose, found.condition_bound, exact)
    if any(isinstance(s, LinearSpring) for s in linkage.springs):
        undirected = undirected_springs(pose)
        withheld = singular | (undirected != "")
    else:   # only a linear spring can pull along no line: none here (its "" at every pose)
        undirected = np.zeros(pose.q.shape[0], dtype="<U1")
        withheld = singular
    if withheld.any():
        for name, value in found.values.items():
            if name.startswith(("F_", "Q_")):
                value[withheld] = np.nan
    n = vals.shape[0]
    return LinkageResults(pose, found.values, exact.all, singular, np.ones(n, dtype=bool),
                          np.zeros(n, dtype="<U1"), undirected=undirected)


class _ExactCondition:
    """:func:`condition` of some or all poses of a static pose set, each computed once."""

    def __init__(self, pose: LinkagePose, entries: Batched | None = None) -> None:
        self.pose = pose
        self.entries = entries
        self.known = np.full(pose.q.shape[0], np.nan)

    def of(self, which: NDArray[np.bool_]) -> Array:
        todo = which & np.isnan(self.known)
        if todo.all():  # every pose (a case solved on its own): K from the pose as it is
            self.known = condition(self.pose, self.entries or coefficient_entries(self.pose))
        elif todo.any():
            rest = np.zeros_like(self.pose.q[todo])
            near = LinkagePose(self.pose.linkage, self.pose.drivers[todo], self.pose.q[todo], rest,
                               rest, self.pose.locked_at[todo])
            self.known[todo] = condition(near, coefficient_entries(near))
        return self.known[which]

    def all(self) -> Array:
        return self.of(np.ones(self.known.shape, dtype=bool))


def _singular_by_bound(pose: LinkagePose, bound: Array, exact: _ExactCondition,
                       rounding: float = 1e-9) -> NDArray[np.bool_]:
    """Condition number > :data:`SINGULAR_CONDITION` at each assembled pose: not where an upper
    bound of it is below (with a margin for the bound's rounding), else by :func:`condition`."""
    assembled = pose.assembled
    singular = np.zeros(assembled.shape, dtype=bool)
    undecided = assembled & ~(bound * (1.0 + rounding) < SINGULAR_CONDITION)
    if undecided.any():
        singular[undecided] = ~(exact.of(undecided) <= SINGULAR_CONDITION)
    return singular
