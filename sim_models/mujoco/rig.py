"""Loads into MuJoCo and forces out of it, for the rig of any linkage
(:class:`.linkage_rig.LinkageRig`, the four-bar and slider-crank among them).

Forces are read from MuJoCo's own state only:

- a driver's effort is the force of its joint equality (its Jacobian row is +1 on the
  driven joint, so the force *is* the generalized force on that joint);
- a loop-closing joint's reaction is the force of its ``connect``;
- a tree joint's reaction comes from ``cfrc_int`` after ``mj_rnePostConstraint``: the
  spatial force of the parent body on the child, whose moment MuJoCo refers to the
  subtree's centre of mass, shifted to the joint point
  (:meth:`.linkage_rig.LinkageRig.values`).

Carried constraint forces (settled statics, :mod:`.settle`). A soft constraint
holds a force f only with a violation r ∝ R·f (R its regulariser), so the
settled mechanism is bent by nanometres; next to a change point the forces are
so sensitive to the pose that this costs 2e-5 of them (seed E1 at θ12 = 179°,
condition number 119; the error grows as the cube of the condition number).
:meth:`.linkage_rig.LinkageRig.carry` therefore moves the constraint forces of a settled state out
of the constraints into explicit loads — each loop force as an equal and
opposite pair at its two sites (``xfrc_applied``, so ``cfrc_int`` sees it),
each holding effort on its held joint (a joint force, which is what a drive
is) — and the mechanism settles again: the constraints now hold only what is
left, and their violation, and the bending, shrink with it. Every reported
force is the carried part plus MuJoCo's current ``efc_force``.

A driven run may give the driven hinge an armature (:data:`.model.Settings`
``drive_armature``); its torque I_a·q̈ is then part of the equality's force
and is subtracted, with MuJoCo's own q̈, from the driver's effort.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]


@dataclass
class LoadTable:
    """Every external load as arrays: site (point), body, global force, pure moment."""

    sites: NDArray[np.int_]
    bodies: NDArray[np.int_]
    forces: Array   # (k, 3)
    torques: Array  # (k,)


def rows_times(a: Array, m: Array) -> Array:
    """``a @ m.T`` for a batch of rows ``a`` (…, k), each row's products summed in one order
    whatever the batch (numpy's einsum does not call BLAS). A matrix product through BLAS
    rounds a row by the rows batched with it, and a settled sweep's reads batch poses as
    they end their passes: measured, the Watt six-bar's 360-pose sweep read one pose 2e-16
    apart when its poses were batched otherwise; with this, bit for bit the same."""
    return np.einsum("...j,kj->...k", a, m)


def cross_z(r: Array, f: Array) -> Array:
    """z-component of r × f for arrays of (.., ≥2) vectors."""
    return r[..., 0] * f[..., 1] - r[..., 1] * f[..., 0]


def load_wrenches(site_xpos: Array, xipos: Array, loads: LoadTable, incidence: Array,
                  body_forces: Array) -> Array:
    """(N, nbody, 6): each body's loads for N states (``site_xpos``, ``xipos`` of each):
    ``body_forces`` (summed through ``incidence``) and, about z, their moments about the
    body's centre of mass from the site positions plus the loads' own couples.

    MuJoCo applies xfrc_applied at the body's centre of mass, so a force at p carries
    the moment (p − x_com) × F. Loads given as qfrc_applied would be invisible to
    cfrc_int (SIMULATORS.md).
    """
    out = np.zeros((site_xpos.shape[0], body_forces.shape[0], 6))
    out[:, :, 0:3] = body_forces  # planar: no moments about x or y
    if loads.sites.size:
        arm = site_xpos[:, loads.sites] - xipos[:, loads.bodies]
        out[:, :, 5] = rows_times(cross_z(arm, loads.forces) + loads.torques, incidence)
    return out
