"""Quasi-static: at what crank speed does the static torque miss the dynamic one by 1 % and 10 %?"""

from __future__ import annotations

import numpy as np
import pandas as pd

from mechcheck.analytic.case import Motion
from mechcheck.analytic.presets import redrawn
from mechcheck.studies.common import (
    SIMULATORS,
    StudyResult,
    levels_reached,
    loglog_by_source,
    realistic_e1,
    reference,
    simulate,
    torque,
)

LEVELS = (0.01, 0.10)


def run(quick: bool = False) -> StudyResult:
    """Seed E1 with steel links at its seed pose, turning steadily at ω; the static analysis
    (weights, no inertia) against the dynamic torque measured by driving each simulator."""
    static_case = realistic_e1()
    t_static = torque(reference(static_case), static_case)
    omegas = np.geomspace(0.5, 200.0, 6 if quick else 14)
    rows = []
    for w in omegas:
        moving = redrawn(static_case, motion=Motion(float(w), 0.0))
        rows.append({"source": "analytic (D'Alembert)", "omega": w,
                     "T_dynamic": torque(reference(moving), moving)})
        for sim in SIMULATORS:
            s = simulate(sim, moving)
            rows.append({"source": sim, "omega": w, "T_dynamic": torque(s, moving),
                         "status": s.status})
    data = pd.DataFrame(rows)
    data["T_static"] = t_static
    data["relative_miss"] = (data["T_static"] - data["T_dynamic"]).abs() / data["T_dynamic"].abs()
    figure = loglog_by_source(data, "omega", "relative_miss", levels=LEVELS,
                              xlabel="crank speed ω [rad/s]",
                              ylabel="|T_static − T_dynamic| / |T_dynamic|",
                              title="Quasi-static assumption (seed E1, steel links)")
    conclusion = (
        "The static drive torque misses the dynamic one "
        + levels_reached(data, "omega", "relative_miss", unit="rad/s", at="ω", levels=LEVELS)
        + f"; the miss grows like ω² (static T12 = {t_static:.4g} N·m).")
    return StudyResult(
        "quasi_static", "Quasi-static loading",
        "At what crank speed does the static drive torque miss the measured dynamic torque "
        "by 1 % and by 10 %?", data, figure, conclusion,
        "Seed E1 at θ12 = 60° with its two loads, steel links (20 × 5 mm) under gravity, "
        "steady ω (α = 0). Static: analytic with ω = 0. Dynamic: MuJoCo and pymunk driven "
        "through the prescribed motion (and the analytic D'Alembert solution for reference).")
