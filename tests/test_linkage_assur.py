"""The closed-form Assur-group path (analytic/linkage_assur.py, linkage_statics.py) against
the general engine's other methods (through solve_linkage, which takes the group path for
a static linkage that decomposes): positions against Newton continuation from the drawn
pose, statics against the dense member-equilibrium solve with its SVD condition number, on
every built-in linkage that decomposes and on random ones. Locks are also checked against
the law of cosines."""

from __future__ import annotations

import math
import pickle
from dataclasses import replace
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings

import mechcheck
from mechcheck import load_cases
from mechcheck.analytic.case import CaseError
from mechcheck.analytic.linkage import Linkage
from mechcheck.analytic.linkage_assur import Crank, Dyad, path
from mechcheck.analytic.linkage_forces import (
    SINGULAR_CONDITION,
    coefficient_matrix,
    condition,
    force_quantities,
    pose_quantities,
    solve_linkage,
)
from mechcheck.analytic.linkage_kinematics import (
    LinkagePose,
    continuation_positions,
    solve_batched,
)
from mechcheck.analytic.linkage_loads import known_vector
from mechcheck.casefile import builtin_case_files, linkage_case
from mechcheck.linkage_file import LinkageCaseSpec

from .strategies import MAX_CONDITION, linkage_tables

#: Two methods for the same equations: rounding only (the tolerance policy's analytic 1e-9),
#: relative to each quantity's scale over the sweep.
RTOL = 1e-9
LINKAGES = {c.name: c.linkage for c in load_cases(*builtin_case_files())
            if c.mechanism == "linkage"}
#: Linkages whose statics go group by group (Coulomb friction is solved densely, at the
#: plan's poses: tests/test_linkage_rrp.py checks those).
PLANNED = sorted(name for name, linkage in LINKAGES.items()
                 if linkage.assur_plan is not None and not linkage.has_coulomb_friction)
#: Seed E1 is drawn to 1e-8 mm at a change point (a2 + a1 = a3 + a4 to rounding): at
#: θ12 = 180° its circles miss by ~1e-11 m over 0.0018°, where the continuation's 2° steps
#: may step over the gap; its sweeps stop short of it (see the lock test below).
SPAN = {"e1-linkage": (-235.0, 115.0), "e1-linkage-seed-sign": (-235.0, 115.0),
        "e1-linkage-driven-from-90": (-265.0, 85.0)}


def static(linkage: Linkage) -> Linkage:
    return replace(linkage, drivers=tuple(replace(d, velocity=0.0, acceleration=0.0)
                                          for d in linkage.drivers))


def sweep(name: str, count: int = 77) -> np.ndarray:
    lo, hi = SPAN.get(name, (-380.0, 380.0))
    return np.radians(np.linspace(lo, hi, count))[:, None]


def dense_statics(linkage: Linkage, values: np.ndarray) -> tuple[dict[str, np.ndarray],
                                                                  np.ndarray, LinkagePose]:
    """The general method: continuation positions, the dense K x = −b, the SVD condition."""
    q, locked = continuation_positions(linkage, values)
    rest = np.zeros_like(q)
    rest[~np.isfinite(q).all(axis=1)] = np.nan
    pose = LinkagePose(linkage, values, q, rest, rest.copy(), locked)
    k = coefficient_matrix(pose)
    cond = condition(pose, k)
    with np.errstate(all="ignore"):
        x = solve_batched(k, -known_vector(pose))
    x[~(cond <= SINGULAR_CONDITION)] = np.nan
    return pose_quantities(pose) | force_quantities(pose, x, []), cond, pose


def assert_same_statics(linkage: Linkage, values: np.ndarray) -> None:
    """Every quantity, NaN pattern, lock fraction and singular verdict of the group-by-group
    statics equals the dense method's (1e-9 of each quantity's scale, where cond < 1e4)."""
    fast = solve_linkage(linkage, values)
    assert linkage.assur_plan is not None and not linkage.is_moving
    expected, cond, pose = dense_statics(linkage, values)
    assembled = np.isfinite(cond)
    assert np.array_equal(fast.pose.assembled, assembled)
    assert np.allclose(fast.pose.locked_at, pose.locked_at, rtol=RTOL, atol=0.0, equal_nan=True)
    scale = np.tile([linkage.scale, linkage.scale, 1.0], len(linkage.moving_links))
    assert np.nanmax(np.abs(fast.pose.q - pose.q) / scale, initial=0.0) <= RTOL
    assert np.array_equal(fast.singular, ~(cond <= SINGULAR_CONDITION) & assembled)
    assert list(fast.values) == list(expected)
    tame = cond < MAX_CONDITION
    for name, want in expected.items():
        got = fast.values[name]
        assert np.array_equal(np.isnan(got), np.isnan(want)), name
        if not tame.any():
            continue
        scale = max(float(np.nanmax(np.abs(want[tame]), initial=0.0)), 1e-2)
        if name.startswith(("phi_", "q_")):
            scale = 1.0
        assert np.nanmax(np.abs(got[tame] - want[tame]), initial=0.0) <= RTOL * scale, name


def test_the_built_in_six_bars_decompose_into_a_crank_and_two_dyads() -> None:
    """Watt II: crank O2, dyad (coupler, rocker), then dyad (link5, output) hung from the
    rocker's C; the slider-crank is a crank and an RRP dyad (rod, slider); linkages with a
    slide in the middle of a dyad, two drivers or a free coordinate do not decompose."""
    plan = LINKAGES["watt-ii-demo"].assur_plan
    assert plan is not None
    kinds = [(type(g).__name__, g.link if isinstance(g, Crank) else g.links) for g in plan.groups]
    assert kinds == [("Crank", "crank"), ("Dyad", ("coupler", "rocker")),
                     ("Dyad", ("link5", "output"))]
    dyad = plan.groups[2]
    assert isinstance(dyad, Dyad) and dyad.bodies == ("rocker", "ground")
    slider = LINKAGES["e2-linkage-frictionless"].assur_plan
    assert slider is not None and [type(g).__name__ for g in slider.groups] == ["Crank", "SlideDyad"]
    for name in ("crank-shaper", "boom-raise", "five-bar-two-drivers", "exam-q1-slider-bar"):
        assert LINKAGES[name].assur_plan is None


@pytest.mark.parametrize("name", PLANNED)
def test_group_statics_equal_the_dense_method(name: str) -> None:
    """Over ±380° of the driver (more than a turn each way, through the locks), static:
    the continuation's poses (1e-9 of the size; angles, whole turns included, to 1e-9 rad)
    and lock fractions, and every reaction, effort, spring force and singular and
    no_solution verdict as the dense solve gives them."""
    assert_same_statics(static(LINKAGES[name]), sweep(name))


def test_the_seed_fourbar_locks_at_its_change_point_by_the_law_of_cosines() -> None:
    """Seed E1 (a1 = 140, a2 = 40 mm, A drawn at 60°): |A B0| = a3 + a4 at the crank angle
    θ with cos θ = (a1² + a2² − (a3 + a4)²)/(2 a1 a2), just short of 180°; the closed form
    locks there, 120° − ε on from the drawn pose."""
    linkage = LINKAGES["e1-linkage"]
    p = linkage.points
    a1, a2 = math.dist(p["A0"], p["B0"]), math.dist(p["A0"], p["A"])
    stretched = math.dist(p["A"], p["B"]) + math.dist(p["B"], p["B0"])
    theta = math.acos((a1 * a1 + a2 * a2 - stretched**2) / (2 * a1 * a2))
    route = path(linkage.assur_plan, np.radians([150.0]))  # type: ignore[arg-type]
    assert route.hi == pytest.approx(theta - math.radians(60.0), abs=1e-9)
    assert 0.0 < math.pi - theta < math.radians(0.01)


def test_a_plan_keeps_the_paths_it_traced() -> None:
    """A second sweep over the same span of nodes gets the path the first traced (the
    plan's memo), and it is the path a fresh plan traces: the same lock and the same
    continuous angles, to the bit; a longer span is traced anew."""
    linkage = LINKAGES["e1-linkage"]
    plan = linkage.assur_plan
    assert plan is not None
    values = np.radians(np.linspace(-40.0, 150.0, 77))
    first = path(plan, values)
    assert path(plan, values[::-1].copy()) is first
    fresh = path(replace(linkage).assur_plan, values)  # type: ignore[arg-type]
    assert fresh is not first and (fresh.lo, fresh.hi) == (first.lo, first.hi)
    for link, angles in first.node_angles.items():
        assert np.array_equal(angles, fresh.node_angles[link], equal_nan=True)
    assert path(plan, np.radians([-60.0, 150.0])) is not first


def test_singular_verdicts_next_to_a_lock_follow_the_exact_condition_number() -> None:
    """Approaching the locking four-bar's toggle to within 1e-15 rad, where the cheap bound
    cannot decide: each verdict is the dense SVD's, condition > 1e8 or not, at that pose."""
    linkage = static(LINKAGES["locking-fourbar"])
    hi = path(linkage.assur_plan, np.radians([180.0])).hi  # type: ignore[arg-type]
    values = (hi - np.array([0.0, 1e-15, 1e-13, 1e-11, 1e-9, 1e-7, 1e-5, 1e-3]))[:, None]
    fast = solve_linkage(linkage, values)
    rest = np.zeros_like(fast.pose.q)
    pose = LinkagePose(linkage, values, fast.pose.q, rest, rest, fast.pose.locked_at)
    cond = condition(pose, coefficient_matrix(pose))
    assert np.array_equal(fast.singular, ~(cond <= SINGULAR_CONDITION))
    assert fast.singular.any() and not fast.singular.all()
    assert np.isnan(fast.values["Q_O2"][fast.singular]).all()


def test_the_condition_number_is_the_dense_one_when_asked_for() -> None:
    """solve_linkage's lazily computed condition numbers are the SVD's of the dense matrix
    at the continuation's poses (1e-9)."""
    linkage = static(LINKAGES["watt-ii-demo"])
    values = np.radians(np.linspace(-90.0, 90.0, 41))[:, None]
    _, cond, _ = dense_statics(linkage, values)
    got = solve_linkage(linkage, values).condition
    assert np.allclose(got, cond, rtol=1e-9, atol=0.0)


def test_a_case_solved_alone_reports_its_condition_number_and_verdict_as_a_sweep() -> None:
    """A case solved on its own (its verdict from the bound, its condition number computed
    when its diagnostics are read): at the locking four-bar's toggle, next to it and far
    from it, the Solution's verdict is `singular` exactly where the condition number exceeds
    1e8, the number is the one the same poses get in one sweep (to the bit), and a pickled
    Solution carries it."""
    case = next(c for c in load_cases(*builtin_case_files()) if c.name == "locking-fourbar")
    linkage = static(case.linkage)
    hi = path(linkage.assur_plan, np.radians([180.0])).hi  # type: ignore[arg-type]
    values = (hi - np.array([0.0, 1e-15, 1e-9, 1e-3, 1.0]))[:, None]
    swept = solve_linkage(linkage, values).condition
    assert (swept > SINGULAR_CONDITION).any() and (swept < SINGULAR_CONDITION).any()
    for value, expected in zip(values[:, 0], swept, strict=True):
        driver = replace(linkage.drivers[0], value=float(value))
        solution = mechcheck.solve(replace(case, geometry=replace(linkage, drivers=(driver,))))
        assert (solution.status == "singular") == (expected > SINGULAR_CONDITION)
        assert solution.diagnostics["condition_number"] == expected
        assert pickle.loads(pickle.dumps(solution)).diagnostics["condition_number"] == expected


SETTINGS = settings(max_examples=12, deadline=None,
                    suppress_health_check=[HealthCheck.filter_too_much])


@SETTINGS
@given(linkage_tables(friction=False, moving=False))
def test_random_linkages_group_statics_equal_the_dense_method(table: dict[str, Any]) -> None:
    """Random four-bars and Watt and Stephenson six-bars with loads, weights and springs,
    swept ±180° from the drawn pose: the same numbers and verdicts as the dense method."""
    try:
        linkage = linkage_case(LinkageCaseSpec.model_validate(table)).linkage
    except CaseError:
        assume(False)
        raise
    assume(linkage.assur_plan is not None)
    assert_same_statics(linkage, np.radians(np.linspace(-180.0, 180.0, 37))[:, None])
