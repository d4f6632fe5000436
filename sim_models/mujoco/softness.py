"""MuJoCo's forces as the constraint softness varies (the rigid-joints study): how far a
soft equality constraint leaves the forces from rigid-body statics."""

from __future__ import annotations

import mujoco

from mechcheck.analytic.case import Case
from mechcheck.sim_models.mujoco.model import STATIC, Settings
from mechcheck.sim_models.mujoco.rig import Rig
from mechcheck.sim_models.mujoco.settle import run_until_settled, seed_at


def forces_at_softness(case: Case, timeconst: float | None,
                       solimp0: float) -> tuple[dict[str, float], dict[str, float]]:
    """The forces of a static case read after one forward pass at the exact pose, and after
    settling, with ``solref`` time constant ``timeconst`` (None: the stiffest, 2·dt) and
    ``solimp[0] = solimp0`` (``solimp[1]`` at least 0.95, the rest as the backend's)."""
    settings = Settings(solref_timeconst=timeconst,
                        solimp=(solimp0, max(solimp0, 0.95), *STATIC.solimp[2:]))
    rig = Rig(case, settings)
    seed_at(rig, case.theta12)
    mujoco.mj_forward(rig.model, rig.data)
    rig.apply_loads()  # loads are read by the next forward pass
    mujoco.mj_forward(rig.model, rig.data)
    first = rig.read()
    rig = Rig(case, settings)
    seed_at(rig, case.theta12)
    return first, run_until_settled(rig).values
