"""The base of every case-file table spec: strict pydantic models, errors in the user's
terms (one :class:`~mechcheck.analytic.case.CaseError` naming the key), and the pieces
both formats share (points, forces, seed and tolerance tables)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Annotated, Any

from pydantic import BaseModel, ConfigDict, Field, ValidationError
from pydantic_core import ErrorDetails

from mechcheck.analytic.values import CaseError, bounded_angle, finite

Pair = Annotated[list[float], Field(min_length=2, max_length=2)]


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False, frozen=True)


class PolarForceSpec(Strict):
    magnitude: Annotated[float, Field(ge=0.0)]
    angle: float


class CartesianForceSpec(Strict):
    x: float
    y: float


class SeedSpec(Strict):
    source: str
    note: str = ""
    printed: dict[str, float] = {}


class ToleranceSpec(Strict):
    backend: str = "*"
    quantity: str = "*"
    rtol: Annotated[float, Field(ge=0.0)]
    atol: Annotated[float, Field(ge=0.0)] = 0.0


#: The names pydantic gives the branches of a union in an error's location (``torque`` is a
#: number or a table: ``('torque', 'list[list[float]]', 1, 1)``): not keys of the file.
_BRANCHES = ("float", "int", "str", "bool")


def _is_branch(part: int | str) -> bool:
    return isinstance(part, str) and (part in _BRANCHES or "[" in part)


def most_specific(errors: Sequence[ErrorDetails]) -> ErrorDetails:
    """The error to report: the first, unless it is one branch of a union another branch of
    which went deeper into the value (a table of numbers with a NaN in it is told about the
    NaN, not that it is not a number)."""
    first = errors[0]
    head = [p for p in first["loc"] if not _is_branch(p)]
    same = [e for e in errors if [p for p in e["loc"] if not _is_branch(p)][:len(head)] == head]
    return max(same, key=lambda e: len(e["loc"]))


def key_of(loc: Sequence[int | str]) -> str:
    """pydantic's location tuple as a TOML-ish key: ``loads[1].force.x`` (a union's branch
    names left out)."""
    out = ""
    for part in loc:
        if _is_branch(part):
            continue
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out


def in_user_terms(error: ErrorDetails) -> str:
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


def validated(model: type[Strict], data: Any, prefix: str = "") -> Any:
    try:
        return model.model_validate(data)
    except ValidationError as error:
        first = most_specific(error.errors())
        key = key_of(first["loc"])
        key = f"{prefix}.{key}" if prefix and key else (key or prefix)
        raise CaseError(in_user_terms(first), key=key) from None


def force_vector(spec: dict[str, Any] | None, key: str) -> tuple[float, float]:
    if spec is None:
        return (0.0, 0.0)
    if "magnitude" in spec or "angle" in spec:
        polar = validated(PolarForceSpec, spec, key)
        finite(polar.magnitude, f"{key}.magnitude")
        a = bounded_angle(math.radians(polar.angle), f"{key}.angle")
        return (polar.magnitude * math.cos(a), polar.magnitude * math.sin(a))
    if "x" in spec or "y" in spec:
        xy = validated(CartesianForceSpec, spec, key)
        return (finite(xy.x, f"{key}.x"), finite(xy.y, f"{key}.y"))
    raise CaseError("must be { magnitude = .., angle = .. } or { x = .., y = .. }", key=key)


def needs_an_effect(load: BaseModel, key: str) -> None:
    """A load table gives a ``force``, a ``torque`` or both: one with neither is a mistake
    (a key misspelt or left out), not a load of zero."""
    if "force" not in load.model_fields_set and "torque" not in load.model_fields_set:
        raise CaseError("a load needs a 'force', a 'torque' or both, and has neither",
                        key=f"{key}.force")
