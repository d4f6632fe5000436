"""pymunk's forces as its solver's settings vary (the rigid-joints study): the iterative
solver converges over steps (``iterations``, ``error_bias``), and a driven run integrates
with a finite time step."""

from __future__ import annotations

import math
from functools import partial
from typing import TYPE_CHECKING

import numpy as np

from mechcheck.analytic.case import Case
from mechcheck.analytic.presets import solve_preset
from mechcheck.sim_models.protocol import ErrorOf, StiffnessStudy
from mechcheck.sim_models.pymunk.backend import settle
from mechcheck.sim_models.pymunk.linkage_dynamics import drive_at_timestep
from mechcheck.sim_models.pymunk.settings import LINKAGE_SETTLE

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.axes import Axes

ITERATIONS = (1, 3, 10, 30, 100)
#: Chipmunk's default error bias, (1 − 0.1)⁶⁰: 10 % of a joint error corrected per 1/60 s,
#: i.e. the fraction 0.9⁶⁰ ≈ 0.0018 left after one second.
DEFAULT_BIAS = 0.9**60
DT = (1e-3, 3e-4, 1e-4, 3e-5)
#: Length of each fixed-step driven run, s: 50 steps at the largest dt. The reading's error
#: is its time step's, not the start's: a 0.1 s run changes it by < 1e-13 of the largest
#: force (measured at dt = 1e-3 and 1e-4 s, where the error is 3.4e-5 and 3.4e-7).
DRIVEN_LEAD = 0.05


def stiffness_study(case: Case, driven: Case, quick: bool, error_of: ErrorOf) -> StiffnessStudy:
    """pymunk's part of the rigid-joints study: the static ``case`` settled at each
    iteration count, at Chipmunk's default error bias and at 0; ``driven`` at each fixed
    time step."""
    rows: list[dict[str, object]] = []
    for bias, label in ((DEFAULT_BIAS, "error_bias 0.9⁶⁰ (default)"), (0.0, "error_bias 0")):
        for n in ITERATIONS[::2] if quick else ITERATIONS:
            settings = LINKAGE_SETTLE.with_(iterations=n, error_bias=bias)
            sol = solve_preset(case, partial(settle, settings=settings), "pymunk")
            rows.append({"simulator": "pymunk", "setting": label, "parameter": "iterations",
                         "value": n, "reading": "settled", "status": sol.status,
                         "steps": sol.diagnostics.get("steps"),
                         "error": error_of(case, sol.values) if sol.status == "ok" else math.nan})
    for dt in DT[::2] if quick else DT:
        sol = solve_preset(driven, partial(drive_at_timestep, dt=dt, lead_time=DRIVEN_LEAD),
                           "pymunk")
        rows.append({"simulator": "pymunk", "setting": "driven (ω = −10, α = 50)",
                     "parameter": "dt", "value": dt, "reading": "driven", "status": sol.status,
                     "error": error_of(driven, sol.values) if sol.status == "ok" else math.nan})
    return StiffnessStudy(rows, _draw, _conclusion)


def _draw(ax: Axes, data: pd.DataFrame) -> None:
    settled = data[data["parameter"] == "iterations"]
    for bias_label, g in settled.groupby("setting", sort=False):
        ax.loglog(g["value"], g["error"].clip(lower=1e-17), "o-",
                  label=f"settled, {bias_label!s}", ms=4)
    driven = data[data["parameter"] == "dt"]
    twin = ax.twiny()
    twin.loglog(driven["value"], driven["error"].clip(lower=1e-17), "k^:",
                label="driven: error vs dt")
    twin.set_xlabel("driven time step dt [s]")
    twin.legend(fontsize=7, loc="upper right")
    ax.set_xlabel("solver iterations per step")
    ax.set_title("pymunk: iterations, error bias, time step")


def _conclusion(data: pd.DataFrame) -> str:
    worst = float(data.loc[data["parameter"] == "iterations", "error"].max())
    driven = data[data["parameter"] == "dt"].sort_values("value")
    slope = float(np.polyfit(np.log(driven["value"].astype(float)),
                             np.log(driven["error"].astype(float)), 1)[0]) \
        if driven["error"].notna().sum() > 1 else math.nan
    return (f"pymunk's settled statics reach {worst:.1e} or better at every iteration count "
            f"and error bias tried (they only change the steps taken), while its driven error "
            f"scales like dt^{slope:.1f}.")
