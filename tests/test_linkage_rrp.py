"""The RRP dyad of the closed-form Assur path (a slider-crank's rod and slider) against the
engine's independent routes: Newton continuation and the dense member-equilibrium solve
(positions, locks, every reaction and effort, singular verdicts), the slider-crank's own
closed-form statics (tests/closed_form/), and the law of sines for where it locks."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from mechcheck.analytic.joint_kinds import PRISMATIC, REVOLUTE
from mechcheck.analytic.linkage import Driver, Joint, Link, Linkage, LinkMass, PointLoad
from mechcheck.analytic.linkage_assur import Crank, SlideDyad, assur_positions, path
from mechcheck.analytic.linkage_kinematics import continuation_positions
from mechcheck.analytic.linkage_statics import static_results
from mechcheck.analytic.presets import SLIDER_CRANK_NAMES, as_linkage
from mechcheck.tolerance import rule

from .builtin import builtin, builtin_cases
from .closed_form import forces
from .test_linkage_assur import RTOL, assert_same_statics, dense_statics, static

SLIDER_CRANKS = sorted(name for name, c in builtin_cases().items() if c.mechanism == "slider_crank")
#: More than a turn each way from the drawn pose, through every lock.
TURNS = np.radians(np.linspace(-380.0, 380.0, 153))[:, None]


def frictionless(linkage: Linkage) -> Linkage:
    return replace(static(linkage), friction=None)


def test_the_tolerance_here_is_within_the_policys_for_the_analytic_backend() -> None:
    """Every comparison below holds to 1e-9 of each quantity's scale, no looser than the
    policy's tolerance for the analytic backend (the reference: its default rule)."""
    assert RTOL <= rule("analytic", "force", "static").rtol


@pytest.mark.parametrize("name", SLIDER_CRANKS)
def test_the_slider_crank_presets_decompose_into_a_crank_and_an_rrp_dyad(name: str) -> None:
    plan = as_linkage(builtin(name)).linkage.assur_plan
    assert plan is not None
    crank, dyad = plan.groups
    assert isinstance(crank, Crank) and crank.link == "crank"
    assert isinstance(dyad, SlideDyad)
    assert dyad.links == ("coupler", "slider") and dyad.bodies == ("crank", "ground")
    assert [j.name for j in dyad.joints] == ["A", "B", "slide"]


@pytest.mark.parametrize("name", SLIDER_CRANKS)
def test_built_in_slider_cranks_equal_newton_and_the_dense_method(name: str) -> None:
    """Static and frictionless, over ±380° of the crank: poses, locks, every quantity and
    singular verdict as continuation and the dense solve give them."""
    assert_same_statics(frictionless(as_linkage(builtin(name)).linkage), TURNS)


def test_seed_e2_equals_the_slider_cranks_closed_form_statics() -> None:
    """Seed E2 over a whole turn: drive torque and every reaction (the slide's force and
    couple included) as tests/closed_form/ computes them from the free-body diagrams."""
    case = builtin("seed-E2-frictionless")
    theta = np.radians(np.arange(-180.0, 180.0, 1.0))
    want = forces.solve_poses(case, theta).values
    linkage = as_linkage(case).linkage
    assert linkage.assur_plan is not None
    got = static_results(linkage.assur_plan, (theta - case.preset.theta12)[:, None]).values
    for legacy, name in SLIDER_CRANK_NAMES.items():
        scale = max(float(np.nanmax(np.abs(want[legacy]))), 1e-2)   # M_slide is 0 here
        assert np.nanmax(np.abs(got[name] - want[legacy])) <= RTOL * scale, name
    assert np.isfinite(got["Q_A0"]).all()


def slider_crank(crank: float, rod: float, offset: float, tilt: float, angle: float,
                 branch: int, *, mirrored: bool = False) -> Linkage:
    """A slider-crank: crank A0–A (A drawn at ``angle``), rod A–B, B on a slide through
    offset·n along u = (cos tilt, sin tilt), ahead of A's foot (branch +1) or behind (−1);
    loads on every link and weights. ``mirrored``: the file names the middle pin's links
    slider first and the slide by the slider on the ground, at a ground point S."""
    a = (crank * math.cos(angle), crank * math.sin(angle))
    u = (math.cos(tilt), math.sin(tilt))
    n = (-u[1], u[0])
    across = offset - (a[0] * n[0] + a[1] * n[1])
    along = (a[0] * u[0] + a[1] * u[1]) + branch * math.sqrt(rod * rod - across * across)
    b = (offset * n[0] + along * u[0], offset * n[1] + along * u[1])
    s = (offset * n[0], offset * n[1])
    points = {"A0": (0.0, 0.0), "A": a, "B": b, "S": s}
    middle = ("slider", "coupler") if mirrored else ("coupler", "slider")
    slide = Joint("slide", PRISMATIC, ("slider", "ground"), "S", (-u[0], -u[1])) if mirrored \
        else Joint("slide", PRISMATIC, ("ground", "slider"), "B", u)
    return Linkage(
        points=points,
        links=(Link("ground", ("A0", "S")), Link("crank", ("A0", "A")),
               Link("coupler", ("A", "B")), Link("slider", ("B",))),
        joints=(Joint("A0", REVOLUTE, ("ground", "crank"), "A0"),
                Joint("A", REVOLUTE, ("crank", "coupler"), "A"),
                Joint("B", REVOLUTE, middle, "B"), slide),
        drivers=(Driver("A0", 0.0),),
        loads=(PointLoad("slider", b, (-300.0 * u[0] + 40.0 * n[0], -300.0 * u[1] + 40.0 * n[1])),
               PointLoad("coupler", ((a[0] + b[0]) / 2, (a[1] + b[1]) / 2), (20.0, -50.0), 3.0),
               PointLoad("crank", a, (5.0, 7.0))),
        masses=(LinkMass("coupler", 2.0, ((a[0] + b[0]) / 2, (a[1] + b[1]) / 2)),
                LinkMass("slider", 1.5, b)),
        gravity=(0.0, -9.81),
    )


def random_slider_cranks(count: int, seed: int) -> list[tuple[float, ...]]:
    """Crank 0.05–0.2 m, rod 0.1–0.4 m, offset up to 0.1 m, any tilt, any drawn crank angle
    that assembles away from the toggle: some turn fully, some lock (crank + |offset| > rod)."""
    rng = np.random.default_rng(seed)
    out: list[tuple[float, ...]] = []
    while len(out) < count:
        crank, rod = rng.uniform(0.05, 0.2), rng.uniform(0.1, 0.4)
        offset, tilt, angle = rng.uniform(-0.1, 0.1), rng.uniform(-math.pi, math.pi), \
            rng.uniform(-math.pi, math.pi)
        a_across = offset - crank * math.sin(angle - tilt)
        if abs(a_across) < 0.9 * rod:
            out.append((crank, rod, offset, tilt, angle, float(rng.choice([-1, 1]))))
    return out


@pytest.mark.parametrize("mirrored", [False, True])
@pytest.mark.parametrize("geometry", random_slider_cranks(8, 20240611))
def test_random_slider_cranks_equal_newton_and_the_dense_method(
        geometry: tuple[float, ...], mirrored: bool) -> None:
    """Offset, tilted slides, both branches, full-turning and locking, either order of the
    dyad in the file: the same poses, locks (the continuation's locked_at), quantities and
    verdicts as the Newton path; and the condition bound is an upper bound."""
    crank, rod, offset, tilt, angle, branch = geometry
    linkage = slider_crank(crank, rod, offset, tilt, angle, int(branch), mirrored=mirrored)
    plan = linkage.assur_plan
    assert plan is not None and isinstance(plan.groups[1], SlideDyad)
    assert plan.groups[1].links == ("coupler", "slider")
    assert_same_statics(linkage, TURNS)
    bound = static_results(plan, TURNS).condition_bound
    cond = dense_statics(linkage, TURNS)[1]
    finite = np.isfinite(cond)
    assert (bound[finite] >= cond[finite]).all()


def test_some_random_slider_cranks_lock_and_some_turn() -> None:
    """The random set covers both kinds of travel (else the test above would not see a lock)."""
    locks = []
    for crank, rod, offset, tilt, angle, branch in random_slider_cranks(8, 20240611):
        linkage = slider_crank(crank, rod, offset, tilt, angle, int(branch))
        locks.append(np.isfinite(continuation_positions(linkage, TURNS)[1]).any())
    assert any(locks) and not all(locks)


def test_a_slider_crank_locks_where_the_rod_is_square_to_the_slide() -> None:
    """Crank 0.2, rod 0.15, no offset, slide along x, A drawn at 10°: the rod stands square
    to the slide when 0.2·sin θ = 0.15, the lock ahead at asin(0.75), behind at
    −asin(0.75); both Newton's locked_at and the closed form's path stop there."""
    linkage = slider_crank(0.2, 0.15, 0.0, 0.0, math.radians(10.0), 1)
    values = np.radians([-150.0, 150.0])[:, None]
    route = path(linkage.assur_plan, values[:, 0])  # type: ignore[arg-type]
    theta = math.asin(0.75)
    assert route.hi == pytest.approx(theta - math.radians(10.0), abs=1e-9)
    assert route.lo == pytest.approx(-theta - math.radians(10.0), abs=1e-9)
    _, locked = continuation_positions(linkage, values)
    assert locked * values[:, 0] == pytest.approx([route.lo, route.hi], abs=1e-9)


@pytest.mark.parametrize("name", ["slidercrank-offset-left-dynamic", "seed-E2-friction"])
def test_moving_and_friction_slider_cranks_are_placed_as_continuation_places_them(name: str) -> None:
    """Positions alone (a moving or friction case takes them from the plan): the same q as
    Newton continuation, whole turns of the angles included, and the same locks."""
    linkage = as_linkage(builtin(name)).linkage
    assert linkage.assur_plan is not None
    q, locked = assur_positions(linkage.assur_plan, TURNS)
    want, want_locked = continuation_positions(linkage, TURNS)
    assert np.array_equal(np.isnan(q), np.isnan(want))
    assert np.allclose(locked, want_locked, rtol=RTOL, atol=0.0, equal_nan=True)
    scale = np.tile([linkage.scale, linkage.scale, 1.0], len(linkage.moving_links))
    assert np.nanmax(np.abs(q - want) / scale) <= RTOL


def slide_on_a_rocker() -> Linkage:
    """A crank-rocker four-bar whose rocker carries a slide: a rod pinned to the ground at
    G drives a slider along the rocker (an RRP dyad whose slide turns with its body)."""
    points = {"A0": (0.0, 0.0), "B0": (0.3, 0.0), "A": (0.0, 0.08), "B": (0.25, 0.2),
              "G": (0.5, 0.35), "C": (0.28, 0.1)}
    rocker = (points["B"][0] - points["B0"][0], points["B"][1] - points["B0"][1])
    length = math.hypot(*rocker)
    return Linkage(
        points=points,
        links=(Link("ground", ("A0", "B0", "G")), Link("crank", ("A0", "A")),
               Link("coupler", ("A", "B")), Link("rocker", ("B0", "B")),
               Link("rod", ("G", "C")), Link("slider", ("C",))),
        joints=(Joint("A0", REVOLUTE, ("ground", "crank"), "A0"),
                Joint("A", REVOLUTE, ("crank", "coupler"), "A"),
                Joint("B", REVOLUTE, ("coupler", "rocker"), "B"),
                Joint("B0", REVOLUTE, ("ground", "rocker"), "B0"),
                Joint("G", REVOLUTE, ("ground", "rod"), "G"),
                Joint("C", REVOLUTE, ("rod", "slider"), "C"),
                Joint("slide", PRISMATIC, ("rocker", "slider"), "C",
                      (rocker[0] / length, rocker[1] / length))),
        drivers=(Driver("A0", 0.0),),
        loads=(PointLoad("slider", points["C"], (30.0, -10.0)),
               PointLoad("rod", points["G"], (0.0, 0.0), 2.0)),
        masses=(LinkMass("rocker", 1.0, (0.28, 0.1)),),
        gravity=(0.0, -9.81),
    )


def test_a_slide_on_a_moving_body_equals_newton_and_the_dense_method() -> None:
    linkage = slide_on_a_rocker()
    plan = linkage.assur_plan
    assert plan is not None
    dyad = plan.groups[-1]
    assert isinstance(dyad, SlideDyad) and dyad.bodies == ("ground", "rocker")
    assert_same_statics(linkage, TURNS)
