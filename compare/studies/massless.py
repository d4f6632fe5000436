"""Massless links: the error in T12 from ignoring realistic link weights, against load size."""

from __future__ import annotations

import dataclasses

import numpy as np
import pandas as pd

from mechcheck.analytic.case import preset_of
from mechcheck.analytic.presets import redrawn
from mechcheck.studies.common import (
    SIMULATORS,
    StudyResult,
    by_source,
    crossing,
    groups,
    loglog_by_source,
    realistic_e1,
    reference,
    simulate,
    torque,
)

LEVELS = (0.01, 0.10)


def run(quick: bool = False) -> StudyResult:
    """Seed E1 (static, θ12 = 60°) with its loads scaled by k: the massless analysis against the
    torque measured with steel links under gravity in each simulator."""
    base = realistic_e1()
    scales = np.geomspace(1e-3, 10.0, 5 if quick else 13)
    rows = []
    for k in scales:
        loads = tuple(dataclasses.replace(ld, force=(k * ld.force[0], k * ld.force[1]))
                      for ld in preset_of(base).loads)
        heavy = redrawn(base, loads=loads)
        massless = redrawn(heavy, masses=(), gravity=(0.0, 0.0))
        t0 = torque(reference(massless), massless)
        load = float(np.hypot(*loads[1].force))
        rows.append({"source": "analytic (with weights)", "load_N": load, "T_massless": t0,
                     "T_weighted": torque(reference(heavy), heavy)})
        for sim in SIMULATORS:
            s = simulate(sim, heavy)
            rows.append({"source": sim, "load_N": load, "T_massless": t0,
                         "T_weighted": torque(s, heavy), "status": s.status})
    data = pd.DataFrame(rows)
    data["relative_error"] = (data["T_massless"] - data["T_weighted"]).abs() / data["T_weighted"].abs()
    # The error falls as the load grows: find where it drops through each level.
    found = {}
    for src, g in groups(data):
        g = g.sort_values("load_N", ascending=False)
        found[src] = [crossing(1.0 / g["load_N"].to_numpy(), g["relative_error"].to_numpy(), lv)
                      for lv in LEVELS]
    figure = loglog_by_source(
        data, "load_N", "relative_error", levels=LEVELS,
        xlabel="rocker load |F14| [N] (the coupler load scales with it)",
        ylabel="|T_massless − T_weighted| / |T_weighted|",
        title="Massless-link assumption (seed E1, steel links)")
    weight = sum(m.mass for m in preset_of(base).masses) * 9.81
    def load_at(level: int) -> dict[str, float | None]:
        """The load (N) at which the error falls through a level: 1 / the crossing of 1/load."""
        out: dict[str, float | None] = {}
        for k, v in found.items():
            inverse = v[level]
            out[k] = None if inverse is None else 1.0 / inverse
        return out

    beyond = f"beyond the {scales[-1]:g}× loads tried"
    conclusion = (f"Ignoring the links' weight ({weight:.3g} N in all) errs in T12 by more than "
                  "1 % when the rocker load is below " + by_source(load_at(0), "N", beyond=beyond)
                  + ", and by more than 10 % below " + by_source(load_at(1), "N", beyond=beyond)
                  + "; the error falls like 1/load.")
    return StudyResult(
        "massless", "Massless links", "How large is the error in T12 from ignoring realistic link "
        "weights, against the load magnitude?", data, figure, conclusion,
        "Seed E1 at θ12 = 60°, both loads scaled together; steel links of 20 × 5 mm section. "
        "Massless: analytic without masses. Weighted: MuJoCo and pymunk settled with the masses "
        "under gravity (and the analytic solution with weights).")
