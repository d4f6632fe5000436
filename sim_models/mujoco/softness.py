"""MuJoCo's forces as the constraint softness varies (the rigid-joints study): how far a
soft equality constraint leaves the forces from rigid-body statics."""

from __future__ import annotations

import mujoco

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage_backends import analytic_results
from mechcheck.analytic.presets import as_linkage, preset_values
from mechcheck.sim_models.mujoco.linkage import driver_values, seed
from mechcheck.sim_models.mujoco.linkage_rig import LinkageRig
from mechcheck.sim_models.mujoco.model import STATIC, Settings
from mechcheck.sim_models.mujoco.settle import run_until_settled


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
