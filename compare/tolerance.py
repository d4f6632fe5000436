"""The one tolerance policy: every comparison's tolerance comes from here.

A tolerance is looked up by (backend family, quantity kind, case kind): each backend
declares the family it is judged by (:mod:`mechcheck.analytic.contract`). Quantity
kinds are ``force``, ``torque`` and ``pose`` (:func:`mechcheck.analytic.solution.quantity_kind`),
and ``energy`` for the analytic reference's own check of a trajectory;
case kinds are ``static``, ``dynamic``, ``friction``, ``near_singular`` (:func:`case_kind`)
and ``trajectory`` (``mechcheck simulate``). Each entry carries the reason for its size.

The relative error of a value is measured against the *scale* of its kind in
that case (:func:`mechcheck.tables.kind_scales`): a reaction component that
happens to be near zero is judged against the case's largest reaction, and a
torque against the largest reaction times the longest link, not against its
own tiny magnitude.

A structure with elastic members (``axial_stiffness``) is judged against the linear,
small-displacement answer of the analytic engine, while a simulator settles to its exact
equilibrium on the stretched geometry: a simulator's tolerance there grows by
:data:`STRAIN_FACTOR` × the analytic ``max_strain`` (:func:`small_displacement_bound`).

A case file may tighten or loosen a tolerance for one case with
``[[case.tolerance]]`` (``backend``, ``quantity`` — a quantity name or kind —,
``rtol``, ``atol``); the comparison row records that it did.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fnmatch import fnmatch
from typing import Literal

from mechcheck import backends as registry
from mechcheck.analytic.case import Case
from mechcheck.analytic.contract import Family
from mechcheck.analytic.solution import quantity_kind

#: Cases whose analytic condition number exceeds this are ``near_singular``:
#: forces are amplified ≥ 10⁴× over an ordinary pose, simulators settle
#: slowly (steps ∝ cond²) and their soft constraints bend measurably.
NEAR_SINGULAR_CONDITION = 1.0e4

#: The small-displacement bound: a simulator's relative error against the linear answer of a
#: structure with elastic members may exceed its own tolerance by this × the largest strain
#: |N|/(E·A). The linear answer takes equilibrium on the drawn geometry; the members turn by
#: their ends' displacements over their length, a few strains, and the forces follow the
#: turned geometry: relative error ≈ c × strain, c set by the geometry. Measured against the
#: exact equilibrium solved on the stretched geometry (tests/test_catalogue_gears.py): on the
#: catalogue's steel bracket (strain 7.6e-5) c = 2.2 for forces, 1.3 for node positions (over
#: its size) and 2.2 for the bars' angles (rad); MuJoCo and pymunk, which settle to within
#: 3e-7 of that exact equilibrium, 0.9 and 1.2 for forces on the tests' three and four bars
#: to one node (strains 3.3e-5, 4.4e-5). 5 leaves a margin of 2.3 over the largest.
STRAIN_FACTOR = 5.0


@dataclass(frozen=True)
class Tolerance:
    rtol: float
    atol: float
    reason: str
    overridden: bool = False


REFERENCE_FAMILY: Family = "reference"
ANALYTIC_FAMILY: Family = "analytic"
EXACT_SOLVES: Family = "exact_solve"
SETTLED: Family = "settled"

#: The case kind of a trajectory (``mechcheck simulate``): a linkage moving freely over time.
TRAJECTORY = "trajectory"

#: The quantity kind of the analytic reference's own check on a trajectory: the residual of
#: its energy balance over the energy it met (:class:`~mechcheck.analytic.trajectory.EnergyBalance`).
ENERGY = "energy"

_RULES: list[tuple[Family | Literal["*"], str, str, Tolerance]] = [
    # (backend family, quantity kind, case kind, tolerance); "*" matches anything; first
    # match wins.
    (REFERENCE_FAMILY, ENERGY, TRAJECTORY, Tolerance(
        1e-8, 0.0, "the reference's energy balance is an identity of its equations of motion: "
        "only the adaptive integrator's tolerance, accumulated over its steps, breaks it; "
        "the targets: 1e-9 on Andrews' squeezer, a drift below 1e-8 of the energy "
        "over 10 s of the N four-bar")),
    ("*", "pose", TRAJECTORY, Tolerance(
        1e-3, 0.0, "a simulator's run over time against the analytic reference: positions "
        "over the case's scale and angles in rad, the worst over the output times; the "
        "accuracy asked of a simulator's trajectory")),
    (ANALYTIC_FAMILY, "*", "near_singular", Tolerance(
        1e-6, 0.0, "same equations by other algebra, but rounding is amplified by the "
        "condition number (up to 1e8 × 2.2e-16 ≈ 2e-8 before a pose is called singular)")),
    (ANALYTIC_FAMILY, "*", "*", Tolerance(
        1e-9, 0.0, "the same rigid-body equations solved another way: only rounding "
        "(condition number × machine epsilon ≲ 1e-12) separates them")),
    (EXACT_SOLVES, "*", "near_singular", Tolerance(
        1e-6, 0.0, "exact constraint solve, rounding amplified by the condition number")),
    (EXACT_SOLVES, "*", "*", Tolerance(
        1e-9, 0.0, "the simulator's constraint forces at the exact analytic pose: "
        "rigid statics up to the solver's convergence (≤1e-12 seen) and rounding")),
    (SETTLED, "*", "static", Tolerance(
        1e-6, 0.0, "settled simulation: stiffened constraints leave a violation of order "
        "1e-8 and the settling thresholds stop it within 1e-7 of equilibrium")),
    (SETTLED, "*", "dynamic", Tolerance(
        1e-3, 0.0, "driven simulation: time discretisation of the prescribed motion and "
        "constraint softness at the instant θ12 (issue target)")),
    (SETTLED, "*", "friction", Tolerance(
        1e-3, 0.0, "friction emulated from the previous step's reactions while driven "
        "slowly: lag of one step and residual inertia of the slow motion (issue target)")),
    (SETTLED, "*", "near_singular", Tolerance(
        1e-2, 0.0, "near a toggle the soft constraints bend by an amount the 1/δ force "
        "growth magnifies; numbers are indicative only")),
    ("*", "*", "*", Tolerance(
        1e-6, 0.0, "default for a backend the policy does not name yet")),
]


def of_tolerance(rel_err: float, abs_err: float, rtol: float, atol: float) -> float:
    """A comparison's error as a fraction of what its tolerance allows: 1 at the tolerance.

    A comparison passes when ``rel_err <= rtol`` or ``abs_err <= atol`` (``abs_err`` in SI,
    as the policy's ``atol``), so this is the smaller of the two ratios, and a comparison
    passes exactly when it is at most 1. A limit of zero allows only a zero error.
    """
    return min(_ratio(rel_err, rtol), _ratio(abs_err, atol))


def _ratio(error: float, limit: float) -> float:
    if limit > 0:
        return error / limit
    return 0.0 if error <= 0 else math.inf


def case_kind(case: Case, condition_number: float) -> str:
    """``near_singular`` above :data:`NEAR_SINGULAR_CONDITION`, else the case's own kind."""
    if condition_number > NEAR_SINGULAR_CONDITION:
        return "near_singular"
    return case.kind


def _matches(pattern: str, value: str) -> bool:
    return pattern == "*" or fnmatch(value, pattern)


def override(case: Case, backend: str, quantity: str, kind: str) -> tuple[float, float] | None:
    """The case file's own tolerance for this comparison, if it sets one (last wins)."""
    found = None
    for selector, rtol, atol in case.tolerance:
        b, q = selector.split(":", 1)
        if _matches(b, backend) and (_matches(q, quantity) or q == kind):
            found = (rtol, atol)
    return found


def rule(backend: str, quantity_kind: str, case_kind: str) -> Tolerance:
    """The policy's tolerance for a backend, quantity kind and case kind (first match wins)."""
    kind = registry.REGISTRY[backend].family if backend in registry.REGISTRY else None
    for fam, qk, ck, tol in _RULES:
        if (fam == "*" or fam == kind) and _matches(qk, quantity_kind) and _matches(ck, case_kind):
            return tol
    raise LookupError(backend)  # unreachable: the last rule matches everything


def small_displacement_bound(backend: str, tol: Tolerance, max_strain: float) -> Tolerance:
    """``tol`` widened by :data:`STRAIN_FACTOR` × ``max_strain`` for a simulator (a settled or
    exact-solve backend) judged against the linear answer of a structure whose elastic
    members stretch by up to ``max_strain``; unchanged for the analytic family, which solves
    the same linear equations, and where nothing stretches."""
    kind = registry.REGISTRY[backend].family if backend in registry.REGISTRY else None
    if max_strain <= 0.0 or kind not in (SETTLED, EXACT_SOLVES):
        return tol
    widened = STRAIN_FACTOR * max_strain
    return Tolerance(tol.rtol + widened, tol.atol, (
        f"{tol.reason}; plus the small-displacement bound {STRAIN_FACTOR:g} × max_strain "
        f"{max_strain:.2g} = {widened:.2g}: the simulator's equilibrium is the exact one on the "
        "stretched members, the reference the linear one on the drawn geometry"))


def tolerance_for(case: Case, backend: str, quantity: str, kind: str,
                  quantity_kind_: str | None = None, max_strain: float = 0.0) -> Tolerance:
    """The tolerance of one comparison row: the case's override or the policy's rule, the
    rule widened by the small-displacement bound where elastic members stretch by up to
    ``max_strain`` (the reference's). ``quantity_kind_`` (force, torque, pose) defaults to
    the four-bar's names' kinds."""
    qkind = quantity_kind_ or quantity_kind(quantity)
    own = override(case, backend, quantity, qkind)
    if own is not None:
        return Tolerance(own[0], own[1], "set in the case file", overridden=True)
    return small_displacement_bound(backend, rule(backend, qkind, kind), max_strain)


def policy_table() -> list[dict[str, str | float]]:
    """The rules as rows, for the README and the report."""
    def members(fam: Family | Literal["*"]) -> str:
        return "any other" if fam == "*" else ", ".join(registry.names_of_family(fam))

    return [{"backends": members(f), "quantity kind": q, "case kind": c,
             "rtol": t.rtol, "atol": t.atol, "reason": t.reason} for f, q, c, t in _RULES]
