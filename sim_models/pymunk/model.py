"""The four-bar's and slider-crank's own pymunk model, which now serves only the turning
experiments (:mod:`.turning`): every backend builds its model with :mod:`.linkage_model`,
the four-bar and slider-crank as their linkage.

One dynamic body per moving link, placed on its link frame (CONVENTIONS.md):
link 2 at A0 along A0→A, link 3 at A along A→B, the rocker at B0 along
B0→B, the slider at pin B along the slide direction u. Pymunk anchors are in
those same frames, so a body-fixed point of the Case is used unchanged.

Joints are pymunk's own constraints:

- pins ``A0``, ``A``, ``B`` (and ``B0``) are :class:`pymunk.PivotJoint`
  with body a = link i and body b = link j, so the impulse the solver
  accumulates on body b is the impulse of F_ij (force *by* i *on* j);
- the slide is a :class:`pymunk.GrooveJoint` (pin B on a line of the ground)
  plus a :class:`pymunk.GearJoint` that keeps the slider at the slide angle;
  the groove's impulse is the guide's normal force at B, the gear's is M14;
- the drive is a :class:`pymunk.GearJoint` from a driver body (the static
  body, or a kinematic "clock" that follows the prescribed motion) to the
  drive link, ratio 1: a two-way angle lock whose torque is T12 (or T14).

No collision shapes are added, so nothing collides.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np
import pymunk

from mechcheck.analytic.case import Case, FourBarGeometry, preset_geometry
from mechcheck.analytic.kinematics import Pose, pose_of
from mechcheck.sim_models.pymunk.settings import SolverSettings

Vec = tuple[float, float]
MassMode = Literal["fictitious", "real"]
DriverKind = Literal["static", "kinematic"]


@dataclass
class Model:
    """A built pymunk mechanism and handles on every constraint that carries a reaction.

    ``pins`` maps joint names to pivots, ``groove``/``slider_lock`` exist for a
    slider-crank only, ``drive`` is the lock on the drive link, ``driver`` the
    body it is locked to, ``reach`` a characteristic radius per link for speeds.
    Friction is applied as explicit loads.
    """

    case: Case
    settings: SolverSettings
    space: pymunk.Space
    bodies: dict[int, pymunk.Body]
    pins: dict[str, pymunk.PivotJoint]
    drive: pymunk.GearJoint
    driver: pymunk.Body
    reach: dict[int, float]
    groove: pymunk.GrooveJoint | None = None
    slider_lock: pymunk.GearJoint | None = None
    mass_mode: MassMode = "fictitious"

    def constraints(self) -> list[pymunk.Constraint]:
        """Every constraint."""
        out: list[pymunk.Constraint] = [*self.pins.values(), self.drive]
        if self.groove is not None and self.slider_lock is not None:
            out += [self.groove, self.slider_lock]
        return out


def slide_axes(case: Case) -> tuple[Vec, Vec]:
    """(u, n): the slide direction and its +90° normal."""
    g = case.ground_angle
    return (math.cos(g), math.sin(g)), (-math.sin(g), math.cos(g))


def link_lengths(case: Case) -> dict[int, float]:
    """Pin-to-pin length of each moving link (the slider gets the rod length)."""
    g = preset_geometry(case)
    if isinstance(g, FourBarGeometry):
        return {2: g.a2, 3: g.a3, 4: g.a4}
    return {2: g.a2, 3: g.a3, 4: g.a3}


def pin_anchors(case: Case) -> dict[str, tuple[int, Vec, int, Vec]]:
    """(link i, anchor on i, link j, anchor on j) per pin; link 1 anchors are world points."""
    g = preset_geometry(case)
    anchors: dict[str, tuple[int, Vec, int, Vec]] = {
        "A0": (1, (0.0, 0.0), 2, (0.0, 0.0)),
        "A": (2, (g.a2, 0.0), 3, (0.0, 0.0)),
    }
    if isinstance(g, FourBarGeometry):
        b0 = (g.a1 * math.cos(case.ground_angle), g.a1 * math.sin(case.ground_angle))
        anchors["B"] = (3, (g.a3, 0.0), 4, (g.a4, 0.0))
        anchors["B0"] = (1, b0, 4, (0.0, 0.0))
    else:
        anchors["B"] = (3, (g.a3, 0.0), 4, (0.0, 0.0))
    return anchors


#: Gauss–Seidel keeps up with a link only while its moment of inertia about
#: the centre of gravity is not tiny against m·d², d the centre's largest
#: distance from the link's pins: then the pin's rows and the rotation are
#: nearly parallel in the mass metric and the iteration stalls. Measured on a
#: random crank (3.55 kg, centre 0.24 m from A0): m·d²/I = 20 settles at 100
#: iterations, 200 needs 800, 660 and above diverge even at 1600; a slider
#: with I = 2e-313 made every run non-finite. Below I = m·d²/POINT_RATIO a
#: link gets fictitious inertia that brings the ratio to INERTIA_RATIO, removed
#: with the massless links' (see :func:`body_inertia`).
POINT_RATIO = 100.0
INERTIA_RATIO = 10.0


def link_pins(case: Case, link: int) -> list[Vec]:
    """The pins of a link in its own frame (the slider's only pin is B at its origin)."""
    length = link_lengths(case)[link]
    if link == 4 and _has_slider(case):
        return [(0.0, 0.0)]
    return [(0.0, 0.0), (length, 0.0)]


def added_inertia(case: Case, link: int, settings: SolverSettings) -> float:
    """Fictitious moment of inertia a massive link gets in a driven run (0 when it needs none).

    A link whose inertia about its centre of gravity is below m·d²/POINT_RATIO
    (or is not a usable number for pymunk, e.g. a subnormal 2e-313: 1/I
    overflows) gets ``fictitious_scale`` × (the fictitious bar's L²/12 times
    ``driven_fictitious_mass`` + m·d²/INERTIA_RATIO).
    """
    real = case.mass_of(link)
    assert real is not None
    length = link_lengths(case)[link]
    d2 = max((px - real.com[0]) ** 2 + (py - real.com[1]) ** 2 for px, py in link_pins(case, link))
    floor = real.mass * max(d2, 1e-8 * length**2) / POINT_RATIO
    if real.inertia > floor:
        return 0.0
    bar = settings.driven_fictitious_mass * length**2 / 12.0
    return settings.fictitious_scale * (bar + real.mass * d2 / INERTIA_RATIO)


def body_inertia(case: Case, link: int, settings: SolverSettings,
                 mode: MassMode) -> tuple[float, float, Vec]:
    """(mass, moment about the centre of gravity, centre of gravity in the link frame).

    ``fictitious``: every link gets ``settings.fictitious_mass`` as a uniform
    bar between its pins (statics: inertia is irrelevant at rest).
    ``real``: the Case's mass and inertia; a massless link gets
    ``settings.driven_fictitious_mass`` × ``settings.fictitious_scale`` as a
    uniform bar, and a link with (nearly) no inertia about its centre of
    gravity the :func:`added_inertia` (see
    :class:`~mechcheck.sim_models.pymunk.settings.SolverSettings`): the price
    of pymunk refusing massless bodies and of its solver stalling on point
    masses off the pins. A driven run removes their inertia forces by
    extrapolation.
    """
    length = link_lengths(case)[link]
    bar_centre = (0.5 * length, 0.0) if not (link == 4 and _has_slider(case)) else (0.0, 0.0)
    if mode == "fictitious":
        m = settings.fictitious_mass
        return m, m * length**2 / 12.0, bar_centre
    real = case.mass_of(link)
    light = settings.driven_fictitious_mass * settings.fictitious_scale
    if real is None:
        return light, light * length**2 / 12.0, bar_centre
    return real.mass, real.inertia + added_inertia(case, link, settings), real.com


def _has_slider(case: Case) -> bool:
    return case.mechanism == "slider_crank"


def make_bodies(case: Case, settings: SolverSettings, mode: MassMode) -> dict[int, pymunk.Body]:
    """The three moving links as dynamic bodies (not yet placed)."""
    bodies = {}
    for link in (2, 3, 4):
        mass, moment, cog = body_inertia(case, link, settings, mode)
        body = pymunk.Body(mass, moment)
        body.center_of_gravity = cog
        bodies[link] = body
    return bodies


def make_pins(case: Case, static: pymunk.Body,
              bodies: dict[int, pymunk.Body]) -> dict[str, pymunk.PivotJoint]:
    """One PivotJoint per pin, body a = link i, body b = link j (F_ij acts on b)."""
    pins = {}
    for name, (i, anchor_i, j, anchor_j) in pin_anchors(case).items():
        a = static if i == 1 else bodies[i]
        pins[name] = pymunk.PivotJoint(a, bodies[j], anchor_i, anchor_j)
    return pins


def make_slide(case: Case, static: pymunk.Body,
               slider: pymunk.Body) -> tuple[pymunk.GrooveJoint, pymunk.GearJoint]:
    """The prismatic joint: pin B on the slide line, slider held at the slide angle.

    The groove runs well past the reachable stroke (|s14| ≤ a2 + a3) so its
    end stops never engage.
    """
    g = preset_geometry(case)
    assert not isinstance(g, FourBarGeometry)
    (ux, uy), (nx, ny) = slide_axes(case)
    e = g.offset
    reach = 2.0 * (g.a2 + g.a3 + abs(e))
    start = (e * nx - reach * ux, e * ny - reach * uy)
    end = (e * nx + reach * ux, e * ny + reach * uy)
    groove = pymunk.GrooveJoint(static, slider, start, end, (0.0, 0.0))
    lock = pymunk.GearJoint(static, slider, case.ground_angle, 1.0)
    return groove, lock


def make_space(settings: SolverSettings) -> pymunk.Space:
    """An empty space: no gravity (weights are explicit forces), constant settings."""
    space = pymunk.Space()
    space.iterations = int(settings.iterations)
    space.gravity = (0.0, 0.0)
    space.damping = settings.damping
    return space


def build_model(case: Case, settings: SolverSettings, *, mass_mode: MassMode = "fictitious",
                driver_kind: DriverKind = "static") -> Model:
    """Build the pymunk model of ``case``, posed on its analytic pose at ``case.theta12``.

    ``driver_kind = "static"`` locks the drive link to the ground at its
    analytic angle; ``"kinematic"`` locks it (phase 0) to a kinematic body
    whose angle the caller moves along the prescribed motion.
    """
    space = make_space(settings)
    static = space.static_body
    bodies = make_bodies(case, settings, mass_mode)
    pins = make_pins(case, static, bodies)
    driver = static if driver_kind == "static" else pymunk.Body(body_type=pymunk.Body.KINEMATIC)
    drive = pymunk.GearJoint(driver, bodies[case.drive_link], 0.0, 1.0)
    model = Model(case, settings, space, bodies, pins, drive, driver,
                  reach={k: max(v, 1e-12) for k, v in link_lengths(case).items()},
                  mass_mode=mass_mode)
    if _has_slider(case):
        model.groove, model.slider_lock = make_slide(case, static, bodies[4])
    space.add(*bodies.values())
    if driver_kind == "kinematic":
        space.add(driver)
    for constraint in model.constraints():
        constraint.error_bias = settings.error_bias
        space.add(constraint)
    place(model, analytic_pose(case, case.theta12))
    return model


def analytic_pose(case: Case, theta12: float) -> Pose:
    """The closed-form pose at one θ12 (static: velocities zero)."""
    return pose_of(case, np.array([theta12]), omega=0.0, alpha=0.0)


def place(model: Model, pose: Pose, index: int = 0) -> None:
    """Put every body on its link frame at ``pose[index]``, at rest, and hold the drive there.

    This only seeds the configuration (and re-poses it in the constraint
    solve); the forces are still pymunk's.
    """
    for link, body in model.bodies.items():
        state = pose.links[link]
        # Angle first: pymunk rotates a body about its centre of gravity, so
        # setting the angle after the position would move the link origin.
        body.angle = float(state.angle[index])
        body.position = (float(state.origin[index, 0]), float(state.origin[index, 1]))
        body.velocity = (0.0, 0.0)
        body.angular_velocity = 0.0
    held = float(pose.links[model.case.drive_link].angle[index])
    if model.driver.body_type == pymunk.Body.STATIC:
        model.drive.phase = held
    else:
        model.driver.angle = held
        model.drive.phase = 0.0
