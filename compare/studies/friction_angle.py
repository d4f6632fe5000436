"""Friction angle: the exact friction-circle radius r·sin(atan μ) against the seed's μ·r."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from mechcheck.analytic.case import Case, Friction, preset_of
from mechcheck.analytic.presets import redrawn
from mechcheck.studies.common import (
    SIMULATORS,
    StudyResult,
    builtin,
    by_source,
    crossing,
    groups,
    plt,
    png,
    reference,
    simulate,
    torque,
)

LEVELS = (0.01,)


def with_pin_coefficient(case: Case, mu: float, pin_mu: float) -> Case:
    """The case with μ on the slide and an effective μ' = pin_mu for the friction circles.

    A friction circle of radius ρ is the moment arm μ'·r = ρ: the exact radius
    r·sin(atan μ) is obtained with μ' = sin(atan μ).
    """
    f = preset_of(case).friction
    assert f is not None
    return redrawn(case, friction=Friction(mu=pin_mu, pin_radius=dict(f.pin_radius), slide_mu=mu,
                                        viscous=dict(f.viscous), direction=f.direction))


def run(quick: bool = False) -> StudyResult:
    """Seed E2 (friction in every joint, crank turning clockwise): drive torque with the
    small-angle circle μ·r and with the exact one r·sin(atan μ), for a range of μ."""
    base = builtin("seed-E2-friction")
    mus = np.linspace(0.05, 0.6, 4 if quick else 12)
    rows = []
    for mu in mus:
        exact_mu = math.sin(math.atan(mu))
        small, exact = (with_pin_coefficient(base, float(mu), m) for m in (float(mu), exact_mu))
        rows.append({"source": "analytic", "mu": mu, "radius_ratio": exact_mu / mu,
                     "T_small_angle": torque(reference(small), small),
                     "T_exact": torque(reference(exact), exact)})
        for sim in SIMULATORS:
            rows.append({"source": sim, "mu": mu, "radius_ratio": exact_mu / mu,
                         "T_small_angle": torque(simulate(sim, small), small),
                         "T_exact": torque(simulate(sim, exact), exact)})
    data = pd.DataFrame(rows)
    data["torque_difference"] = (data["T_small_angle"] - data["T_exact"]).abs() / data["T_exact"].abs()
    data["radius_difference"] = 1.0 / data["radius_ratio"] - 1.0
    found = {src: crossing(g["mu"], g["torque_difference"], 0.01)
             for src, g in groups(data)}
    radius_1pct = _radius_level(0.01)
    fig, ax = plt.subplots(figsize=(7, 4.2))
    a = data[data["source"] == "analytic"]
    ax.plot(a["mu"], 100 * a["radius_difference"], "k-", label="circle radius: μ·r vs r·sin(atan μ)")
    for src, g in groups(data):
        ax.plot(g["mu"], 100 * g["torque_difference"], "o-" if src == "analytic" else "s--",
                label=f"drive torque ({src})", ms=4)
    ax.axhline(1.0, color="grey", ls=":", lw=0.8)
    ax.set_xlabel("friction coefficient μ")
    ax.set_ylabel("small-angle over exact [%]")
    ax.set_title("Friction-circle radius and drive torque (seed E2)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    conclusion = (f"μ·r overstates the friction-circle radius by 1 % from μ = {radius_1pct:.3f} "
                  "(it is √(1 + μ²) times too large); seed E2's drive torque changes by 1 % only "
                  "from μ = " + by_source(found, beyond=f"beyond {mus[-1]:g}")
                  + ", because part of the torque goes to the load and to slide friction, "
                  "which the circle radius does not touch.")
    return StudyResult(
        "friction_angle", "Friction angle", "How far is the small-angle friction circle μ·r from "
        "the exact r·sin(atan μ), and what does that do to the drive torque?", data, png(fig),
        conclusion,
        "Seed E2 slider-crank at θ12 = 55°, crank clockwise, pin radii 50/250/50 mm, slide "
        "friction μ·|N| unchanged. The exact circle is entered as an effective coefficient "
        "sin(atan μ) for the pins; analytic and each simulator (driven slowly) with each.")


def _radius_level(level: float) -> float:
    """μ at which μ / sin(atan μ) − 1 = √(1 + μ²) − 1 reaches ``level``."""
    return math.sqrt((1.0 + level) ** 2 - 1.0)
