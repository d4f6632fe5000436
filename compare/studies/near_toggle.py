"""Near toggle and change points: force growth, condition number, settling effort and the
distance below which each simulator's number stops being trustworthy."""

from __future__ import annotations

import math
from typing import cast

import numpy as np
import pandas as pd

from mechcheck.analytic.presets import redrawn
from mechcheck.studies.common import SIMULATORS, StudyResult, builtin, plt, png, reference, simulate
from mechcheck.tables import comparison_rows
from mechcheck.tolerance import NEAR_SINGULAR_CONDITION

#: Issue 13's target, condition number 1e4: seed E1 at condition number 1.03e4, added to
#: the full grid so the study shows it met (the grid's own points on either side are at
#: 5300 and 13 100), in degrees. It was MuJoCo's reach before steady plain passes were
#: extrapolated by their ratio (:meth:`.settle.Refinement.steady_ratio`).
MUJOCO_REACH_DELTA = 0.0115


def run(quick: bool = False) -> StudyResult:
    """Seed E1 approaching its change point θ12 = 180° by δ: analytic |F34| and condition
    number; each simulator's settled error (against the analytic solution) and steps."""
    base = builtin("seed-E1-as-stated")
    deltas = np.geomspace(30.0, 1e-4, 6 if quick else 15)  # degrees
    if not quick:
        deltas = np.sort(np.append(deltas, MUJOCO_REACH_DELTA))[::-1]
    rows = []
    for d in deltas:
        case = redrawn(base, theta12=math.pi - math.radians(float(d)))
        ref = reference(case)
        f34 = math.hypot(ref.values.get("F34_x", math.nan), ref.values.get("F34_y", math.nan))
        row = {"delta_deg": d, "F34_N": f34,
               "condition_number": float(ref.diagnostics["condition_number"]),
               "analytic_status": ref.status}
        for sim in SIMULATORS:
            s = simulate(sim, case)
            errors = [cast(float, r["rel_err"]) for r in comparison_rows(case, ref, s)
                      if r["quantity"] not in ("theta13", "theta14")] if s.status == "ok" else []
            row[f"{sim}_status"] = s.status
            row[f"{sim}_error"] = max(errors) if errors else math.nan
            row[f"{sim}_steps"] = float(s.diagnostics.get("steps", math.nan))
            row[f"{sim}_seconds"] = float(s.diagnostics.get("wall_time_s", math.nan))
        rows.append(row)
    data = pd.DataFrame(rows)
    ok = data["F34_N"].notna()
    slope = float(np.polyfit(np.log(data.loc[ok, "delta_deg"]), np.log(data.loc[ok, "F34_N"]), 1)[0]) \
        if ok.sum() > 2 else math.nan
    trust, reach = {}, {}
    for sim in SIMULATORS:
        bad = data[(data[f"{sim}_status"] != "ok") | (data[f"{sim}_error"] > 1e-6)]
        trust[sim] = float(bad["delta_deg"].max()) if len(bad) else None
        good = data[(data[f"{sim}_status"] == "ok") & (data[f"{sim}_error"] <= 1e-6)]
        reach[sim] = float(good["condition_number"].max()) if len(good) else math.nan
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    ax = axes[0]
    ax.loglog(data["delta_deg"], data["F34_N"], "k-o", ms=4, label="|F34| (analytic)")
    ax.loglog(data["delta_deg"], data["condition_number"], "k--", label="condition number")
    ax.axhline(NEAR_SINGULAR_CONDITION, color="orange", ls=":", lw=0.8)
    ax.invert_xaxis()
    ax.set_xlabel("distance from the change point δ [deg]")
    ax.set_title("Force growth")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, which="both")
    ax = axes[1]
    for sim in SIMULATORS:
        ax.loglog(data["delta_deg"], data[f"{sim}_error"].clip(lower=1e-17), "s-", ms=4,
                  label=f"{sim} error")
        ax.loglog(data["delta_deg"], data[f"{sim}_steps"] * 1e-12, ".:", label=f"{sim} steps × 1e-12")
    ax.axhline(1e-6, color="grey", ls=":", lw=0.8)
    ax.invert_xaxis()
    ax.set_xlabel("distance from the change point δ [deg]")
    ax.set_title("Simulator error against the analytic solution")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3, which="both")
    parts = [(f"{sim} misses 1e-6 (or does not settle) from δ = {v:.3g}° inward" if v is not None
              else f"{sim} stays within 1e-6 at every δ tried")
             + f" (within it up to condition number {reach[sim]:.3g})" for sim, v in trust.items()]
    conclusion = (f"|F34| grows like δ^{slope:.2f} (1/δ expected) towards the change point; "
                  + "; ".join(parts) + "; the analytic pose is withheld as singular only at "
                  "δ = 0.")
    return StudyResult(
        "near_toggle", "Near toggle and change points", "How do forces, the condition number and "
        "settling grow near a change point, and where does each simulator stop being "
        "trustworthy?", data, png(fig), conclusion,
        "Seed E1 (a Grashof change-point linkage, 80 + 140 = 100 + 120) at θ12 = 180° − δ, "
        "statics. Errors are the largest relative error over forces and torques under the "
        "comparison's measure.")
