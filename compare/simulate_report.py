"""The report of ``mechcheck simulate``: Markdown and one self-contained HTML file.

Its first screen is ``run``'s (:func:`mechcheck.report.view_model`: the verdict, a line per
backend, the matrix of cases × backends). Each case's section adds one figure (matplotlib,
Agg) of four panels: a key joint coordinate and the point that moves most, over time, by the
reference and each simulator's finest run; the reference's energy terms; and accuracy
against cost, each run's error against its wall time (log-log, a line per simulator and
integrator, the default run marked, the tolerance drawn); then the table of every run and,
where a simulator never reaches its tolerance, a sentence saying so with its diagnostics.
"""

from __future__ import annotations

import base64
import io
import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage_backends import quantity_units
from mechcheck.analytic.trajectory import Trajectory
from mechcheck.backends import REFERENCE
from mechcheck.casefile import AnySpec
from mechcheck.figures import figure_file
from mechcheck.output import file_stem
from mechcheck.report import fmt, render_pair, sci, view_model
from mechcheck.simulate_run import ENERGY_RESIDUAL, SimulateResult
from mechcheck.tolerance import TRAJECTORY, rule

if TYPE_CHECKING:
    from matplotlib.axes import Axes

#: A case's figure: size (inches) and resolution, four panels in two rows.
FIGURE_SIZE = (11.0, 7.0)
DPI = 90
#: An error of exactly zero, drawn on the log scale at this floor (below any rounding).
ERROR_FLOOR = 1e-17


def key_quantities(case: Case, reference: Trajectory) -> tuple[str, list[str]]:
    """What the trajectory panels plot: the first driver's joint coordinate (or the joint
    that moves most), and x and y of the point that moves most, by the reference."""
    quantities = reference.quantities(case.linkage)
    ranges = {q: float(np.ptp(v)) if len(v) else 0.0 for q, v in quantities.items()}
    joints = [q for q in quantities if q.startswith("q_")]
    driver = f"q_{case.linkage.drivers[0].joint}" if case.linkage.drivers else None
    joint = driver if driver in quantities else max(joints, key=lambda q: ranges[q], default="")
    points = [q[2:] for q in quantities if q.startswith("x_")]
    point = max(points, key=lambda p: ranges[f"x_{p}"] + ranges[f"y_{p}"], default="")
    return joint, ([f"x_{point}", f"y_{point}"] if point else [])


def plotted(case: Case, run: Trajectory, quantity: str) -> np.ndarray:
    """A run's quantity in the unit the panel shows (mm, degrees) as the file gives lengths."""
    unit = quantity_units(case.linkage)[quantity]
    values = np.asarray(run.quantities(case.linkage)[quantity], dtype=float)
    return np.degrees(values) if unit == "deg" else values * 1000.0


def panel_label(case: Case, quantity: str) -> str:
    unit = quantity_units(case.linkage)[quantity]
    return f"{quantity}, {'deg' if unit == 'deg' else 'mm'}"


def draw_trajectories(ax: Axes, case: Case, runs: Mapping[str, tuple[Trajectory, ...]],
                      quantities: list[str], reference: Trajectory) -> None:
    """Each quantity over time by the reference (solid) and each simulator's finest run."""
    for quantity in quantities:
        line = ax.plot(reference.times, plotted(case, reference, quantity), lw=2.2, alpha=0.6,
                       label=f"{quantity}: {REFERENCE}")[0]
        for style, (backend, own) in zip(("--", ":", "-."), simulators(runs).items(), strict=False):
            finest = own[-1]
            if finest.status == "ok" and np.shape(finest.coordinates) == np.shape(
                    reference.coordinates):
                ax.plot(finest.times, plotted(case, finest, quantity), style, lw=1.2,
                        color=line.get_color(), label=f"{quantity}: {backend}")
    ax.set_xlabel("time, s")
    ax.set_ylabel(", ".join(panel_label(case, q) for q in quantities))
    ax.legend(fontsize=7, loc="best")


def simulators(runs: Mapping[str, tuple[Trajectory, ...]]) -> dict[str, tuple[Trajectory, ...]]:
    return {b: r for b, r in runs.items() if b != REFERENCE}


def draw_energy(ax: Axes, reference: Trajectory) -> None:
    """The reference's energy terms over time, and its balance's residual."""
    energy = reference.energy
    if energy is None:
        ax.text(0.5, 0.5, "the reference reports no energy balance", ha="center",
                transform=ax.transAxes)
        return
    for name, values in (("kinetic", energy.kinetic), ("potential", energy.potential),
                         ("work of loads and efforts", energy.work),
                         ("dissipated", energy.dissipated), ("residual", energy.residual)):
        ax.plot(reference.times, values, lw=1.4, ls=":" if name == "residual" else "-",
                label=name)
    ax.set_xlabel("time, s")
    ax.set_ylabel("energy, J")
    ax.legend(fontsize=7, loc="best")


def ladder_lines(runs: tuple[Trajectory, ...]) -> dict[str, list[int]]:
    """A simulator's runs split into the lines of the accuracy-against-cost plot, each line a
    ladder of time steps: by the settings that take several values at one time step (its
    integrators, its iteration counts), not by those that follow the step. Run indices in
    ladder order, by label."""
    steps: dict[object, list[Mapping[str, object]]] = {}
    for run in runs:
        steps.setdefault(run.settings.get("dt"), []).append(run.settings)
    keys = [k for k in dict.fromkeys(k for run in runs for k in run.settings)
            if k != "dt" and any(len({repr(s.get(k)) for s in same}) > 1
                                 for same in steps.values())]
    lines: dict[str, list[int]] = {}
    for index, run in enumerate(runs):
        label = ", ".join(f"{k}={run.settings.get(k)}" if k != "integrator"
                          else str(run.settings.get(k)) for k in keys)
        lines.setdefault(f"{run.backend} {label}".strip(), []).append(index)
    return lines


def draw_cost(ax: Axes, rungs: pd.DataFrame, runs: Mapping[str, tuple[Trajectory, ...]],
              tolerance: float) -> None:
    """Each run's error against its wall time, log-log: a line per simulator and integrator
    (or iteration count), the default runs ringed, the tolerance drawn."""
    shown = False
    for backend, own in simulators(runs).items():
        table = rungs[rungs["backend"] == backend].set_index("rung")
        for label, indices in ladder_lines(own).items():
            line = table.loc[[i for i in indices if i in table.index]]
            line = line[np.isfinite(line["error"]) & (line["wall_time"] > 0)]
            if not len(line):
                continue
            error = np.maximum(line["error"].to_numpy(dtype=float), ERROR_FLOOR)
            drawn = ax.loglog(line["wall_time"], error, "o-", ms=3.5, lw=1.1, label=label)[0]
            default = line["default"].astype(bool).to_numpy()
            if default.any():
                ax.loglog(line["wall_time"].to_numpy()[default], error[default], "s", ms=11,
                          mfc="none", color=drawn.get_color(),
                          label=None if shown else "default settings")
                shown = True
    ax.axhline(tolerance, color="#b00020", lw=1.0, ls="--", label=f"tolerance {tolerance:.0e}")
    if not ax.lines[:-1]:
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.text(0.5, 0.5, "no simulator's run to compare", ha="center", transform=ax.transAxes)
    ax.set_xlabel("wall time, s")
    ax.set_ylabel("error (worst over time; /scale, rad)")
    ax.legend(fontsize=6.5, loc="best")


def trajectory_figure(case: Case, runs: Mapping[str, tuple[Trajectory, ...]],
                      rungs: pd.DataFrame) -> bytes | None:
    """The case's four panels as PNG bytes; None without a reference run to plot."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    reference = runs.get(REFERENCE, ())
    if not reference or reference[-1].status != "ok":
        return None
    ref = reference[-1]
    joint, point = key_quantities(case, ref)
    figure = Figure(figsize=FIGURE_SIZE)
    axes = figure.subplots(2, 2)
    figure.subplots_adjust(left=0.08, right=0.98, bottom=0.08, top=0.93, wspace=0.25, hspace=0.3)
    figure.suptitle(case.name)
    draw_trajectories(axes[0, 0], case, runs, [joint] if joint else [], ref)
    draw_trajectories(axes[0, 1], case, runs, point, ref)
    draw_energy(axes[1, 0], ref)
    draw_cost(axes[1, 1], rungs, runs, rule(REFERENCE, "pose", TRAJECTORY).rtol)
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=DPI)
    return buffer.getvalue()


def unreached(case: Case, rungs: pd.DataFrame, runs: Mapping[str, tuple[Trajectory, ...]],
              tolerance: float) -> list[str]:
    """A sentence per simulator none of whose runs reaches ``tolerance``: its smallest error,
    at which settings, and what its diagnostics say of that run."""
    out = []
    for backend, own in rungs[rungs["backend"] != REFERENCE].groupby("backend", sort=False):
        errors = own["error"].to_numpy(dtype=float)
        if (errors <= tolerance).any():
            continue
        finite = np.where(np.isfinite(errors), errors, np.inf)
        best = int(np.argmin(finite))
        row = own.iloc[best]
        if not math.isfinite(finite[best]):
            out.append(f"{backend} never reaches the tolerance {tolerance:.0e}: none of its "
                       f"{len(own)} runs gave a number to compare ({row['message'] or row['status']}).")
            continue
        run = runs[str(backend)][int(row["rung"])]
        why = ", ".join(f"{k} = {float(v):.3g}" for k, v in run.diagnostics.items())
        out.append(f"{backend} never reaches the tolerance {tolerance:.0e} at any of its "
                   f"{len(own)} settings: its smallest error is {sci(finite[best])} "
                   f"({row['settings'] or 'its only setting'}, {row['quantity']} at "
                   f"t = {fmt(float(row['time']), 4)} s)"
                   + (f"; that run's diagnostics: {why}." if why else "."))
    return out


def trajectory_view(case: Case, result: SimulateResult, base: dict[str, Any],
                    figure: bytes | None, drawing: bytes | None = None) -> dict[str, Any]:
    """A case's section: ``run``'s (inputs, drawing, verdicts, diagnostics) with the
    figure, the table of runs, the unreached tolerances, the energy check and the events."""
    runs = result.trajectories.get(case.name, {})
    rungs = result.rungs[result.rungs["case"] == case.name]
    tolerance = rule(REFERENCE, "pose", TRAJECTORY).rtol
    energy = result.detail[(result.detail["case"] == case.name)
                           & (result.detail["quantity"] == ENERGY_RESIDUAL)]
    reference = runs.get(REFERENCE, ())
    return base | {
        "figure": base64.b64encode(figure).decode() if figure else None,
        "figure_file": figure_file(case.name),
        "drawing": base64.b64encode(drawing).decode() if drawing else None,
        "drawing_file": drawn_file(case.name),
        "rungs": rungs.to_dict("records"),
        "unreached": unreached(case, rungs, runs, tolerance),
        "energy": energy.to_dict("records")[0] if len(energy) else None,
        "events": list(reference[-1].events) if reference else [],
        "end": case.simulation.end if case.simulation else math.nan,
        "outputs": len(case.simulation.outputs) if case.simulation else 0,
    }


def drawn_file(case_name: str) -> str:
    """A case's drawing as its file draws it, in the report's ``figures/`` folder beside its figure."""
    return f"{file_stem(case_name)}-drawn.png"


def figures(result: SimulateResult) -> dict[str, bytes]:
    """Each case's figure (PNG) by case name, where the reference gave a run."""
    out = {}
    for case in result.cases:
        png = trajectory_figure(case, result.trajectories.get(case.name, {}),
                                result.rungs[result.rungs["case"] == case.name])
        if png is not None:
            out[case.name] = png
    return out


def render_simulate(result: SimulateResult, specs: Mapping[str, AnySpec],
                    title: str = "mechcheck trajectory report",
                    pictures: Mapping[str, bytes] | None = None,
                    drawn: Mapping[str, bytes] | None = None) -> tuple[str, str]:
    """(Markdown, HTML) of a simulate run. ``pictures``: each case's figure by case name
    (default: :func:`figures`); ``drawn``: each case's mechanism as its file draws it
    (:func:`mechcheck.report.drawings`); the Markdown links to them in ``figures/``, the
    HTML holds them."""
    shown = figures(result) if pictures is None else pictures
    drawn = {} if drawn is None else drawn
    # A seed's printed answers are values at one pose: a trajectory has none to set beside.
    unseeded = {name: spec.model_copy(update={"seed": None}) for name, spec in specs.items()}
    model = view_model(result, unseeded, title, {})
    model["cases"] = [trajectory_view(case, result, view, shown.get(case.name),
                                      drawn.get(case.name))
                      for case, view in zip(result.cases, model["cases"], strict=True)]
    return render_pair("simulate", model)

