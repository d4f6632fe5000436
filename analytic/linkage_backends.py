"""The analytic backends for a linkage case: the member-equilibrium matrix method
(``analytic``), superposition of single loads (``superposition``) and the power
equation (``virtual_work``), each returning a :class:`~mechcheck.analytic.solution.Solution`
in the quantities of LINKAGES.md.
"""

from __future__ import annotations

import math
import time

import numpy as np

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage import LinearSpring, Linkage
from mechcheck.analytic.linkage_forces import (
    LinkageResults,
    coefficient_matrix,
    known_vector,
    solve_linkage,
)
from mechcheck.analytic.linkage_kinematics import Array, LinkagePose, perp, solve_batched, solve_pose
from mechcheck.analytic.solution import Solution, Status

COULOMB_REFUSAL = ("the method applies only to linkages without Coulomb friction: friction "
                   "moments depend on the total reactions")


def quantity_units(linkage: Linkage) -> dict[str, str]:
    """The table unit of every quantity a linkage reports (LINKAGES.md "What comes out")."""
    units: dict[str, str] = {}
    for name in linkage.points:
        units[f"x_{name}"] = units[f"y_{name}"] = "m"
    for link in linkage.moving_links:
        units[f"phi_{link}"] = "deg"
    for joint in linkage.joints:
        units[f"F_{joint.name}_x"] = units[f"F_{joint.name}_y"] = "N"
        units[f"q_{joint.name}"] = "deg" if joint.kind == "revolute" else "m"
        if joint.kind == "prismatic":
            units[f"M_{joint.name}"] = "N*m"
    for driver in linkage.drivers:
        units[f"Q_{driver.joint}"] = "N*m" if linkage.joint(driver.joint).kind == "revolute" else "N"
    for spring in linkage.springs:
        units[f"S_{spring.name}"] = "N" if isinstance(spring, LinearSpring) else "N*m"
    return units


def lock_message(linkage: Linkage, fraction: float) -> str:
    """Where the drivers were when the linkage locked, in the file's units."""
    parts = []
    for driver in linkage.drivers:
        value = fraction * driver.value
        if linkage.joint(driver.joint).kind == "revolute":
            parts.append(f"rotation {math.degrees(value):.6g}° of {driver.joint}")
        else:
            parts.append(f"displacement {value:.6g} m of {driver.joint}")
    return "the linkage locks at " + ", ".join(parts) + " on the way from the drawn pose"


def verdict(case: Case, results: LinkageResults, index: int) -> tuple[Status, str] | None:
    """Why a pose has no unique forces, or None."""
    linkage = case.linkage
    if results.stable is not None and not np.isfinite(results.stable[index]):
        return "no_solution", ("no equilibrium pose of the free coordinates was found from the "
                               "drawn pose")
    if not results.pose.assembled[index]:
        return "no_solution", lock_message(linkage, float(results.pose.locked_at[index]))
    if linkage.redundant:
        return "indeterminate", ("the joints' constraints are redundant at the drawn pose "
                                 f"(rank {linkage.joint_rank} < {2 * len(linkage.joints)}): the "
                                 "reactions are not unique")
    cond = float(results.condition[index])
    if results.singular[index]:
        return "singular", (f"condition number {cond:.3g} exceeds 1e+08: the pose is at or next "
                            "to a toggle or dead point, where statics is singular; forces withheld")
    if results.indeterminate[index]:
        return "indeterminate", (f"the relative motion at {results.reversing[index]} reverses at "
                                 "this pose: Coulomb friction there may take any value within "
                                 "its bound, so the forces are not unique; forces withheld")
    if not results.converged[index]:
        return "no_solution", ("the friction equations have no solution with the assumed senses "
                               "of motion (the linkage self-locks)")
    return None


def solution_from(case: Case, backend: str, results: LinkageResults, *, method: str,
                  elapsed: float, index: int = 0, only: set[str] | None = None) -> Solution:
    """A Solution for one pose of a linkage's results, with its verdict.

    ``only`` keeps the force quantities a method gives (virtual work: the drivers' efforts).
    """
    linkage = case.linkage
    diagnostics: dict[str, float | str] = {
        "method": method, "condition_number": float(results.condition[index]),
        "dof": linkage.dof, "gruebler": linkage.gruebler, "wall_time_s": elapsed,
    }
    values = {q: float(v[index]) for q, v in results.values.items() if np.isfinite(v[index])}
    pose_only = {q: v for q, v in values.items() if q.startswith(("x_", "y_", "phi_", "q_"))}
    if only is not None:
        values = {q: v for q, v in values.items() if q in only or q in pose_only}
    if results.stable is not None:
        diagnostics["stable"] = "yes" if results.stable[index] == 1.0 else (
            "no" if results.stable[index] == 0.0 else "not found")
    found = verdict(case, results, index)
    units = quantity_units(linkage)
    if found is not None:
        return Solution(case.name, backend, pose_only, status=found[0], message=found[1],
                        diagnostics=diagnostics, units=units)
    return Solution(case.name, backend, values, diagnostics=diagnostics, units=units)


def solve(case: Case) -> Solution:
    """The ``analytic`` backend for a linkage: the member-equilibrium matrix method."""
    start = time.perf_counter()
    results = solve_linkage(case.linkage)
    return solution_from(case, "analytic", results, method="member-equilibrium matrix method",
                         elapsed=time.perf_counter() - start)


def not_applicable(case: Case, backend: str) -> Solution:
    return Solution(case.name, backend, {}, status="not_applicable", message=COULOMB_REFUSAL,
                    units=quantity_units(case.linkage))


def superposition(case: Case) -> Solution:
    """The ``superposition`` backend: each known load alone (every external load, weight
    with inertia of each mass, spring and viscous term), the solutions added."""
    if case.has_coulomb_friction:
        return not_applicable(case, "superposition")
    start = time.perf_counter()
    linkage = case.linkage
    results = solve_linkage(linkage)
    pose = results.pose
    k = coefficient_matrix(pose)
    x = sum((solve_batched(k, -b) for b in single_loads(linkage, pose)),
            start=np.zeros((1, k.shape[2])))
    values = dict(results.values)
    values.update(_forces_from(pose, x))
    summed = LinkageResults(pose, values, results.condition, results.converged, results.reversing)
    return solution_from(case, "superposition", summed, method="superposition of single loads",
                         elapsed=time.perf_counter() - start)


def single_loads(linkage: Linkage, pose: LinkagePose) -> list[Array]:
    """The known vector of each load alone: b is linear in the loads, so they add up to b."""
    out = []
    parts: list[Linkage] = []
    bare = Linkage(linkage.points, linkage.links, linkage.joints, linkage.drivers)
    for load in linkage.loads:
        parts.append(_with(bare, loads=(load,)))
    for mass in linkage.masses:
        parts.append(_with(bare, masses=(mass,), gravity=linkage.gravity))
    for spring in linkage.springs:
        parts.append(_with(bare, springs=(spring,)))
    if linkage.friction is not None:
        parts.append(_with(bare, friction=linkage.friction))
    for part in parts:
        out.append(known_vector(LinkagePose(part, pose.drivers, pose.q, pose.qdot, pose.qddot,
                                            pose.locked_at)))
    return out


def _with(bare: Linkage, **changes: object) -> Linkage:
    from dataclasses import replace

    return replace(bare, **changes)  # type: ignore[arg-type]


def _forces_from(pose: LinkagePose, x: Array) -> dict[str, Array]:
    from mechcheck.analytic.linkage_forces import force_quantities

    return force_quantities(pose, x, [])


def virtual_work(case: Case) -> Solution:
    """The ``virtual_work`` backend: each driver's effort from the power equation.

    Moving driver k alone at unit rate (the others held), ideal joints do no work, so
    Q_k = −(power of every known force: loads, weights, inertia, springs, viscous terms).
    A link's known forces, reduced to the global origin as (F, M), have power
    F·v_O + M·ω with v_O = ṫ − ω·perp(t) the velocity of the link's point at the origin.
    """
    if case.has_coulomb_friction:
        return not_applicable(case, "virtual_work")
    start = time.perf_counter()
    linkage = case.linkage
    results = solve_linkage(linkage)
    pose = results.pose
    b = known_vector(pose)
    values = {q: v for q, v in results.values.items() if q.startswith(("x_", "y_", "phi_", "q_"))}
    for k, driver in enumerate(linkage.drivers):
        rates = np.zeros((1, len(linkage.drivers)))
        rates[0, k] = 1.0
        virtual = solve_pose(linkage, pose.drivers, rates, np.zeros_like(rates))
        values[f"Q_{driver.joint}"] = -_power(linkage, pose, virtual, b)
    summed = LinkageResults(pose, values, results.condition, results.converged, results.reversing)
    return solution_from(case, "virtual_work", summed, method="power equation",
                         elapsed=time.perf_counter() - start,
                         only={f"Q_{d.joint}" for d in linkage.drivers})


def _power(linkage: Linkage, pose: LinkagePose, virtual: LinkagePose, b: Array) -> Array:
    power = np.zeros(b.shape[0])
    for n, link in enumerate(linkage.moving_links):
        t, _ = pose.link_state(link, pose.q)
        v, omega = virtual.link_state(link, virtual.qdot)
        v_origin = v - omega[:, None] * perp(t)
        power += b[:, 3 * n] * v_origin[:, 0] + b[:, 3 * n + 1] * v_origin[:, 1] \
            + b[:, 3 * n + 2] * omega
    return power
