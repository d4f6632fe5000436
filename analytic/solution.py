"""What every backend returns: :class:`Solution`.

Values are SI with angles in radians, keyed by the CONVENTIONS quantity names
(``T12``/``T14``, ``F12_x`` … ``F14_y``, ``M14``, ``theta13``, ``theta14``,
``s14``). Unit conversion (radians → degrees) happens only when tables and
reports are drawn (:data:`QUANTITY_UNITS`).
"""

from __future__ import annotations

import functools
import re
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING, Literal

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import ArrayLike

Status = Literal["ok", "singular", "indeterminate", "not_settled", "not_applicable", "no_solution",
                 "error"]

#: Quantity -> (unit in tables, factor from the stored SI/radian value).
QUANTITY_UNITS: dict[str, tuple[str, float]] = {
    "T12": ("N*m", 1.0), "T14": ("N*m", 1.0), "M14": ("N*m", 1.0),
    **{f"F{j}_{c}": ("N", 1.0) for j in ("12", "23", "34", "14") for c in "xy"},
    "theta13": ("deg", 57.29577951308232), "theta14": ("deg", 57.29577951308232),
    "s14": ("m", 1.0),
}

#: The smallest force level, N, against which errors and changes of forces are judged
#: (times the longest link: of torques). A case without loads has zero forces, and its
#: simulators report rounding noise instead (1e-13 to 3e-12 N, measured on unloaded
#: four-bars and slider-cranks): judged against zero that noise would fail every
#: tolerance and keep every settling run from stopping. A hundredth of a newton, about the
#: weight of one gram, is below any force a machine's force analysis resolves, and the
#: noise is below 1e-9 of it, the tightest tolerance of the policy.
FORCE_FLOOR_N = 0.01

#: The order quantities are written in.
QUANTITY_ORDER = list(QUANTITY_UNITS)

#: The quantities of a linkage (LINKAGES.md "What comes out"); their units depend on the
#: joint or spring they name, so a Solution states them (:attr:`Solution.units`).
LINKAGE_QUANTITY = re.compile(r"F_\w+_[xytr]|M_\w+|N_\w+|Q_\w+|S_\w+|[xy]_\w+|phi_\w+|q_\w+")


@functools.lru_cache(maxsize=256)
def unknown_quantities(names: tuple[str, ...], with_units: tuple[str, ...]) -> frozenset[str]:
    """The ``names`` that are neither a four-bar/slider-crank quantity nor a linkage
    quantity (LINKAGES.md) among ``with_units``. Cached: a sweep builds thousands of
    Solutions with the same names."""
    linkage = set(with_units)
    return frozenset(q for q in names if q not in QUANTITY_UNITS
                     and not (LINKAGE_QUANTITY.fullmatch(q) and q in linkage))


def check_quantities(names: tuple[str, ...], with_units: tuple[str, ...]) -> None:
    """Refuse :func:`unknown_quantities`."""
    unknown = unknown_quantities(names, with_units)
    if unknown:
        raise ValueError(f"unknown quantities, or linkage quantities without a unit: "
                         f"{sorted(unknown)}")


#: Order of a linkage's quantities in tables: by family, then by name.
LINKAGE_FAMILIES = ("Q_", "F_", "M_", "N_", "S_", "x_", "y_", "phi_", "q_")

DEGREES_PER_RADIAN = 57.29577951308232


def unit_factor(unit: str) -> float:
    """From the stored SI/radian value to the table unit."""
    return DEGREES_PER_RADIAN if unit == "deg" else 1.0


#: The quantity kind of each unit that is not a pose's (:func:`kind_of_unit`).
UNIT_KINDS = {"N": "force", "N*m": "torque"}


def kind_of_unit(unit: str) -> str:
    """``force`` (N), ``torque`` (N*m) or ``pose`` (deg, m): the policy's quantity kind."""
    return UNIT_KINDS.get(unit, "pose")


def order_key(quantity: str) -> tuple[int, int, str]:
    """Sort key: the CONVENTIONS order for the four-bar and slider-crank, then linkages'
    quantities by family and name."""
    if quantity in QUANTITY_UNITS:
        return (0, QUANTITY_ORDER.index(quantity), "")
    family = next((i for i, f in enumerate(LINKAGE_FAMILIES) if quantity.startswith(f)),
                  len(LINKAGE_FAMILIES))
    return (1, family, quantity)


#: The family of a linkage's joint coordinates (``q_<joint>``): they count whole turns.
JOINT_COORDINATE = "q_"


def wraps(quantity: str, unit: str) -> bool:
    """Whether the tables wrap ``quantity`` to [−180°, 180°): every angle but a joint
    coordinate. An angle of a link or of a four-bar's coupler names a direction, one way
    whichever backend gives it; a joint coordinate says how far a joint has turned from the
    drawn pose, and a driver turned 400° has turned 400°, not 40° (every backend counts the
    turns: the analytic continuation and the simulators' hinges alike)."""
    return unit == "deg" and not quantity.startswith(JOINT_COORDINATE)


def table_values(quantity: str, values: ArrayLike, unit: str | None = None) -> np.ndarray:
    """Values as the tables show them: in table units (degrees for angles), angles wrapped
    to [−180°, 180°) (CONVENTIONS.md) but joint coordinates, which keep their turns
    (:func:`wraps`). ``unit`` is needed for a linkage's quantities (see
    :meth:`Solution.unit`)."""
    import numpy as np  # here: `mechcheck --help` and the pytest plugin never need it

    unit = unit or QUANTITY_UNITS[quantity][0]
    out = np.asarray(values, dtype=float) * unit_factor(unit)
    return (out + 180.0) % 360.0 - 180.0 if wraps(quantity, unit) else out


def table_value(quantity: str, value: float, unit: str | None = None) -> float:
    """:func:`table_values` for one number."""
    return float(table_values(quantity, value, unit))


def quantity_kind(quantity: str, unit: str | None = None) -> str:
    """``torque``, ``force`` or ``pose``: the tolerance policy's quantity kind."""
    return kind_of_unit(unit or QUANTITY_UNITS[quantity][0])


Later = Callable[[], "float | str"]


class Diagnostics(Mapping[str, "float | str"]):
    """Read-only diagnostics, some of them computed when first read (given as a function of
    nothing): a number that costs as much as the solve that reports it (the analytic
    condition number, an SVD) is computed for the reader who asks for it, exactly as it
    would have been, and once."""

    def __init__(self, entries: Mapping[str, float | str | Later]) -> None:
        self._entries = dict(entries)

    def __getitem__(self, key: str) -> float | str:
        value = self._entries[key]
        if callable(value):
            value = self._entries[key] = value()
        return value

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)

    def __repr__(self) -> str:
        return repr(dict(self))


@dataclass(frozen=True)
class Solution:
    """One backend's answer for one Case.

    ``status`` is ``ok`` or a verdict that explains why some or all numbers are
    absent: ``singular`` (ill-conditioned pose; forces withheld),
    ``indeterminate`` (a Coulomb friction term reverses at this very pose: its
    value anywhere in ±μ·r·|F| is consistent, so the forces are not unique),
    ``not_settled`` (a simulator did not reach equilibrium within its budget),
    ``not_applicable`` (the method does not apply, e.g. superposition with
    friction), ``no_solution`` (e.g. the friction equations lock).
    ``diagnostics`` says how trustworthy the numbers are (condition number,
    iterations, steps, wall time, residuals …).

    ``values`` are SI with angles in **radians** (N, N·m, m, rad), as every
    backend computes them; :meth:`in_table_units` gives them as the tables show
    them (degrees). A Solution is immutable: ``values``, ``diagnostics`` and ``units``
    are read-only copies of what it was made with (``dataclasses.replace`` makes another).
    """

    case: str
    backend: str
    values: Mapping[str, float]
    status: Status = "ok"
    message: str = ""
    diagnostics: Mapping[str, float | str] = field(default_factory=dict)
    #: The table unit (N, N*m, m, deg) of each linkage quantity; the four-bar's and
    #: slider-crank's are fixed (QUANTITY_UNITS).
    units: Mapping[str, str] = field(default_factory=dict)

    def unit(self, quantity: str) -> str:
        return self.units.get(quantity) or QUANTITY_UNITS[quantity][0]

    def in_table_units(self) -> dict[str, float]:
        """``values`` as the tables show them: N, N·m, m, and degrees wrapped to [−180°, 180°)
        (joint coordinates ``q_`` keep their turns)."""
        return {q: table_value(q, v, self.unit(q)) for q, v in self.values.items()}

    def __reduce__(self) -> tuple[type[Solution], tuple[object, ...]]:
        # A read-only mapping does not pickle: a Solution crosses a process as plain dicts.
        return (Solution, (self.case, self.backend, dict(self.values), self.status, self.message,
                           dict(self.diagnostics), dict(self.units)))

    @classmethod
    def batch(cls, case: str, backend: str, names: tuple[str, ...],
              rows: Iterable[Sequence[float]], diagnostics: Iterable[dict[str, float | str]],
              units: Mapping[str, str]) -> list[Solution]:
        """``ok`` Solutions of one case and backend at many poses, each row of ``rows`` the
        values of ``names`` at one pose: as if made one by one (:meth:`__post_init__`:
        read-only copies, the same check of the names, done once here as the names are
        the same) but for one shared copy of ``units``. Each ``diagnostics`` dict becomes
        its Solution's own (read-only): they must be fresh dicts no one else holds. A
        sweep builds hundreds of Solutions, and the copying was most of a pose's time."""
        shared = MappingProxyType(dict(units))
        check_quantities(names, tuple(shared))
        out = []
        for row, diagnostic in zip(rows, diagnostics, strict=True):
            solution = object.__new__(cls)
            # A frozen dataclass refuses setattr; its __dict__ is what __init__ would fill.
            vars(solution).update(case=case, backend=backend,
                                  values=MappingProxyType(dict(zip(names, row, strict=True))),
                                  status="ok", message="",
                                  diagnostics=MappingProxyType(diagnostic), units=shared)
            out.append(solution)
        return out

    def __post_init__(self) -> None:
        for name in ("values", "diagnostics", "units"):
            given = getattr(self, name)
            if not isinstance(given, Diagnostics):   # read-only already
                object.__setattr__(self, name, MappingProxyType(dict(given)))
        check_quantities(tuple(self.values), tuple(self.units))
