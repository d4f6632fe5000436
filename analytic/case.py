"""The one immutable description of a problem: :class:`Case`.

A Case is built once (from a TOML file by :mod:`mechcheck.casefile`, or in code)
and flows unchanged through every backend. Everything inside is SI and radians;
the file format's degrees and millimetres are converted at the border.

Every value checks itself when built and raises :class:`CaseError` naming the
offending key, so an impossible problem never reaches a solver.

Examples
--------
>>> import math
>>> case = Case(
...     name="demo",
...     geometry=FourBarGeometry(a1=0.14, a2=0.08, a3=0.10, a4=0.12),
...     theta12=math.radians(60.0),
... )
>>> case.mechanism
'four_bar'
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Literal, TypeVar, Union

if TYPE_CHECKING:
    from mechcheck.analytic.linkage import Linkage

Mechanism = Literal["four_bar", "slider_crank", "linkage"]
Vec2 = tuple[float, float]
V = TypeVar("V")

FOUR_BAR_PINS = ("A0", "A", "B", "B0")
SLIDER_CRANK_PINS = ("A0", "A", "B")
MOVING_LINKS = (2, 3, 4)
NAME_PATTERN = re.compile(r"[A-Za-z0-9_-]+")
_CONTROL = re.compile(r"[\x00-\x1f\x7f]")


class CaseError(ValueError):
    """An unusable case: names the file, the case and the key at fault.

    ``str(error)`` is the one-line message the command line prints.
    """

    def __init__(self, message: str, *, key: str = "", case: str = "", file: str = "") -> None:
        self.message = message
        self.key = key
        self.case = case
        self.file = file
        super().__init__(self.__str__())

    def located(self, *, file: str | None = None, case: str | None = None,
                key_prefix: str = "") -> CaseError:
        """The same error with its place filled in (outer callers know more)."""
        key = f"{key_prefix}.{self.key}" if key_prefix and self.key else (self.key or key_prefix)
        return CaseError(self.message, key=key, case=case if case is not None else self.case,
                         file=file if file is not None else self.file)

    def __str__(self) -> str:
        where = []
        if self.file:
            where.append(self.file)
        if self.case:
            where.append(f"case '{self.case}'")
        if self.key:
            where.append(f"key '{self.key}'")
        text = (": ".join(where) + ": " if where else "") + self.message
        # One line whatever the file held: control characters (a newline in a name) are escaped.
        return _CONTROL.sub(lambda m: repr(m[0])[1:-1], text)


#: The largest magnitude of any value, in SI units (m, N, N·m, kg, kg·m², rad/s …): far
#: beyond any machine, and far enough below float64's 1e308 that the products the
#: equations form (m·ω²·length, force·length², length⁴) can neither overflow nor lose
#: the 1e-9 agreement the backends are held to. A length of 1e155 overflowed; 1e200 N gave NaN.
MAX_MAGNITUDE = 1e12
#: The shortest link, m: below a micrometre a link is no drawing of a machine, and lengths
#: near 1e-300 vanish when squared (the loop equations then divide by zero).
MIN_LINK_LENGTH = 1e-6
#: The largest angle, degrees (≈ 278 turns): beyond it sin and cos of a float64 angle lose
#: the digits the 1e-9 agreement needs.
MAX_ANGLE_DEG = 1e5


def finite(value: float, key: str, limit: float = MAX_MAGNITUDE) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise CaseError(f"must be a number, got {value!r}", key=key)
    if not math.isfinite(value):
        raise CaseError(f"must be finite, got {value!r}", key=key)
    if abs(value) > limit:
        raise CaseError(f"must be at most {limit:g} in magnitude (SI units), got {value:g}: "
                        "no machine is that large, and the arithmetic would overflow", key=key)
    return float(value)


def bounded_angle(value: float, key: str) -> float:
    """An angle in radians, refused (in the file's degrees) beyond ±MAX_ANGLE_DEG."""
    value = finite(value, key, limit=math.inf)
    if abs(value) > math.radians(MAX_ANGLE_DEG):
        raise CaseError(f"must be within ±{MAX_ANGLE_DEG:g}°, got {math.degrees(value):g}°",
                        key=key)
    return value


def _positive(value: float, key: str) -> float:
    value = finite(value, key)
    if value <= 0.0:
        raise CaseError(f"must be > 0, got {value:g}", key=key)
    return value


def _link_length(value: float, key: str) -> float:
    value = _positive(value, key)
    if value < MIN_LINK_LENGTH:
        raise CaseError(f"must be at least {MIN_LINK_LENGTH:g} m (a micrometre), got {value:g} m",
                        key=key)
    return value


def _nonnegative(value: float, key: str) -> float:
    value = finite(value, key)
    if value < 0.0:
        raise CaseError(f"must be >= 0, got {value:g}", key=key)
    return value


def _vec2(value: Vec2, key: str) -> Vec2:
    if len(value) != 2:
        raise CaseError(f"must be a pair [x, y], got {value!r}", key=key)
    return (finite(value[0], f"{key}[0]"), finite(value[1], f"{key}[1]"))


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

    def __post_init__(self) -> None:
        for key in ("a1", "a2", "a3", "a4"):
            object.__setattr__(self, key, _link_length(getattr(self, key), f"geometry.{key}"))

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

    def __post_init__(self) -> None:
        object.__setattr__(self, "a2", _link_length(self.a2, "geometry.a2"))
        object.__setattr__(self, "a3", _link_length(self.a3, "geometry.a3"))
        object.__setattr__(self, "offset", finite(self.offset, "geometry.offset"))

    @property
    def scale(self) -> float:
        return max(self.a2, self.a3, abs(self.offset))


Geometry = Union[FourBarGeometry, SliderCrankGeometry, "Linkage"]


PresetGeometry = FourBarGeometry | SliderCrankGeometry


def preset_geometry(case: Case) -> PresetGeometry:
    """The four-bar's or slider-crank's geometry, for code that has a closed form for them."""
    g = case.geometry
    if isinstance(g, (FourBarGeometry, SliderCrankGeometry)):
        return g
    raise TypeError(f"case {case.name!r} is a linkage: it has no four-bar or slider-crank "
                    "geometry")


def _linkage_type() -> type:
    from mechcheck.analytic.linkage import Linkage

    return Linkage


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
        object.__setattr__(self, "at", _vec2(self.at, "at"))
        object.__setattr__(self, "force", _vec2(self.force, "force"))
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
        object.__setattr__(self, "mass", _positive(self.mass, "mass"))
        object.__setattr__(self, "com", _vec2(self.com, "com"))
        object.__setattr__(self, "inertia", _nonnegative(self.inertia, "inertia"))


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
        object.__setattr__(self, "mu", _nonnegative(self.mu, "friction.mu"))
        if self.slide_mu is not None:
            object.__setattr__(self, "slide_mu",
                               _nonnegative(self.slide_mu, "friction.slide_mu"))
        for name in ("pin_radius", "viscous"):
            values = {joint: _nonnegative(v, f"friction.{name}.{joint}")
                      for joint, v in dict(getattr(self, name)).items()}
            object.__setattr__(self, name, FrozenMap(values))
        if self.direction not in (-1, 0, 1):
            raise CaseError("must be 'cw' or 'ccw'", key="friction.direction")

    def pin_moment_arm(self, joint: str) -> float:
        """μ·r of a pin: the radius of the (small-angle) friction circle."""
        return self.mu * self.pin_radius.get(joint, 0.0)

    def slide_coefficient(self) -> float:
        return self.mu if self.slide_mu is None else self.slide_mu


class FrozenMap(Mapping[str, V]):
    """A read-only, hashable, picklable mapping, so that the values holding it stay immutable."""

    def __init__(self, items: Mapping[str, V]) -> None:
        self._items = dict(items)

    def __getitem__(self, key: str) -> V:
        return self._items[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._items)

    def __len__(self) -> int:
        return len(self._items)

    def __hash__(self) -> int:
        return hash(tuple(sorted(self._items.items())))

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Mapping) and dict(self._items) == dict(other)

    def __repr__(self) -> str:
        return repr(self._items)


@dataclass(frozen=True)
class Case:
    """One force-analysis problem at one pose, in SI units and radians.

    Parameters
    ----------
    name : unique within a run (letters, digits, ``-`` and ``_``).
    geometry : :class:`FourBarGeometry` or :class:`SliderCrankGeometry`; it
        fixes ``mechanism``.
    theta12 : input angle, rad, global (from +x).
    branch : ``open``/``crossed`` (four-bar) or ``right``/``left`` (slider-crank).
    ground_angle : direction of A0→B0, or of the slide axis, rad.
    drive_link : 2, or 4 (four-bar only): the link the balancing torque acts on.
    gravity : (gx, gy), m/s².
    loads, masses : tuples of :class:`Load` and :class:`Mass`.
    motion : prescribed ω, α of link 2.
    friction : :class:`Friction` or None.
    tolerance : per-case tolerance overrides (see :mod:`mechcheck.tolerance`),
        as ``((selector, rtol, atol), ...)``.
    source : where the case came from (a file path), for messages only.
    """

    name: str
    geometry: Geometry
    theta12: float
    branch: str = ""
    ground_angle: float = 0.0
    drive_link: int = 2
    gravity: Vec2 = (0.0, 0.0)
    loads: tuple[Load, ...] = ()
    masses: tuple[Mass, ...] = ()
    motion: Motion = Motion()
    friction: Friction | None = None
    tolerance: tuple[tuple[str, float, float], ...] = ()
    source: str = ""

    def __post_init__(self) -> None:
        try:
            self._validate()
        except CaseError as error:
            raise error.located(case=self.name, file=self.source) from None

    def _validate(self) -> None:
        from mechcheck.analytic.linkage import Linkage  # late: linkage needs CaseError

        if not isinstance(self.name, str) or not NAME_PATTERN.fullmatch(self.name):
            raise CaseError(f"must use only letters, digits, '-' and '_', got {self.name!r}",
                            key="name")
        if isinstance(self.geometry, Linkage):
            # A linkage carries its own drivers, loads, masses and friction (LINKAGES.md).
            object.__setattr__(self, "gravity", _vec2(self.geometry.gravity, "gravity"))
            return
        if not isinstance(self.geometry, (FourBarGeometry, SliderCrankGeometry)):
            raise CaseError("must be a FourBarGeometry, SliderCrankGeometry or Linkage",
                            key="geometry")
        branches = ("open", "crossed") if self.mechanism == "four_bar" else ("right", "left")
        if self.branch == "":
            object.__setattr__(self, "branch", branches[0])
        if self.branch not in branches:
            raise CaseError(f"must be one of {', '.join(map(repr, branches))} for a "
                            f"{self.mechanism}, got {self.branch!r}", key="branch")
        object.__setattr__(self, "theta12", bounded_angle(self.theta12, "theta12"))
        object.__setattr__(self, "ground_angle", bounded_angle(self.ground_angle, "ground_angle"))
        object.__setattr__(self, "gravity", _vec2(self.gravity, "gravity"))
        if self.drive_link not in (2, 4):
            raise CaseError(f"must be 2 or 4, got {self.drive_link!r}", key="drive_link")
        if self.drive_link == 4 and self.mechanism == "slider_crank":
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
        from mechcheck.analytic.assembly import check_geometry  # late: assembly needs Case defined

        check_geometry(self.geometry)

    def _validate_friction(self) -> None:
        f = self.friction
        if f is None:
            return
        joints = FOUR_BAR_PINS if self.mechanism == "four_bar" else SLIDER_CRANK_PINS
        for joint in f.pin_radius:
            if joint not in joints:
                raise CaseError(f"unknown pin {joint!r} for a {self.mechanism}; pins are "
                                f"{', '.join(joints)}", key=f"friction.pin_radius.{joint}")
        viscous_joints = joints + (("slide",) if self.mechanism == "slider_crank" else ())
        for joint in f.viscous:
            if joint not in viscous_joints:
                raise CaseError(f"unknown joint {joint!r} for a {self.mechanism}; joints are "
                                f"{', '.join(viscous_joints)}", key=f"friction.viscous.{joint}")
        if f.slide_mu is not None and self.mechanism == "four_bar":
            raise CaseError("a four_bar has no slide", key="friction.slide_mu")
        omega_sense = (self.motion.omega > 0) - (self.motion.omega < 0)
        if f.direction and omega_sense and f.direction != omega_sense:
            raise CaseError(f"says {'ccw' if f.direction > 0 else 'cw'} but motion.omega = "
                            f"{self.motion.omega:g} turns the other way", key="friction.direction")
        if not omega_sense and not f.direction and self.has_friction:
            raise CaseError("is required when motion.omega is 0: friction opposes a motion, "
                            "so its sense must be given ('cw' or 'ccw')", key="friction.direction")

    # -- derived facts ----------------------------------------------------------------
    @property
    def mechanism(self) -> Mechanism:
        if isinstance(self.geometry, FourBarGeometry):
            return "four_bar"
        return "slider_crank" if isinstance(self.geometry, SliderCrankGeometry) else "linkage"

    @property
    def linkage(self) -> Linkage:
        """The mechanism as a linkage: a linkage case's own, or a preset drawn at this pose."""
        from mechcheck.analytic.presets import linkage_of

        if isinstance(self.geometry, (FourBarGeometry, SliderCrankGeometry)):
            return linkage_of(self)
        return self.geometry

    @property
    def input_sense(self) -> int:
        """+1 CCW, -1 CW, 0 unknown: the sense friction opposes."""
        if self.motion.omega:
            return 1 if self.motion.omega > 0 else -1
        return self.friction.direction if self.friction else 0

    @property
    def has_coulomb_friction(self) -> bool:
        """True when any Coulomb term is present (the equations are then nonlinear)."""
        if self.mechanism == "linkage":
            return self.linkage.has_coulomb_friction
        f = self.friction
        if f is None:
            return False
        pins = FOUR_BAR_PINS if self.mechanism == "four_bar" else SLIDER_CRANK_PINS
        if any(f.pin_moment_arm(j) > 0.0 for j in pins):
            return True
        return self.mechanism == "slider_crank" and f.slide_coefficient() > 0.0

    @property
    def has_viscous_friction(self) -> bool:
        f = self.linkage.friction if self.mechanism == "linkage" else self.friction
        return f is not None and any(c > 0.0 for c in f.viscous.values())

    @property
    def has_friction(self) -> bool:
        return self.has_coulomb_friction or self.has_viscous_friction

    @property
    def kind(self) -> str:
        """``static``, ``dynamic`` or ``friction``: keys the tolerance policy."""
        if self.has_friction:
            return "friction"
        moving = self.linkage.is_moving if self.mechanism == "linkage" else not self.motion.is_static
        return "dynamic" if moving else "static"

    def mass_of(self, link: int) -> Mass | None:
        return next((m for m in self.masses if m.link == link), None)

    def with_(self, **changes: object) -> Case:
        """A copy with some fields changed (and re-validated)."""
        return replace(self, **changes)  # type: ignore[arg-type]
