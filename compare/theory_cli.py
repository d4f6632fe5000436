"""``mechcheck theory``: mobility, Grashof, limit positions, transmission angle."""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from mechcheck.analytic.values import CaseError, length_text

if TYPE_CHECKING:
    from mechcheck.analytic.case import Case

# The theory (numpy) and the case-file reader (pydantic) are imported in the commands
# that use them: this module is loaded for every `mechcheck` invocation, --help included.

app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="Mechanism theory of linkages: mobility, Grashof class, dead "
                       "positions, transmission angle, a slider-crank's full rotation, a "
                       "linkage's driver ranges and locks.")

#: The seed 001 mobility catalogue: (name, u, joints, spatial, printed S).
MOBILITY_CATALOGUE = [
    ("slider-crank", 4, "3R,1P", False, 1), ("four-bar", 4, "4R", False, 1),
    ("shaper (kurs)", 5, "3R,2P,1Cs", False, 1), ("five-bar", 5, "5R", False, 2),
    ("seven-link", 7, "8R", False, 2), ("garage door", 6, "7R", False, 1),
    ("wave-maker", 4, "2R,2S", True, 2), ("wave-maker, one S keyed", 4, "2R,1S,1Ss", True, 1),
    ("gear pair", 3, "2R,1G", False, 1), ("excavator bucket", 10, "12R,1P", False, 1),
    ("mixed", 9, "8R,2P,2G", False, 2), ("self-closing hinge", 3, "2C,1S", True, 1),
    ("truss", 9, "12R", False, 0), ("over-constrained", 6, "8R", False, -1),
]
#: The seed 001 Grashof examples: (A0A crank, AB coupler, B0B rocker, A0B0 ground, printed).
GRASHOF_CATALOGUE = [
    (100.0, 220.0, 150.0, 250.0, "crank-rocker"), (300.0, 315.0, 290.0, 215.0, "double-crank"),
    (415.0, 115.0, 500.0, 218.0, "double-rocker"),
    (100.0, 229.0, 99.0, 300.0, "non-Grashof double-rocker"),
]


def parse_joints(text: str) -> dict[str, int]:
    """``"3R,1P,1Cs"`` → {"R": 3, "P": 1, "Cs": 1}."""
    out: dict[str, int] = {}
    for part in filter(None, (p.strip() for p in text.split(","))):
        match = re.fullmatch(r"(\d*)([A-Za-z]+)", part)
        if not match:
            raise CaseError(f"cannot read {part!r}: write COUNT TYPE, e.g. 3R", key="joints")
        out[match[2]] = out.get(match[2], 0) + int(match[1] or 1)
    return out


def fail(error: CaseError) -> typer.Exit:
    typer.echo(f"mechcheck: error: {error}", err=True)
    return typer.Exit(2)


@app.command("mobility")
def mobility_command(
    links: Annotated[int, typer.Option(help="u: number of links, ground included.")],
    joints: Annotated[str, typer.Option(help="Joints as COUNT TYPE, e.g. 3R,1P (the seed's "
                                        "types: R, P, Cs, G, C, S, Ss).")],
    spatial: Annotated[bool, typer.Option(help="λ = 6 (spatial) instead of 3.")] = False,
) -> None:
    """Degrees of freedom by Gruebler–Kutzbach, S = λ(u − m − 1) + ΣSi."""
    from mechcheck.analytic import theory

    try:
        s = theory.mobility(links, parse_joints(joints), spatial=spatial)
    except CaseError as error:
        raise fail(error) from None
    typer.echo(f"S = {s}: {theory.mobility_meaning(s)}")


@app.command("grashof")
def grashof_command(
    ground: Annotated[float, typer.Option(help="A0B0")], crank: Annotated[float, typer.Option(
        help="A0A")], coupler: Annotated[float, typer.Option(help="AB")],
    rocker: Annotated[float, typer.Option(help="B0B")],
) -> None:
    """Grashof class of a four-bar from its four lengths."""
    from mechcheck.analytic import theory

    try:
        g = theory.grashof(ground=ground, crank=crank, coupler=coupler, rocker=rocker)
    except CaseError as error:
        raise fail(error) from None
    relation = "<" if g.s_plus_l < g.p_plus_q else (">" if g.s_plus_l > g.p_plus_q else "=")
    typer.echo(f"{g.kind} (s + l = {g.s_plus_l:g} {relation} p + q = {g.p_plus_q:g}; "
               f"shortest: {g.shortest})")


def describe(case: Case) -> list[str]:
    """The theory facts of one case, as lines."""
    from mechcheck.analytic import theory
    from mechcheck.analytic.assembly import assembly_range_text
    from mechcheck.analytic.case import FourBarGeometry, SliderCrankGeometry, preset_of

    if not case.is_preset:
        return describe_linkage(case)
    g = preset_of(case).geometry
    lines = [f"{case.name} ({case.mechanism}, {preset_of(case).branch} branch)",
             f"  assembly: {assembly_range_text(case)}"]
    ext = theory.transmission_extremes(case)
    lines.append(f"  transmission angle: μmin = {math.degrees(ext.mu_min):.4f}° at θ12 = "
                 f"{math.degrees(ext.theta12_at_min):.4f}°, μmax = {math.degrees(ext.mu_max):.4f}° "
                 f"at θ12 = {math.degrees(ext.theta12_at_max):.4f}°")
    if isinstance(g, FourBarGeometry):
        cls = theory.grashof(ground=g.a1, crank=g.a2, coupler=g.a3, rocker=g.a4)
        lines.append(f"  Grashof: {cls.kind} (s + l = {length_text(cls.s_plus_l, case.length_unit)}, "
                     f"p + q = {length_text(cls.p_plus_q, case.length_unit)})")
        if cls.kind == "crank-rocker" and cls.shortest == "crank":
            for lp in theory.limit_positions(case):
                lines.append(f"  dead position ({lp.name}, |A0B| = "
                             f"{length_text(lp.distance, case.length_unit)}): θ12 = "
                             f"{math.degrees(lp.theta12):.4f}°, rocker θ14 = "
                             f"{math.degrees(lp.theta14):.4f}°")
    else:
        assert isinstance(g, SliderCrankGeometry)
        turns = theory.slider_crank_rotates(g)
        lines.append(f"  crank turns fully: {'yes' if turns else 'no'} (a2 + |e| "
                     f"{'<' if turns else '>='} a3)")
        if turns:
            lines.append(f"  stroke: {length_text(theory.slider_stroke(g), case.length_unit)}")
    return lines


def _signed(rotates: bool, value: float, length_unit: str) -> str:
    """A driver's value with its sign: degrees, or a length in the case file's unit."""
    if rotates:
        return f"{math.degrees(value):+.6f}°"
    return ("+" if value >= 0.0 else "") + length_text(value, length_unit)


def describe_linkage(case: Case) -> list[str]:
    """A linkage's links, joints, mobility (formula and rank), each driver's reachable range
    with its lock positions, and, for one driver, the mechanical advantage at the pose."""
    from collections import Counter

    from mechcheck.analytic import theory

    linkage = case.linkage
    counts = Counter(j.kind.name for j in linkage.joints)
    kinds = ", ".join(f"{n} {name}" for name, n in counts.items())
    lines = [f"{case.name} (linkage)",
             f"  links: {len(linkage.links)} ({', '.join(link.name for link in linkage.links)})",
             f"  joints: {len(linkage.joints)} ({kinds})",
             f"  mobility: Gruebler–Kutzbach 3(n − 1) − Σ(3 − Sᵢ) = {linkage.gruebler}; by the rank of "
             f"the constraint Jacobian at the drawn pose: {linkage.dof}"
             + ("" if linkage.gruebler == linkage.dof else
                " (they differ: redundant constraints or a singular drawing)"),
             f"  drivers: {len(linkage.drivers)}; free coordinates: "
             f"{linkage.dof - len(linkage.drivers)}"]
    for r in theory.driver_ranges(linkage):
        ends = [f"locks at {_signed(r.kind.rotates, v, case.length_unit)}" if v is not None else
                f"no lock within {_signed(r.kind.rotates, r.travel, case.length_unit)[1:]}"
                for v in (r.low, r.high)]
        full = r.kind.rotates and r.low is None and r.high is None
        lines.append(f"  driver {r.joint}: " + ("turns fully" if full else
                                                f"decreasing: {ends[0]}; increasing: {ends[1]}"))
    for label, load, effort in theory.mechanical_advantage(case):
        unit = "N·m" if linkage.joint(linkage.drivers[0].joint).kind.rotates else "N"
        lines.append(f"  mechanical advantage ({label}): {load:g} N against {effort:+.6g} {unit} "
                     f"at the driver: |F|/|Q| = {load / abs(effort) if effort else math.inf:.6g}"
                     f" N per {unit}")
    return lines


@app.command("case", help="Each case's theory: a four-bar's or slider-crank's Grashof class, "
             "assembly range, dead positions and transmission extremes; a linkage's mobility, "
             "driver ranges and locks.")
def case_command(files: Annotated[list[Path], typer.Argument(help="Case files (TOML).")]) -> None:
    from mechcheck.casefile import load_cases

    try:
        cases = load_cases(*files)
    except CaseError as error:
        raise fail(error) from None
    for case in cases:
        typer.echo("\n".join(describe(case)))


#: The case file (under the package's ``cases/``) of each planar catalogue row that has one:
#: the catalogue's own, or the built-in linkage of the same mechanism.
CATALOGUE_FILES = {
    "slider-crank": "linkages/seed_e2_slider_crank.toml", "four-bar": "linkages/seed_e1_fourbar.toml",
    "shaper (kurs)": "catalogue/shaper.toml", "five-bar": "linkages/five_bar_two_drivers.toml",
    "seven-link": "catalogue/seven_link.toml", "garage door": "catalogue/garage_door.toml",
    "excavator bucket": "catalogue/excavator_bucket.toml", "truss": "catalogue/truss.toml",
    "gear pair": "catalogue/gear_pair.toml", "mixed": "catalogue/mixed.toml",
    "over-constrained": "catalogue/over_constrained.toml",
}
CASES = Path(__file__).parent / "cases"


def file_mobility(relative: str) -> tuple[int, dict[str, int], int, int, int]:
    """A catalogue file's links (ground included), joints by seed letter, its mobility twice
    (Gruebler–Kutzbach with each kind's Sᵢ, and 3(n − 1) − rank J at the drawn pose: the
    freedoms it moves with) and its redundant constraint rows (those beyond rank J)."""
    from mechcheck.casefile import load_cases

    linkage = load_cases(CASES / relative)[0].linkage
    joints: dict[str, int] = {}
    for joint in linkage.joints:
        letter = joint.kind.symbol
        joints[letter] = joints.get(letter, 0) + 1
    redundant = linkage.constraint_rows - linkage.joint_rank
    return len(linkage.links), joints, linkage.gruebler, linkage.dof, redundant


def rank_text(dof: int, redundant: int) -> str:
    """The rank count as the line shows it: the freedoms, and the redundant rows where there
    are any (a structure of S = −1 moves with 0 freedoms and has 1 redundant row: the rank
    of J cannot be negative, so the printed S is freedoms − redundant rows)."""
    return f"{dof:2d} rank J" + (f", {redundant} redundant" if redundant else "")


def mobility_row(name: str, u: int, joints: str, spatial: bool, printed: int) -> tuple[str, bool]:
    """One catalogue row as a line, and whether it agrees with the printed S: from its case
    file where it has one (whose links and joints must be the row's), else from the table."""
    from mechcheck.analytic import theory

    head = f"mobility  {name:26s} u={u:<3d} {joints:12s} λ={6 if spatial else 3}  "
    relative = CATALOGUE_FILES.get(name)
    if relative is None or not (CASES / relative).is_file():  # an installation without it
        s = theory.mobility(u, parse_joints(joints), spatial=spatial)
        return (f"{head}S = {s:2d}{'':21s} (printed {printed:2d})  "
                f"{'table, spatial' if spatial else 'table'}", s == printed)
    links, counts, gruebler, dof, redundant = file_mobility(relative)
    same = links == u and counts == parse_joints(joints)
    line = (f"{head}S = {gruebler:2d} Gruebler, {rank_text(dof, redundant)} "
            f"(printed {printed:2d})  file cases/{relative}")
    if not same:
        found = ",".join(f"{n}{k}" for k, n in counts.items())
        line += f" (which has u={links}, {found})"
    by_rank = (dof, redundant) == (max(printed, 0), max(-printed, 0))
    return line, same and gruebler == printed and by_rank


@app.command("catalogue", help="Seed 001's catalogue of mechanisms (mobility and Grashof "
             "examples), recomputed: a planar row's mobility from its linkage case file where it "
             "has one (Gruebler–Kutzbach and the rank of the constraint Jacobian), the others "
             "from the table's counts.")
def catalogue_command() -> None:
    from mechcheck.analytic import theory

    bad = 0
    for row in MOBILITY_CATALOGUE:
        line, agrees = mobility_row(*row)
        bad += not agrees
        typer.echo(line)
    for crank, coupler, rocker, ground, printed_kind in GRASHOF_CATALOGUE:
        kind = theory.grashof(ground=ground, crank=crank, coupler=coupler, rocker=rocker).kind
        bad += kind != printed_kind
        typer.echo(f"grashof   A0A={crank:g} AB={coupler:g} B0B={rocker:g} A0B0={ground:g}: "
                   f"{kind} (printed {printed_kind})")
    raise typer.Exit(1 if bad else 0)
