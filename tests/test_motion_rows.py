"""The trajectory reference's vectorised terms against the engine's general per-joint code,
at random states of every built-in linkage: the constraint rows (``analytic/motion_rows.py``)
against :func:`constraint_system` and :func:`quadratic_terms`, and the mass matrix and forces
(``analytic/motion_terms.py``) against the known forces of the member-equilibrium equations
(:func:`known_vector`, D'Alembert inertia included), through the power they do on any
motion: known_vector·v_O = (F − 𝕄·q̈)·v for every v (the virtual-work identity, the forces
reduced to the origin on one side and to each link's coordinates on the other)."""

from __future__ import annotations

import dataclasses
from functools import cache
from pathlib import Path

import numpy as np
import pytest

import mechcheck
from mechcheck.analytic.case import Case
from mechcheck.analytic.linalg import FEW_POSES, Batched
from mechcheck.analytic.linkage import JointFriction, Linkage
from mechcheck.analytic.linkage_dynamics import origin_velocities
from mechcheck.analytic.linkage_kinematics import LinkagePose, constraint_system, quadratic_terms
from mechcheck.analytic.linkage_loads import known_vector
from mechcheck.analytic.motion_rows import joint_rows
from mechcheck.analytic.motion_terms import terms
from mechcheck.analytic.rigid import Constraints, Layout, joint_rows as starts_of
from mechcheck.casefile import load_cases

CASES = Path(mechcheck.__file__).parent / "cases"
#: Two computations of the same sums in another order: rounding of the largest term.
ROUNDING = 1e-12


@cache
def linkages() -> dict[str, Case]:
    files = sorted(CASES.rglob("*.toml"))
    found: dict[str, Case] = {}
    for case in load_cases(*files):
        if case.linkage.moving_links:
            found.setdefault(case.name, case)
    return found


def random_state(case: Case, seed: int) -> tuple[np.ndarray, ...]:
    rng = np.random.default_rng(seed)
    n = 3 * len(case.linkage.moving_links)
    size = case.linkage.scale
    scales = np.tile([size, size, 1.0], n // 3)
    return tuple(rng.normal(size=n) * scales for _ in range(4))


@pytest.mark.parametrize("name", sorted(linkages()))
def test_rows_are_the_joints_own(name: str) -> None:
    case = linkages()[name]
    linkage = case.linkage
    rows = joint_rows(linkage)
    for seed in range(3):
        q, qdot, _, _ = random_state(case, seed)
        state = rows.at(q)
        targets = np.zeros((1, len(linkage.drivers)))
        phi, jac = constraint_system(linkage, q[None, :], targets)
        gamma = quadratic_terms(linkage, q[None, :], qdot[None, :])[0]
        dense = jac.dense()[0]
        np.testing.assert_allclose(state.phi, phi[0], rtol=0,
                                   atol=ROUNDING * max(1.0, np.abs(phi).max()))
        np.testing.assert_allclose(rows.dense(state), dense, rtol=0,
                                   atol=ROUNDING * max(1.0, np.abs(dense).max()))
        np.testing.assert_allclose(rows.quadratic(state, qdot), gamma, rtol=0,
                                   atol=ROUNDING * max(1.0, np.abs(gamma).max()))
        residual_only = rows.at(q, jacobian=False)
        np.testing.assert_array_equal(residual_only.phi, state.phi)


@pytest.mark.parametrize("name", sorted(linkages()))
@pytest.mark.parametrize("poses", [3, FEW_POSES + 1])
def test_pins_at_once_are_the_kinds_own_rows(name: str, poses: int) -> None:
    """The statics write the rows a kind declares as one ``coincide`` (its ``plan``) for
    every pin at once: the same numbers as each joint's kind writes with its own
    ``constrain``, joint by joint, at a few poses (the carried points) and at many."""
    case = linkages()[name]
    linkage = case.linkage
    q = np.array([random_state(case, seed)[0] for seed in range(poses)])
    phi, jac = constraint_system(linkage, q, np.zeros((poses, 0)), drivers=False)
    layout = Layout(linkage)
    own = Constraints(layout, q, np.zeros((poses, layout.joint_rows)),
                      Batched(layout.joint_rows, layout.size, poses))
    for joint, row in zip(linkage.joints, starts_of(linkage).values(), strict=True):
        joint.kind.constrain(own, joint, row)
    np.testing.assert_array_equal(phi, own.phi)
    np.testing.assert_array_equal(jac.dense(), own.jac.dense())


def damped(linkage: Linkage) -> Linkage:
    """The linkage with a damper on every spring and viscous friction at every joint that
    takes it (none of the built-in files has both)."""
    springs = tuple(dataclasses.replace(s, damping=0.3 * s.stiffness + 0.1) for s in linkage.springs)
    viscous = {j.name: 0.2 for j in linkage.joints if j.kind.frictional}
    friction = dataclasses.replace(linkage.friction or JointFriction(), viscous=viscous)
    return dataclasses.replace(linkage, springs=springs, friction=friction)


@pytest.mark.parametrize("damping", [False, True])
@pytest.mark.parametrize("name", sorted(linkages()))
def test_mass_matrix_and_forces_do_the_known_forces_power(name: str, damping: bool) -> None:
    case = linkages()[name]
    linkage = damped(case.linkage) if damping else case.linkage
    own = terms(linkage)
    for seed in range(3):
        q, qdot, qddot, v = random_state(case, seed)
        angles = np.append(q[2::3], 0.0)
        cos, sin = np.cos(angles), np.sin(angles)
        forces = own.forces(q, qdot, cos, sin)
        mine = (forces.total - own.mass_times(cos, sin, qddot[:, None])[:, 0]) @ v
        pose = LinkagePose(linkage, np.zeros((1, len(linkage.drivers))), q[None, :],
                           qdot[None, :], qddot[None, :], np.full(1, np.nan))
        known = known_vector(pose)[0]
        theirs = known @ origin_velocities(q, v[:, None])[:, 0]
        scale = np.abs(known).max(initial=1.0) * np.abs(v).max() * max(1.0, np.abs(q).max())
        assert abs(mine - theirs) <= ROUNDING * scale * len(v)
