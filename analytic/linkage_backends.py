"""The analytic backends for a linkage case: the member-equilibrium matrix method
(``analytic``), superposition of single loads (``superposition``) and the power
equation (``virtual_work``), each returning a :class:`~mechcheck.analytic.solution.Solution`
in the quantities of LINKAGES.md.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np
from numpy.typing import NDArray

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage import LinearSpring, Linkage
from mechcheck.analytic.linkage_elastic import axial_forces, compatible_forces, largest_strain
from mechcheck.analytic.linkage_equilibrium import unstable_reason
from mechcheck.analytic.linkage_forces import (
    LinkageResults,
    coefficient_matrix,
    force_quantities,
    solve_linkage,
)
from mechcheck.analytic.linkage_kinematics import Array, LinkagePose, perp, solve_batched, solve_pose
from mechcheck.analytic.linkage_loads import known_vector
from mechcheck.analytic.rigid import kept
from mechcheck.analytic.solution import Diagnostics, Later, Solution, Status
from mechcheck.analytic.values import CaseError

COULOMB_REFUSAL = ("the method applies only to linkages without Coulomb friction: friction "
                   "moments depend on the total reactions")
NONLINEAR_REFUSAL = ("superposition adds the solutions of single loads: a gear's radial tooth "
                     "force, tan α·|F_t|, follows the size of the total tangential force and "
                     "does not add")


class CoulombRefused(ValueError):
    """A method that superposes or uses power refuses Coulomb friction."""


def quantity_units(linkage: Linkage) -> dict[str, str]:
    """The table unit of every quantity a linkage reports (LINKAGES.md "What comes out"):
    derived once per linkage (:func:`.rigid.kept`), a copy of its own to each caller."""
    return dict(kept(linkage, "quantity units", lambda: _quantity_units(linkage)))


def _quantity_units(linkage: Linkage) -> dict[str, str]:
    units: dict[str, str] = {}
    for name in linkage.points:
        units[f"x_{name}"] = units[f"y_{name}"] = "m"
    for link in linkage.moving_links:
        units[f"phi_{link}"] = "deg"
    for joint in linkage.joints:
        units |= joint.kind.quantities(joint)
        units[f"q_{joint.name}"] = joint.kind.coordinate_unit
    for driver in linkage.drivers:
        units[f"Q_{driver.joint}"] = linkage.joint(driver.joint).kind.effort_unit
    for spring in linkage.springs:
        units[f"S_{spring.name}"] = "N" if isinstance(spring, LinearSpring) else "N*m"
    for member in linkage.elastic_links:
        units[f"N_{member.name}"] = "N"
    return units


def lock_message(linkage: Linkage, fraction: float, target: Array | None = None,
                 length_unit: str = "m") -> str:
    """Where the drivers were when the linkage locked on their way to ``target`` (default:
    the case's values), in the file's units (degrees, ``length_unit``)."""
    parts = []
    values = [d.value for d in linkage.drivers] if target is None else target.tolist()
    for driver, full in zip(linkage.drivers, values, strict=True):
        kind = linkage.joint(driver.joint).kind
        parts.append(f"{kind.describe(fraction * full, length_unit)} of {driver.joint}")
    return "the linkage locks at " + ", ".join(parts) + " on the way from the drawn pose"


def verdict(case: Case, results: LinkageResults, index: int) -> tuple[Status, str] | None:
    """Why a pose has no unique forces, or None: the first rule of :func:`_verdict_rules`
    that holds at the pose."""
    for holds, status, message in _verdict_rules(case, results):
        if holds[index]:
            return status, message(index)
    return None


def pose_verdicts(case: Case, results: LinkageResults) -> tuple[NDArray[np.object_],
                                                                 NDArray[np.object_]]:
    """Every pose's verdict (``"ok"`` where it has forces) and its message: :func:`verdict`
    at every pose, looked up only where a rule holds."""
    n = results.pose.q.shape[0]
    statuses = texts(n, "ok")
    messages = texts(n, "")
    rules = _verdict_rules(case, results)
    flagged = np.zeros(n, dtype=bool)
    for holds, _, _ in rules:
        flagged |= holds
    for index in np.flatnonzero(flagged):
        found = verdict(case, results, int(index))
        if found is not None:
            statuses[index], messages[index] = found
    if results.stable is not None:   # an answer, but the reader must learn it is unstable
        for index in np.flatnonzero((statuses == "ok") & (results.stable == 0.0)):
            messages[index] = unstable_reason(case.linkage, results.pose.drivers[index])
    return statuses, messages


@dataclass(frozen=True)
class DecidedPoses:
    """Many poses, each decided as ``run`` decides one: each quantity's column, and per pose
    the verdict (``"ok"`` where it has forces), its message and the condition number,
    computed when first asked for (an SVD per pose, about as long as the statics; the
    verdicts need it only near a toggle, and have it there already)."""

    values: dict[str, NDArray[np.float64]]
    statuses: NDArray[np.object_]
    messages: NDArray[np.object_]
    condition_of: Callable[[], NDArray[np.float64]]

    @cached_property
    def condition(self) -> NDArray[np.float64]:
        return np.asarray(self.condition_of(), dtype=float)


def texts(n: int, text: str) -> NDArray[np.object_]:
    """``text`` at each of n poses, as an array of Python strings (``np.full`` assigns an
    object array element by element: 40 times slower for a sweep's 10⁶ poses; ``fill``
    twice as fast as ``np.repeat``)."""
    out = np.empty(n, dtype=object)
    out.fill(text)
    return out


Rule = tuple[NDArray[np.bool_], Status, Callable[[int], str]]


def _verdict_rules(case: Case, results: LinkageResults) -> list[Rule]:
    """The verdicts a pose can have, in the order they are decided: where each holds, and
    its message at a pose."""
    linkage = case.linkage
    pose = results.pose
    n = pose.q.shape[0]
    every = np.ones(n, dtype=bool)
    rules: list[Rule] = []
    if results.stable is not None:
        rules.append((~np.isfinite(results.stable), "no_solution", lambda i: (
            "no equilibrium pose of the free coordinates was found from the drawn pose")))
    rules.append((~pose.assembled, "no_solution", lambda i: lock_message(
        linkage, float(pose.locked_at[i]), pose.drivers[i], case.length_unit)))
    if results.undecided is not None:
        rules.append((results.undecided, "indeterminate", lambda i: (
            f"the joints' constraints are redundant (rank {linkage.joint_rank} < "
            f"{linkage.constraint_rows}): the reactions are not unique"
            + (" (their self-stress runs through rigid members only: give those members "
               "axial_stiffness)" if linkage.elastic_links else
               "; members with axial_stiffness (E·A) would decide them"))))
    if linkage.drawn_at_change_point:
        rules.append((every, "singular", lambda i: (
            f"the linkage is drawn on a change point (its joints' constraints are dependent "
            f"there, rank {linkage.drawn_rank} < {linkage.joint_rank}): statics is singular "
            "at the drawing, and which branch the linkage takes when driven from it is not "
            "determined; draw it a little way off the change point")))
    rules.append((results.singular, "singular", lambda i: (
        f"condition number {float(results.condition[i]):.3g} exceeds 1e+08: the pose is at or "
        "next to a toggle or dead point, where statics is singular; forces withheld")))
    if results.undirected is not None:
        undirected = results.undirected
        rules.append((undirected != "", "indeterminate", lambda i: (
            f"the ends of spring {undirected[i]} meet at this pose while it carries a tension: "
            "a force without a line of action, so the forces are not unique; forces withheld")))
    rules.append((results.reversing != "", "indeterminate", lambda i: (
        f"the relative motion at {results.reversing[i]} reverses at this pose: Coulomb friction "
        "there may take any value within its bound, so the forces are not unique; forces "
        "withheld")))
    rules.append((~results.converged, "no_solution", lambda i: (
        "the friction equations have no solution with the assumed senses of motion (the "
        "linkage self-locks)")))
    return rules


def solution_from(case: Case, backend: str, results: LinkageResults, *, method: str,
                  elapsed: float, index: int = 0, only: set[str] | None = None) -> Solution:
    """A Solution for one pose of a linkage's results, with its verdict.

    ``only`` keeps the force quantities a method gives (virtual work: the drivers' efforts).
    """
    linkage = case.linkage
    # The condition number when first read (an SVD, as long as the rest of a static pose's
    # solve): the verdicts below do not read it where its bound decides.
    diagnostics: dict[str, float | str | Later] = {
        "method": method, "condition_number": lambda: float(results.condition[index]),
        "dof": linkage.dof, "gruebler": linkage.gruebler, "wall_time_s": elapsed,
    }
    axial = {q: v[index:index + 1] for q, v in results.values.items() if q.startswith("N_")} \
        if linkage.elastic_links else {}
    if axial:   # how small the displacements statics neglects are
        one = slice(index, index + 1)
        diagnostics["max_strain"] = float(largest_strain(results.pose.take(one), axial)[0])
    # Every value is kept: one that is not finite at a pose without a verdict is a failure
    # of the method, which the harness reports as such rather than as a missing row.
    values = {q: v.item(index) for q, v in results.values.items()}
    pose_only = {q: v for q, v in values.items()
                 if q.startswith(("x_", "y_", "phi_", "q_")) and math.isfinite(v)}
    if only is not None:
        values = {q: v for q, v in values.items() if q in only or q in pose_only}
    if results.stable is not None:
        diagnostics["stable"] = "yes" if results.stable[index] == 1.0 else (
            "no" if results.stable[index] == 0.0 else "not found")
        # An unstable pose is still the answer (its forces hold there), but the reader must
        # learn that the search found no stable one, and why.
        if results.stable[index] == 0.0 and verdict(case, results, index) is None:
            return Solution(case.name, backend, values, diagnostics=Diagnostics(diagnostics),
                            units=quantity_units(linkage),
                            message=unstable_reason(linkage, results.pose.drivers[index]))
    found = verdict(case, results, index)
    units = quantity_units(linkage)
    if found is not None:
        return Solution(case.name, backend, pose_only, status=found[0], message=found[1],
                        diagnostics=Diagnostics(diagnostics), units=units)
    return Solution(case.name, backend, values, diagnostics=Diagnostics(diagnostics), units=units)


#: Why a linkage without drivers cannot be swept.
NOTHING_TO_SWEEP = ("a linkage sweep moves the first driver, and this linkage has none (its "
                    "free coordinates are solved case by case: use `mechcheck run`)")


def driver_values(case: Case, first: Array | None) -> Array | None:
    """Driver values (N, d) with the first driver at ``first`` (its unit: rad or m, from the
    drawn pose) and the others at the case's values; None: the case's own pose."""
    if first is None:
        return None
    if not case.linkage.drivers:
        raise CaseError(NOTHING_TO_SWEEP, key="drivers", case=case.name)
    own = np.array([d.value for d in case.linkage.drivers])
    values = np.tile(own, (np.size(first), 1))
    values[:, 0] = np.asarray(first, dtype=float)
    return values


def analytic_results(case: Case, first: Array | None = None) -> LinkageResults:
    """The member-equilibrium matrix method at each value of the first driver."""
    return solve_linkage(case.linkage, driver_values(case, first))


def superposition_results(case: Case, first: Array | None = None) -> LinkageResults:
    """Each known load alone (every external load, weight with inertia of each mass, spring
    and viscous term), the solutions added; refuses Coulomb friction."""
    if case.has_coulomb_friction:
        raise CoulombRefused(COULOMB_REFUSAL)
    linkage = case.linkage
    if any(j.kind.nonlinear_coefficient(j) > 0.0 for j in linkage.joints):
        raise CoulombRefused(NONLINEAR_REFUSAL)
    results = analytic_results(case, first)
    pose = results.pose
    k = coefficient_matrix(pose)
    x = sum((_single_load_forces(pose, k, part) for part in single_load_parts(linkage)),
            start=np.zeros((1, k.shape[2])))
    x[results.withheld] = np.nan
    values = dict(results.values)
    values.update(_forces_from(pose, x))
    if linkage.elastic_links:
        values.update(axial_forces(pose, k, x))
    return replace(results, values=values)


def _single_load_forces(pose: LinkagePose, k: Array, part: Linkage) -> Array:
    """The reactions under one load alone (``part``: the linkage with that load only): from
    equilibrium, and, where the joints are redundant and elastic members decide them, from
    compatible stretches too (linear in the loads as well)."""
    alone = replace(pose, linkage=part)
    b = known_vector(alone)
    if part.redundant and part.elastic_links:
        return compatible_forces(alone, k, b)[0]
    return solve_batched(k, -b)


def virtual_work_results(case: Case, first: Array | None = None) -> LinkageResults:
    """Each driver's effort from the power equation.

    Moving driver k alone at unit rate (the others held), ideal joints do no work, so
    Q_k = −(power of every known force: loads, weights, inertia, springs, viscous terms).
    A link's known forces, reduced to the global origin as (F, M), have power
    F·v_O + M·ω with v_O = ṫ − ω·perp(t) the velocity of the link's point at the origin.
    """
    if case.has_coulomb_friction:
        raise CoulombRefused(COULOMB_REFUSAL)
    linkage = case.linkage
    results = analytic_results(case, first)
    pose = results.pose
    b = known_vector(pose)
    values = {q: v for q, v in results.values.items() if q.startswith(("x_", "y_", "phi_", "q_"))}
    for k, driver in enumerate(linkage.drivers):
        rates = np.zeros((pose.q.shape[0], len(linkage.drivers)))
        rates[:, k] = 1.0
        virtual = solve_pose(linkage, pose.drivers, rates, np.zeros_like(rates))
        effort = -_power(linkage, pose, virtual, b)
        effort[results.withheld] = np.nan
        values[f"Q_{driver.joint}"] = effort
    return replace(results, values=values)


def _backend(results_of: Callable[[Case], LinkageResults], name: str, method: str,
             case: Case, only: set[str] | None = None) -> Solution:
    start = time.perf_counter()
    try:
        results = results_of(case)
    except CoulombRefused as refusal:
        return Solution(case.name, name, {}, status="not_applicable", message=str(refusal),
                        units=quantity_units(case.linkage))
    return solution_from(case, name, results, method=method, elapsed=time.perf_counter() - start,
                         only=only)


def solve(case: Case) -> Solution:
    """The ``analytic`` backend for a linkage: the member-equilibrium matrix method."""
    return _backend(analytic_results, "analytic", "member-equilibrium matrix method", case)


def superposition(case: Case) -> Solution:
    """The ``superposition`` backend for a linkage (:func:`superposition_results`)."""
    return _backend(superposition_results, "superposition", "superposition of single loads",
                    case)


def virtual_work(case: Case) -> Solution:
    """The ``virtual_work`` backend for a linkage: the drivers' efforts and the pose."""
    return _backend(virtual_work_results, "virtual_work", "power equation", case,
                    only={f"Q_{d.joint}" for d in case.linkage.drivers})


def single_load_parts(linkage: Linkage) -> list[Linkage]:
    """The linkage with each known load alone (an external load, a mass's weight and
    inertia, a spring, the viscous terms): b is linear in the loads, so theirs add up to b."""
    bare = Linkage(linkage.points, linkage.links, linkage.joints, linkage.drivers)
    parts = [replace(bare, loads=(load,)) for load in linkage.loads]
    parts += [replace(bare, masses=(mass,), gravity=linkage.gravity) for mass in linkage.masses]
    parts += [replace(bare, springs=(spring,)) for spring in linkage.springs]
    if linkage.friction is not None:
        parts.append(replace(bare, friction=linkage.friction))
    return parts


def single_loads(linkage: Linkage, pose: LinkagePose) -> list[Array]:
    """The known vector of each load alone (:func:`single_load_parts`)."""
    return [known_vector(replace(pose, linkage=part)) for part in single_load_parts(linkage)]


def _forces_from(pose: LinkagePose, x: Array) -> dict[str, Array]:
    return force_quantities(pose, x, [])


def _power(linkage: Linkage, pose: LinkagePose, virtual: LinkagePose, b: Array) -> Array:
    power = np.zeros(b.shape[0])
    for n, link in enumerate(linkage.moving_links):
        t, _ = pose.link_state(link, pose.q)
        v, omega = virtual.link_state(link, virtual.qdot)
        v_origin = v - omega[:, None] * perp(t)
        power += b[:, 3 * n] * v_origin[:, 0] + b[:, 3 * n + 1] * v_origin[:, 1] \
            + b[:, 3 * n + 2] * omega
    return power
