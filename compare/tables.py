"""Tidy long tables (CONVENTIONS.md): results, comparison and diagnostics.

Values are converted from SI/radians to table units (degrees) only here.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Sequence

import numpy as np
import pandas as pd

from mechcheck.analytic.case import Case
from mechcheck.analytic.solution import (
    FORCE_FLOOR_N,
    Solution,
    kind_of_unit,
    order_key,
    table_value,
    unit_factor,
    wraps,
)
from mechcheck.backends import REFERENCE
from mechcheck.tolerance import NEAR_SINGULAR_CONDITION, case_kind, of_tolerance, tolerance_for

RESULT_COLUMNS = ["case", "backend", "quantity", "value", "unit"]
COMPARISON_COLUMNS = ["case", "quantity", "backend", "value", "reference", "abs_err",
                      "rel_err", "tolerance", "passed"]
DIAGNOSTIC_COLUMNS = ["case", "backend", "status", "key", "value"]

#: Smallest scale a force error is measured against, N (torques: times the longest
#: link): :data:`~mechcheck.analytic.solution.FORCE_FLOOR_N`, the weight of about a gram.
SCALE_FLOOR = FORCE_FLOOR_N


def ordered(values: Iterable[str]) -> list[str]:
    return sorted(values, key=order_key)


def results_frame(solutions: Sequence[Solution]) -> pd.DataFrame:
    """One row per reported number; absent quantities have no row."""
    rows = [(s.case, s.backend, q, table_value(q, s.values[q], s.unit(q)), s.unit(q))
            for s in solutions for q in ordered(s.values)]
    return pd.DataFrame(rows, columns=RESULT_COLUMNS)


def kind_scales(case: Case, reference: Solution) -> dict[str, float]:
    """Scale of each quantity kind in a case.

    Forces: the largest reference reaction, or the largest reference torque over the
    longest link if that is larger (a torque the drive takes straight from a load leaves
    every reaction zero, yet a simulator bears it through joints with lever arms of that
    size). Torques: the largest reference torque, or the largest reaction times the
    longest link if that is larger (a drive torque that happens to vanish at a dead
    centre is still made of forces with lever arms of that size). Angles: 1 rad. s14:
    the longest link.
    """
    scales = {"force": SCALE_FLOOR, "torque": SCALE_FLOOR, "angle": 1.0,
              "length": case.scale}
    for q, v in reference.values.items():
        kind = kind_of_unit(reference.unit(q))
        if kind in ("force", "torque"):
            scales[kind] = max(scales[kind], abs(v))
    forces, torques, length = scales["force"], scales["torque"], case.scale
    scales["force"], scales["torque"] = max(forces, torques / length), max(torques, forces * length)
    return scales


def error_scale(unit: str, scales: dict[str, float]) -> float:
    """What an error in ``unit`` is measured against (angles: 1 rad; lengths and positions:
    the longest link; forces and torques: their kind's scale)."""
    kind = kind_of_unit(unit)
    if kind == "pose":
        return scales["length"] if unit == "m" else scales["angle"]
    return scales[kind]


def comparison_rows(case: Case, reference: Solution, other: Solution) -> list[dict[str, object]]:
    """One row per quantity both solutions report, with the policy's tolerance."""
    scales = kind_scales(case, reference)
    kind = case_kind(case, float(reference.diagnostics.get("condition_number", 0.0)))
    strain = float(reference.diagnostics.get("max_strain", 0.0))
    rows: list[dict[str, object]] = []
    for q in ordered(set(reference.values) & set(other.values)):
        ref, val, unit = reference.values[q], other.values[q], reference.unit(q)
        abs_err = abs(val - ref)
        if wraps(q, unit):
            abs_err = abs(math.remainder(val - ref, math.tau))  # a direction: modulo a turn
        rel_err = abs_err / error_scale(unit, scales)
        tol = tolerance_for(case, other.backend, q, kind, kind_of_unit(unit), strain)
        rows.append({
            "case": case.name, "quantity": q, "backend": other.backend,
            "value": table_value(q, val, unit), "reference": table_value(q, ref, unit),
            "abs_err": abs_err * unit_factor(unit), "rel_err": rel_err,
            "tolerance": tol.rtol,
            "passed": bool(rel_err <= tol.rtol or abs_err <= tol.atol),
            # Not written to comparison.csv (the contract fixes its columns); the report uses them.
            "atol": tol.atol, "case_kind": kind, "reason": tol.reason,
            "overridden": tol.overridden,
            "of_tolerance": of_tolerance(rel_err, abs_err, tol.rtol, tol.atol),
        })
    return rows


def comparison_detail(cases: Sequence[Case], solutions: Sequence[Solution]) -> pd.DataFrame:
    """Every comparison against the reference backend, with tolerance provenance."""
    by_case: dict[str, dict[str, Solution]] = {}
    for s in solutions:
        by_case.setdefault(s.case, {})[s.backend] = s
    rows: list[dict[str, object]] = []
    for case in cases:
        found = by_case.get(case.name, {})
        reference = found.get(REFERENCE)
        if reference is None:
            continue
        for backend, other in found.items():
            if backend != REFERENCE:
                rows += comparison_rows(case, reference, other)
    columns = [*COMPARISON_COLUMNS, "atol", "case_kind", "reason", "overridden", "of_tolerance"]
    return pd.DataFrame(rows, columns=columns)


def diagnostics_frame(solutions: Sequence[Solution]) -> pd.DataFrame:
    """Each backend's verdict, message and diagnostics, long format."""
    rows: list[tuple[str, str, str, str, str]] = []
    for s in solutions:
        rows.append((s.case, s.backend, s.status, "message", s.message))
        rows += [(s.case, s.backend, s.status, k, str(v)) for k, v in s.diagnostics.items()]
    return pd.DataFrame(rows, columns=DIAGNOSTIC_COLUMNS)


def sweep_comparison(case: Case, reference: pd.DataFrame, reference_status: pd.DataFrame,
                     other: pd.DataFrame) -> pd.DataFrame:
    """Per-pose comparisons of backends' sweeps (``other``: one or more backends, each
    backend's rows together) against the reference, vectorised.

    Same measure and policy as :func:`comparison_rows`, with the case kind taken
    per pose (``near_singular`` where the reference's condition number says so).
    Columns: the comparison columns of CONVENTIONS.md plus ``theta12``.
    """
    # Names and units are worked on as integer codes over their few distinct values, and
    # rows are matched, grouped and judged in numpy: pandas' merge, group-by and string
    # columns took most of a resumed sweep's comparing, mostly in their first use.
    names, (ref_q, other_q) = shared_codes(reference["quantity"], other["quantity"])
    units, (ref_u,) = shared_codes(reference["unit"])
    poses = np.unique(reference["theta12"].to_numpy(dtype=float))
    ref_pose = np.searchsorted(poses, reference["theta12"].to_numpy(dtype=float))
    theta = other["theta12"].to_numpy(dtype=float)
    row = matching_rows(ref_pose * len(names) + ref_q, pose_index(poses, theta), other_q,
                        len(names))
    found = row >= 0
    if not found.any():
        return pd.DataFrame(columns=["case", "theta12", *COMPARISON_COLUMNS[1:]])
    row, theta, other_q = row[found], theta[found], other_q[found]
    pose = ref_pose[row]
    unit = ref_u[row]
    kinds = ("force", "torque", "pose")  # indices into the per-pose scales below
    unit_kind = np.array([kinds.index(kind_of_unit(u)) for u in units], dtype=np.intp)
    factor = np.array([unit_factor(u) for u in units])[unit]
    kind = unit_kind[unit]
    is_force, is_torque, is_pose = (kind == k for k in range(len(kinds)))
    ref_value = reference["value"].to_numpy(dtype=float)
    # Scale of each force/torque kind at each pose: the largest reference magnitude
    # (NaN where the pose has none of that kind, then the floor).
    largest = np.full((len(poses), len(kinds)), np.nan)
    np.fmax.at(largest, (ref_pose, unit_kind[ref_u]), np.abs(ref_value))
    largest = np.nan_to_num(largest, nan=SCALE_FLOOR)
    scale = np.maximum(largest[pose, kind], SCALE_FLOOR)
    # Forces at least the largest torque over the longest link, torques at least the
    # largest reaction times it (see kind_scales).
    length = case.scale
    force_at, torque_at = largest[pose, 0], largest[pose, 1]
    scale = np.where(is_torque, np.maximum(scale, force_at * length), scale)
    scale = np.where(is_force, np.maximum(scale, torque_at / length), scale)
    is_angle = np.array([u == "deg" for u in units], dtype=bool)[unit]
    scale = np.where(is_pose, np.where(is_angle, factor, length), scale)
    value = other["value"].to_numpy(dtype=float)[found]
    diff = value - ref_value[row]
    # Directions compare modulo a turn; joint coordinates count their turns (wraps).
    wrapping = np.array([wraps(q, u) for q in names for u in units], dtype=bool).reshape(
        len(names), len(units))[other_q, unit]
    diff = np.where(wrapping, (diff + 180.0) % 360.0 - 180.0, diff)
    abs_err = np.abs(diff)
    rel_err = abs_err / scale
    status_poses = reference_status["theta12"].to_numpy(dtype=float)
    order = np.argsort(status_poses, kind="stable")
    at = pose_index(status_poses[order], theta)
    cond = np.where(at >= 0, reference_status["condition_number"].to_numpy(dtype=float)[
        order][np.maximum(at, 0)], np.nan)
    near = cond > NEAR_SINGULAR_CONDITION
    backends, (backend,) = shared_codes(other["backend"])
    backend = backend[found]
    # One rule per distinct (backend, quantity, pose kind, unit), spread back by its codes.
    rule_key = ((backend * len(names) + other_q) * 2 + near) * len(units) + unit
    distinct, codes = np.unique(rule_key, return_inverse=True)
    rules = []
    for key in distinct.tolist():
        rest, u = divmod(key, len(units))
        rest, is_near = divmod(rest, 2)
        b, q = divmod(rest, len(names))
        rules.append(tolerance_for(case, backends[b], names[q],
                                   "near_singular" if is_near else case.kind,
                                   kind_of_unit(units[u])))
    rtol = np.array([r.rtol for r in rules])[codes]
    atol = np.array([r.atol for r in rules])[codes]
    passed = (rel_err <= rtol) | (abs_err / factor <= atol)
    return pd.DataFrame({
        "case": case.name, "theta12": theta, "quantity": np.array(names, dtype=object)[other_q],
        "backend": np.array(backends, dtype=object)[backend], "value": value,
        "reference": ref_value[row], "abs_err": abs_err, "rel_err": rel_err,
        "tolerance": rtol, "passed": passed,
        "case_kind": np.where(near, "near_singular", case.kind),
    })


def shared_codes(*columns: pd.Series) -> tuple[list[str], list[np.ndarray]]:
    """The distinct strings of ``columns`` together, and each column as codes into them
    (a sweep's tables are read with shared categories: their codes are used as they are)."""
    dtypes = {c.dtype for c in columns}
    if len(dtypes) == 1 and isinstance(columns[0].dtype, pd.CategoricalDtype):
        return ([str(c) for c in columns[0].cat.categories],
                [c.cat.codes.to_numpy(dtype=np.intp) for c in columns])
    codes, distinct = pd.factorize(np.concatenate([c.to_numpy(dtype=object) for c in columns]))
    bounds = np.cumsum([0, *(len(c) for c in columns)])
    return ([str(d) for d in distinct],
            [codes[a:b].astype(np.intp) for a, b in itertools.pairwise(bounds)])


def pose_index(poses: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Where each of ``theta`` is in the sorted ``poses`` (exactly), or -1."""
    if not len(poses):
        return np.full(len(theta), -1, dtype=np.intp)
    at = np.minimum(np.searchsorted(poses, theta), len(poses) - 1)
    return np.where(poses[at] == theta, at, -1)


def matching_rows(ref_keys: np.ndarray, pose: np.ndarray, quantity: np.ndarray,
                  n_names: int) -> np.ndarray:
    """For each row (``pose``, ``quantity``), the reference row with the same key, or -1
    (an inner join on pose and quantity, keeping the rows' own order)."""
    order = np.argsort(ref_keys, kind="stable")
    keys = pose * n_names + quantity
    at = pose_index(ref_keys[order], keys)
    return np.where((pose >= 0) & (at >= 0), order[np.maximum(at, 0)], -1)
