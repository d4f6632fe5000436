"""A linkage's compiled model and data: put it in a pose, apply the loads, read the forces
back in the quantities of LINKAGES.md, with the interface :mod:`.settle` drives (loads in
and forces out: :mod:`.rig`). Built in three parts: the model and where everything is in
it (:mod:`.linkage_build`), the loads (:mod:`.linkage_loads`), the read-out
(:mod:`.linkage_readout`).
"""

from __future__ import annotations

from mechcheck.sim_models.mujoco.linkage_build import Array
from mechcheck.sim_models.mujoco.linkage_loads import CarriedPairs, RigLoads
from mechcheck.sim_models.mujoco.linkage_readout import ReadPlan, RigReadout, Snapshot, one_state

__all__ = ["Array", "CarriedPairs", "LinkageRig", "ReadPlan", "Snapshot", "one_state"]


class LinkageRig(RigLoads, RigReadout):
    """One linkage Case's compiled model and data, with loads, pose and force read-out."""
