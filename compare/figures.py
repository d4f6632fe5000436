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


def _names(case: Case) -> tuple[str, str, list[tuple[str, str]], str]:
    """(drive quantity, its unit, reactions as (label, quantity stem), x-axis label)."""
    if case.mechanism != "linkage":
        return (f"T1{case.drive_link}", "N·m",
                [(f"|F{j}|", f"F{j}") for j in ("12", "23", "34", "14")], "θ12 [deg]")
    linkage = case.linkage
    first = linkage.drivers[0].joint
    revolute = linkage.joint(first).kind == "revolute"
    return (f"Q_{first}", "N·m" if revolute else "N",
            [(f"|F_{j.name}|", f"F_{j.name}") for j in linkage.joints],
            f"driver {first} from the drawn pose [{'deg' if revolute else 'mm'}]")


def sweep_figure(case: Case, results: pd.DataFrame, status: pd.DataFrame,
                 comparison: pd.DataFrame) -> bytes:
    """PNG bytes of the four-panel figure of one case's sweep."""
    drive, drive_unit, reactions, x_label = _names(case)
    backends = [str(b) for b in pd.unique(results["backend"])]
    fig, axes = plt.subplots(2, 2, figsize=(11, 7.5), sharex=True)
    (ax_t, ax_f), (ax_e, ax_mu) = axes
    for b in backends:
        s = _series(results, b, drive)
        style = {"lw": 1.6} if b == REFERENCE else {"ls": "none", "marker": ".", "ms": 3}
        ax_t.plot(s["theta12"], s["value"], label=b, **style)
    ax_t.set_ylabel(f"{drive} [{drive_unit}]")
    ax_t.set_title("Drive effort")
    ax_t.legend(fontsize=7, ncol=2)
    for label, stem in reactions:
        x = _series(results, REFERENCE, f"{stem}_x").set_index("theta12")["value"]
        y = _series(results, REFERENCE, f"{stem}_y").set_index("theta12")["value"]
        ax_f.plot(x.index, np.hypot(x, y.reindex(x.index)), label=label)
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
    _condition_or_transmission(ax_mu, case, results, status)
    for ax in axes.flat:
        _mark_singular(ax, status)
        ax.grid(alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel(x_label)
    fig.suptitle(f"{case.name}: sweep over {x_label.split(' [')[0]} (dashed red: singular pose)")
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=90)
    plt.close(fig)
    return buffer.getvalue()


def _condition_or_transmission(ax: Axes, case: Case, results: pd.DataFrame,
                               status: pd.DataFrame) -> None:
    """The four-bar's and slider-crank's transmission angle; a linkage's condition number
    (how close each pose is to a toggle), which every mechanism has."""
    if case.mechanism == "linkage":
        ref = _thin(status[status["backend"] == REFERENCE].sort_values("theta12"))
        ax.plot(ref["theta12"], ref["condition_number"], color="k")
        ax.axhline(NEAR_SINGULAR_CONDITION, color="grey", lw=0.8, ls=":")
        ax.set_yscale("log")
        ax.set_ylabel("condition number (analytic)")
        ax.set_title("Distance from toggles (dotted: near-singular line)")
        return
    theta = np.sort(results.loc[results["backend"] == REFERENCE, "theta12"].unique())
    theta = theta[:: max(1, len(theta) // MAX_POINTS)]
    ax.plot(theta, np.degrees(transmission_angle(case, np.radians(theta))), color="k")
    ax.axhline(40.0, color="grey", lw=0.8, ls=":")
    ax.set_ylabel("transmission angle μ [deg]")
    ax.set_title("Transmission angle (dotted: 40° guideline)")
