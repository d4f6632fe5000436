"""Tidy long tables (CONVENTIONS.md): results, comparison and diagnostics.

Values are converted from SI/radians to table units (degrees) only here.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

import pandas as pd

from analytic.case import Case
from analytic.solution import QUANTITY_ORDER, QUANTITY_UNITS, Solution, quantity_kind
from compare.backends import REFERENCE
from compare.tolerance import case_kind, tolerance_for

RESULT_COLUMNS = ["case", "backend", "quantity", "value", "unit"]
COMPARISON_COLUMNS = ["case", "quantity", "backend", "value", "reference", "abs_err",
                      "rel_err", "tolerance", "passed"]
DIAGNOSTIC_COLUMNS = ["case", "backend", "status", "key", "value"]

#: Smallest scale an error is measured against (N, N·m): a case without loads
#: has zero reactions, and its simulator noise must not divide by zero.
SCALE_FLOOR = 1e-9


def in_table_units(quantity: str, value: float) -> float:
    return value * QUANTITY_UNITS[quantity][1]


def ordered(values: Iterable[str]) -> list[str]:
    return sorted(values, key=QUANTITY_ORDER.index)


def results_frame(solutions: Sequence[Solution]) -> pd.DataFrame:
    """One row per reported number; absent quantities have no row."""
    rows = [(s.case, s.backend, q, in_table_units(q, s.values[q]), QUANTITY_UNITS[q][0])
            for s in solutions for q in ordered(s.values)]
    return pd.DataFrame(rows, columns=RESULT_COLUMNS)


def kind_scales(case: Case, reference: Solution) -> dict[str, float]:
    """Scale of each quantity kind in a case: the largest reference magnitude of that kind."""
    scales = {"force": SCALE_FLOOR, "torque": SCALE_FLOOR, "angle": 1.0,
              "length": case.geometry.scale}
    for q, v in reference.values.items():
        kind = quantity_kind(q)
        if kind in ("force", "torque"):
            scales[kind] = max(scales[kind], abs(v))
    return scales


def error_scale(quantity: str, scales: dict[str, float]) -> float:
    """What a quantity's error is measured against (angles: 1 rad; s14: the longest link)."""
    kind = quantity_kind(quantity)
    if kind == "pose":
        return scales["length"] if quantity == "s14" else scales["angle"]
    return scales[kind]


def comparison_rows(case: Case, reference: Solution, other: Solution) -> list[dict[str, object]]:
    """One row per quantity both solutions report, with the policy's tolerance."""
    scales = kind_scales(case, reference)
    kind = case_kind(case, float(reference.diagnostics.get("condition_number", 0.0)))
    rows: list[dict[str, object]] = []
    for q in ordered(set(reference.values) & set(other.values)):
        ref, val = reference.values[q], other.values[q]
        abs_err = abs(val - ref)
        if quantity_kind(q) == "pose" and q != "s14":
            abs_err = abs(math.remainder(val - ref, math.tau))  # angles wrap
        rel_err = abs_err / error_scale(q, scales)
        tol = tolerance_for(case, other.backend, q, kind)
        rows.append({
            "case": case.name, "quantity": q, "backend": other.backend,
            "value": in_table_units(q, val), "reference": in_table_units(q, ref),
            "abs_err": in_table_units(q, abs_err), "rel_err": rel_err,
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
