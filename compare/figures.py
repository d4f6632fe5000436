"""Sweep figures (matplotlib, Agg): one four-panel figure per case over θ12.

Panels: drive torque per backend; reaction magnitudes; relative error per
backend on a log scale against its tolerance; the transmission angle (a
linkage's condition number, with its output toggles dotted). Singular poses (toggle and
change points) are marked with vertical lines on every panel, near-singular ones ticked.

A figure is made in two steps, so that the drawing can run in a sweep's worker pool:
:func:`sweep_plot` reduces the sweep's tables to the curves drawn, thinned to at most
:data:`MAX_POINTS` points each (small enough to send to a worker), and :func:`draw_sweep`
draws them with a fixed layout. Only the drawing imports matplotlib.
"""

from __future__ import annotations

import io
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from mechcheck.analytic.case import Case, preset_of
from mechcheck.analytic.theory import output_toggles
from mechcheck.analytic.transmission import transmission_angle
from mechcheck.backends import REFERENCE
from mechcheck.output import file_stem
from mechcheck.tolerance import NEAR_SINGULAR_CONDITION

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from mechcheck.analytic.solution import Solution

#: Figures never plot more points than this per curve: a 10⁶-pose sweep is thinned to
#: each bucket's first, smallest, largest and last point (:func:`thin`), which at this
#: density draws the same picture as every point (a curve spans ~800 pixels at 90 dpi).
MAX_POINTS = 4000
#: The figure's size (inches) and fixed margins (fractions of it): measured text extents
#: never decide the layout (matplotlib's tight layout took over a third of a figure's time).
FIGURE_SIZE = (11.0, 7.5)
MARGINS = {"left": 0.075, "right": 0.985, "bottom": 0.075, "top": 0.915, "wspace": 0.2,
           "hspace": 0.16}
#: The most singular poses marked with a vertical line per panel.
MAX_SINGULAR_LINES = 50


def figure_file(case_name: str) -> str:
    """The file name of a case's sweep figure, in the sweep's ``figures/``."""
    return f"{file_stem(case_name)}.png"


def thin(x: np.ndarray, y: np.ndarray, limit: int = MAX_POINTS) -> tuple[np.ndarray, np.ndarray]:
    """At most ``limit`` points of the curve (x ascending) that keep its shape: in each of
    ``limit // 4`` runs of consecutive points, the first, the smallest, the largest and the
    last. Every extreme of the curve and both ends survive; so does every gap, as a drawn
    line only ever joins neighbours. NaNs are treated as absent."""
    n = len(x)
    if n <= limit:
        return x, y
    buckets = limit // 4
    edges = (np.arange(buckets + 1) * n) // buckets
    starts, stops = edges[:-1], edges[1:] - 1
    filled = np.where(np.isnan(y), 0.0, y)  # a NaN is never an extreme; 0 only marks it kept
    low = np.minimum.reduceat(filled, starts)
    high = np.maximum.reduceat(filled, starts)
    bucket = np.repeat(np.arange(starts.size), np.diff(edges))
    at_low = np.flatnonzero(filled == low[bucket])
    at_high = np.flatnonzero(filled == high[bucket])
    # The first index of each bucket that reaches the bucket's minimum (maximum).
    first_low = at_low[np.unique(bucket[at_low], return_index=True)[1]]
    first_high = at_high[np.unique(bucket[at_high], return_index=True)[1]]
    keep = np.unique(np.concatenate([starts, stops, first_low, first_high]))
    return x[keep], y[keep]


@dataclass(frozen=True)
class Curve:
    """One drawn curve: its legend label and its (thinned) points."""

    label: str
    x: np.ndarray
    y: np.ndarray

    @classmethod
    def of(cls, label: str, series: pd.Series) -> Curve:
        """The curve of a series indexed by θ12 (sorted here), thinned."""
        series = series.sort_index()
        x, y = thin(series.index.to_numpy(dtype=float), series.to_numpy(dtype=float))
        return cls(label, x, y)


@dataclass(frozen=True)
class SweepPlot:
    """Everything one case's figure shows, ready to draw."""

    title: str
    x_label: str
    drive_label: str
    drive: list[Curve]
    reactions: list[Curve]
    errors: list[tuple[Curve, Curve]]
    lower: Curve
    lower_is_condition: bool
    singular: np.ndarray
    near_singular: np.ndarray
    #: A linkage's output toggles on the sweep's axis (:func:`.theory.output_toggles`).
    toggles: np.ndarray = field(default_factory=lambda: np.zeros(0))


def _names(case: Case, axis: str | None = None) -> tuple[str, str, list[tuple[str, str]], str]:
    """(drive quantity, its unit, reactions as (label, quantity stem), x-axis label);
    ``axis``: the sweep's axis by name and unit (:func:`mechcheck.sweep.driver_axis`)."""
    if case.is_preset:
        return (f"T1{preset_of(case).drive_link}", "N·m",
                [(f"|F{j}|", f"F{j}") for j in ("12", "23", "34", "14")], "θ12 [deg]")
    linkage = case.linkage
    first = linkage.drivers[0].joint
    turns = linkage.joint(first).kind.rotates
    return (f"Q_{first}", "N·m" if turns else "N",
            [(f"|F_{j.name}|", f"F_{j.name}") for j in linkage.joints],
            f"{axis or f'driver {first}, ' + ('deg' if turns else 'mm')} from the drawn pose")


def sweep_plot(case: Case, results: pd.DataFrame, status: pd.DataFrame,
               comparison: pd.DataFrame, axis: str | None = None,
               unit: str | None = None) -> SweepPlot:
    """The curves of one case's sweep figure from its long results, statuses and
    comparisons (each thinned to at most :data:`MAX_POINTS` points); ``axis``: the sweep's
    axis by name and unit (:func:`mechcheck.sweep.driver_axis`), ``unit`` its unit (a
    sliding driver's length unit; default the case's own)."""
    drive, drive_unit, reactions, x_label = _names(case, axis)
    backends = [str(b) for b in pd.unique(results["backend"])]
    drive_curves = [Curve.of(b, _series(results, b, drive)) for b in backends]
    reference = results[results["backend"] == REFERENCE]
    reaction_curves = []
    for label, stem in reactions:
        x, y = _series(reference, REFERENCE, f"{stem}_x"), _series(reference, REFERENCE, f"{stem}_y")
        magnitude = np.hypot(x.to_numpy(), y.reindex(x.index).to_numpy())
        reaction_curves.append(Curve.of(label, pd.Series(magnitude, index=x.index)))
    errors = []
    for b in backends:
        rows = comparison[comparison["backend"] == b]
        if len(rows):
            by_pose = rows.groupby("theta12")
            errors.append((Curve.of(b, by_pose["rel_err"].max().clip(lower=1e-17)),
                           Curve.of(b, by_pose["tolerance"].min())))
    ref = status[status["backend"] == REFERENCE]
    near = ref[(ref["condition_number"] > NEAR_SINGULAR_CONDITION) & (ref["status"] == "ok")]
    near_theta = np.sort(near["theta12"].to_numpy(dtype=float))
    return SweepPlot(
        title=f"{case.name}: sweep over {x_label.split(' [')[0].split(', ')[0]} (dashed red: "
              "singular pose)",
        x_label=x_label, drive_label=f"{drive} [{drive_unit}]", drive=drive_curves,
        reactions=reaction_curves, errors=errors, lower=_lower_curve(case, ref),
        lower_is_condition=not case.is_preset,
        singular=np.sort(ref.loc[ref["status"] == "singular", "theta12"].to_numpy(
            dtype=float))[:MAX_SINGULAR_LINES],
        near_singular=thin(near_theta, near_theta)[0],
        toggles=np.zeros(0) if case.is_preset else _toggles(case, ref, unit))


def _toggles(case: Case, ref_status: pd.DataFrame, unit: str | None) -> np.ndarray:
    """A linkage's output toggles between the sweep's poses, on its axis: computed from the
    analytic kinematics, which a simulator's forces never enter."""
    from mechcheck.sweep import axis_unit, grid_si

    unit = unit or axis_unit(case)
    grid = np.unique(ref_status["theta12"].to_numpy(dtype=float))
    # Brackets need no more poses than the figure draws; Brent's method does the rest.
    grid = np.unique(np.append(grid[::-(-grid.size // MAX_POINTS) or 1], grid[-1:]))
    si = grid_si(case, grid, unit)
    toggles = output_toggles(case.linkage, si)
    # Back on the axis: grid_si is linear in the grid.
    return toggles * (grid[-1] - grid[0]) / (si[-1] - si[0]) if grid.size > 1 else toggles


def _series(results: pd.DataFrame, backend: str, quantity: str) -> pd.Series:
    """One backend's values of one quantity, indexed by θ12 (masks on the categorical
    columns: a 10⁶-pose sweep has 10⁷ rows, and only a few series are drawn)."""
    rows = results[(results["backend"] == backend) & (results["quantity"] == quantity)]
    return rows.set_index("theta12")["value"]


def _lower_curve(case: Case, ref_status: pd.DataFrame) -> Curve:
    """The four-bar's and slider-crank's transmission angle (deg); a linkage's condition
    number (how close each pose is to a toggle), which every mechanism has."""
    if not case.is_preset:
        return Curve.of("condition", ref_status.set_index("theta12")["condition_number"])
    # Computed, not read: at most MAX_POINTS evenly spread poses show this closed form.
    theta = np.sort(ref_status["theta12"].to_numpy(dtype=float))
    theta = theta[::-(-len(theta) // MAX_POINTS) or 1]
    return Curve("μ", theta, np.degrees(transmission_angle(case, np.radians(theta))))


def warm_up() -> None:
    """Import matplotlib for :func:`draw_sweep` (a worker warming up)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot


def draw_sweep(plot: SweepPlot) -> bytes:
    """PNG bytes of the four-panel figure (matplotlib imported here: only where drawn)."""
    import matplotlib

    matplotlib.use("Agg")  # files only: no display on CI machines
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=FIGURE_SIZE, sharex=True)
    fig.subplots_adjust(**MARGINS)
    (ax_t, ax_f), (ax_e, ax_mu) = axes
    for curve in plot.drive:
        style = {"lw": 1.6} if curve.label == REFERENCE else {"ls": "none", "marker": ".", "ms": 3}
        ax_t.plot(curve.x, curve.y, label=curve.label, **style)
    ax_t.set_ylabel(plot.drive_label)
    ax_t.set_title("Drive effort")
    ax_t.legend(fontsize=7, ncol=2)
    for curve in plot.reactions:
        ax_f.plot(curve.x, curve.y, label=curve.label)
    ax_f.set_yscale("log")
    ax_f.set_ylabel("reaction [N] (analytic)")
    ax_f.set_title("Reaction magnitudes")
    ax_f.legend(fontsize=7)
    for worst, tolerance in plot.errors:
        line = ax_e.plot(worst.x, worst.y, ".", ms=3, label=worst.label)[0]
        ax_e.plot(tolerance.x, tolerance.y, "-", lw=0.8, color=line.get_color(), alpha=0.6)
    ax_e.set_yscale("log")
    ax_e.set_ylabel("worst relative error (dots) / tolerance (line)")
    ax_e.set_title("Error against the tolerance" if plot.errors
                   else "Error against the tolerance (nothing to compare)")
    if plot.errors:
        ax_e.legend(fontsize=7, ncol=2)
    _draw_lower(ax_mu, plot)
    for ax in axes.flat:
        for theta in plot.singular:
            ax.axvline(theta, color="crimson", lw=0.8, ls="--", alpha=0.7)
        if plot.near_singular.size:
            ax.plot(plot.near_singular, np.zeros(plot.near_singular.size), "|", color="orange",
                    transform=ax.get_xaxis_transform(), ms=8)
        ax.grid(alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel(plot.x_label)
    fig.suptitle(plot.title)
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=90)
    plt.close(fig)
    return buffer.getvalue()


def _draw_lower(ax: Axes, plot: SweepPlot) -> None:
    ax.plot(plot.lower.x, plot.lower.y, color="k")
    if plot.lower_is_condition:
        ax.axhline(NEAR_SINGULAR_CONDITION, color="grey", lw=0.8, ls=":")
        ax.set_yscale("log")
        ax.set_ylabel("condition number (analytic)")
        ax.set_title("Distance from toggles (dotted: near-singular line)")
        for theta in plot.toggles:   # output toggles: the condition number stays flat there
            ax.axvline(theta, color="tab:purple", lw=1.0, ls=":")
            ax.annotate("toggle", (theta, 0.5), xycoords=("data", "axes fraction"),
                        xytext=(2, 0), textcoords="offset points", fontsize=7,
                        color="tab:purple", rotation=90)
        return
    ax.axhline(40.0, color="grey", lw=0.8, ls=":")
    ax.set_ylabel("transmission angle μ [deg]")
    ax.set_title("Transmission angle (dotted: 40° guideline)")



#: Poses of the cycle drawn beside a sweep's curves, evenly spread over its poses with forces.
DRAWN_POSES = 4


def poses_file(case_name: str) -> str:
    """The file name of a case's drawn poses, in the sweep's ``figures/``."""
    return f"{file_stem(case_name)}-poses.png"


def cycle_panels(case: Case, results: pd.DataFrame,
                 status: pd.DataFrame) -> list[tuple[Case, Solution, str]]:
    """The mechanism at :data:`DRAWN_POSES` poses of one case's sweep, from the reference's
    own rows (each a Case at the pose, its Solution in SI and a panel title) for
    :func:`mechcheck.drawing.panels_png`: poses where the reference has forces, spread
    evenly over them."""
    from mechcheck.analytic.presets import redrawn
    from mechcheck.analytic.solution import Solution
    from mechcheck.sweep import units_of

    ref = status[(status["backend"] == REFERENCE) & (status["status"] == "ok")]
    grid = np.sort(ref["theta12"].to_numpy(dtype=float))
    if not grid.size:
        return []
    chosen = grid[np.unique(np.arange(DRAWN_POSES) * grid.size // DRAWN_POSES)]
    rows = results[(results["backend"] == REFERENCE) & results["theta12"].isin(chosen)]
    x_label = _names(case)[3]
    units = units_of(case)
    panels = []
    for value in chosen:
        mine = rows[rows["theta12"] == value]
        values = {str(q): math.radians(v) if u == "deg" else float(v)
                  for q, v, u in zip(mine["quantity"], mine["value"], mine["unit"], strict=True)}
        at = redrawn(case, theta12=math.radians(value)) if case.is_preset else case
        if at.geometry is None:
            continue
        solution = Solution(case.name, REFERENCE, values,
                            units={q: units[q] for q in values if q in units})
        panels.append((at, solution, f"{x_label.split(' [')[0]} = {value:g}"
                                     f"{'°' if 'deg' in x_label else ' mm'}"))
    return panels
