"""Superposition with friction: the error of summing single-load friction solutions, against μ."""

from __future__ import annotations

import numpy as np
import pandas as pd

from mechcheck.analytic.case import Case, Friction, preset_of
from mechcheck.analytic.presets import redrawn
from mechcheck.studies.common import (
    SIMULATORS,
    StudyResult,
    builtin,
    crossing,
    groups,
    loglog_by_source,
    reached,
    reference,
    simulate,
    torque,
)

LEVELS = (0.01, 0.10)


def with_friction(case: Case, mu: float) -> Case:
    """Seed E1 with friction circles at all four pins (radius 10 mm), crank turning CCW."""
    return redrawn(case, friction=Friction(mu=mu, pin_radius={"A0": 0.01, "A": 0.01, "B": 0.01,
                                                           "B0": 0.01}, direction=1))


def single_loads(case: Case) -> list[Case]:
    return [redrawn(case, loads=(ld,)) for ld in preset_of(case).loads]


def run(quick: bool = False) -> StudyResult:
    """Seed E1 with pin friction: T12 under both loads against the sum of the T12 each load
    needs alone (each with its own friction), by analytic and by each simulator."""
    base = builtin("seed-E1-as-stated")
    mus = np.concatenate([[0.0], np.geomspace(0.01, 0.5, 4 if quick else 10)])
    rows = []
    for mu in mus:
        case = with_friction(base, float(mu))
        parts = single_loads(case)
        rows.append({"source": "analytic", "mu": mu, "T_all": torque(reference(case), case),
                     "T_sum": sum(torque(reference(p), p) for p in parts)})
        for sim in SIMULATORS:
            rows.append({"source": sim, "mu": mu, "T_all": torque(simulate(sim, case), case),
                         "T_sum": sum(torque(simulate(sim, p), p) for p in parts)})
    data = pd.DataFrame(rows)
    data["superposition_error"] = (data["T_sum"] - data["T_all"]).abs() / data["T_all"].abs()
    found = {src: [crossing(g["mu"].to_numpy()[1:], g["superposition_error"].to_numpy()[1:], lv)
                   for lv in LEVELS] for src, g in groups(data)}
    figure = loglog_by_source(data[data["mu"] > 0], "mu", "superposition_error", levels=LEVELS,
                              xlabel="friction coefficient μ (pin radius 10 mm)",
                              ylabel="|ΣT_single − T_all| / |T_all|",
                              title="Superposition with friction (seed E1)")
    zero = data[data["mu"] == 0.0]["superposition_error"].max()
    tried = f"μ = {mus[-1]:g}"
    conclusion = (f"Without friction superposition is exact (largest error {zero:.1e}); with pin "
                  "friction the sum of single-load solutions misses T12 by 1 % "
                  + reached({k: v[0] for k, v in found.items()}, "", at="μ", tried=tried)
                  + " and by 10 % "
                  + reached({k: v[1] for k, v in found.items()}, "", at="μ", tried=tried) + ".")
    return StudyResult(
        "superposition_friction", "Superposition with friction",
        "How wrong is summing single-load solutions when the joints have Coulomb friction?",
        data, figure, conclusion,
        "Seed E1 at θ12 = 60°, friction circles at all four pins (r = 10 mm), crank turning "
        "counter-clockwise. Each load alone and both together, by the analytic friction-circle "
        "solution and by each simulator (driven slowly, friction from its own reactions).")
