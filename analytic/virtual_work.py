"""The ``virtual_work`` backend: the drive torque from the power equation.

    T·ω_d + Σ F·v_P + Σ τ·ω + Σ m g·v_G − Σ m a_G·v_G − Σ I_G α ω + P_viscous = 0

with velocities from the kinematics. For a static case the velocities are
virtual: a unit input speed gives the velocity ratios. No reaction appears,
so this method gives the drive torque alone, and it cannot account for
Coulomb friction (whose power depends on the reactions).
"""

from __future__ import annotations

import time

import numpy as np
from numpy.typing import ArrayLike

from analytic.case import Case
from analytic.equilibrium import JOINT_LINKS, SINGULAR_CONDITION, relative_omega
from analytic.forces import drive_quantity, pose_values
from analytic.kinematics import Array, Pose, as_angles, pose_of
from analytic.solution import Solution

REFUSAL = ("the power (virtual work) method gives the drive torque only for systems without "
           "Coulomb friction: friction power depends on the unknown reactions")


def load_power(case: Case, actual: Pose, virtual: Pose) -> Array:
    """Virtual power of every known load: actual forces times virtual velocities."""
    power = np.zeros(actual.theta12.shape[0])
    for load in case.loads:
        _, v, _ = virtual.point(load.link, load.at)
        power += v @ np.asarray(load.force) + load.torque * virtual.links[load.link].omega
    for m in case.masses:
        _, v, _ = virtual.point(m.link, m.com)
        _, _, acc = actual.point(m.link, m.com)
        power += m.mass * (v @ np.asarray(case.gravity))
        power -= m.mass * np.einsum("ij,ij->i", acc, v)
        power -= m.inertia * actual.links[m.link].alpha * virtual.links[m.link].omega
    if case.friction is not None:
        for joint, c in case.friction.viscous.items():
            if joint == "slide":
                assert actual.s14_dot is not None and virtual.s14_dot is not None
                power -= c * actual.s14_dot * virtual.s14_dot
            elif joint in JOINT_LINKS:
                power -= c * relative_omega(actual, joint) * relative_omega(virtual, joint)
    return power


def drive_torque(case: Case, theta12: ArrayLike | None = None) -> tuple[Array, Array]:
    """(T, ω_d): the drive torque and the virtual speed of the driven link (unit ω2).

    ω_d → 0 (a rocker dead point with drive_link = 4) makes T singular.
    """
    angles = as_angles(case.theta12 if theta12 is None else theta12)
    actual = pose_of(case, angles)
    virtual = pose_of(case, angles, omega=1.0, alpha=0.0)
    omega_d = virtual.links[case.drive_link].omega
    with np.errstate(divide="ignore", invalid="ignore"):
        return -load_power(case, actual, virtual) / omega_d, omega_d


def transmission_sine(case: Case, pose: Pose) -> float:
    """|sin μ|: coupler–rocker angle (four-bar) or rod–slide normal (slider-crank)."""
    if pose.s14 is None:
        return abs(float(np.sin(pose.theta13[0] - pose.theta14[0])))
    return abs(float(np.cos(pose.theta13[0] - case.ground_angle)))


def solve(case: Case) -> Solution:
    """The ``virtual_work`` backend: the drive torque alone, plus the pose."""
    if case.has_coulomb_friction:
        return Solution(case.name, "virtual_work", {}, status="not_applicable", message=REFUSAL)
    start = time.perf_counter()
    torque, omega_d = drive_torque(case)
    pose = pose_of(case, omega=0.0, alpha=0.0)
    values = {q: float(v[0]) for q, v in pose_values(case, pose).items()}
    # The power method's own measures of singularity: the velocity ratios exist
    # only while the loop's velocity equations are regular (sine of the
    # transmission angle), and the torque only while the driven link moves.
    virtual = pose_of(case, omega=1.0, alpha=0.0)
    transmission = transmission_sine(case, pose)
    ratios = [abs(float(virtual.links[k].omega[0])) for k in (2, 3, 4)]
    if virtual.s14_dot is not None:
        ratios.append(abs(float(virtual.s14_dot[0])) / case.geometry.scale)
    ratio = abs(float(omega_d[0])) / max(ratios)
    diagnostics: dict[str, float | str] = {
        "method": "power equation", "drive_speed_ratio": ratio,
        "transmission_sine": transmission,
        "wall_time_s": time.perf_counter() - start,
    }
    if (not np.isfinite(torque[0]) or ratio < 1.0 / SINGULAR_CONDITION
            or transmission < 1.0 / SINGULAR_CONDITION):
        return Solution(case.name, "virtual_work", values, status="singular",
                        message="toggle, change or dead point: the velocity ratios or the driven "
                        "link's speed vanish, so the power equation cannot fix the torque",
                        diagnostics=diagnostics)
    values[drive_quantity(case)] = float(torque[0])
    return Solution(case.name, "virtual_work", values, diagnostics=diagnostics)
