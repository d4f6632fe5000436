"""Case files (TOML, CONVENTIONS.md) → validated, immutable :class:`~mechcheck.analytic.case.Case`.

Structure and types are checked by pydantic models (unknown keys, missing
keys, wrong types, non-finite numbers); physical sense (positive lengths,
masses, assemblable pose …) by the Case values themselves. Either way the
error is one :class:`~mechcheck.analytic.case.CaseError` naming the file, the case and
the key, and nothing is returned for a file with any bad case.

Extensions beyond CONVENTIONS.md (all optional): ``description``, a
``[case.seed]`` table (the source and printed answers of a seed example, shown
beside the computed values in the report) and ``[[case.tolerance]]`` entries
(see :mod:`mechcheck.tolerance`).
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, ValidationError
from pydantic_core import ErrorDetails

from mechcheck.analytic.case import (
    Case,
    CaseError,
    FourBarGeometry,
    Friction,
    Load,
    Mass,
    Motion,
    SliderCrankGeometry,
    bounded_angle,
    finite,
)

Pair = Annotated[list[float], Field(min_length=2, max_length=2)]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False, frozen=True)


class FourBarGeometrySpec(_Strict):
    a1: float
    a2: float
    a3: float
    a4: float


class SliderCrankGeometrySpec(_Strict):
    a2: float
    a3: float
    offset: float = 0.0


class PolarForceSpec(_Strict):
    magnitude: Annotated[float, Field(ge=0.0)]
    angle: float


class CartesianForceSpec(_Strict):
    x: float
    y: float


class LoadSpec(_Strict):
    link: int
    at: Pair = [0.0, 0.0]
    force: dict[str, Any] | None = None
    torque: float = 0.0


class MassSpec(_Strict):
    link: int
    mass: float
    com: Pair = [0.0, 0.0]
    inertia: float = 0.0


class MotionSpec(_Strict):
    omega: float = 0.0
    alpha: float = 0.0


class FrictionSpec(_Strict):
    mu: Annotated[float, Field(ge=0.0)] = 0.0
    pin_radius: dict[str, float] = {}
    slide_mu: Annotated[float, Field(ge=0.0)] | None = None
    viscous: dict[str, float] = {}
    direction: Literal["cw", "ccw"] | None = None


class SeedSpec(_Strict):
    source: str
    note: str = ""
    printed: dict[str, float] = {}


class ToleranceSpec(_Strict):
    backend: str = "*"
    quantity: str = "*"
    rtol: Annotated[float, Field(ge=0.0)]
    atol: Annotated[float, Field(ge=0.0)] = 0.0


class CaseSpec(_Strict):
    name: str
    mechanism: Literal["four_bar", "slider_crank"]
    length_unit: Literal["m", "mm"] = "m"
    theta12: float
    branch: str | None = None
    ground_angle: float = 0.0
    drive_link: int = 2
    gravity: Pair = [0.0, 0.0]
    geometry: dict[str, Any]
    loads: list[LoadSpec] = []
    masses: list[MassSpec] = []
    motion: MotionSpec = MotionSpec()
    friction: FrictionSpec | None = None
    description: str = ""
    seed: SeedSpec | None = None
    tolerance: list[ToleranceSpec] = []


def _key(loc: Sequence[int | str]) -> str:
    """pydantic's location tuple as a TOML-ish key: ``loads[1].force.x``."""
    out = ""
    for part in loc:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out


def _in_user_terms(error: ErrorDetails) -> str:
    """pydantic's complaint, said in the terms of the case file (TOML keys, values, tables)."""
    kind, ctx, given = error["type"], error.get("ctx") or {}, error.get("input")
    if kind == "extra_forbidden":
        return "unknown key: not part of the case-file format ('mechcheck new' writes an example)"
    if kind == "missing":
        return "is required but missing"
    if kind in ("float_type", "float_parsing", "int_type", "int_parsing", "bool_type"):
        return f"must be a number, got {given!r}"
    if kind == "finite_number":
        return f"must be finite, got {given!r}"
    if kind == "string_type":
        return f"must be a text in quotes, got {given!r}"
    if kind == "literal_error":
        return f"must be {ctx.get('expected')}, got {given!r}"
    if kind in ("too_short", "too_long"):
        bound = ctx.get("min_length", ctx.get("max_length"))
        what = "a pair [x, y]" if bound == 2 else f"a list of {bound} values"
        return f"must be {what}, got {ctx.get('actual_length')} value(s)"
    if kind in ("model_type", "dict_type", "model_attributes_type"):
        return f"must be a table ({{ key = value, … }} or a [section]), got {given!r}"
    if kind == "list_type":
        return f"must be a list ([ … ], or [[…]] tables), got {given!r}"
    if kind == "greater_than_equal":
        return f"must be >= {ctx.get('ge')}, got {given!r}"
    return str(error["msg"])


def _validated(model: type[_Strict], data: Any, prefix: str = "") -> Any:
    try:
        return model.model_validate(data)
    except ValidationError as error:
        first = error.errors()[0]
        key = _key(first["loc"])
        key = f"{prefix}.{key}" if prefix and key else (key or prefix)
        raise CaseError(_in_user_terms(first), key=key) from None


def _force(spec: dict[str, Any] | None, key: str) -> tuple[float, float]:
    if spec is None:
        return (0.0, 0.0)
    if "magnitude" in spec or "angle" in spec:
        polar = _validated(PolarForceSpec, spec, key)
        finite(polar.magnitude, f"{key}.magnitude")
        a = bounded_angle(math.radians(polar.angle), f"{key}.angle")
        return (polar.magnitude * math.cos(a), polar.magnitude * math.sin(a))
    if "x" in spec or "y" in spec:
        xy = _validated(CartesianForceSpec, spec, key)
        return (xy.x, xy.y)
    raise CaseError("must be { magnitude = .., angle = .. } or { x = .., y = .. }", key=key)


def _built(factory: Any, key: str, *args: Any, **kwargs: Any) -> Any:
    """Construct a Case value, prefixing its key with where it sits in the file."""
    try:
        return factory(*args, **kwargs)
    except CaseError as error:
        raise error.located(key_prefix=key) from None


def case_from_spec(spec: CaseSpec, source: str = "") -> Case:
    """Convert one validated table: lengths to metres, degrees to radians."""
    scale = 1e-3 if spec.length_unit == "mm" else 1.0

    def pt(p: list[float]) -> tuple[float, float]:
        return (p[0] * scale, p[1] * scale)

    if spec.mechanism == "four_bar":
        g = _validated(FourBarGeometrySpec, spec.geometry, "geometry")
        geometry: FourBarGeometry | SliderCrankGeometry = _built(
            FourBarGeometry, "", g.a1 * scale, g.a2 * scale, g.a3 * scale, g.a4 * scale)
    else:
        g = _validated(SliderCrankGeometrySpec, spec.geometry, "geometry")
        geometry = _built(SliderCrankGeometry, "", g.a2 * scale, g.a3 * scale, g.offset * scale)
    loads = tuple(_built(Load, f"loads[{i}]", link=ld.link, at=pt(ld.at),
                         force=_force(ld.force, f"loads[{i}].force"), torque=ld.torque)
                  for i, ld in enumerate(spec.loads))
    masses = tuple(_built(Mass, f"masses[{i}]", link=m.link, mass=m.mass, com=pt(m.com),
                          inertia=m.inertia) for i, m in enumerate(spec.masses))
    friction = None
    if spec.friction is not None:
        f = spec.friction
        friction = _built(
            Friction, "", mu=f.mu,
            pin_radius={k: v * scale for k, v in f.pin_radius.items()},
            slide_mu=f.slide_mu, viscous=dict(f.viscous),
            direction={"cw": -1, "ccw": 1, None: 0}[f.direction])
    return Case(
        name=spec.name, geometry=geometry, theta12=math.radians(spec.theta12),
        branch=spec.branch or "", ground_angle=math.radians(spec.ground_angle),
        drive_link=spec.drive_link, gravity=(spec.gravity[0], spec.gravity[1]),
        loads=loads, masses=masses,
        motion=_built(Motion, "", omega=spec.motion.omega, alpha=spec.motion.alpha),
        friction=friction,
        tolerance=tuple((f"{t.backend}:{t.quantity}", t.rtol, t.atol) for t in spec.tolerance),
        source=source,
    )


def parse_cases(data: dict[str, Any], source: str) -> list[tuple[Case, CaseSpec]]:
    """Every ``[[case]]`` of a parsed TOML document, validated."""
    unknown = sorted(set(data) - {"case"})
    if unknown:
        raise CaseError("unknown top-level key (a file holds [[case]] tables only)",
                        key=unknown[0], file=source)
    tables = data.get("case")
    if not isinstance(tables, list) or not tables:
        raise CaseError("the file holds no [[case]] table", key="case", file=source)
    out = []
    for i, table in enumerate(tables):
        name = table.get("name") if isinstance(table, dict) else None
        label = name if isinstance(name, str) else f"#{i + 1}"
        try:
            spec = _validated(CaseSpec, table)
            out.append((case_from_spec(spec, source), spec))
        except CaseError as error:
            raise error.located(file=source, case=label) from None
    return out


def read_case_text(path: str | Path) -> str:
    """The text of a case file: UTF-8 (a byte-order mark is accepted), or one clear error."""
    source = str(path)
    try:
        raw = Path(path).read_bytes()
    except FileNotFoundError:
        raise CaseError("no such file", file=source) from None
    except IsADirectoryError:
        raise CaseError("is a directory, not a case file", file=source) from None
    except PermissionError:
        raise CaseError("cannot be read: permission denied", file=source) from None
    except OSError as error:  # a symlink loop, a name too long, an I/O error …
        raise CaseError(f"cannot be read: {error.strerror or error}", file=source) from None
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        raise CaseError(f"is not UTF-8 text (byte 0x{raw[error.start]:02x} at offset "
                        f"{error.start}); TOML files are UTF-8", file=source) from None


def parse_toml(text: str, source: str) -> dict[str, Any]:
    """A TOML document, or one clear error (broken syntax, arrays nested without end)."""
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as error:
        raise CaseError(f"not valid TOML: {error}", file=source) from None
    except RecursionError:
        raise CaseError("not usable TOML: arrays or tables are nested too deeply",
                        file=source) from None


def load_file(path: str | Path) -> list[tuple[Case, CaseSpec]]:
    """Read and validate one case file (all or nothing)."""
    source = str(path)
    return parse_cases(parse_toml(read_case_text(path), source), source)


def load_specs(paths: Iterable[str | Path]) -> list[tuple[Case, CaseSpec]]:
    """Every case of every file, with case names unique across the run."""
    seen: dict[str, str] = {}
    out = []
    for path in paths:
        for case, spec in load_file(path):
            if case.name in seen:
                raise CaseError(f"duplicate case name (also in {seen[case.name]})",
                                key="name", case=case.name, file=str(path))
            seen[case.name] = str(path)
            out.append((case, spec))
    return out


def load_cases(*paths: str | Path) -> list[Case]:
    """The Cases of one or more files, validated, in file order."""
    return [case for case, _ in load_specs(paths)]


def builtin_case_files() -> list[Path]:
    """The case files shipped with the package (the seed examples and the suite)."""
    return sorted((Path(__file__).parent / "cases").glob("*.toml"))


def builtin_sweep_files() -> list[Path]:
    """The sweeps shipped with the package: the seed four-bar and slider-crank."""
    return sorted((Path(__file__).parent / "sweeps").glob("*.toml"))
