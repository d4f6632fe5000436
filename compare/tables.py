"""Tidy long tables (CONVENTIONS.md): results, comparison and diagnostics.

Values are converted from SI/radians to table units (degrees) only here.
"""

from __future__ import annotations

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
)
from mechcheck.backends import REFERENCE
from mechcheck.tolerance import NEAR_SINGULAR_CONDITION, case_kind, tolerance_for

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
              "length": case.geometry.scale}
    for q, v in reference.values.items():
        kind = kind_of_unit(reference.unit(q))
        if kind in ("force", "torque"):
            scales[kind] = max(scales[kind], abs(v))
    forces, torques, length = scales["force"], scales["torque"], case.geometry.scale
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
    rows: list[dict[str, object]] = []
    for q in ordered(set(reference.values) & set(other.values)):
        ref, val, unit = reference.values[q], other.values[q], reference.unit(q)
        abs_err = abs(val - ref)
        if unit == "deg":
            abs_err = abs(math.remainder(val - ref, math.tau))  # angles wrap
        rel_err = abs_err / error_scale(unit, scales)
        tol = tolerance_for(case, other.backend, q, kind, kind_of_unit(unit))
        rows.append({
            "case": case.name, "quantity": q, "backend": other.backend,
            "value": table_value(q, val, unit), "reference": table_value(q, ref, unit),
            "abs_err": abs_err * unit_factor(unit), "rel_err": rel_err,
            "tolerance": tol.rtol,
            "passed": bool(rel_err <= tol.rtol or abs_err <= tol.atol),
            # Not written to comparison.csv (the contract fixes its columns); the report uses them.
            "atol": tol.atol, "case_kind": kind, "reason": tol.reason,
            "overridden": tol.overridden,
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
    columns = [*COMPARISON_COLUMNS, "atol", "case_kind", "reason", "overridden"]
    return pd.DataFrame(rows, columns=columns)


def diagnostics_frame(solutions: Sequence[Solution]) -> pd.DataFrame:
    """Each backend's verdict, message and diagnostics, long format."""
    rows: list[tuple[str, str, str, str, str]] = []
    for s in solutions:
        rows.append((s.case, s.backend, s.status, "message", s.message))
        rows += [(s.case, s.backend, s.status, k, str(v)) for k, v in s.diagnostics.items()]
    return pd.DataFrame(rows, columns=DIAGNOSTIC_COLUMNS)


def kinds_of(units: pd.Series) -> dict[str, str]:
    """The kind of each distinct unit in ``units``."""
    return {u: kind_of_unit(u) for u in units.unique()}


def sweep_comparison(case: Case, reference: pd.DataFrame, reference_status: pd.DataFrame,
                     other: pd.DataFrame) -> pd.DataFrame:
    """Per-pose comparisons of backends' sweeps (``other``: one or more backends, each
    backend's rows together) against the reference, vectorised.

    Same measure and policy as :func:`comparison_rows`, with the case kind taken
    per pose (``near_singular`` where the reference's condition number says so).
    Columns: the comparison columns of CONVENTIONS.md plus ``theta12``.
    """
    keys = ["theta12", "quantity"]
    ref = reference[[*keys, "value", "unit"]].rename(columns={"value": "reference"})
    # Names and units stay categories (a sweep's tables share them: read together) until
    # the result: mapped and factorised by their few distinct values, never walked as
    # strings row by row (Arrow strings took half of a resumed sweep's comparing).
    if not isinstance(ref["quantity"].dtype, pd.CategoricalDtype) or \
            not ref["quantity"].dtype == other["quantity"].dtype:
        ref = ref.assign(quantity=ref["quantity"].astype(str))
        other = other.assign(quantity=other["quantity"].astype(str))
    merged = other.drop(columns="unit").merge(ref, on=keys)
    if merged.empty:
        return pd.DataFrame(columns=["case", "theta12", *COMPARISON_COLUMNS[1:]])
    quantity = merged["quantity"]
    unit = merged["unit"]
    # Mapped through a table of the few distinct units, not the function row by row.
    factor = unit.map({u: unit_factor(u) for u in unit.unique()}).to_numpy()
    kind = unit.map(kinds_of(unit))
    # Scale of each force/torque kind at each pose: the largest reference magnitude.
    ref_kind = ref.assign(kind=ref["unit"].map(kinds_of(ref["unit"])), mag=ref["reference"].abs())
    scale_table = ref_kind.groupby(["theta12", "kind"], observed=True)["mag"].max()
    kinds = set(scale_table.index.get_level_values("kind"))
    scale = scale_table.reindex(pd.MultiIndex.from_arrays([merged["theta12"], kind])).to_numpy()
    scale = np.maximum(np.nan_to_num(scale, nan=SCALE_FLOOR), SCALE_FLOOR)
    # Forces at least the largest torque over the longest link, torques at least the
    # largest reaction times it (see kind_scales).
    length = case.geometry.scale
    force_at, torque_at = (np.nan_to_num(merged["theta12"].map(scale_table.xs(k, level="kind"))
                                         .to_numpy(dtype=float) if k in kinds else
                                         np.full(len(merged), np.nan), nan=SCALE_FLOOR)
                           for k in ("force", "torque"))
    scale = np.where(kind == "torque", np.maximum(scale, force_at * length), scale)
    scale = np.where(kind == "force", np.maximum(scale, torque_at / length), scale)
    is_angle = (unit == "deg").to_numpy()
    scale = np.where(kind == "pose", np.where(is_angle, factor, case.geometry.scale), scale)
    diff = merged["value"].to_numpy() - merged["reference"].to_numpy()
    diff = np.where(is_angle, (diff + 180.0) % 360.0 - 180.0, diff)
    abs_err = np.abs(diff)
    rel_err = abs_err / scale
    cond = merged["theta12"].map(reference_status.set_index("theta12")["condition_number"])
    pose_kind = np.where(cond.to_numpy() > NEAR_SINGULAR_CONDITION, "near_singular", case.kind)
    # One rule per distinct (backend, quantity, pose kind, unit), spread back by its codes:
    # the columns are Arrow strings, which are slow to walk element by element.
    codes, keys_found = pd.MultiIndex.from_arrays(
        [merged["backend"], quantity, pose_kind, unit]).factorize()
    rules = [tolerance_for(case, str(b), q, k, kind_of_unit(u)) for b, q, k, u in keys_found]
    rtol = np.array([r.rtol for r in rules])[codes]
    atol = np.array([r.atol for r in rules])[codes]
    passed = (rel_err <= rtol) | (abs_err / factor <= atol)
    return pd.DataFrame({
        "case": case.name, "theta12": merged["theta12"], "quantity": quantity.astype(str),
        "backend": merged["backend"].astype(str), "value": merged["value"],
        "reference": merged["reference"], "abs_err": abs_err, "rel_err": rel_err,
        "tolerance": rtol, "passed": passed, "case_kind": pose_kind,
    })
