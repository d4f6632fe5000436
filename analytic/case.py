"""The one immutable description of a problem: :class:`Case`.

A Case is built once (from a TOML file by :mod:`mechcheck.casefile`, or in code)
and flows unchanged through every backend. Its mechanism is always a
:class:`~mechcheck.analytic.linkage.Linkage`; a four-bar or slider-crank is drawn as one
when it is built (:func:`mechcheck.analytic.presets.preset_case`) and keeps its
:class:`Preset` beside it. Everything inside is SI and radians; the file format's degrees
and millimetres are converted at the border.

Every value checks itself when built and raises :class:`CaseError` naming the
offending key, so an impossible problem never reaches a solver.

Examples
--------
>>> import math
>>> from mechcheck.analytic.presets import preset_case
>>> case = preset_case(
...     name="demo",
...     geometry=FourBarGeometry(a1=0.14, a2=0.08, a3=0.10, a4=0.12),
...     theta12=math.radians(60.0),
... )
>>> case.mechanism, [j.name for j in case.linkage.joints]
('four_bar', ['A0', 'A', 'B', 'B0'])
"""

from __future__ import annotations

import itertools
import re
from collections.abc import Mapping
from dataclasses import dataclass, field, fields, replace
from typing import TYPE_CHECKING, ClassVar, Literal

from mechcheck.analytic.linkage import Linkage
from mechcheck.analytic.values import (
    MAX_TIME,
    CaseError,
    FrozenMap,
    Vec2,
    bounded_angle,
    finite,
    link_length,
    nonnegative,
    pair,
    positive,
)

if TYPE_CHECKING:
    from mechcheck.analytic.presets import Renaming

Mechanism = Literal["four_bar", "slider_crank", "linkage"]

FOUR_BAR_PINS = ("A0", "A", "B", "B0")
SLIDER_CRANK_PINS = ("A0", "A", "B")
MOVING_LINKS = (2, 3, 4)
NAME_PATTERN = re.compile(r"[A-Za-z0-9_-]+")


def _link(link: int, key: str) -> int:
    if isinstance(link, bool) or not isinstance(link, int) or link not in MOVING_LINKS:
        raise CaseError(f"must be 2, 3 or 4 (the moving links), got {link!r}", key=key)
    return link


@dataclass(frozen=True)
class FourBarGeometry:
    """Link lengths of a four-bar, metres: ground a1 = A0B0, crank a2 = A0A,
    coupler a3 = AB, rocker a4 = B0B."""

    a1: float
    a2: float
    a3: float
    a4: float

    #: What a four-bar is, for the code that asks (never by comparing names).
    mechanism: ClassVar[Mechanism] = "four_bar"
    branches: ClassVar[tuple[str, str]] = ("open", "crossed")
    pins: ClassVar[tuple[str, ...]] = FOUR_BAR_PINS
    joints: ClassVar[tuple[str, ...]] = FOUR_BAR_PINS
    #: Link 4 turns about B0: it can take the drive (``drive_link = 4``) and has θ14.
    rocker: ClassVar[bool] = True

    def __post_init__(self) -> None:
        for key in ("a1", "a2", "a3", "a4"):
            object.__setattr__(self, key, link_length(getattr(self, key), f"geometry.{key}"))
        why = self.never_assembles()
        if why:
            raise CaseError(f"cannot be assembled at any θ12: {why}", key="geometry")

    def never_assembles(self) -> str | None:
        """Why no θ12 assembles this four-bar, or None if some does."""
        lengths = (self.a1, self.a2, self.a3, self.a4)
        if max(lengths) > sum(lengths) - max(lengths):
            return "a link is longer than the other three together"
        return None

    @property
    def scale(self) -> float:
        """A characteristic length (the longest link), for dimensionless measures."""
        return max(self.a1, self.a2, self.a3, self.a4)


@dataclass(frozen=True)
class SliderCrankGeometry:
    """Crank a2 = A0A, connecting rod a3 = AB and offset e of the slide line, metres."""

    a2: float
    a3: float
    offset: float = 0.0

    mechanism: ClassVar[Mechanism] = "slider_crank"
    branches: ClassVar[tuple[str, str]] = ("right", "left")
    pins: ClassVar[tuple[str, ...]] = SLIDER_CRANK_PINS
    joints: ClassVar[tuple[str, ...]] = (*SLIDER_CRANK_PINS, "slide")
    #: Link 4 slides: it has s14, no rotation to drive.
    rocker: ClassVar[bool] = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "a2", link_length(self.a2, "geometry.a2"))
        object.__setattr__(self, "a3", link_length(self.a3, "geometry.a3"))
        object.__setattr__(self, "offset", finite(self.offset, "geometry.offset"))
        why = self.never_assembles()
        if why:
            raise CaseError(f"cannot be assembled at any θ12: {why}", key="geometry")

    def never_assembles(self) -> str | None:
        """Why no θ12 assembles this slider-crank, or None if some does."""
        if abs(self.offset) > self.a2 + self.a3:
            return "the offset exceeds crank plus rod"
        return None

    @property
    def scale(self) -> float:
        return max(self.a2, self.a3, abs(self.offset))


PresetGeometry = FourBarGeometry | SliderCrankGeometry


@dataclass(frozen=True)
class Load:
    """An external force at a body-fixed point plus an optional pure moment.

    ``at`` is in the link frame (metres); ``force`` is global (N); ``torque`` is
    CCW positive (N·m).
    """

    link: int
    at: Vec2 = (0.0, 0.0)
    force: Vec2 = (0.0, 0.0)
    torque: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "link", _link(self.link, "link"))
        object.__setattr__(self, "at", pair(self.at, "at"))
        object.__setattr__(self, "force", pair(self.force, "force"))
        object.__setattr__(self, "torque", finite(self.torque, "torque"))


@dataclass(frozen=True)
class Mass:
    """Mass (kg), centre of mass in the link frame (m) and inertia about it (kg·m²)."""

    link: int
    mass: float
    com: Vec2 = (0.0, 0.0)
    inertia: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "link", _link(self.link, "link"))
        object.__setattr__(self, "mass", positive(self.mass, "mass"))
        object.__setattr__(self, "com", pair(self.com, "com"))
        object.__setattr__(self, "inertia", nonnegative(self.inertia, "inertia"))


@dataclass(frozen=True)
class Motion:
    """Prescribed motion of link 2 at the pose: ω (rad/s) and α (rad/s²), CCW +."""

    omega: float = 0.0
    alpha: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "omega", finite(self.omega, "motion.omega"))
        object.__setattr__(self, "alpha", finite(self.alpha, "motion.alpha"))

    @property
    def is_static(self) -> bool:
        return self.omega == 0.0 and self.alpha == 0.0


@dataclass(frozen=True)
class Friction:
    """Joint friction: Coulomb (friction circle, μ·r·|F|) at pins, μ·|N| on the
    slide, and viscous terms.

    ``direction`` is the sense of the input rotation (+1 CCW, -1 CW) that the
    friction opposes; 0 means "take it from motion.omega".
    """

    mu: float = 0.0
    pin_radius: Mapping[str, float] = field(default_factory=dict)
    slide_mu: float | None = None
    viscous: Mapping[str, float] = field(default_factory=dict)
    direction: int = 0

    def __post_init__(self) -> None:
        object.__setattr__(self, "mu", nonnegative(self.mu, "friction.mu"))
        if self.slide_mu is not None:
            object.__setattr__(self, "slide_mu",
                               nonnegative(self.slide_mu, "friction.slide_mu"))
        for name in ("pin_radius", "viscous"):
            values = {joint: nonnegative(v, f"friction.{name}.{joint}")
                      for joint, v in dict(getattr(self, name)).items()}
            object.__setattr__(self, name, FrozenMap(values))
        if self.direction not in (-1, 0, 1):
            raise CaseError("must be 'cw' or 'ccw'", key="friction.direction")

    def pin_moment_arm(self, joint: str) -> float:
        """μ·r of a pin: the radius of the (small-angle) friction circle."""
        return self.mu * self.pin_radius.get(joint, 0.0)

    def slide_coefficient(self) -> float:
        return self.mu if self.slide_mu is None else self.slide_mu


@dataclass(frozen=True)
class Preset:
    """A four-bar or slider-crank as its case file writes it: link lengths, input angle,
    branch and loads in the preset's own words (CONVENTIONS.md), SI units and radians.

    A :class:`Case` keeps it beside the linkage it is drawn as, for what only the preset
    has: sweeps over θ12, the theory commands, the closed-form position analysis that
    draws the linkage, and the report's echo of the file.

    Parameters
    ----------
    geometry : :class:`FourBarGeometry` or :class:`SliderCrankGeometry`.
    theta12 : input angle, rad, global (from +x).
    branch : ``open``/``crossed`` (four-bar) or ``right``/``left`` (slider-crank).
    ground_angle : direction of A0→B0, or of the slide axis, rad.
    drive_link : 2, or 4 (four-bar only): the link the balancing torque acts on.
    gravity : (gx, gy), m/s².
    loads, masses : tuples of :class:`Load` and :class:`Mass`.
    motion : prescribed ω, α of link 2.
    friction : :class:`Friction` or None.
    """

    geometry: PresetGeometry
    theta12: float
    branch: str = ""
    ground_angle: float = 0.0
    drive_link: int = 2
    gravity: Vec2 = (0.0, 0.0)
    loads: tuple[Load, ...] = ()
    masses: tuple[Mass, ...] = ()
    motion: Motion = Motion()
    friction: Friction | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.geometry, (FourBarGeometry, SliderCrankGeometry)):
            raise CaseError("must be a FourBarGeometry or SliderCrankGeometry", key="geometry")
        branches = self.geometry.branches
        if self.branch == "":
            object.__setattr__(self, "branch", branches[0])
        if self.branch not in branches:
            raise CaseError(f"must be one of {', '.join(map(repr, branches))} for a "
                            f"{self.mechanism}, got {self.branch!r}", key="branch")
        object.__setattr__(self, "theta12", bounded_angle(self.theta12, "theta12"))
        object.__setattr__(self, "ground_angle", bounded_angle(self.ground_angle, "ground_angle"))
        object.__setattr__(self, "gravity", pair(self.gravity, "gravity"))
        if self.drive_link not in (2, 4):
            raise CaseError(f"must be 2 or 4, got {self.drive_link!r}", key="drive_link")
        if self.drive_link == 4 and not self.geometry.rocker:
            raise CaseError("the drive can act on link 4 only for a four_bar (a slider has "
                            "no rotation to drive)", key="drive_link")
        object.__setattr__(self, "loads", tuple(self.loads))
        object.__setattr__(self, "masses", tuple(self.masses))
        seen: set[int] = set()
        for i, m in enumerate(self.masses):
            if m.link in seen:
                raise CaseError(f"link {m.link} has more than one mass entry", key=f"masses[{i}].link")
            seen.add(m.link)
        self._validate_friction()

    def _validate_friction(self) -> None:
        f = self.friction
        if f is None:
            return
        self._check_joint_names(f)
        omega_sense = (self.motion.omega > 0) - (self.motion.omega < 0)
        if f.direction and omega_sense and f.direction != omega_sense:
            raise CaseError(f"says {'ccw' if f.direction > 0 else 'cw'} but motion.omega = "
                            f"{self.motion.omega:g} turns the other way", key="friction.direction")
        if not omega_sense and not f.direction and self.has_friction:
            raise CaseError("is required when motion.omega is 0: friction opposes a motion, "
                            "so its sense must be given ('cw' or 'ccw')", key="friction.direction")

    def _check_joint_names(self, f: Friction) -> None:
        g = self.geometry
        for table, known, what in ((f.pin_radius, g.pins, "pin"), (f.viscous, g.joints, "joint")):
            for joint in table:
                if joint not in known:
                    key = "pin_radius" if what == "pin" else "viscous"
                    raise CaseError(f"unknown {what} {joint!r} for a {self.mechanism}; {what}s are "
                                    f"{', '.join(known)}", key=f"friction.{key}.{joint}")
        if f.slide_mu is not None and g.rocker:
            raise CaseError("a four_bar has no slide", key="friction.slide_mu")

    @property
    def mechanism(self) -> Mechanism:
        return self.geometry.mechanism

    @property
    def input_sense(self) -> int:
        """+1 CCW, -1 CW, 0 unknown: the sense friction opposes."""
        if self.motion.omega:
            return 1 if self.motion.omega > 0 else -1
        return self.friction.direction if self.friction else 0

    @property
    def has_coulomb_friction(self) -> bool:
        """True when any Coulomb term is present (the equations are then nonlinear)."""
        f = self.friction
        if f is None:
            return False
        if any(f.pin_moment_arm(j) > 0.0 for j in self.geometry.pins):
            return True
        return not self.geometry.rocker and f.slide_coefficient() > 0.0

    @property
    def has_viscous_friction(self) -> bool:
        return self.friction is not None and any(c > 0.0 for c in self.friction.viscous.values())

    @property
    def has_friction(self) -> bool:
        return self.has_coulomb_friction or self.has_viscous_friction

    @property
    def is_moving(self) -> bool:
        return not self.motion.is_static

    def mass_of(self, link: int) -> Mass | None:
        return next((m for m in self.masses if m.link == link), None)


#: The most output times a trajectory may ask for.
MAX_OUTPUTS = 100_000


@dataclass(frozen=True)
class Simulation:
    """A linkage released to move freely (``[case.simulate]``): from time 0, where its
    drivers stand at their values with their velocities, to ``end`` (s), read at each of
    ``outputs`` (s, increasing, within 0 … end). ``rates`` gives the joint rates at time 0
    (rad/s or m/s) of joints that no driver holds; every other free coordinate starts at
    rest."""

    end: float
    outputs: tuple[float, ...]
    rates: Mapping[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not 0.0 < finite(self.end, "simulate.end") <= MAX_TIME:
            raise CaseError(f"must be within 0 … {MAX_TIME:g} s (and above 0), got {self.end:g}",
                            key="simulate.end")
        outputs = tuple(finite(t, "simulate.outputs") for t in self.outputs)
        if not 0 < len(outputs) <= MAX_OUTPUTS:
            raise CaseError(f"must name 1 … {MAX_OUTPUTS} times, got {len(outputs)}",
                            key="simulate.outputs")
        if outputs[0] < 0.0 or outputs[-1] > self.end * (1.0 + 1e-12):
            raise CaseError(f"must lie within 0 … end ({self.end:g} s)", key="simulate.outputs")
        if any(b <= a for a, b in itertools.pairwise(outputs)):
            raise CaseError("must increase", key="simulate.outputs")
        object.__setattr__(self, "outputs", outputs)
        object.__setattr__(self, "rates", FrozenMap(
            {j: finite(v, f"simulate.rates.{j}") for j, v in self.rates.items()}))

    def check_against(self, linkage: Linkage) -> None:
        """The rates name joints of ``linkage`` that no driver holds."""
        driven = {d.joint for d in linkage.drivers}
        names = {j.name for j in linkage.joints}
        for joint in self.rates:
            if joint not in names:
                raise CaseError(f"unknown joint {joint!r}", key=f"simulate.rates.{joint}")
            if joint in driven:
                raise CaseError("a driven joint starts at its driver's velocity: give it there",
                                key=f"simulate.rates.{joint}")
        if not linkage.free_motion:
            raise CaseError("a linkage to simulate is built with free_motion=True",
                            key="simulate")


@dataclass(frozen=True)
class Case:
    """One force-analysis problem at one pose, in SI units and radians: a mechanism drawn
    as a :class:`~mechcheck.analytic.linkage.Linkage`, which is all a backend sees.

    Parameters
    ----------
    name : unique within a run (letters, digits, ``-`` and ``_``).
    geometry : the linkage, drawn at the case's pose. None only for a preset whose
        closed form does not assemble at its θ12 (its verdict is then the preset's).
    preset : the four-bar or slider-crank the linkage was drawn from, or None. Build such
        a case with :func:`mechcheck.analytic.presets.preset_case`, which draws it.
    tolerance : per-case tolerance overrides (see :mod:`mechcheck.tolerance`),
        as ``((selector, rtol, atol), ...)``.
    source : where the case came from (a file path), for messages only.
    names : how the linkage's results read under the preset's names
        (:class:`~mechcheck.analytic.presets.Renaming`); None for a linkage.
    length_unit : the unit its file writes lengths in (a key of ``LENGTH_UNITS``), for
        messages only: they quote lengths as the file wrote them.
    simulation : given, the case is a trajectory (``mechcheck simulate``): its linkage
        moves freely from its drawn state; None for a case at one pose.
    """

    name: str
    geometry: Linkage | None
    preset: Preset | None = None
    tolerance: tuple[tuple[str, float, float], ...] = ()
    source: str = ""
    names: Renaming | None = field(default=None, compare=False, repr=False)
    length_unit: str = field(default="m", compare=False)
    simulation: Simulation | None = None

    def __post_init__(self) -> None:
        try:
            self._validate()
        except CaseError as error:
            raise error.located(case=self.name, file=self.source) from None

    def _validate(self) -> None:
        if not isinstance(self.name, str) or not NAME_PATTERN.fullmatch(self.name):
            raise CaseError(f"must use only letters, digits, '-' and '_', got {self.name!r}",
                            key="name")
        if self.preset is not None and not isinstance(self.preset, Preset):
            raise CaseError("must be a Preset", key="preset")
        if self.geometry is None and self.preset is None:
            raise CaseError("must be a Linkage", key="geometry")
        if self.geometry is not None and not isinstance(self.geometry, Linkage):
            raise CaseError("must be a Linkage (a four-bar or slider-crank is drawn as one "
                            "by mechcheck.analytic.presets.preset_case)", key="geometry")
        if self.simulation is not None:
            if self.preset is not None:
                raise CaseError("a trajectory is written in the linkage format", key="simulate")
            self.simulation.check_against(self.linkage)
        elif self.geometry is not None and self.geometry.free_motion:
            raise CaseError("a linkage that moves freely needs a [case.simulate] table",
                            key="simulate")

    # -- derived facts ----------------------------------------------------------------
    @property
    def mechanism(self) -> Mechanism:
        """The case file's ``mechanism``: a label for tables and messages."""
        return "linkage" if self.preset is None else self.preset.mechanism

    @property
    def is_preset(self) -> bool:
        """Drawn from a four-bar or slider-crank: read under the preset's names, swept over
        θ12 (:mod:`mechcheck.analytic.presets`)."""
        return self.preset is not None

    @property
    def linkage(self) -> Linkage:
        """The mechanism as a linkage at the case's pose."""
        if self.geometry is None:
            raise TypeError(f"case {self.name!r} does not assemble at its θ12: it has no "
                            "linkage to draw")
        return self.geometry

    @property
    def gravity(self) -> Vec2:
        return self.preset.gravity if self.preset is not None else self.linkage.gravity

    @property
    def scale(self) -> float:
        """A characteristic length, for dimensionless measures and absolute tolerances: a
        preset's longest link, a linkage's own scale."""
        return self.preset.geometry.scale if self.preset is not None else self.linkage.scale

    @property
    def has_coulomb_friction(self) -> bool:
        """True when any Coulomb term is present (the equations are then nonlinear)."""
        return (self.preset or self.linkage).has_coulomb_friction

    @property
    def has_viscous_friction(self) -> bool:
        if self.preset is not None:
            return self.preset.has_viscous_friction
        f = self.linkage.friction
        return f is not None and any(c > 0.0 for c in f.viscous.values())

    @property
    def has_friction(self) -> bool:
        return self.has_coulomb_friction or self.has_viscous_friction

    @property
    def is_trajectory(self) -> bool:
        """Moves freely over time (``mechcheck simulate``) rather than standing at one pose."""
        return self.simulation is not None

    @property
    def kind(self) -> str:
        """``static``, ``dynamic``, ``friction`` or ``trajectory``: keys the tolerance policy."""
        if self.simulation is not None:
            return "trajectory"
        if self.has_friction:
            return "friction"
        return "dynamic" if (self.preset or self.linkage).is_moving else "static"

    def with_(self, **changes: object) -> Case:
        """A copy with some fields changed (and re-validated). A preset's own fields
        (``theta12``, ``loads``, …) change through
        :func:`mechcheck.analytic.presets.redrawn`, which draws its linkage again."""
        moved = sorted(set(changes) & PRESET_FIELDS)
        if moved:
            raise TypeError(f"{', '.join(moved)} belong to the case's preset: "
                            "mechcheck.analytic.presets.redrawn(case, ...) changes them")
        return replace(self, **changes)  # type: ignore[arg-type]


def preset_of(case: Case | Preset) -> Preset:
    """The preset a case was drawn from (or the preset itself), for code that has a closed
    form for four-bars and slider-cranks."""
    if isinstance(case, Preset):
        return case
    if case.preset is None:
        raise TypeError(f"case {case.name!r} is a linkage: it has no four-bar or "
                        "slider-crank preset")
    return case.preset


#: The preset's fields that a Case does not have (``geometry`` is the case's linkage).
PRESET_FIELDS = frozenset(f.name for f in fields(Preset)) - {"geometry"}
