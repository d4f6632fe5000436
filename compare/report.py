"""The accuracy report: Markdown and one self-contained HTML file.

Built from Jinja2 templates (``compare/templates``) over a small view model;
every number shown is taken from the same tables that are written to CSV.
"""

from __future__ import annotations

import base64
import html
import math
import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import jinja2
import pandas as pd

from mechcheck.analytic.case import Case, preset_of
from mechcheck.analytic.solution import Solution
from mechcheck.backends import REFERENCE
from mechcheck.casefile import AnySpec
from mechcheck.figures import figure_file
from mechcheck.linkage_file import DriverSpec, LinkageCaseSpec
from mechcheck.output import file_stem
from mechcheck.run import RunResult
from mechcheck.seeds import SeedRow, seed_row
from mechcheck.tables import ordered, table_value
from mechcheck.tolerance import policy_table

_ENV = jinja2.Environment(
    loader=jinja2.PackageLoader("mechcheck", "templates"),
    autoescape=jinja2.select_autoescape(["html.j2"]),
    trim_blocks=True, lstrip_blocks=True, keep_trailing_newline=True,
)


def fmt(value: float | None, digits: int = 6) -> str:
    """Numbers for humans: significant digits, '—' for absent."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "—"
    if value == 0:
        return "0"
    if abs(value) >= 1e5 or abs(value) < 1e-3:
        return f"{value:.{digits - 1}e}"
    return f"{value:.{digits}g}"


def sci(value: float | None) -> str:
    """An error or a tolerance: two significant digits, '—' for absent."""
    return "—" if value is None else f"{value:.1e}"


_ENV.filters["fmt"] = fmt
_ENV.filters["sci"] = sci


@dataclass(frozen=True)
class BackendSummary:
    backend: str
    compared: int
    failed: int
    worst: dict[str, float]   # quantity kind → worst rel_err
    verdicts: dict[str, int]


#: Bands of a comparison's error as a fraction of what its tolerance allows (its
#: ``of_tolerance``, 1 at the tolerance): upper bound and name. They colour the matrix of
#: cases × backends; a comparison outside its tolerance is ``fail`` whatever its number.
BANDS: tuple[tuple[float, str], ...] = ((1e-3, "far"), (0.1, "clear"), (1.0, "near"))

#: Markdown's marker of each band: a circle that fills as the error nears its tolerance.
MARKERS = {"far": "○", "clear": "◔", "near": "◑", "fail": "●"}

#: The legend of the matrix's colours, in the order shown.
LEGEND = (("far", "≤ 0.001 of its tolerance"), ("clear", "≤ 0.1"), ("near", "≤ 1"),
          ("fail", "outside tolerance"), ("verdict", "a verdict, no numbers"),
          ("failing", "a verdict that fails the run"))


@dataclass(frozen=True)
class BackendLine:
    """One backend's line at the top of the report."""

    backend: str
    compared: int
    failed: int
    verdicts: dict[str, int]
    worst: dict[str, Any] | None   # the comparison row nearest to (or furthest past) its tolerance


def severity(row: Mapping[str, Any]) -> tuple[bool, float, float]:
    """Orders comparison rows from best to worst: failed last, then by the fraction of the
    tolerance used, then by the relative error."""
    return (not bool(row["passed"]), float(row["of_tolerance"]), float(row["rel_err"]))


def worst_row(rows: Iterable[dict[str, Any]]) -> dict[str, Any] | None:
    return max(rows, key=severity, default=None)


def band(row: Mapping[str, Any]) -> str:
    """The colour band of a comparison row: ``fail`` exactly when it failed."""
    if not bool(row["passed"]):
        return "fail"
    ratio = float(row["of_tolerance"])
    return next((name for bound, name in BANDS if ratio <= bound), "near")


_ENV.filters["band"] = band


def backend_lines(backends: list[str], by_backend: Mapping[str, list[dict[str, Any]]],
                  solutions: list[Solution]) -> list[BackendLine]:
    """Per backend: comparisons, failures, verdicts and its single worst comparison."""
    out = []
    for backend in backends:
        rows = by_backend.get(backend, [])
        verdicts: dict[str, int] = {}
        for s in solutions:
            if s.backend == backend and s.status != "ok":
                verdicts[s.status] = verdicts.get(s.status, 0) + 1
        out.append(BackendLine(backend, len(rows), sum(not r["passed"] for r in rows),
                               verdicts, worst_row(rows)))
    return out


def matrix_cell(solution: Solution | None, rows: list[dict[str, Any]],
                fail_on: tuple[str, ...]) -> dict[str, str]:
    """One case on one backend: a failing verdict; else its worst relative error, banded by
    the fraction of its tolerance; else the verdict that left it without numbers."""
    if solution is not None and solution.status in fail_on:
        return {"band": "failing", "text": solution.status, "title": solution.message}
    worst = worst_row(rows)
    if worst is not None:
        note = "" if solution is None or solution.status == "ok" else \
            f"; {solution.status}: {solution.message}"
        return {"band": band(worst), "text": sci(worst["rel_err"]),
                "title": row_summary(worst) + note}
    if solution is not None and solution.status != "ok":
        return {"band": "verdict", "text": solution.status, "title": solution.message}
    return {"band": "none", "text": "—",
            "title": "not run" if solution is None else "no quantity in common with analytic"}


def row_summary(row: Mapping[str, Any]) -> str:
    """A comparison in words, for a cell's tooltip."""
    return (f"{row['quantity']}: relative error {sci(row['rel_err'])}, tolerance "
            f"{sci(row['tolerance'])}, {sci(row['of_tolerance'])} of it")


def quantity_worst(detail: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """One case's worst comparison of each quantity over the backends, worst first."""
    by_quantity: dict[str, list[dict[str, Any]]] = {}
    for row in detail:
        by_quantity.setdefault(str(row["quantity"]), []).append(row)
    worst = [w for rows in by_quantity.values() if (w := worst_row(rows)) is not None]
    return [{**w, "band": band(w)} for w in sorted(worst, key=severity, reverse=True)]


def case_drawing(case: Case, solution: Solution | None) -> bytes | None:
    """A PNG of the mechanism at the reference's pose with its reactions, for the case's
    section; as its file draws it where the reference gives no pose; None for a preset that
    assembles nowhere (it has no linkage to draw)."""
    from mechcheck.drawing import drawing_png

    if case.geometry is None:
        return None
    if solution is not None:
        try:
            return drawing_png(case, solution)
        except ValueError:   # no pose at this θ: the mechanism as its file draws it
            pass
    return drawing_png(case)


def drawings(result: RunResult) -> dict[str, bytes]:
    """Each case's drawing (PNG) at the reference's solution, by case name."""
    reference = {s.case: s for s in result.solutions if s.backend == REFERENCE}
    out = {}
    for case in result.cases:
        png = case_drawing(case, reference.get(case.name))
        if png is not None:
            out[case.name] = png
    return out


def drawing_file(case_name: str) -> str:
    """A case's drawing's file name, in the report's ``drawings/`` folder."""
    return f"{file_stem(case_name)}.png"


def shown_path(path: str) -> str:
    """A case file's path as the report shows it: inside the package as ``mechcheck/…``,
    else relative to the current directory, so a report does not depend on where the
    clone or the installation sits."""
    absolute = Path(path).absolute()
    package = Path(__file__).parent
    if absolute.is_relative_to(package):
        return "mechcheck/" + absolute.relative_to(package).as_posix()
    try:
        return os.path.relpath(absolute)
    except ValueError:   # another drive (Windows): nothing relative to name
        return path


#: Above this many cases, the sections of passing cases are folded (<details>) so that a
#: large run's page stays readable; the matrix at the top links to every case.
FOLD_ABOVE = 50


def case_inputs(case: Case, spec: AnySpec | None) -> list[str]:
    """The case's inputs as written in its file (file units), so a section reads alone."""
    if isinstance(spec, LinkageCaseSpec):
        return linkage_inputs(spec)
    if spec is None:
        return [f"{case.mechanism} (built in code; no file to echo)"]
    unit = spec.length_unit
    lines = [f"{spec.mechanism}, θ12 = {fmt(spec.theta12)}°, {preset_of(case).branch} branch, ground "
             f"angle {fmt(spec.ground_angle)}°, drive on link {spec.drive_link}, lengths in {unit}",
             "geometry: " + ", ".join(f"{k} = {fmt(v)}" for k, v in spec.geometry.items())]
    for load in spec.loads:
        force = ", ".join(f"{k} = {fmt(v)}" for k, v in (load.force or {}).items())
        lines.append(f"load on link {load.link} at {_pair(load.at)}: force {{{force}}}, "
                     f"torque {fmt(load.torque)} N·m")
    for m in spec.masses:
        lines.append(f"mass on link {m.link}: {fmt(m.mass)} kg at {_pair(m.com)}, inertia "
                     f"{fmt(m.inertia)} kg·m²")
    if any(spec.gravity):
        lines.append(f"gravity {_pair(spec.gravity)} m/s²")
    if spec.motion.omega or spec.motion.alpha:
        lines.append(f"motion: ω = {fmt(spec.motion.omega)} rad/s, α = {fmt(spec.motion.alpha)} rad/s²")
    if spec.friction is not None:
        f = spec.friction
        parts = [f"μ = {fmt(f.mu)}"]
        parts += [f"pin radius {j} = {fmt(r)}" for j, r in f.pin_radius.items()]
        parts += [f"slide μ = {fmt(f.slide_mu)}"] if f.slide_mu is not None else []
        parts += [f"viscous {j} = {fmt(c)}" for j, c in f.viscous.items()]
        parts += [f"direction {f.direction}"] if f.direction else []
        lines.append("friction: " + ", ".join(parts))
    return lines


def linkage_inputs(spec: LinkageCaseSpec) -> list[str]:
    """A linkage table's inputs, one line per kind of entry, in the file's units."""
    lines = [f"linkage of {len(spec.links)} links and {len(spec.joints)} joints, lengths in "
             f"{spec.length_unit}",
             "points: " + ", ".join(f"{n} {_pair(p)}" for n, p in spec.points.items()),
             "links: " + "; ".join(f"{link.name} ({', '.join(link.points)})" for link in spec.links),
             "joints: " + "; ".join(f"{j.name} {j.kind} {j.links[0]}–{j.links[1]} at {j.at}"
                                    + (f" along {_pair(j.axis)}" if j.axis else "")
                                    for j in spec.joints)]
    lines += [_driver_line(d) for d in spec.drivers]
    lines += _load_lines(spec)
    if any(spec.gravity):
        lines.append(f"gravity {_pair(spec.gravity)} m/s²")
    if spec.friction is not None:
        lines.append(f"friction: {spec.friction.model_dump()}")
    if spec.simulate is not None:
        outputs = spec.simulate.outputs
        count = outputs if isinstance(outputs, int) else len(outputs)
        lines.append(f"simulate: end {fmt(spec.simulate.end)} s, {count} output times"
                     + "".join(f", rate {j} = {fmt(v)}" for j, v in spec.simulate.rates.items()))
    return lines


def _driver_line(d: DriverSpec) -> str:
    """A driver's line: its value, velocity, and its acceleration or effort."""
    move = (f"rotation {fmt(d.rotation)}°" if d.rotation is not None
            else f"displacement {fmt(d.displacement or 0.0)}")
    effort = next(((k, v) for k, v in (("torque", d.torque), ("force", d.force))
                   if v is not None), None)
    return (f"driver {d.joint}: {move}, velocity {fmt(d.velocity)}, "
            + (f"{effort[0]} {effort[1]}" if effort else f"acceleration {fmt(d.acceleration)}")
            + (f", sense {d.sense}" if d.sense else ""))


def _load_lines(spec: LinkageCaseSpec) -> list[str]:
    """The lines of the loads, masses and springs."""
    lines = []
    for ld in spec.loads:
        force = ", ".join(f"{k} = {fmt(v)}" for k, v in (ld.force or {}).items())
        lines.append(f"load on {ld.link} at {ld.at if isinstance(ld.at, str) else _pair(ld.at)}: "
                     f"force {{{force}}}, torque {fmt(ld.torque)} N·m")
    for m in spec.masses:
        lines.append(f"mass on {m.link}: {fmt(m.mass)} kg at "
                     f"{m.com if isinstance(m.com, str) else _pair(m.com)}, inertia "
                     f"{fmt(m.inertia)} kg·m²")
    lines += ["spring " + ", ".join(f"{k} = {v}" for k, v in s.items()) for s in spec.springs]
    return lines


def _pair(p: list[float]) -> str:
    return f"[{fmt(p[0])}, {fmt(p[1])}]"


def case_view(case: Case, spec: AnySpec | None, solutions: list[Solution],
              detail: list[dict[str, Any]], folded: bool, drawing: bytes | None) -> dict[str, Any]:
    """Values of every backend side by side, with errors, for one case.

    ``detail`` holds this case's comparison rows only, as records: the caller splits
    the table once, so that the report is built in time linear in the number of cases.
    """
    backends = [s.backend for s in solutions]
    rows = quantity_rows(solutions, detail)
    failed = sum(not r["passed"] for r in detail)
    verdicts = [s for s in solutions if s.status != "ok"]
    return {
        "name": case.name, "anchor": f"case-{case.name}",
        "description": spec.description if spec else "",
        "mechanism": case.mechanism, "kind": str(detail[0]["case_kind"]) if detail
        else case.kind, "source": shown_path(case.source) if case.source else "",
        "backends": backends, "rows": rows,
        "inputs": case_inputs(case, spec),
        "compared": len(detail), "failed": failed,
        "quantity_worst": quantity_worst(detail),
        "folded": folded and not failed and not verdicts,
        "verdicts": verdicts,
        "diagnostics": [(s.backend, s.status, dict(s.diagnostics)) for s in solutions],
        "overrides": list(case.tolerance),
        "drawing": base64.b64encode(drawing).decode() if drawing else None,
        "drawing_file": drawing_file(case.name),
    }


def quantity_rows(solutions: list[Solution], detail: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """One row per quantity: each backend's value in table units, with its comparison."""
    hits = {(r["quantity"], r["backend"]): r for r in detail}
    rows = []
    for q in ordered({q for s in solutions for q in s.values}):
        cells = [_cell(q, s, hits.get((q, s.backend))) for s in solutions]
        unit = next(s.unit(q) for s in solutions if q in s.values)
        rows.append({"quantity": q, "unit": unit, "cells": cells})
    return rows


def _cell(q: str, s: Solution, hit: dict[str, Any] | None) -> dict[str, Any]:
    return {
        "value": table_value(q, s.values[q], s.unit(q)) if q in s.values else None,
        "rel_err": float(hit["rel_err"]) if hit else None,
        "passed": bool(hit["passed"]) if hit else None,
        "tolerance": float(hit["tolerance"]) if hit else None,
        "overridden": bool(hit["overridden"]) if hit else False,
        "band": band(hit) if hit else None,
    }


def seed_rows(result: RunResult, specs: Mapping[str, AnySpec]) -> list[SeedRow]:
    """Printed seed answers beside the reference backend's values."""
    out = []
    for case in result.cases:
        spec = specs.get(case.name)
        if spec is None or spec.seed is None:
            continue
        ref = next(s for s in result.solutions if s.case == case.name and s.backend == REFERENCE)
        for key, printed in spec.seed.printed.items():
            out.append(seed_row(case, ref, key, printed, spec.seed.source, spec.seed.note))
    return out


def view_model(result: RunResult, specs: Mapping[str, AnySpec], title: str,
               pictures: Mapping[str, bytes]) -> dict[str, Any]:
    """Everything the report's templates show: the verdict, the backends' lines, the matrix
    of cases × backends, then each case's section."""
    by_case: dict[str, list[Solution]] = {}
    for s in result.solutions:
        by_case.setdefault(s.case, []).append(s)
    per_case: dict[str, list[dict[str, Any]]] = {}
    per_backend: dict[str, list[dict[str, Any]]] = {}
    for record in result.detail.to_dict("records"):
        row = {str(k): v for k, v in record.items()}
        per_case.setdefault(str(row["case"]), []).append(row)
        per_backend.setdefault(str(row["backend"]), []).append(row)
    backends = [b for b in dict.fromkeys(s.backend for s in result.solutions) if b != REFERENCE]
    lines = backend_lines(backends, per_backend, result.solutions)
    seeds = seed_rows(result, specs)
    return {
        "title": title,
        "passed": result.exit_status == 0,
        "n_cases": len(result.cases),
        "n_comparisons": len(result.detail),
        "nothing_compared": result.nothing_compared,
        "n_failed": len(result.failed_comparisons),
        "wall_time_s": result.wall_time_s,
        "fail_on": ", ".join(result.fail_on),
        "lines": lines,
        "closest": max(((line.backend, line.worst) for line in lines if line.worst),
                       key=lambda pair: severity(pair[1]), default=None),
        "backends": backends,
        "matrix": [matrix_row(c.name, by_case.get(c.name, []), per_case.get(c.name, []),
                              backends, result.fail_on) for c in result.cases],
        "legend": LEGEND, "markers": MARKERS,
        "failures": result.failed_comparisons.to_dict("records"),
        "failing_verdicts": result.failing_verdicts,
        "seeds": seeds,
        "seed_notes": {r.case: r.note for r in seeds},
        "cases": [case_view(c, specs.get(c.name), by_case.get(c.name, []),
                            per_case.get(c.name, []), folded=len(result.cases) > FOLD_ABOVE,
                            drawing=pictures.get(c.name))
                  for c in result.cases],
        "policy": policy_table(),
    }


def matrix_row(case: str, solutions: list[Solution], detail: list[dict[str, Any]],
               backends: list[str], fail_on: tuple[str, ...]) -> dict[str, Any]:
    """One case's row of the matrix: a cell per backend."""
    solution = {s.backend: s for s in solutions}
    rows: dict[str, list[dict[str, Any]]] = {}
    for row in detail:
        rows.setdefault(str(row["backend"]), []).append(row)
    return {"case": case, "anchor": f"case-{case}",
            "cells": [matrix_cell(solution.get(b), rows.get(b, []), fail_on) for b in backends]}


def render(result: RunResult, specs: Mapping[str, AnySpec],
           title: str = "mechcheck accuracy report",
           pictures: Mapping[str, bytes] | None = None) -> tuple[str, str]:
    """(Markdown, HTML) of a run. ``pictures``: each case's drawing by case name (default:
    :func:`drawings`); the Markdown links to them in ``drawings/``, the HTML holds them."""
    model = view_model(result, specs, title, drawings(result) if pictures is None else pictures)
    return render_pair("report", model)


def render_pair(template: str, model: Mapping[str, Any]) -> tuple[str, str]:
    """(Markdown, HTML) of a view model through ``<template>.md.j2`` and ``.html.j2``."""
    return (_ENV.get_template(f"{template}.md.j2").render(**model),
            _ENV.get_template(f"{template}.html.j2").render(**model, escape=html.escape))


def _pose_list(values: pd.Series, limit: int = 20, unit: str = "deg") -> str:
    """The poses as the sweep's axis gives them: degrees with °, a length with its unit."""
    mark = "°" if unit == "deg" else f" {unit}"
    items = [fmt(float(v), 5) + mark for v in values.to_numpy()[:limit]]
    more = len(values) - limit
    return ", ".join(items) + (f" … ({more} more)" if more > 0 else "")


#: The note :func:`mechcheck.run.gated_message` appends to the reference's reason.
GATED_NOTE = r"; not run \(the pose verdict of [^)]*\)$"


def verdict_groups(statuses: pd.DataFrame, unit: str = "deg") -> list[dict[str, str]]:
    """One case's poses without numbers, grouped by verdict and by the backends that gave it:
    which poses (in the sweep axis' ``unit``), and why (the first pose's reason; the status
    table has each pose's)."""
    rest = statuses[statuses["status"] != "ok"]
    backends = sorted({str(b) for b in statuses["backend"].unique()})
    # Each (pose, verdict) with the set of backends that gave it there.
    who_gave: dict[tuple[str, tuple[str, ...]], list[float]] = {}
    for (theta, status), group in rest.groupby(["theta12", "status"], observed=True, sort=True):
        who = tuple(sorted(str(b) for b in group["backend"]))
        who_gave.setdefault((str(status), who), []).append(float(theta))  # type: ignore[arg-type]
    out = []
    for (status, who), poses in sorted(who_gave.items()):
        mine = rest[(rest["status"] == status) & rest["backend"].isin(who)
                    & rest["theta12"].isin(poses)]
        first = mine[(mine["theta12"] == poses[0]) & (mine["backend"] == who[0])]
        reason = str(first["message"].iloc[0]) if len(first) else ""
        # The gated backends repeat the reference's reason with a note: one reason.
        reasons = mine["message"].astype(str).str.replace(GATED_NOTE, "", regex=True)
        if reasons.nunique() > 1:
            reason += " (first pose; other poses' reasons in the status table)"
        out.append({"status": status, "backends": "every backend" if list(who) == backends
                    else ", ".join(who), "poses": _pose_list(pd.Series(poses), unit=unit),
                    "reason": reason})
    return out


def restart_groups(statuses: pd.DataFrame, unit: str = "deg") -> list[dict[str, str]]:
    """One case's poses that a simulator ran again from the analytic pose after its sweep's
    continuation left the analytic branch, per backend: which poses, and the first reason."""
    if "restart" not in statuses.columns:   # parts of a sweep without the column
        return []
    out = []
    restarted = statuses[statuses["restart"].astype(str) != ""]
    for backend, rows in restarted.groupby("backend", observed=True, sort=True):
        out.append({"backend": str(backend), "count": str(len(rows)),
                    "poses": _pose_list(rows["theta12"], unit=unit),
                    "reason": str(rows["restart"].iloc[0])})
    return out


def cost_per_pose(statuses: pd.DataFrame) -> dict[str, float]:
    """Each backend's median wall time per pose it ran (s): the poses it gave a number or
    a verdict of its own, not those the pose gate or its method withheld."""
    if "wall_time_s" not in statuses.columns:
        return {}
    ran = statuses[statuses["wall_time_s"] > 0.0]
    return {str(b): float(t) for b, t in
            ran.groupby("backend", observed=True)["wall_time_s"].median().items()}


def failed_pose_counts(failed: pd.DataFrame) -> dict[str, int]:
    """Per backend, the poses with at least one comparison outside tolerance (a pose counts
    once, however many of its quantities failed)."""
    if not len(failed):
        return {}
    poses = failed[["case", "backend", "theta12"]].drop_duplicates()
    return {str(b): int(n) for b, n in poses["backend"].value_counts().items()}


def sweep_view_model(cases: list[Case], specs: Mapping[str, AnySpec], statuses: pd.DataFrame,
                     comparison: pd.DataFrame, figures: dict[str, bytes], *, title: str,
                     n_poses: int, wall_time_s: float, executed: int, reused: int,
                     fail_on: tuple[str, ...],
                     axes: Mapping[str, tuple[str, str]] | None = None) -> dict[str, Any]:
    """The sweep report's view model (verdict first, then one section per case); ``axes``:
    each case's sweep axis as (label, unit) (:func:`mechcheck.sweep.driver_axis`; default
    θ12 in degrees)."""
    failed = comparison[~comparison["passed"].astype(bool)] if len(comparison) else comparison
    failing = statuses[statuses["status"].isin(fail_on)] if len(statuses) else statuses
    poses_failed = failed_pose_counts(failed)
    summaries = []
    for backend in (str(b) for b in pd.unique(statuses["backend"])):
        if backend == REFERENCE:
            continue
        rows = comparison[comparison["backend"] == backend] if len(comparison) else comparison
        worst = {str(q): float(e) for q, e in rows.groupby("quantity")["rel_err"].max().items()} \
            if len(rows) else {}
        counts = statuses[(statuses["backend"] == backend) & (statuses["status"] != "ok")]
        summaries.append(BackendSummary(
            backend, len(rows), poses_failed.get(backend, 0),
            {q: float(worst[q]) for q in ordered(worst)},
            {str(k): int(v) for k, v in counts["status"].value_counts().items() if v}))
    case_views = []
    for case in cases:
        label, unit = (axes or {}).get(case.name, ("θ12, deg", "deg"))
        st = statuses[statuses["case"] == case.name]
        ref = st[st["backend"] == REFERENCE]
        spec = specs.get(case.name)
        mine = failed[failed["case"] == case.name] if len(failed) else failed
        case_views.append({
            "name": case.name, "description": spec.description if spec else "",
            "mechanism": case.mechanism, "kind": case.kind,
            # No figure when the sweep was run without them (--no-figures).
            "figure": figure_file(case.name) if case.name in figures else None,
            "figure_b64": base64.b64encode(figures[case.name]).decode()
            if case.name in figures else None,
            "axis": label,
            "verdicts": verdict_groups(st, unit),
            "restarts": restart_groups(st, unit),
            "near_singular": _pose_list(ref.loc[(ref["condition_number"] > 1e4)
                                                & (ref["status"] == "ok"), "theta12"], unit=unit),
            "failures": mine.head(30).to_dict("records"),
        })
    return {
        "title": title, "passed": not len(failed) and not len(failing),
        "n_cases": len(cases), "n_poses": n_poses, "n_comparisons": len(comparison),
        "n_failed": sum(poses_failed.values()), "n_failing_verdicts": len(failing),
        "costs": cost_per_pose(statuses),
        "fail_on": ", ".join(fail_on), "wall_time_s": wall_time_s,
        "executed": executed, "reused": reused, "summaries": summaries, "cases": case_views,
        "policy": policy_table(),
    }


def render_sweep(model: dict[str, Any]) -> tuple[str, str]:
    """(Markdown, HTML) of a sweep."""
    return (_ENV.get_template("sweep.md.j2").render(**model),
            _ENV.get_template("sweep.html.j2").render(**model))
