"""The generic linkage engine (analytic/linkage*.py) against the closed-form presets and
against known lock positions: the four-bar and the slider-crank written as linkages must
give the same numbers as their own closed forms, independent code paths."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import assume, given, settings

from mechcheck.analytic import linkage_kinematics
from mechcheck.analytic.case import Case, FourBarGeometry
from mechcheck.analytic.kinematics import pose_of
from mechcheck.analytic.linkage_forces import solve_linkage
from mechcheck.analytic.linkage_kinematics import continuation_positions, solve_pose
from mechcheck.analytic.presets import FOUR_BAR_NAMES, SLIDER_CRANK_NAMES, preset_case, redrawn

from .closed_form import forces
from .strategies import MAX_CONDITION, cases

#: Two methods for the same rigid-body equations: only rounding separates them (the
#: tolerance policy's analytic-family 1e-9, relative to the case's force and torque scale).
RTOL = 1e-9


def scales(values: dict[str, float], length: float) -> tuple[float, float]:
    force = max([abs(v) for q, v in values.items() if q.startswith("F")] + [1e-2])
    torque = max([abs(v) for q, v in values.items() if q[0] in "TM"] + [force * length])
    return force, torque


@settings(max_examples=80, deadline=None)
@given(cases(friction=None, dynamic=None, gravity=None))
def test_presets_through_the_generic_engine_equal_the_closed_forms(case: Case) -> None:
    """A random four-bar or slider-crank (static, dynamic, friction; any branch, ground
    angle, offset) written as a linkage has the closed form's reactions and drive torque."""
    assume(case.preset.drive_link == 2)
    closed = forces.solve(case)
    generic = solve_linkage(case.linkage)
    names = FOUR_BAR_NAMES if case.mechanism == "four_bar" else SLIDER_CRANK_NAMES
    force, torque = scales(dict(closed.values), case.scale)
    for legacy, name in names.items():
        expected = closed.values[legacy]
        got = float(generic.values[name][0])
        scale = force if legacy.startswith("F") else torque
        assert abs(got - expected) <= RTOL * scale, (legacy, got, expected)
    pose = pose_of(case)
    assert float(generic.values["phi_coupler"][0]) == pytest.approx(0.0, abs=1e-12)
    drawn_theta13 = math.atan2(*(pose.joints["B"][0] - pose.joints["A"][0])[::-1])
    assert math.remainder(drawn_theta13 - closed.values["theta13"], math.tau) == pytest.approx(
        0.0, abs=1e-9)


@settings(max_examples=40, deadline=None)
@given(cases(friction=False, dynamic=True))
def test_a_driven_preset_reaches_the_closed_form_pose_and_motion(case: Case) -> None:
    """Driving the crank 40° on from the drawn pose reaches the closed form's coupler angle,
    angular velocity and acceleration at θ12 + 40° on the same branch (continuation)."""
    assume(case.preset.drive_link == 2)
    later = redrawn(case, theta12=case.preset.theta12 + math.radians(40.0))
    assume(forces.solve(later).status == "ok")
    # No lock or branch point on the way: where the path passes a singular pose (an
    # isosceles slider-crank's B through A0) the branches meet and either may follow.
    path = forces.solve_poses(case, np.linspace(case.preset.theta12, later.preset.theta12, 81))
    assume(bool(np.all(path.condition < MAX_CONDITION)))
    # A change-point geometry folds flat at one pose, where the branches cross: sampled
    # conditions can step over that one pose. For a four-bar that is s + l = p + q; for a
    # slider-crank a3 = a2 + |e|, where the rod's reach of the slide line just touches its
    # limit (the rod stands square to the slide) instead of crossing it (isosceles, e = 0:
    # B passes through A0). Seen: a2 = a3 = 1 m, θ12 = 1 rad followed the other branch.
    g = case.preset.geometry
    if isinstance(g, FourBarGeometry):
        s, p, q, l_ = sorted((g.a1, g.a2, g.a3, g.a4))
        assume(abs(s + l_ - p - q) > 1e-3 * l_)
    else:
        assume(abs(g.a3 - g.a2 - abs(g.offset)) > 1e-3 * g.scale)
    linkage = case.linkage
    moved = solve_pose(linkage, [math.radians(40.0)])
    start, end = pose_of(case), pose_of(later)
    phi, omega, alpha = (float(v[0]) for v in moved.angle("coupler"))
    assert math.remainder(start.theta13[0] + phi - end.theta13[0], math.tau) == pytest.approx(
        0.0, abs=1e-9)
    assert omega == pytest.approx(float(end.links[3].omega[0]), rel=1e-9, abs=1e-9)
    assert alpha == pytest.approx(float(end.links[3].alpha[0]), rel=1e-9, abs=1e-7)


def test_a_non_grashof_crank_locks_where_the_theory_says() -> None:
    """The non-Grashof four-bar (100, 229, 99, 300) drawn at θ12 = 0 locks at ±97.2616°
    (|A B0| reaches a3 + a4 = 328: cos θ12 = (300² + 100² − 328²)/(2·300·100))."""
    case = preset_case("jam", FourBarGeometry(0.300, 0.100, 0.229, 0.099), 0.0)
    limit = math.degrees(math.acos((0.300**2 + 0.100**2 - 0.328**2) / (2 * 0.300 * 0.100)))
    assert limit == pytest.approx(97.2616, abs=1e-4)
    pose = solve_pose(case.linkage, np.radians([[50.0], [120.0], [-150.0]]), [0.0], [0.0])
    assert pose.assembled.tolist() == [True, False, False]
    reached = np.degrees(pose.locked_at[1:] * np.radians([120.0, -150.0]))
    assert reached == pytest.approx([limit, -limit], abs=1e-6)


def test_a_kept_path_gives_the_poses_and_locks_of_a_fresh_walk(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The continuation keeps each mechanism's path in whole steps, for any Linkage value of
    it: the non-Grashof four-bar above solved in parts (near, farther, past its lock on
    both sides, nearer again, one part as the mechanism drawn with another driver value)
    gives every part's poses and lock points, to the last bit, as walks with nothing kept,
    in fewer steps."""
    linkage = preset_case("jam", FourBarGeometry(0.300, 0.100, 0.229, 0.099), 0.0).linkage
    other = replace(linkage, drivers=(replace(linkage.drivers[0], value=0.3),))
    parts = [(linkage, [10.0, 30.0]), (other, [90.0, 45.5, 120.0]), (linkage, [-150.0, -20.0]),
             (other, [5.0, 96.0, 97.0, -97.0]), (linkage, [100.0, 3.0])]
    steps: list[int] = []
    anchor = linkage_kinematics._anchor

    def counted(*args: object) -> object:
        steps.append(1)
        return anchor(*args)  # type: ignore[arg-type]

    monkeypatch.setattr(linkage_kinematics, "_anchor", counted)
    monkeypatch.setattr(linkage_kinematics, "_PATHS", {})
    kept = [continuation_positions(lk, np.radians(np.array(values))[:, None])
            for lk, values in parts]
    walked = len(steps)
    monkeypatch.setattr(linkage_kinematics, "KEPT_PATHS", 0)
    for (lk, values), (q, locked) in zip(parts, kept, strict=True):
        fresh_q, fresh_locked = continuation_positions(lk, np.radians(np.array(values))[:, None])
        assert np.array_equal(q, fresh_q, equal_nan=True), values
        assert np.array_equal(locked, fresh_locked, equal_nan=True), values
    assert np.isfinite(kept[1][1]).tolist() == [False, False, True]  # 120° is past the lock
    assert 2 * walked < len(steps) - walked
