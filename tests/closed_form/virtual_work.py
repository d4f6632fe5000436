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

from mechcheck.analytic.assembly import unassembled_verdict
from mechcheck.analytic.case import Case
from mechcheck.analytic.kinematics import Array, Pose, as_angles, pose_of
from mechcheck.analytic.solution import Solution

from .equilibrium import JOINT_LINKS, SINGULAR_CONDITION, relative_omega
from .forces import PoseResults, drive_quantity, pose_values

REFUSAL = ("the power (virtual work) method gives the drive torque only for systems without "
           "Coulomb friction: friction power depends on the unknown reactions")


def load_power(case: Case, actual: Pose, virtual: Pose) -> Array:
    """Virtual power of every known load: actual forces times virtual velocities."""
    power = np.zeros(actual.theta12.shape[0])
    for load in case.preset.loads:
        _, v, _ = virtual.point(load.link, load.at)
        power += v @ np.asarray(load.force) + load.torque * virtual.links[load.link].omega
    for m in case.preset.masses:
        _, v, _ = virtual.point(m.link, m.com)
        _, _, acc = actual.point(m.link, m.com)
        power += m.mass * (v @ np.asarray(case.gravity))
        power -= m.mass * np.einsum("ij,ij->i", acc, v)
        power -= m.inertia * actual.links[m.link].alpha * virtual.links[m.link].omega
    if case.preset.friction is not None:
        for joint, c in case.preset.friction.viscous.items():
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
    angles = as_angles(case.preset.theta12 if theta12 is None else theta12)
    actual = pose_of(case, angles)
    virtual = pose_of(case, angles, omega=1.0, alpha=0.0)
    omega_d = virtual.links[case.preset.drive_link].omega
    with np.errstate(divide="ignore", invalid="ignore"):
        return -load_power(case, actual, virtual) / omega_d, omega_d


def transmission_sine(case: Case, pose: Pose) -> Array:
    """|sin μ| per pose: coupler–rocker angle (four-bar) or rod–slide normal (slider-crank)."""
    if pose.s14 is None:
        return np.abs(np.sin(pose.theta13 - pose.theta14))
    return np.abs(np.cos(pose.theta13 - case.preset.ground_angle))


def solve_poses(case: Case, theta12_rad: ArrayLike | None = None) -> PoseResults:
    """The drive torque at each θ12 (rad); NaN where the power equation is singular.

    The power method's own measures of singularity: velocity ratios exist only
    while the loop's velocity equations are regular (sine of the transmission
    angle), and the torque only while the driven link moves (its speed ratio
    to the fastest link). ``condition`` holds the reciprocal of the smaller.
    """
    # A pose that does not assemble is NaN by design (its verdict is no_solution):
    # the arithmetic on it must not warn.
    with np.errstate(invalid="ignore", divide="ignore"):
        if case.has_coulomb_friction:
            raise ValueError(REFUSAL)
        angles = as_angles(case.preset.theta12 if theta12_rad is None else theta12_rad)
        torque, omega_d = drive_torque(case, angles)
        pose = pose_of(case, angles, omega=0.0, alpha=0.0)
        virtual = pose_of(case, angles, omega=1.0, alpha=0.0)
        speeds = [np.abs(virtual.links[k].omega) for k in (2, 3, 4)]
        if virtual.s14_dot is not None:
            speeds.append(np.abs(virtual.s14_dot) / case.scale)
        ratio = np.abs(omega_d) / np.max(speeds, axis=0)
        with np.errstate(divide="ignore"):
            condition = 1.0 / np.minimum(ratio, transmission_sine(case, pose))
        condition = np.where(np.isfinite(condition) & np.isfinite(torque), condition, np.inf)
        torque = np.where(condition <= SINGULAR_CONDITION, torque, np.nan)
        values = pose_values(case, pose) | {drive_quantity(case): torque}
        n = angles.shape[0]
        return PoseResults(angles, values, condition, np.zeros(n, dtype=int), np.ones(n, dtype=bool))


def solve(case: Case) -> Solution:
    """The ``virtual_work`` backend: the drive torque alone, plus the pose."""
    if not case.is_preset:
        raise TypeError(f"case {case.name!r} is a linkage: it has no closed form")
    if case.has_coulomb_friction:
        return Solution(case.name, "virtual_work", {}, status="not_applicable", message=REFUSAL)
    start = time.perf_counter()
    results = solve_poses(case)
    values = {q: float(v[0]) for q, v in results.values.items()}
    diagnostics: dict[str, float | str] = {
        "method": "power equation", "condition_number": float(results.condition[0]),
        "wall_time_s": time.perf_counter() - start,
    }
    if not np.isfinite(values["theta13"]):
        status, message = unassembled_verdict(case, case.preset.theta12)
        return Solution(case.name, "virtual_work", {}, status=status, message=message,
                        diagnostics=diagnostics)
    if results.singular[0]:
        del values[drive_quantity(case)]
        return Solution(case.name, "virtual_work", values, status="singular",
                        message="toggle, change or dead point: the velocity ratios or the driven "
                                "link's speed vanish, so the power equation cannot fix the torque",
                        diagnostics=diagnostics)
    return Solution(case.name, "virtual_work", values, diagnostics=diagnostics)
