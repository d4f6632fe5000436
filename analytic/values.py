"""The small values every case is built from, and the one error they raise.

Every number of a case file passes through :func:`finite` or :func:`bounded_angle`, and
every problem is one :class:`CaseError` naming the key. Both the four-bar and
slider-crank :class:`~mechcheck.analytic.case.Case` and the general
:class:`~mechcheck.analytic.linkage.Linkage` build on this module, which imports neither.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from contextvars import ContextVar
from typing import TypeVar

Vec2 = tuple[float, float]
V = TypeVar("V")

#: The name of the fixed link of every linkage.
GROUND = "ground"
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


#: The largest rotation of a driver from the drawn pose, degrees (ten turns). The pose is
#: found by continuation from the drawn pose in steps of at most 2°, so time and memory grow
#: with the rotation: 1e8° took 3.7 GB.
MAX_DRIVER_ROTATION_DEG = 3600.0
#: The largest displacement of a driver from the drawn pose, in multiples of the linkage's
#: size (``Linkage.scale``, about the extent of its drawing). The continuation steps 2 % of
#: that size, so time grows with the travel (1e9 mm ran for minutes); no slide of a drawn linkage
#: reaches ten times the drawing.
MAX_DRIVER_TRAVEL = 10.0

#: Metres per unit of the lengths a case file may be written in.
LENGTH_UNITS = {"m": 1.0, "mm": 1e-3}
# Values are checked in SI, but a message quotes a length in the unit its file is written
# in: the reader of a millimetre file must recognise the number they wrote.
_QUOTED_UNIT: ContextVar[str] = ContextVar("quoted_length_unit", default="m")


@contextmanager
def lengths_quoted_in(unit: str) -> Iterator[None]:
    """Within this block, messages quote lengths in ``unit`` (a key of LENGTH_UNITS)."""
    token = _QUOTED_UNIT.set(unit)
    try:
        yield
    finally:
        _QUOTED_UNIT.reset(token)


#: Significant digits of a length a message quotes: a drawing in millimetres to four
#: decimals has up to nine (1234.5678 mm), and a message that rounded them away would show
#: two lengths a check tells apart (a gear's centre distance, to 1e-6 of it) as one.
QUOTED_DIGITS = 9


def length_text(metres: float, unit: str | None = None) -> str:
    """A length for a message, in ``unit``, by default the unit of the file being read
    (metres outside one), to :data:`QUOTED_DIGITS`."""
    unit = unit or _QUOTED_UNIT.get()
    return f"{metres / LENGTH_UNITS[unit]:.{QUOTED_DIGITS}g} {unit}"


#: The longest time a trajectory may span, s: a simulator steps it at its finest time step.
MAX_TIME = 1.0e4


def finite(value: float, key: str, limit: float = MAX_MAGNITUDE) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise CaseError(f"must be a number, got {value!r}", key=key)
    if isinstance(value, int) and value.bit_length() > 1023:
        # Python integers are unbounded: float() would raise, and printing one can too.
        raise CaseError(f"must be finite, got an integer of {value.bit_length()} bits, beyond "
                        "any floating-point number", key=key)
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


def positive(value: float, key: str) -> float:
    value = finite(value, key)
    if value <= 0.0:
        raise CaseError(f"must be > 0, got {value:g}", key=key)
    return value


def link_length(value: float, key: str) -> float:
    value = finite(value, key)
    if value < MIN_LINK_LENGTH:
        bound = "> 0" if value <= 0.0 else f"at least {length_text(MIN_LINK_LENGTH)} (a micrometre)"
        raise CaseError(f"must be {bound}, got {length_text(value)}", key=key)
    return value


def nonnegative(value: float, key: str) -> float:
    value = finite(value, key)
    if value < 0.0:
        raise CaseError(f"must be >= 0, got {value:g}", key=key)
    return value


def driver_rotation(value: float, key: str) -> float:
    """A driver's rotation from the drawn pose in radians, refused (in degrees) beyond
    ±MAX_DRIVER_ROTATION_DEG."""
    value = finite(value, key, limit=math.inf)
    if abs(value) > math.radians(MAX_DRIVER_ROTATION_DEG):
        raise CaseError(f"must be within ±{MAX_DRIVER_ROTATION_DEG:g}° (ten turns), got "
                        f"{math.degrees(value):g}°: the pose is found by continuation from the "
                        "drawn pose in steps of 2°, so each turn costs time and memory", key=key)
    return value


def driver_displacement(value: float, size: float, key: str) -> float:
    """A driver's displacement from the drawn pose in metres, refused beyond
    ±MAX_DRIVER_TRAVEL times the linkage's size ``size`` (m)."""
    value = finite(value, key)
    bound = MAX_DRIVER_TRAVEL * size
    # The slack keeps a travel written as exactly the bound, in mm, from failing by rounding.
    if abs(value) > bound * (1.0 + 1e-12):
        raise CaseError(f"must be within ±{MAX_DRIVER_TRAVEL:g} × the linkage's size "
                        f"(±{length_text(bound)}), got {length_text(value)}: the pose is found "
                        "by continuation from the drawn pose in steps of 2 % of its size, so "
                        "a longer travel costs time without bound", key=key)
    return value


def too_close(points: Sequence[tuple[str, Vec2]]) -> tuple[str, str, float] | None:
    """Two of ``points`` closer than MIN_LINK_LENGTH but not at one place, with their
    distance, or None.

    In linear time: on a grid of cells MIN_LINK_LENGTH / 2 wide, two different places in
    one cell are too close, so each cell holds one place and only the 5 × 5 cells around it
    can hold another within reach.
    """
    cell = MIN_LINK_LENGTH / 2.0
    grid: dict[tuple[int, int], tuple[str, Vec2]] = {}
    for name, (x, y) in points:
        i, j = math.floor(x / cell), math.floor(y / cell)
        for di in range(-2, 3):
            for dj in range(-2, 3):
                other = grid.get((i + di, j + dj))
                if other is None or other[1] == (x, y):
                    continue
                distance = math.hypot(x - other[1][0], y - other[1][1])
                if distance < MIN_LINK_LENGTH:
                    return other[0], name, distance
        grid.setdefault((i, j), (name, (x, y)))
    return None


def pair(value: Vec2, key: str) -> Vec2:
    """Two finite numbers, or one error naming ``key``."""
    if isinstance(value, str) or not hasattr(value, "__len__") or len(value) != 2:
        raise CaseError(f"must be a pair [x, y], got {value!r}", key=key)
    return (finite(value[0], f"{key}[0]"), finite(value[1], f"{key}[1]"))


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
