"""The ``analytic`` backend: drive torque and every joint reaction by the
member-equilibrium matrix method (:mod:`mechcheck.analytic.equilibrium`), with Coulomb
friction solved to convergence (:mod:`mechcheck.analytic.friction`).

:func:`solve_poses` is vectorised over an array of θ12; :func:`solve` wraps it
for one Case and returns a :class:`~mechcheck.analytic.solution.Solution`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mechcheck.analytic.assembly import unassembled_verdict
from mechcheck.analytic.case import Case, FourBarGeometry
from mechcheck.analytic.kinematics import Placement, Pose, as_angles, placement_of, pose_of
from mechcheck.analytic.solution import Solution, Status

from .equilibrium import (
    SINGULAR_CONDITION,
    Array,
    coefficient_matrix,
    condition,
    core_condition,
    eliminate,
    fixed_wrenches,
    known_vector,
    slide_frame,
    solve_members,
)
from .friction import (
    coulomb_terms,
    reversing_joints,
    slide_friction_force,
    solve_with_friction,
)

FORCE_QUANTITIES = ("F12_x", "F12_y", "F23_x", "F23_y", "F34_x", "F34_y", "F14_x", "F14_y")


def drive_quantity(case: Case) -> str:
    """``T12`` or ``T14``, after the link the drive acts on."""
    return f"T1{case.preset.drive_link}"


@dataclass(frozen=True)

class PoseResults:
    """Vectorised results: each array has one entry per θ12.

    ``values`` holds pose quantities (``theta13``, ``theta14`` or ``s14``)
    and the forces and drive torque (NaN where ``singular``, ``indeterminate``
    or not ``converged``). ``condition`` is the dimensionless condition number.
    ``reversing`` names, per pose, the joints whose Coulomb friction reverses
    there ("" where none).
    """

    theta12: Array
    values: dict[str, Array]
    condition: Array
    iterations: NDArray[np.int_]
    converged: NDArray[np.bool_]
    reversing: NDArray[np.str_] | None = None

    @property
    def indeterminate(self) -> NDArray[np.bool_]:
        if self.reversing is None:
            return np.zeros(self.theta12.shape, dtype=bool)
        return self.reversing != ""

    @property
    def assembled(self) -> NDArray[np.bool_]:
        return np.isfinite(self.values["theta13"])

    @property
    def singular(self) -> NDArray[np.bool_]:
        return ~(self.condition <= SINGULAR_CONDITION)


def wrap_angle(angle: Array) -> Array:
    """Angles reported in [−π, π), so tables never show 370°."""
    return np.remainder(angle + np.pi, 2.0 * np.pi) - np.pi


def pose_values(case: Case, pose: Pose | Placement) -> dict[str, Array]:
    """theta13 and theta14 (four-bar) or s14 (slider-crank)."""
    out = {"theta13": wrap_angle(pose.theta13)}
    if isinstance(case.preset.geometry, FourBarGeometry):
        out["theta14"] = wrap_angle(pose.theta14)
    else:
        assert pose.s14 is not None
        out["s14"] = pose.s14
    return out


def slide_friction_along(case: Case, pose: Pose, normal: Array) -> Array | float:
    """The friction force on the slider along u (Coulomb and viscous); 0 without friction."""
    along: Array | float = 0.0
    for t in coulomb_terms(case, pose.theta12):
        if t.joint == "slide":
            along = along + slide_friction_force(t, normal)
    if case.preset.friction is not None and case.preset.friction.viscous.get("slide", 0.0) > 0.0:
        assert pose.s14_dot is not None
        along = along - case.preset.friction.viscous["slide"] * pose.s14_dot
    return along


def unknowns_to_values(case: Case, x: list[Array], along: Array | float = 0.0) -> dict[str, Array]:
    """Name the solved unknowns (x's columns) in CONVENTIONS terms: F14 is assembled for a
    slider from the normal N14 and the friction ``along`` the slide."""
    out = dict(zip(FORCE_QUANTITIES[:6], x[:6], strict=True))
    if isinstance(case.preset.geometry, FourBarGeometry):
        out["F14_x"], out["F14_y"] = x[6], x[7]
    else:
        u, nrm = slide_frame(case)
        out["F14_x"] = x[6] * nrm[0] + along * u[0]
        out["F14_y"] = x[6] * nrm[1] + along * u[1]
        out["M14"] = x[7]
    out[drive_quantity(case)] = x[8]
    return out


def named_values(case: Case, pose: Pose, x: Array) -> dict[str, Array]:
    """The pose's values and the unknowns x (N, 9), named."""
    return pose_values(case, pose) | unknowns_to_values(
        case, list(x.T), slide_friction_along(case, pose, x[:, 6]))


def static_results(case: Case, angles: Array) -> PoseResults:
    """:func:`solve_poses` for a static case without friction, from positions alone: the
    fixed loads in one right-hand side, the members solved on flat coordinates."""
    place = placement_of(case, angles)
    cond = core_condition(case, place.joints)
    x = solve_members(case, place.joints, fixed_wrenches(case, place))
    withheld = ~(cond <= SINGULAR_CONDITION)
    if withheld.any():
        for column in x:
            column[withheld] = np.nan
    n = angles.shape[0]
    return PoseResults(angles, pose_values(case, place) | unknowns_to_values(case, x), cond,
                       np.zeros(n, dtype=int), np.ones(n, dtype=bool))


def solve_poses(case: Case, theta12_rad: ArrayLike | None = None) -> PoseResults:
    """Static or dynamic force analysis of ``case`` at each θ12 (rad).

    Poses beyond :data:`~mechcheck.analytic.equilibrium.SINGULAR_CONDITION`, and
    friction poses whose Newton iteration did not converge, get NaN forces.
    """
    # A pose that does not assemble is NaN by design (its verdict is no_solution):
    # the arithmetic on it must not warn.
    with np.errstate(invalid="ignore", divide="ignore"):
        angles = as_angles(case.preset.theta12 if theta12_rad is None else theta12_rad)
        if case.kind == "static":
            return static_results(case, angles)
        pose = pose_of(case, angles)
        cond = condition(case, pose)
        b = known_vector(case, pose)
        x = eliminate(case, pose, b)
        iterations = np.zeros(angles.shape[0], dtype=int)
        converged = np.ones(angles.shape[0], dtype=bool)
        reversing = None
        withheld = ~(cond <= SINGULAR_CONDITION)
        if case.has_coulomb_friction:
            k = coefficient_matrix(case, pose)
            x, iterations, converged = solve_with_friction(case, pose, k, b, x)
            reversing = np.full(angles.shape[0], "", dtype=object)
            for joint, where in reversing_joints(coulomb_terms(case, angles)):
                reversing[where] = np.where(reversing[where] == "", joint,
                                            reversing[where] + ", " + joint)
            reversing = reversing.astype(str)
            withheld |= ~converged | (reversing != "")
        x[withheld] = np.nan
        return PoseResults(angles, named_values(case, pose, x), cond, iterations, converged,
                           reversing)


@dataclass(frozen=True)

class PoseVerdict:
    """Why no force analysis exists at a pose: a property of the pose, so every
    backend, analytic or simulated, reports the same verdict there."""

    status: Status
    message: str
    condition: float


def verdict_at(case: Case, results: PoseResults, index: int) -> PoseVerdict | None:
    """The pose's verdict (unassembled, singular, indeterminate friction, no solution), or
    None if regular."""
    cond = float(results.condition[index])
    if not np.isfinite(results.values["theta13"][index]):
        status, message = unassembled_verdict(case, float(results.theta12[index]))
        return PoseVerdict(status, message, cond)
    if results.singular[index]:
        return PoseVerdict("singular", f"condition number {cond:.3g} exceeds "
                           f"{SINGULAR_CONDITION:.0e}: the pose is at or next to a toggle/change "
                           "point, where statics is singular; forces withheld", cond)
    if results.indeterminate[index]:
        assert results.reversing is not None
        return PoseVerdict("indeterminate", f"the relative motion at {results.reversing[index]} "
                           "reverses at this pose: Coulomb friction there may take any value "
                           "within ±μ·r·|F| (±μ·|N| on the slide), so the drive torque and "
                           "reactions are not unique; forces withheld", cond)
    if not results.converged[index]:
        return PoseVerdict("no_solution", "the friction equations have no solution with the "
                           "assumed senses of motion (the mechanism self-locks)", cond)
    return None


def pose_verdicts(case: Case, results: PoseResults) -> tuple[NDArray[np.object_],
                                                             NDArray[np.object_]]:
    """Every pose's verdict (``"ok"`` where it has forces) and its message: :func:`verdict_at`
    at every pose, looked up only where the pose is flagged."""
    n = len(results.theta12)
    statuses = np.full(n, "ok", dtype=object)
    messages = np.full(n, "", dtype=object)
    flagged = ~results.assembled | results.singular | results.indeterminate | ~results.converged
    for index in np.flatnonzero(flagged):
        found = verdict_at(case, results, int(index))
        if found is not None:
            statuses[index], messages[index] = found.status, found.message
    return statuses, messages


def solution_from(case: Case, backend: str, results: PoseResults, index: int = 0, *,
                  method: str, elapsed: float) -> Solution:
    """A :class:`Solution` for one pose of vectorised results, with its verdict."""
    cond = float(results.condition[index])
    diagnostics: dict[str, float | str] = {
        "method": method, "condition_number": cond, "wall_time_s": elapsed,
    }
    if case.has_coulomb_friction:
        diagnostics["newton_iterations"] = int(results.iterations[index])
    verdict = verdict_at(case, results, index)
    if verdict is not None:
        pose_only = {q: float(v[index]) for q, v in results.values.items()
                     if q in ("theta13", "theta14", "s14")}
        return Solution(case.name, backend, pose_only, status=verdict.status,
                        message=verdict.message, diagnostics=diagnostics)
    values = {q: float(v[index]) for q, v in results.values.items()}
    return Solution(case.name, backend, values, diagnostics=diagnostics)


def unassemblable_solution(case: Case, backend: str, theta12: float) -> Solution:
    """What any backend reports at a swept θ12 (rad) where the mechanism has no position."""
    status, message = unassembled_verdict(case, theta12)
    return Solution(case.name, backend, {}, status=status, message=message,
                    diagnostics={"theta12": theta12})


def solve(case: Case) -> Solution:
    """The ``analytic`` backend: the full force analysis of one Case."""
    if not case.is_preset:
        raise TypeError(f"case {case.name!r} is a linkage: it has no closed form")
    start = time.perf_counter()
    results = solve_poses(case)
    return solution_from(case, "analytic", results, method="member-equilibrium matrix method",
                         elapsed=time.perf_counter() - start)
