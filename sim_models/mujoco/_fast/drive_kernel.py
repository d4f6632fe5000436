"""A driven run's steps and readings in numba (:func:`..linkage_dynamics.read_stretch`;
imported through :func:`mechcheck.sim_models.compiled.kernel` only where numba is installed).

Step for step it does what the Python loop does (:func:`..linkage_dynamics.plain_stretch`):
MuJoCo's position stage, the loads at the positions it found
(:class:`..linkage_dynamics.PointLoads`, the same sums in the same order), the rest of the
forward pass, an Euler step; at each reading a forward pass, ``mj_rnePostConstraint`` and
the read-out's arrays copied out. Only the interpreter's per-step overhead is gone.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from mechcheck.sim_models.mujoco._fast.exact_kernel import capture
from mechcheck.sim_models.mujoco._fast.plans import DrivePlan, MjCalls


@njit(nogil=True, cache=True)
def loaded_forward(mj: MjCalls, p: DrivePlan, moments: np.ndarray) -> None:
    """A forward pass with the loads at the current positions: the position stage, the
    loads' xfrc_applied from its site and centre positions, the stages after it."""
    mj.fwd_position(mj.m, mj.d)
    moments[:] = 0.0
    for i in range(p.sites.size):
        site, body = p.sites[i], p.bodies[i]
        arm_x = p.d_sites[site, 0] - p.d_centres[body, 0]
        arm_y = p.d_sites[site, 1] - p.d_centres[body, 1]
        moments[body] += (arm_x * p.fy[i] - arm_y * p.fx[i]) + p.torques[i]
    p.d_xfrc[:] = p.base
    for b in range(moments.size):
        p.d_xfrc[b, 5] = p.base[b, 5] + moments[b]
    mj.forward_skip(mj.m, mj.d, p.skip_position, 0)


@njit(nogil=True, cache=True)
def drive(mj: MjCalls, p: DrivePlan) -> None:
    """``p.steps[k]`` steps, then reading k, for every k (:func:`.exact_kernel.capture`
    into row k)."""
    moments = np.zeros(p.base.shape[0])
    for k in range(p.steps.size):
        for _ in range(p.steps[k]):
            loaded_forward(mj, p, moments)
            mj.euler(mj.m, mj.d)
        loaded_forward(mj, p, moments)
        mj.rne(mj.m, mj.d)
        capture(p.capture, k)
