"""Rigid joints: simulator force error against constraint softness.

MuJoCo's equality constraints are soft (``solref``, ``solimp``); pymunk's
iterative solver converges over steps (``iterations``, ``error_bias``) and
integrates driven motion with a finite step. The study measures how far
each setting leaves the simulators' forces from rigid-body statics and
dynamics (the analytic solution), with the comparison's error measure.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import cast

import pandas as pd

from mechcheck import backends
from mechcheck.analytic.case import Case, Motion
from mechcheck.analytic.solution import Solution
from mechcheck.studies.common import StudyResult, builtin, plt, png, realistic_e1, reference
from mechcheck.tables import comparison_rows


def worst_error(case: Case, values: Mapping[str, float]) -> float:
    """Largest relative error over forces and torques (the comparison's measure)."""
    ref = reference(case)
    sim = Solution(case.name, "study", {q: v for q, v in values.items() if q in ref.values})
    rows = comparison_rows(case, ref, sim)
    return max((cast(float, r["rel_err"]) for r in rows
                if r["quantity"] not in ("theta13", "theta14", "s14")), default=math.nan)


def run(quick: bool = False) -> StudyResult:
    """Seed E1 statics, and E1 with steel links driven, through each installed simulator's
    stiffness experiment (:class:`~mechcheck.sim_models.protocol.Simulator`): one panel and
    one sentence each."""
    case = builtin("seed-E1-as-stated")
    driven_case = realistic_e1(motion=Motion(-10.0, 50.0))
    simulators = [s for s in backends.simulators() if s.available]
    studies = [s.stiffness_study(case, driven_case, quick, worst_error) for s in simulators]
    frames = [pd.DataFrame(study.rows) for study in studies]
    data = pd.concat(frames, ignore_index=True) if frames else pd.DataFrame()
    fig, axes = plt.subplots(1, max(1, len(studies)), figsize=(5.5 * max(1, len(studies)), 4.2),
                             squeeze=False)
    for ax, study, frame in zip(axes[0], studies, frames, strict=False):
        study.draw(ax, frame)
        ax.set_ylabel("worst relative force/torque error")
        ax.axhline(1e-6, color="grey", ls=":", lw=0.8)
        ax.grid(alpha=0.3, which="both")
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7, loc="lower left")
    conclusion = " ".join(study.conclusion(frame) for study, frame in zip(studies, frames,
                                                                           strict=True))
    return StudyResult(
        "rigid_joints", "Rigid joints", "How far do the simulators' soft or iterative "
        "constraints leave the forces from rigid-body mechanics, and which settings close the "
        "gap?", data, png(fig), conclusion,
        "Seed E1 statics at θ12 = 60°. MuJoCo: solimp[0] from 0.9 (default) to 0.9999 with "
        "solref's time constant at its default 0.02 s or at 2·dt, read after one forward pass "
        "at the exact pose (what a user would read) and after settling. pymunk: settled with "
        "1–100 iterations per step at Chipmunk's default error bias and at 0; driven E1 with "
        "steel links at ω = −10 rad/s, α = 50 rad/s² for dt from 1e-3 to 3e-5 s.")
