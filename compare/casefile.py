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
import os
import stat
import tomllib
from collections.abc import Iterable
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import Field

from mechcheck.analytic.case import (
    Case,
    CaseError,
    FourBarGeometry,
    Friction,
    Load,
    Mass,
    Motion,
    SliderCrankGeometry,
)
from mechcheck.analytic.linkage_backends import NOTHING_TO_SWEEP, quantity_units
from mechcheck.analytic.values import LENGTH_UNITS, lengths_quoted_in
from mechcheck.linkage_file import LinkageCaseSpec, linkage_from_spec, simulation_from_spec
from mechcheck.specs import Pair, SeedSpec, Strict, ToleranceSpec, force_vector, needs_an_effect, validated


class FourBarGeometrySpec(Strict):
    a1: float
    a2: float
    a3: float
    a4: float


class SliderCrankGeometrySpec(Strict):
    a2: float
    a3: float
    offset: float = 0.0


class LoadSpec(Strict):
    link: int
    at: Pair = [0.0, 0.0]
    force: dict[str, Any] | None = None
    torque: float = 0.0


class MassSpec(Strict):
    link: int
    mass: float
    com: Pair = [0.0, 0.0]
    inertia: float = 0.0


class MotionSpec(Strict):
    omega: float = 0.0
    alpha: float = 0.0


class FrictionSpec(Strict):
    mu: Annotated[float, Field(ge=0.0)] = 0.0
    pin_radius: dict[str, float] = {}
    slide_mu: Annotated[float, Field(ge=0.0)] | None = None
    viscous: dict[str, float] = {}
    direction: Literal["cw", "ccw"] | None = None


class CaseSpec(Strict):
    """One ``four_bar`` or ``slider_crank`` table, structurally valid."""

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


def _built(factory: Any, key: str, *args: Any, **kwargs: Any) -> Any:
    """Construct a Case value, prefixing its key with where it sits in the file."""
    try:
        return factory(*args, **kwargs)
    except CaseError as error:
        raise error.located(key_prefix=key) from None


def case_from_spec(spec: CaseSpec, source: str = "") -> Case:
    """Convert one validated table (lengths to metres, degrees to radians) and draw it as
    its linkage (:func:`~mechcheck.analytic.presets.preset_case`); its messages quote
    lengths in the file's unit."""
    with lengths_quoted_in(spec.length_unit):
        return _preset_case(spec, source)


def _preset_case(spec: CaseSpec, source: str) -> Case:
    scale = LENGTH_UNITS[spec.length_unit]

    def pt(p: list[float]) -> tuple[float, float]:
        return (p[0] * scale, p[1] * scale)

    if spec.mechanism == "four_bar":
        g = validated(FourBarGeometrySpec, spec.geometry, "geometry")
        geometry: FourBarGeometry | SliderCrankGeometry = _built(
            FourBarGeometry, "", g.a1 * scale, g.a2 * scale, g.a3 * scale, g.a4 * scale)
    else:
        g = validated(SliderCrankGeometrySpec, spec.geometry, "geometry")
        geometry = _built(SliderCrankGeometry, "", g.a2 * scale, g.a3 * scale, g.offset * scale)
    for i, ld in enumerate(spec.loads):
        needs_an_effect(ld, f"loads[{i}]")
    loads = tuple(_built(Load, f"loads[{i}]", link=ld.link, at=pt(ld.at),
                         force=force_vector(ld.force, f"loads[{i}].force"), torque=ld.torque)
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
    # Drawing needs numpy: imported here, so that the commands that only list need none.
    from mechcheck.analytic.presets import preset_case

    return preset_case(
        name=spec.name, geometry=geometry, theta12=math.radians(spec.theta12),
        branch=spec.branch or "", ground_angle=math.radians(spec.ground_angle),
        drive_link=spec.drive_link, gravity=(spec.gravity[0], spec.gravity[1]),
        loads=loads, masses=masses,
        motion=_built(Motion, "", omega=spec.motion.omega, alpha=spec.motion.alpha),
        friction=friction,
        tolerance=tuple((f"{t.backend}:{t.quantity}", t.rtol, t.atol) for t in spec.tolerance),
        source=source, length_unit=spec.length_unit,
    )


#: The spec of any case table: either format.
AnySpec = CaseSpec | LinkageCaseSpec


def linkage_case(spec: LinkageCaseSpec, source: str = "") -> Case:
    """A ``mechanism = "linkage"`` table as a Case holding its Linkage."""
    linkage = linkage_from_spec(spec)
    if spec.seed is not None:
        check_printed_keys(spec.seed.printed, quantity_units(linkage))
    simulation = None if spec.simulate is None else simulation_from_spec(spec.simulate)
    return Case(name=spec.name, geometry=linkage,
                tolerance=tuple((f"{t.backend}:{t.quantity}", t.rtol, t.atol)
                                for t in spec.tolerance),
                source=source, length_unit=spec.length_unit, simulation=simulation)


def check_printed_keys(printed: Iterable[str], quantities: Iterable[str]) -> None:
    """A linkage's printed answers name its own quantities: the seed table gives each its
    computed value and the unit its joint, link or spring has."""
    known = set(quantities)
    for key in printed:
        if key not in known:
            raise CaseError(f"unknown quantity {key!r} of this linkage: a printed answer names "
                            "one of its quantities (Q_<driver joint>, F_<joint>_x, phi_<link>, "
                            "q_<joint>, …)", key=f"seed.printed.{key}")


def parse_cases(data: dict[str, Any], source: str) -> list[tuple[Case, AnySpec]]:
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
            if isinstance(table, dict) and table.get("mechanism") == "linkage":
                linkage_spec = validated(LinkageCaseSpec, table)
                out.append((linkage_case(linkage_spec, source), linkage_spec))
            else:
                spec = validated(CaseSpec, table)
                out.append((case_from_spec(spec, source), spec))
        except CaseError as error:
            raise error.located(file=source, case=label) from None
    return out


#: The largest case file read, bytes. A 5,000-loop linkage file is about 5 MB; a file
#: beyond this is no hand-written case, and reading it whole could exhaust the memory.
MAX_CASE_FILE_BYTES = 64 * 2**20

#: What a path that is not a regular file is, by its file-type bits.
_NOT_REGULAR = ((stat.S_ISDIR, "a directory"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
                (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                (stat.S_ISSOCK, "a socket"))


def _refuse_unless_regular(mode: int, size: int, source: str) -> None:
    """Refuse a FIFO, device, socket or directory, and a file larger than the cap."""
    for test, kind in _NOT_REGULAR:
        if test(mode):
            suffix = "" if kind == "a directory" else "; give a regular file"
            raise CaseError(f"is {kind}, not a case file{suffix}", file=source)
    if not stat.S_ISREG(mode):
        raise CaseError("is not a regular file; give a case file", file=source)
    if size > MAX_CASE_FILE_BYTES:
        raise CaseError(f"is {size:,} bytes; a case file holds at most "
                        f"{MAX_CASE_FILE_BYTES:,} bytes ({MAX_CASE_FILE_BYTES // 2**20} MiB)",
                        file=source)


def _read_bounded(path: str | Path, source: str) -> bytes:
    """At most the cap's bytes of a regular file, or a CaseError.

    The type is checked by name before anything is opened: opening a FIFO for reading
    waits for a writer, and opening some devices acts on them. The descriptor is then
    checked again (the path may have been swapped meanwhile; non-blocking, so a FIFO
    swapped in cannot hang the open), and the read stops one byte past the cap, because a
    pseudo-file's size (``/proc``) says nothing of its length.
    """
    info = os.stat(path)
    _refuse_unless_regular(info.st_mode, info.st_size, source)
    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_NOCTTY | os.O_CLOEXEC)
    with os.fdopen(fd, "rb") as handle:
        info = os.fstat(fd)
        _refuse_unless_regular(info.st_mode, info.st_size, source)
        raw = handle.read(MAX_CASE_FILE_BYTES + 1)
    if len(raw) > MAX_CASE_FILE_BYTES:
        raise CaseError(f"holds more than {MAX_CASE_FILE_BYTES:,} bytes "
                        f"({MAX_CASE_FILE_BYTES // 2**20} MiB), the most a case file may",
                        file=source)
    return raw


def read_case_text(path: str | Path) -> str:
    """The text of a case file: UTF-8 (a byte-order mark is accepted), or one clear error.

    Only a regular file of at most :data:`MAX_CASE_FILE_BYTES` is read.
    """
    source = str(path)
    try:
        raw = _read_bounded(path, source)
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


def load_file(path: str | Path) -> list[tuple[Case, AnySpec]]:
    """Read and validate one case file (all or nothing)."""
    source = str(path)
    return parse_cases(parse_toml(read_case_text(path), source), source)


def load_specs(paths: Iterable[str | Path], *, sweep: bool = False,
               trajectory: bool | None = None) -> list[tuple[Case, AnySpec]]:
    """Every case of every file, with case names unique across the run; ``sweep``: every case
    can be swept (a linkage has a driver to move); ``trajectory``: True, every case moves
    over time (``mechcheck simulate``), False, none does (``run``, ``sweep``), None: either
    (``validate``)."""
    seen: dict[str, str] = {}
    out = []
    for path in paths:
        for case, spec in load_file(path):
            if case.name in seen:
                raise CaseError(f"duplicate case name (also in {seen[case.name]})",
                                key="name", case=case.name, file=str(path))
            if trajectory is not None:
                check_case_kind(case, trajectory)
            if sweep and not case.is_preset and not case.linkage.drivers:
                raise CaseError(NOTHING_TO_SWEEP, key="drivers", case=case.name, file=str(path))
            seen[case.name] = str(path)
            out.append((case, spec))
    return out


def check_case_kind(case: Case, trajectory: bool) -> None:
    """Refuse a case the command cannot run: a trajectory (it has ``[case.simulate]``) where
    one pose is solved (``trajectory`` False), a case at one pose where a trajectory is run."""
    if case.is_trajectory and not trajectory:
        raise CaseError("the case moves over time ([case.simulate]): run it with mechcheck "
                        "simulate", key="simulate", case=case.name, file=case.source)
    if trajectory and not case.is_trajectory:
        raise CaseError("no [case.simulate] table: the case stands at one pose; run it with "
                        "mechcheck run, or give it a [case.simulate] table to run it with "
                        "mechcheck simulate", key="simulate", case=case.name, file=case.source)


def load_cases(*paths: str | Path) -> list[Case]:
    """The Cases of one or more files, validated, in file order."""
    return [case for case, _ in load_specs(paths)]


def builtin_case_files() -> list[Path]:
    """The case files shipped with the package: the seed examples, the suite, the
    built-in linkages (``cases/linkages/``) and three users' own mechanisms, kept as
    regression cases with their hand checks (``cases/users/``)."""
    cases = Path(__file__).parent / "cases"
    return sorted(cases.glob("*.toml")) + sorted((cases / "linkages").glob("*.toml")) \
        + sorted((cases / "users").glob("*.toml"))


def catalogue_case_files() -> list[Path]:
    """Seed 001's catalogue of mechanisms as case files (``cases/catalogue/``), shipped with
    the package beside the built-in suite."""
    return sorted((Path(__file__).parent / "cases" / "catalogue").glob("*.toml"))


def builtin_trajectory_files() -> list[Path]:
    """The trajectory cases shipped with the package (``cases/trajectories/``), run by
    ``mechcheck simulate`` without files; none when the folder is empty or missing."""
    return sorted((Path(__file__).parent / "cases" / "trajectories").glob("*.toml"))


def builtin_sweep_files() -> list[Path]:
    """The sweeps shipped with the package: the seed four-bar and slider-crank."""
    return sorted((Path(__file__).parent / "sweeps").glob("*.toml"))
