"""Sweep figures (matplotlib, Agg): one four-panel figure per case over θ12.

Panels: drive torque per backend; reaction magnitudes; relative error per
backend on a log scale against its tolerance; the transmission angle. Singular
poses (toggle and change points) are marked with vertical lines on every
panel, near-singular ones shaded.
"""

from __future__ import annotations

import io

import matplotlib

matplotlib.use("Agg")  # files only: no display on CI machines

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.axes import Axes

from mechcheck.analytic.case import Case
from mechcheck.analytic.transmission import transmission_angle
from mechcheck.backends import REFERENCE
from mechcheck.tolerance import NEAR_SINGULAR_CONDITION

#: Figures never plot more points than this per line (a 10⁶-pose sweep is thinned).
MAX_POINTS = 4000


def _thin(frame: pd.DataFrame) -> pd.DataFrame:
    step = max(1, len(frame) // MAX_POINTS)
    return frame.iloc[::step]


def _series(results: pd.DataFrame, backend: str, quantity: str) -> pd.DataFrame:
    rows = results[(results["backend"] == backend) & (results["quantity"] == quantity)]
    return _thin(rows.sort_values("theta12"))


def _mark_singular(ax: Axes, status: pd.DataFrame) -> None:
    ref = status[status["backend"] == REFERENCE]
    for theta in ref.loc[ref["status"] == "singular", "theta12"].to_numpy()[:50]:
        ax.axvline(theta, color="crimson", lw=0.8, ls="--", alpha=0.7)
    near = ref[(ref["condition_number"] > NEAR_SINGULAR_CONDITION) & (ref["status"] == "ok")]
    if len(near):
        ax.plot(near["theta12"], np.zeros(len(near)), "|", color="orange",
                transform=ax.get_xaxis_transform(), ms=8)


def sweep_figure(case: Case, results: pd.DataFrame, status: pd.DataFrame,
                 comparison: pd.DataFrame) -> bytes:
    """PNG bytes of the four-panel figure of one case's sweep."""
    drive = f"T1{case.drive_link}"
    backends = [str(b) for b in pd.unique(results["backend"])]
    fig, axes = plt.subplots(2, 2, figsize=(11, 7.5), sharex=True)
    (ax_t, ax_f), (ax_e, ax_mu) = axes
    for b in backends:
        s = _series(results, b, drive)
        style = {"lw": 1.6} if b == REFERENCE else {"ls": "none", "marker": ".", "ms": 3}
        ax_t.plot(s["theta12"], s["value"], label=b, **style)
    ax_t.set_ylabel(f"{drive} [N·m]")
    ax_t.set_title("Drive torque")
    ax_t.legend(fontsize=7, ncol=2)
    for j in ("12", "23", "34", "14"):
        x = _series(results, REFERENCE, f"F{j}_x").set_index("theta12")["value"]
        y = _series(results, REFERENCE, f"F{j}_y").set_index("theta12")["value"]
        ax_f.plot(x.index, np.hypot(x, y.reindex(x.index)), label=f"|F{j}|")
    ax_f.set_yscale("log")
    ax_f.set_ylabel("reaction [N] (analytic)")
    ax_f.set_title("Reaction magnitudes")
    ax_f.legend(fontsize=7)
    for b in backends:
        rows = comparison[comparison["backend"] == b]
        if rows.empty:
            continue
        worst = rows.groupby("theta12")["rel_err"].max().clip(lower=1e-17)
        tol = rows.groupby("theta12")["tolerance"].min()
        line = ax_e.plot(worst.index, worst.to_numpy(), ".", ms=3, label=b)[0]
        ax_e.plot(tol.index, tol.to_numpy(), "-", lw=0.8, color=line.get_color(), alpha=0.6)
    ax_e.set_yscale("log")
    ax_e.set_ylabel("worst relative error (dots) / tolerance (line)")
    ax_e.set_title("Error against the tolerance" if len(comparison)
                   else "Error against the tolerance (nothing to compare)")
    if len(comparison):
        ax_e.legend(fontsize=7, ncol=2)
    theta = np.sort(results.loc[results["backend"] == REFERENCE, "theta12"].unique())
    theta = theta[:: max(1, len(theta) // MAX_POINTS)]
    ax_mu.plot(theta, np.degrees(transmission_angle(case, np.radians(theta))), color="k")
    ax_mu.axhline(40.0, color="grey", lw=0.8, ls=":")
    ax_mu.set_ylabel("transmission angle μ [deg]")
    ax_mu.set_title("Transmission angle (dotted: 40° guideline)")
    for ax in axes.flat:
        _mark_singular(ax, status)
        ax.grid(alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("θ12 [deg]")
    fig.suptitle(f"{case.name}: sweep over θ12 (dashed red: singular pose)")
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=90)
    plt.close(fig)
    return buffer.getvalue()
