"""The analytic backend against the independent reference (tests/reference_solver.py).

Acceptance criterion: on cases it has never seen — static, dynamic, Coulomb and
viscous friction, mm- and m-sized, tilted ground, crossed/left branch, drive on
link 4 — ``mechcheck.analytic.forces.solve`` agrees with the maximal-coordinate,
Lagrange-multiplier reference to 1e-9 relative in every quantity it reports.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings, strategies as st

from mechcheck.analytic.case import (
    Case,
    FourBarGeometry,
    Friction,
    Load,
    Mass,
    Motion,
    SliderCrankGeometry,
)
from mechcheck.analytic.presets import preset_case, redrawn
from mechcheck.analytic.solution import Solution

from . import reference_solver as ref
from .closed_form.forces import solve as analytic_solve

#: The acceptance criterion. Forces are compared against the largest force
#: component of the case: every force comes out of one linear solve whose
#: rounding error is of order cond·eps times the largest of them.
FORCE_RTOL = 1e-9
#: Torques likewise, against max(|T|, |M14|, largest force × longest link): a
#: torque is a sum of force × lever-arm terms, each of size F·L, whose rounding
#: errors do not shrink when the terms cancel.
TORQUE_RTOL = 1e-9
#: Angles are dimensionless: an absolute 1e-9 rad (compared modulo 2π; the
#: backend reports θ14 unwrapped, e.g. 350° where the reference has −10°).
ANGLE_ATOL = 1e-9
#: s14 against the longest link length.
LENGTH_RTOL = 1e-9
#: Poses whose (dimensionless) condition number exceeds this are skipped. Near
#: a toggle or change point the reactions grow like 1/sin(transmission angle)
#: and a relative change of cond·eps in the data changes them by that much; at
#: cond = 1e4 rounding alone is ~2e-12, leaving three orders of margin to 1e-9.
#: Above that, disagreement would measure ill-conditioning, not correctness.
CONDITION_LIMIT = 1e4

#: Coulomb friction flips sign where a relative speed passes through zero (a dead
#: centre: ṡ = 0 or ω_j = ω_i). Within rounding of such a pose the sense — and so
#: the answer, by 2·μ·r·|F| — is decided by rounding noise, so random poses whose
#: smallest relative speed (over |ω2|, or |ω2|·L) is below this are skipped. Exact
#: dead centres, where sign(0) = 0 applies, are tested explicitly below.
MIN_SENSE_SPEED = 1e-8

#: Hypothesis budget: the whole module stays well under 30 s.
PROPERTY_SETTINGS = settings(max_examples=400, deadline=None,
                             suppress_health_check=[HealthCheck.filter_too_much,
                                                    HealthCheck.too_slow])


def wrap(angle: float) -> float:
    """An angle difference wrapped into (−π, π]."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


def normalized_errors(case: Case, got: Solution, expected: dict[str, float]
                      ) -> dict[str, float]:
    """Each quantity's error divided by its tolerance (≤ 1 passes)."""
    length = case.scale
    forces = [abs(v) for q, v in expected.items() if q.startswith("F")]
    force_scale = max(forces)
    torque_scale = max([abs(expected[q]) for q in ("T12", "T14", "M14") if q in expected]
                       + [force_scale * length])
    out = {}
    for q, want in expected.items():
        have = got.values[q]
        if q in ("theta13", "theta14"):
            out[q] = abs(wrap(have - want)) / ANGLE_ATOL
        elif q == "s14":
            out[q] = abs(have - want) / (LENGTH_RTOL * length)
        elif q.startswith("F"):
            out[q] = abs(have - want) / (FORCE_RTOL * max(force_scale, 1e-300))
        else:
            out[q] = abs(have - want) / (TORQUE_RTOL * max(torque_scale, 1e-300))
    return out


def assert_agrees(case: Case, got: Solution) -> float:
    """Assert the backend's Solution equals the reference in every quantity; return the
    worst error as a fraction of its tolerance."""
    assert got.status == "ok", got.message
    expected = ref.solve(case).values
    assert set(got.values) == set(expected), (sorted(got.values), sorted(expected))
    errors = normalized_errors(case, got, expected)
    bad = {q: (got.values[q], expected[q]) for q, e in errors.items() if not e <= 1.0}
    assert not bad, f"{case.name}: analytic vs reference {bad}"
    return max(errors.values())


# -- random cases ----------------------------------------------------------------------
def unit(angle: float) -> np.ndarray:
    return np.array([math.cos(angle), math.sin(angle)])


angles = st.floats(-math.pi, math.pi, allow_nan=False)


def _force(magnitude: float, direction: float) -> tuple[float, float]:
    return (magnitude * math.cos(direction), magnitude * math.sin(direction))


@st.composite
def loads_and_masses(draw: st.DrawFn, length: float) -> dict[str, object]:
    """1–3 loads on random links at random body-fixed points, optional masses and gravity."""
    coord = st.floats(-length, length, allow_nan=False)
    loads = tuple(
        Load(link=draw(st.sampled_from([2, 3, 4])), at=(draw(coord), draw(coord)),
             force=_force(draw(st.floats(1.0, 100.0)), draw(angles)),
             torque=draw(st.one_of(st.just(0.0), st.floats(-20.0 * length, 20.0 * length))))
        for _ in range(draw(st.integers(1, 3))))
    masses = tuple(
        Mass(link=link, mass=draw(st.floats(0.05, 5.0)), com=(draw(coord), draw(coord)),
             inertia=draw(st.floats(0.0, 0.2)) * length**2)
        for link in (2, 3, 4) if draw(st.booleans()))
    gravity = draw(st.sampled_from([(0.0, 0.0), (0.0, -9.81), (3.0, -7.0)]))
    return {"loads": loads, "masses": masses, "gravity": gravity}


@st.composite
def motion_and_friction(draw: st.DrawFn, length: float, joints: tuple[str, ...],
                        slide: bool) -> dict[str, object]:
    """ω, α (each possibly 0) and optional Coulomb + viscous friction with its sense."""
    omega = draw(st.sampled_from([0.0, -1.0, 1.0])) * draw(st.floats(0.1, 20.0))
    alpha = draw(st.one_of(st.just(0.0), st.floats(-300.0, 300.0)))
    out: dict[str, object] = {"motion": Motion(omega=omega, alpha=alpha)}
    if draw(st.booleans()):
        radii = {j: draw(st.floats(0.0, 0.3)) * length for j in joints if draw(st.booleans())}
        viscous = {j: draw(st.floats(0.0, 0.5)) for j in (*joints, *(("slide",) if slide else ()))
                   if draw(st.booleans())}
        sense = 0 if omega else draw(st.sampled_from([-1, 1]))
        if omega and draw(st.booleans()):
            sense = 1 if omega > 0 else -1
        out["friction"] = Friction(
            mu=draw(st.floats(0.0, 0.3)), pin_radius=radii, viscous=viscous, direction=sense,
            slide_mu=draw(st.one_of(st.none(), st.floats(0.0, 0.3))) if slide else None)
    return out


@st.composite
def four_bar_cases(draw: st.DrawFn) -> Case:
    """An assemblable four-bar built from its pose: A0, B0 = a1·e(g), A = a2·e(θ12) and a
    free point B; a3 = |AB|, a4 = |B0B|, and the branch is the side of A→B0 that B is on."""
    length = draw(st.sampled_from([0.001, 0.1, 1.0, 25.0]))  # mm-sized … large, in metres
    g, t12 = draw(angles), draw(angles)
    a1 = draw(st.floats(0.3, 1.0)) * length
    a2 = draw(st.floats(0.1, 1.0)) * length
    a4 = draw(st.floats(0.2, 1.2)) * length
    b0, a = a1 * unit(g), a2 * unit(t12)
    b = b0 + a4 * unit(draw(angles))
    a3 = float(np.hypot(*(b - a)))
    assume(a3 > 0.1 * length)
    side = ref.cross2(a - b0, b - b0)
    assume(abs(side) > 1e-6 * length**2)
    extra = draw(loads_and_masses(max(a1, a2, a3, a4)))
    extra |= draw(motion_and_friction(max(a1, a2, a3, a4), ("A0", "A", "B", "B0"), False))
    return preset_case(name="fb-random", geometry=FourBarGeometry(a1, a2, a3, a4), theta12=t12,
                ground_angle=g, branch="open" if side < 0 else "crossed",
                drive_link=draw(st.sampled_from([2, 4])), **extra)


@st.composite
def slider_crank_cases(draw: st.DrawFn) -> Case:
    """An assemblable slider-crank built from its pose: A = a2·e(θ12), B = s·u + e·n with
    s = A·u + δ; a3 = |AB|, and the branch is right for δ > 0, left for δ < 0."""
    length = draw(st.sampled_from([0.001, 0.1, 1.0, 25.0]))
    g, t12 = draw(angles), draw(angles)
    u = unit(g)
    n = np.array([-u[1], u[0]])
    a2 = draw(st.floats(0.1, 1.0)) * length
    offset = draw(st.one_of(st.just(0.0), st.floats(-0.5, 0.5))) * length
    delta = draw(st.sampled_from([-1.0, 1.0])) * draw(st.floats(0.05, 1.5)) * length
    a = a2 * unit(t12)
    b = (a @ u + delta) * u + offset * n
    a3 = float(np.hypot(*(b - a)))
    scale = max(a2, a3, abs(offset))
    extra = draw(loads_and_masses(scale))
    extra |= draw(motion_and_friction(scale, ("A0", "A", "B"), True))
    return preset_case(name="sc-random", geometry=SliderCrankGeometry(a2, a3, offset), theta12=t12,
                ground_angle=g, branch="right" if delta > 0 else "left",
                **extra)


def usable(case: Case) -> Solution:
    """The backend's answer, or reject the example: near-singular poses (the backend's
    condition number over CONDITION_LIMIT), self-locking friction (status != ok), poses
    where a Coulomb term's relative speed is within MIN_SENSE_SPEED of zero, and poses
    near a toggle of the crank-driven kinematics (the reference's kinematic condition
    number over CONDITION_LIMIT: with drive_link = 4 the backend's force condition
    number does not see the rocker toggle, where ω3, ω4 → ∞) are out of scope, and so are
    poses where the reference's own friction iteration does not converge."""
    got = analytic_solve(case)
    cond = got.diagnostics.get("condition_number", math.inf)
    assume(isinstance(cond, float) and cond <= CONDITION_LIMIT)
    assume(got.status == "ok")
    # Decided before the reference's forces: next to a toggle its friction Newton may not
    # converge, and the pose is out of scope anyway.
    assume(ref.kinematic_condition(case) <= CONDITION_LIMIT)
    try:
        reference = ref.solve(case)
    except ref.ReferenceError as error:
        # The reference's Coulomb Newton is plain (no line search): next to a change point
        # with a large friction circle it may not converge where the backend's does. Such an
        # example has no reference to compare with; every one it solves is compared.
        assume("friction" not in str(error))
        raise
    assume(reference.min_sense_speed >= MIN_SENSE_SPEED)
    return got


@PROPERTY_SETTINGS
@given(four_bar_cases())
def test_four_bar_matches_reference(case: Case) -> None:
    """For any assemblable, well-conditioned four-bar pose, loading, motion and friction,
    the member-equilibrium backend and the Lagrange-multiplier reference give the same
    drive torque, reactions and pose to 1e-9."""
    assert_agrees(case, usable(case))


@PROPERTY_SETTINGS
@given(slider_crank_cases())
def test_slider_crank_matches_reference(case: Case) -> None:
    """For any assemblable, well-conditioned slider-crank pose, loading, motion and
    friction, the backend and the reference give the same T12, reactions, M14 and pose."""
    assert_agrees(case, usable(case))


# -- explicit unseen cases -------------------------------------------------------------
def _polar(magnitude: float, degrees: float) -> tuple[float, float]:
    return (magnitude * math.cos(math.radians(degrees)),
            magnitude * math.sin(math.radians(degrees)))


_FB = FourBarGeometry(a1=0.180, a2=0.060, a3=0.150, a4=0.110)
_SC = SliderCrankGeometry(a2=0.045, a3=0.170, offset=0.012)
_FB_LOADS = (Load(3, (0.070, 0.030), _polar(80.0, 115.0)), Load(4, (0.050, -0.010),
                                                                  _polar(40.0, -30.0), 1.5))
_SC_LOADS = (Load(4, (0.0, 0.0), _polar(250.0, 190.0)), Load(3, (0.080, 0.015),
                                                              _polar(30.0, 75.0)))
_MASSES = (Mass(2, 0.4, (0.020, 0.0), 1.2e-4), Mass(3, 1.1, (0.075, 0.005), 2.6e-3),
           Mass(4, 0.7, (0.050, 0.0), 8.0e-4))
_PIN_FRICTION = Friction(mu=0.15, pin_radius={"A0": 0.010, "A": 0.008, "B": 0.006, "B0": 0.012},
                         viscous={"A0": 0.02, "B0": 0.01})

UNSEEN: list[tuple[str, Case]] = [
    ("static-four-bar", preset_case(name="u1", geometry=_FB, theta12=math.radians(75.0),
                             loads=_FB_LOADS)),
    ("dynamic-four-bar", preset_case(name="u2", geometry=_FB, theta12=math.radians(200.0),
                              loads=_FB_LOADS, masses=_MASSES, gravity=(0.0, -9.81),
                              motion=Motion(omega=30.0, alpha=-400.0))),
    ("coulomb-viscous-four-bar", preset_case(name="u3", geometry=_FB, theta12=math.radians(130.0),
                                      loads=_FB_LOADS, masses=_MASSES,
                                      motion=Motion(omega=-12.0, alpha=50.0),
                                      friction=_PIN_FRICTION)),
    ("quasi-static-friction-ccw", preset_case(name="u4", geometry=_FB, theta12=math.radians(40.0),
                                       loads=_FB_LOADS,
                                       friction=Friction(mu=0.2, pin_radius={"A": 0.01, "B": 0.01},
                                                         direction=1))),
    ("tilted-ground-crossed", preset_case(name="u5", geometry=_FB, theta12=math.radians(95.0),
                                   branch="crossed", ground_angle=math.radians(-35.0),
                                   loads=_FB_LOADS, masses=_MASSES, gravity=(0.0, -9.81),
                                   motion=Motion(omega=8.0, alpha=20.0))),
    ("drive-on-link-4", preset_case(name="u6", geometry=_FB, theta12=math.radians(250.0),
                             drive_link=4, loads=_FB_LOADS, masses=_MASSES,
                             gravity=(0.0, -9.81), motion=Motion(omega=5.0, alpha=-60.0),
                             friction=_PIN_FRICTION)),
    ("mm-sized-four-bar", preset_case(name="u7", geometry=FourBarGeometry(0.0018, 0.0006, 0.0015,
                                                                   0.0011),
                               theta12=math.radians(75.0),
                               loads=(Load(3, (0.0007, 0.0003), _polar(0.8, 115.0)),),
                               masses=(Mass(3, 1e-4, (0.0007, 0.0), 1e-11),),
                               motion=Motion(omega=300.0, alpha=0.0))),
    ("m-sized-four-bar", preset_case(name="u8", geometry=FourBarGeometry(18.0, 6.0, 15.0, 11.0),
                              theta12=math.radians(75.0),
                              loads=(Load(3, (7.0, 3.0), _polar(8000.0, 115.0)),),
                              masses=(Mass(3, 500.0, (7.0, 0.0), 9000.0),),
                              gravity=(0.0, -9.81), motion=Motion(omega=0.3, alpha=0.05))),
    ("static-slider-crank", preset_case(name="u9", geometry=_SC, theta12=math.radians(35.0),
                                 loads=_SC_LOADS)),
    ("dynamic-slider-left-tilted", preset_case(name="u10", geometry=_SC, theta12=math.radians(-120.0),
                                        branch="left", ground_angle=math.radians(60.0),
                                        loads=_SC_LOADS, masses=_MASSES, gravity=(0.0, -9.81),
                                        motion=Motion(omega=-40.0, alpha=300.0))),
    ("slider-coulomb-viscous", preset_case(name="u11", geometry=_SC, theta12=math.radians(140.0),
                                    loads=_SC_LOADS, masses=_MASSES,
                                    motion=Motion(omega=25.0, alpha=0.0),
                                    friction=Friction(mu=0.1, slide_mu=0.2,
                                                      pin_radius={"A0": 0.01, "A": 0.012,
                                                                  "B": 0.008},
                                                      viscous={"slide": 3.0, "A": 0.01}))),
    ("slider-quasi-static-cw", preset_case(name="u12", geometry=_SC, theta12=math.radians(300.0),
                                    ground_angle=math.radians(180.0), loads=_SC_LOADS,
                                    friction=Friction(mu=0.12, pin_radius={"A": 0.01},
                                                      direction=-1))),
]


@pytest.mark.parametrize("case", [c for _, c in UNSEEN], ids=[i for i, _ in UNSEEN])
def test_unseen_case(case: Case) -> None:
    """On each hand-written unseen case the backend reproduces the reference's drive
    torque, reactions and pose to 1e-9."""
    got = analytic_solve(case)
    cond = got.diagnostics["condition_number"]
    assert isinstance(cond, float) and cond <= CONDITION_LIMIT
    assert_agrees(case, got)


DEAD_CENTRE = preset_case(name="u13", geometry=SliderCrankGeometry(0.05, 0.2),
              theta12=0.7, ground_angle=0.7, gravity=(0.0, -9.81),
              loads=(Load(4, (0.0, 0.0), (30.0, 10.0)),),
              masses=(Mass(4, 2.0),),
              friction=Friction(mu=0.2, direction=1))


def test_exact_dead_centre_is_indeterminate() -> None:
    """At an exact slide dead centre the slide friction reverses: the backend withholds forces.

    Coulomb friction may take any value in ±μ·|N| where the sliding speed
    passes through zero, so the drive torque is not unique. The reference's
    sign(0) = 0 convention picks the friction-free member of that set, which
    is what the backend gives with the friction removed.
    """
    got = analytic_solve(DEAD_CENTRE)
    assert got.status == "indeterminate", got.message
    assert "slide" in got.message and not any(q.startswith(("F", "T")) for q in got.values)
    frictionless = analytic_solve(redrawn(DEAD_CENTRE, friction=None))
    expected = ref.solve(DEAD_CENTRE).values
    errors = normalized_errors(DEAD_CENTRE, frictionless, expected)
    assert max(errors.values()) <= 1.0, errors


# -- units: a mechanism 1000× larger ---------------------------------------------------
def _scaled(case: Case, factor: float) -> Case:
    """The same case with every length (links, offset, points, pin radii) × factor."""
    g = case.preset.geometry
    geometry: FourBarGeometry | SliderCrankGeometry
    if isinstance(g, FourBarGeometry):
        geometry = FourBarGeometry(g.a1 * factor, g.a2 * factor, g.a3 * factor, g.a4 * factor)
    else:
        geometry = SliderCrankGeometry(g.a2 * factor, g.a3 * factor, g.offset * factor)
    s = lambda p: (p[0] * factor, p[1] * factor)  # noqa: E731
    f = case.preset.friction
    friction = None if f is None else Friction(
        mu=f.mu, slide_mu=f.slide_mu, direction=f.direction,
        pin_radius={j: r * factor for j, r in f.pin_radius.items()})
    return redrawn(case,
        geometry=geometry, friction=friction,
        loads=tuple(Load(ld.link, s(ld.at), ld.force, ld.torque * factor) for ld in case.preset.loads),
        masses=tuple(Mass(m.link, m.mass, s(m.com), m.inertia) for m in case.preset.masses))


#: Cases for which scaling lengths by k scales torques by k and leaves forces alone:
#: loads, static weights and Coulomb friction with scaled pin radii. (It does NOT hold
#: with motion — inertia forces m·a grow with length — nor with viscous friction,
#: whose moments c·ω do not depend on length.)
SCALABLE: list[tuple[str, Case]] = [
    ("four-bar-coulomb-weight", preset_case(
        name="s1", geometry=_FB, theta12=math.radians(130.0), loads=_FB_LOADS,
        masses=(Mass(3, 1.1, (0.075, 0.005)),), gravity=(0.0, -9.81),
        friction=Friction(mu=0.15, pin_radius={"A0": 0.01, "A": 0.008, "B0": 0.012},
                          direction=-1))),
    ("slider-slide-friction", preset_case(
        name="s2", geometry=_SC, theta12=math.radians(35.0), ground_angle=0.3,
        loads=_SC_LOADS, friction=Friction(mu=0.1, slide_mu=0.25, pin_radius={"B": 0.01},
                                           direction=1))),
]


@pytest.mark.parametrize("case", [c for _, c in SCALABLE], ids=[i for i, _ in SCALABLE])
def test_metres_versus_millimetre_sized(case: Case) -> None:
    """A mechanism 1000× larger (mm read as m) with the same forces needs 1000× the
    torques and the same reactions and angles, in the backend and the reference alike."""
    small, big = analytic_solve(case), analytic_solve(_scaled(case, 1000.0))
    assert_agrees(case, small)
    assert_agrees(_scaled(case, 1000.0), big)
    forces = max(abs(v) for q, v in small.values.items() if q.startswith("F"))
    for q, v in small.values.items():
        if q in ("T12", "T14", "M14"):
            assert big.values[q] == pytest.approx(1000.0 * v, abs=TORQUE_RTOL * 1000.0 * forces
                                                  * case.scale)
        elif q == "s14":
            assert big.values[q] == pytest.approx(1000.0 * v, rel=LENGTH_RTOL)
        elif q.startswith("F"):
            assert big.values[q] == pytest.approx(v, abs=FORCE_RTOL * forces)
        else:
            assert abs(wrap(big.values[q] - v)) <= ANGLE_ATOL
