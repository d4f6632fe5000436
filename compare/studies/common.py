"""What every assumption study shares: its result type, the simulators it runs,
a crossing finder for the one-line conclusions, and the study cases."""

from __future__ import annotations

import io
import math
from collections.abc import Callable
from dataclasses import dataclass

import matplotlib

matplotlib.use("Agg")  # files only: no display on CI machines

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from numpy.typing import ArrayLike

from mechcheck import backends
from mechcheck.analytic.case import Case, FourBarGeometry, Mass, preset_of
from mechcheck.analytic.presets import redrawn
from mechcheck.analytic.solution import Solution
from mechcheck.casefile import builtin_case_files, load_cases

#: The simulators every study measures with: their settled or driven backends.
SIMULATORS = tuple(backends.names_of_family("settled"))


def reference(case: Case) -> Solution:
    """The analytic reference's Solution of ``case`` (the one engine; a preset as its
    linkage)."""
    return backends.load(backends.REFERENCE)(case)


@dataclass(frozen=True)
class StudyResult:
    """One study: what was asked, the data, a figure, and the conclusion computed from the data."""

    name: str
    title: str
    question: str
    data: pd.DataFrame
    figure: bytes
    conclusion: str
    method: str


def simulate(backend: str, case: Case) -> Solution:
    """Run one simulator backend on a case behind the pose gate, as ``mechcheck run`` does (a
    crash becomes an ``error`` verdict)."""
    from mechcheck.run import solve_gated

    return solve_gated(backend, case)


def builtin(name: str) -> Case:
    return next(c for c in load_cases(*builtin_case_files()) if c.name == name)


def steel_bar(link: int, length: float, width: float = 0.02, thickness: float = 0.005) -> Mass:
    """A uniform steel bar (ρ = 7850 kg/m³) along the link's x axis: m = ρ·A·L, I = m·L²/12."""
    mass = 7850.0 * width * thickness * length
    return Mass(link, mass, (length / 2.0, 0.0), mass * length**2 / 12.0)


def realistic_e1(**changes: object) -> Case:
    """Seed E1 (SEEDS.md) with steel links of 20 × 5 mm section under gravity."""
    case = builtin("seed-E1-as-stated")
    g = preset_of(case).geometry
    assert isinstance(g, FourBarGeometry)
    masses = (steel_bar(2, g.a2), steel_bar(3, g.a3), steel_bar(4, g.a4))
    return redrawn(case, name="E1-steel", masses=masses, gravity=(0.0, -9.81), **changes)


def groups(data: pd.DataFrame) -> list[tuple[str, pd.DataFrame]]:
    """The study's rows per source, in order of appearance (analytic first)."""
    return [(str(src), g) for src, g in data.groupby("source", sort=False)]


def crossing(x: ArrayLike, y: ArrayLike, level: float) -> float | None:
    """The first x at which y rises through ``level`` (log-log interpolation), or None."""
    xs, ys = np.asarray(x, float), np.asarray(y, float)
    for i in range(1, len(xs)):
        if ys[i - 1] < level <= ys[i] and ys[i - 1] > 0:
            t = (math.log(level) - math.log(ys[i - 1])) / (math.log(ys[i]) - math.log(ys[i - 1]))
            return float(math.exp(math.log(xs[i - 1]) + t * (math.log(xs[i]) - math.log(xs[i - 1]))))
    return None


def fmt_value(value: float | None, unit: str = "", digits: int = 3) -> str:
    return "—" if value is None else f"{value:.{digits}g}{' ' + unit if unit else ''}"


def by_source(values: dict[str, float | None], unit: str = "", *, beyond: str = "") -> str:
    """The first source's value with the simulators' beside it: "X (mujoco Y, pymunk Z)",
    or "X (every simulator agrees)" when they give the same three digits.

    ``beyond`` describes a level that was not reached within the sweep.
    """
    def one(v: float | None) -> str:
        return beyond if v is None else fmt_value(v, unit)

    texts = [one(v) for v in values.values()]
    if len(set(texts)) == 1:
        return texts[0] + (" (every simulator agrees)" if len(texts) > 1 else "")
    rest = ", ".join(f"{src} {t}" for src, t in list(zip(values, texts, strict=True))[1:])
    return f"{texts[0]} ({rest})"


def reached(values: dict[str, float | None], unit: str, *, at: str, tried: str) -> str:
    """"from ω = X rad/s (…)", or "only beyond the 200 rad/s tried" if no source reached it."""
    if all(v is None for v in values.values()):
        return f"only beyond the {tried} tried"
    return f"from {at} = " + by_source(values, unit, beyond=f"beyond {tried}")


def levels_reached(data: pd.DataFrame, x: str, y: str, *, unit: str, at: str,
                   levels: tuple[float, float] = (0.01, 0.10)) -> str:
    """"by 1 % from ω = X (…) and by 10 % from ω = Y (…)": where each source's ``y`` first
    rises through each level along ``x`` (from the sweep's last ``x`` on if never)."""
    found = {src: [crossing(g[x], g[y], level) for level in levels] for src, g in groups(data)}
    tried = f"{data[x].max():g}{' ' + unit if unit else ''}"
    first, second = ({src: v[i] for src, v in found.items()} for i in range(2))
    return (f"by {levels[0] * 100:g} % " + reached(first, unit, at=at, tried=tried)
            + f" and by {levels[1] * 100:g} % " + reached(second, unit, at=at, tried=tried))


def loglog_by_source(data: pd.DataFrame, x: str, y: str, *, levels: tuple[float, ...],
                     xlabel: str, ylabel: str, title: str) -> bytes:
    """The usual study figure: one log-log curve per source (analytic solid, simulators
    dashed), dotted lines at the conclusion's levels."""
    fig, ax = plt.subplots(figsize=(7, 4.2))
    for src, g in groups(data):
        ax.loglog(g[x], g[y], "o-" if src.startswith("analytic") else "s--", label=src, ms=4)
    for level in levels:
        ax.axhline(level, color="grey", ls=":", lw=0.8)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3, which="both")
    return png(fig)


def png(fig: Figure) -> bytes:
    buffer = io.BytesIO()
    fig.tight_layout()
    fig.savefig(buffer, format="png", dpi=90)
    plt.close(fig)
    return buffer.getvalue()


def torque(solution: Solution, case: Case) -> float:
    """The drive torque of a solution, NaN when the backend gave none."""
    return float(solution.values.get(f"T1{preset_of(case).drive_link}", math.nan))


Study = Callable[[bool], StudyResult]
