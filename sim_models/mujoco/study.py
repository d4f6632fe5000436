"""How far MuJoCo's default constraint softness is from rigid-body statics.

For each seed case and each softness (MuJoCo's defaults solref = (0.02, 1),
solimp = (0.9, 0.95, …) vs the stiffened settings used by the backends,
solref = (2·dt, 1), solimp = 0.9999), two readings are compared with the
analytic forces:

- ``one forward``: one ``mj_forward`` at rest in the exact analytic pose, as a
  user would read ``efc_force`` — the soft solver returns only part of the
  rigid force when nothing has moved yet;
- ``settled``: one settling pass (:func:`.settle.run_until_settled`) with that
  softness — without the backend's refinement passes, which carry the
  constraint forces and so remove most of the softness's effect.

The error is max |sim − ref| over the reactions (N) relative to the largest
reaction, and |ΔT12|/|T12|, in percent.
"""

from __future__ import annotations

import mujoco

from analytic.case import Case
from analytic.forces import solve
from sim_models.mujoco.model import MUJOCO_DEFAULT_SOFTNESS, STATIC, Settings
from sim_models.mujoco.rig import Rig
from sim_models.mujoco.settle import run_until_settled, seed_at

SOFTNESS = {"MuJoCo default": MUJOCO_DEFAULT_SOFTNESS, "stiffened (this backend)": STATIC}


def percent_errors(case: Case, values: dict[str, float]) -> tuple[float, float]:
    """(largest reaction error, drive-torque error), percent."""
    ref = solve(case).values
    forces = [q for q in ref if q.startswith("F")]
    scale = max(abs(ref[q]) for q in forces)
    force_err = max(abs(values[q] - ref[q]) for q in forces) / scale
    torque = f"T1{case.drive_link}"
    return 100.0 * force_err, 100.0 * abs(values[torque] - ref[torque]) / abs(ref[torque])


def one_forward(case: Case, settings: Settings) -> dict[str, float]:
    """Forces MuJoCo reports after a single forward pass at the exact pose, at rest."""
    rig = Rig(case, settings)
    seed_at(rig, case.theta12)
    mujoco.mj_forward(rig.model, rig.data)
    rig.apply_loads()
    mujoco.mj_forward(rig.model, rig.data)
    return rig.read()


def stiffness_study(cases: list[Case]) -> list[dict[str, float | str]]:
    """One row per (case, softness, reading) with the errors in percent.

    The seed cases come from the built-in case files (loaded by the caller:
    ``sim_models`` does not depend on ``compare``).
    """
    rows: list[dict[str, float | str]] = []
    for case in cases:
        for label, settings in SOFTNESS.items():
            rig = Rig(case, settings)
            seed_at(rig, case.theta12)
            settled = run_until_settled(rig)
            for reading, values, steps in (("one forward", one_forward(case, settings), 1),
                                           ("settled", settled.values, settled.steps)):
                force_err, torque_err = percent_errors(case, values)
                rows.append({"case": case.name, "softness": label, "reading": reading,
                             "steps": steps, "force_error_pct": force_err,
                             "torque_error_pct": torque_err})
    return rows


def markdown_table(rows: list[dict[str, float | str]]) -> str:
    """The study as a Markdown table."""
    lines = ["| case | softness | reading | steps | reaction error % | T12 error % |",
             "|---|---|---|---:|---:|---:|"]
    for r in rows:
        lines.append(f"| {r['case']} | {r['softness']} | {r['reading']} | {r['steps']} | "
                     f"{r['force_error_pct']:.3g} | {r['torque_error_pct']:.3g} |")
    return "\n".join(lines)
