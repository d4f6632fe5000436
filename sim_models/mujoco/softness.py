"""MuJoCo's forces as the constraint softness varies (the rigid-joints study): how far a
soft equality constraint leaves the forces from rigid-body statics."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import mujoco

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage_backends import analytic_results
from mechcheck.analytic.presets import as_linkage, preset_values
from mechcheck.sim_models.mujoco.linkage import driver_values, seed
from mechcheck.sim_models.mujoco.linkage_rig import LinkageRig
from mechcheck.sim_models.mujoco.model import STATIC, Settings
from mechcheck.sim_models.mujoco.settle import run_until_settled
from mechcheck.sim_models.protocol import ErrorOf, StiffnessStudy

if TYPE_CHECKING:
    import pandas as pd
    from matplotlib.axes import Axes


def forces_at_softness(case: Case, timeconst: float | None,
                       solimp0: float) -> tuple[dict[str, float], dict[str, float]]:
    """The forces of a static case read after one forward pass at the exact pose, and after
    settling, with ``solref`` time constant ``timeconst`` (None: the stiffest, 2·dt) and
    ``solimp[0] = solimp0`` (``solimp[1]`` at least 0.95, the rest as the backend's); a
    four-bar or slider-crank under its own quantity names."""
    settings = Settings(solref_timeconst=timeconst,
                        solimp=(solimp0, max(solimp0, 0.95), *STATIC.solimp[2:]))
    linkage = as_linkage(case) if case.is_preset else case
    qpos = LinkageRig(linkage, settings).joint_states(analytic_results(linkage).pose)[0][0]

    def seeded() -> LinkageRig:
        rig = LinkageRig(linkage, settings)
        seed(rig, qpos, driver_values(linkage))
        return rig

    rig = seeded()
    mujoco.mj_forward(rig.model, rig.data)
    rig.apply_loads()  # loads are read by the next forward pass
    mujoco.mj_forward(rig.model, rig.data)
    first, settled = rig.read(), run_until_settled(seeded()).values
    if case.is_preset:
        return preset_values(case, first), preset_values(case, settled)
    return first, settled


#: MuJoCo's own defaults: solref = (0.02, 1), solimp[0] = 0.9.
DEFAULT_TIMECONST = 0.02
SOLIMP = (0.9, 0.99, 0.999, 0.9999)


def stiffness_study(case: Case, driven: Case, quick: bool,
                    error_of: ErrorOf) -> StiffnessStudy:
    """MuJoCo's part of the rigid-joints study: the static ``case`` read after one forward
    pass at the exact pose and after settling, at each solimp[0] with solref's time constant
    at its default and at 2·dt (``driven`` is not used: the soft constraint is the
    question)."""
    rows: list[dict[str, object]] = []
    for timeconst, label in ((DEFAULT_TIMECONST, "solref 0.02 (default)"),
                             (None, "solref 2·dt (stiffest)")):
        for d0 in SOLIMP[::3] if quick else SOLIMP:
            first, settled = forces_at_softness(case, timeconst, d0)
            for reading, values in (("one forward pass", first), ("settled", settled)):
                rows.append({"simulator": "mujoco", "setting": label, "parameter": "solimp[0]",
                             "value": d0, "reading": reading, "error": error_of(case, values)})
    return StiffnessStudy(rows, _draw, _conclusion)


def _draw(ax: Axes, data: pd.DataFrame) -> None:
    for key, g in data.groupby(["setting", "reading"], sort=False):
        setting, reading = (str(k) for k in key)
        ax.loglog(1.0 - g["value"], g["error"].clip(lower=1e-17),
                  "o-" if reading == "settled" else "s--", label=f"{setting}, {reading}", ms=4)
    ax.set_xlabel("1 − solimp[0] (softness at zero violation)")
    ax.set_title("MuJoCo: constraint softness")
    ax.invert_xaxis()


def _conclusion(data: pd.DataFrame) -> str:
    def pick(setting: str, reading: str, value: float) -> float:
        rows = data[(data["setting"] == setting) & (data["reading"] == reading)
                    & ((data["value"] - value).abs() < 1e-12)]
        return float(rows["error"].iloc[0]) if len(rows) else math.nan

    default_first = pick("solref 0.02 (default)", "one forward pass", 0.9)
    stiff_first = pick("solref 2·dt (stiffest)", "one forward pass", 0.9999)
    stiff_settled = pick("solref 2·dt (stiffest)", "settled", 0.9999)
    return (f"MuJoCo's default softness misses rigid statics by {100 * default_first:.3g} % on "
            f"one forward pass; the stiffest settings (solimp 0.9999, solref 2·dt) leave "
            f"{100 * stiff_first:.2g} % on one pass and {stiff_settled:.1e} once settled.")
