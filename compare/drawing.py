"""Drawings of a mechanism at a pose: its links, joints, ground, springs, loads and the
reactions of one backend (``mechcheck draw``, the reports).

A drawing is made in two steps. :func:`scene_of` computes the *scene*, plain frozen data in
the case file's frame (metres, newtons): bars and plates through their links' points, each
joint's marks as its kind draws it (:meth:`~mechcheck.analytic.joint_kinds.JointKind.drawing`),
ground marks, springs, and load and reaction arrows scaled so that the largest force is a
fixed fraction of the drawing's extent. :func:`render` draws a scene with matplotlib (Agg)
and places the labels where their boxes overlap no other label (:class:`LabelPlacer`).
Nothing in the picture depends on where the drawing sits or how large it is: every size is
a fraction of the extent, every label offset is in pixels of a figure of fixed size.

>>> import mechcheck
>>> from mechcheck.drawing import drawing_png
>>> case = mechcheck.load_cases()[0]
>>> drawing_png(case, mechcheck.solve(case))[:8]
b'\\x89PNG\\r\\n\\x1a\\n'
"""

from __future__ import annotations

import io
import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

from mechcheck.analytic.case import Case
from mechcheck.analytic.joint_kinds.drawing import JointDrawing, Pin, PitchCircle, Slide, rotated
from mechcheck.analytic.linkage import LinearSpring, Linkage, TorsionSpring
from mechcheck.analytic.solution import Solution
from mechcheck.analytic.values import GROUND, CaseError, Vec2

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure
    from matplotlib.text import Text

#: The longest force arrow, as a fraction of the drawing's extent.
ARROW_FRACTION = 0.3
#: Forces smaller than this fraction of the largest get no arrow: a reaction of 1e-13 N
#: in a pin that carries nothing is round-off, not a force to draw.
NEGLIGIBLE_FORCE = 1e-9
#: Sizes of the marks, as fractions of the extent.
GROUND_WIDTH = 0.06
RAIL_HALF_LENGTH = 0.18
BLOCK_SIZE = (0.08, 0.045)
SLOT_HALF_WIDTH = 0.012
ZIGZAG_AMPLITUDE = 0.015
COIL_RADIUS = 0.035
MARGIN = 0.08
#: The default figure (inches) and resolution: the size every built-in case is checked at
#: for overlapping labels (tests/test_drawing.py).
FIGURE_SIZE = (8.0, 5.5)
#: The band above the drawing for the title and caption (inches).
TITLE_BAND = 0.7
DPI = 100
FONT_SIZE = 8.0
#: Label placement, in display pixels: the gap kept around each label, the step between
#: rings of candidate positions and how many rings are tried before any obstacle but
#: another label is allowed under a label.
LABEL_PAD = 1.5
RING_STEP = 5.0
NEAR_RINGS = 12
FAR_RINGS = 400
DIRECTIONS = 16
#: A label further than this (pixels) from its anchor gets a leader line.
LEADER_DISTANCE = 18.0

#: The gid of every placed label, so that a test finds them.
LABEL_GID = "mechcheck-label"

REACTION_COLOUR = "crimson"
LOAD_COLOUR = "royalblue"
SPRING_COLOUR = "darkgreen"
GROUND_COLOUR = "0.35"

Role = Literal["load", "reaction"]


# -- the scene ----------------------------------------------------------------------------
@dataclass(frozen=True)
class Bar:
    """A link drawn as a bar (two points) or a plate (three or more, their convex hull)."""

    link: str
    corners: tuple[Vec2, ...]


@dataclass(frozen=True)
class Zigzag:
    """A linear spring or an elastic member between two points."""

    name: str
    ends: tuple[Vec2, Vec2]


@dataclass(frozen=True)
class Coil:
    """A torsion spring at a pin."""

    name: str
    at: Vec2


@dataclass(frozen=True)
class Arrow:
    """A force (N) at a point, and the arrow that draws it (m, tail at ``at``)."""

    label: str
    at: Vec2
    force: Vec2
    vector: Vec2
    role: Role


@dataclass(frozen=True)
class Couple:
    """A load's pure moment (N·m, CCW +) at a point of its link."""

    label: str
    at: Vec2
    torque: float


@dataclass(frozen=True)
class Scene:
    """Everything one drawing shows, in the case file's frame (m, N)."""

    title: str
    bars: tuple[Bar, ...]
    joints: tuple[JointDrawing, ...]
    grounds: tuple[Vec2, ...]
    zigzags: tuple[Zigzag, ...]
    coils: tuple[Coil, ...]
    arrows: tuple[Arrow, ...]
    couples: tuple[Couple, ...]
    points: Mapping[str, Vec2]
    extent: float
    #: Metres of arrow per newton: the largest force is ARROW_FRACTION of the extent.
    force_scale: float
    caption: str = ""

    def limits(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """(x, y) ranges holding every point, circle and arrow, with a margin."""
        tips = [(a.at[0] + a.vector[0], a.at[1] + a.vector[1]) for a in self.arrows]
        xs, ys = reach([*self.points.values(), *tips], self.joints)
        pad = MARGIN * self.extent
        return (min(xs) - pad, max(xs) + pad), (min(ys) - pad, max(ys) + pad)


def reach(points: Sequence[Vec2], sketches: Sequence[JointDrawing]) -> tuple[list[float],
                                                                              list[float]]:
    """The x and y coordinates a drawing must hold: the points and each pitch circle's
    left, right, bottom and top."""
    xs, ys = [p[0] for p in points], [p[1] for p in points]
    for sketch in sketches:
        for mark in sketch.marks:
            if isinstance(mark, PitchCircle):
                (cx, cy), r = mark.centre, mark.radius
                xs += [cx - r, cx + r]
                ys += [cy - r, cy + r]
    return xs, ys


@dataclass(frozen=True)
class Pose:
    """A linkage at one pose (:class:`~mechcheck.analytic.joint_kinds.drawing.Placement`):
    its points in the file's frame (m) and each link's turn from the drawn pose (rad)."""

    linkage: Linkage
    points: Mapping[str, Vec2]
    turns: Mapping[str, float] = field(default_factory=dict)

    def point(self, name: str) -> Vec2:
        return self.points[name]

    def turn(self, link: str) -> float:
        return self.turns.get(link, 0.0)

    def carried(self, link: str, drawn: Vec2) -> Vec2:
        """Where a point fixed to ``link`` (given at the drawn pose, relative to the
        linkage's reference point as the linkage holds it) is now."""
        linkage = self.linkage
        ref = next(lk for lk in linkage.links if lk.name == link).points[0]
        r0 = linkage.points[ref]
        dx, dy = rotated(self.turn(link), (drawn[0] - r0[0], drawn[1] - r0[1]))
        rx, ry = self.points[ref]
        return (rx + dx, ry + dy)


def drawn_pose(linkage: Linkage) -> Pose:
    """The linkage as its file draws it."""
    return Pose(linkage, {n: linkage.drawn(p) for n, p in linkage.points.items()})


def linkage_values(case: Case, solution: Solution) -> dict[str, float]:
    """A solution's values under the linkage's own names (a four-bar's ``F23_x`` is its
    linkage's ``F_A_x``)."""
    names = case.names.names if case.names is not None else {}
    return {names.get(q, q): float(v) for q, v in solution.values.items()}


def solved_pose(case: Case, solution: Solution) -> Pose:
    """The pose a solution reports: its ``x_``/``y_`` of every point and ``phi_`` of every
    link; a four-bar's or slider-crank's is the pose its linkage is drawn at (the input
    angle places it). ValueError if the solution has no pose."""
    linkage = case.linkage
    values = linkage_values(case, solution)
    if all(f"x_{p}" in values and f"y_{p}" in values for p in linkage.points):
        points = {p: (values[f"x_{p}"], values[f"y_{p}"]) for p in linkage.points}
        turns = {link: values.get(f"phi_{link}", 0.0) for link in linkage.moving_links}
        if all(math.isfinite(v) for xy in points.values() for v in xy):
            return Pose(linkage, points, turns)
    if case.is_preset:
        return drawn_pose(linkage)
    why = f"{solution.status}: {solution.message}" if solution.status != "ok" else \
        "it reports no point positions"
    raise ValueError(f"{solution.backend} gives no pose for case {case.name!r} ({why})")


def bars(pose: Pose) -> Iterator[Bar]:
    """Each moving rigid link through its points and the points its loads, mass and springs
    act at (a coupler point off the line of its pins makes it a plate); a link of one point
    has its joints' marks only."""
    for link in pose.linkage.links:
        if link.name == GROUND or link.axial_stiffness is not None:
            continue
        corners = tuple(dict.fromkeys([*(pose.point(p) for p in link.points),
                                       *attached(pose, link.name)]))
        if len(corners) >= 2:
            yield Bar(link.name, hull(corners))


def attached(pose: Pose, link: str) -> Iterator[Vec2]:
    """Where loads, the centre of mass and spring ends sit on ``link``, now."""
    linkage = pose.linkage
    yield from (pose.carried(link, ld.at) for ld in linkage.loads if ld.link == link)
    yield from (pose.carried(link, m.com) for m in linkage.masses if m.link == link)
    for spring in linkage.springs:
        if isinstance(spring, LinearSpring):
            yield from (pose.carried(link, at) for owner, at in spring.ends if owner == link)


def hull(points: tuple[Vec2, ...]) -> tuple[Vec2, ...]:
    """The convex hull's corners in order; two points, or points on one line: its ends."""
    if len(points) > 2:
        from scipy.spatial import ConvexHull, QhullError

        try:
            return tuple(points[i] for i in ConvexHull(points).vertices)
        except QhullError:   # collinear: a bar between the extreme points
            pass
    first = points[0]
    far = max(points, key=lambda p: math.dist(p, first))
    return (max(points, key=lambda p: math.dist(p, far)), far)


def zigzags(pose: Pose) -> Iterator[Zigzag]:
    """Linear springs between their ends, and elastic members between their points."""
    for spring in pose.linkage.springs:
        if isinstance(spring, LinearSpring):
            (la, pa), (lb, pb) = spring.ends
            yield Zigzag(spring.name, (pose.carried(la, pa), pose.carried(lb, pb)))
    for link in pose.linkage.elastic_links:
        a, b = link.points
        yield Zigzag(link.name, (pose.point(a), pose.point(b)))


def coils(pose: Pose) -> Iterator[Coil]:
    for spring in pose.linkage.springs:
        if isinstance(spring, TorsionSpring):
            yield Coil(spring.name, pose.point(pose.linkage.joint(spring.joint).at))


def ground_points(linkage: Linkage) -> tuple[str, ...]:
    ground = next(link for link in linkage.links if link.name == GROUND)
    return tuple(dict.fromkeys(ground.points))


@dataclass(frozen=True)
class Force:
    """A force before it is scaled into an arrow."""

    label: str
    at: Vec2
    force: Vec2
    role: Role


def load_forces(pose: Pose, gravity: Vec2) -> Iterator[Force]:
    """The case's forces at their points, and each mass's weight at its centre."""
    for load in pose.linkage.loads:
        if load.force != (0.0, 0.0):
            yield Force(newtons("", load.force), pose.carried(load.link, load.at), load.force,
                        "load")
    if gravity != (0.0, 0.0):
        for m in pose.linkage.masses:
            weight = (m.mass * gravity[0], m.mass * gravity[1])
            yield Force(newtons(f"W_{m.link}", weight), pose.carried(m.link, m.com), weight,
                        "load")


def couples(pose: Pose) -> Iterator[Couple]:
    for load in pose.linkage.loads:
        if load.torque:
            yield Couple(f"{load.torque:.3g} N·m", pose.carried(load.link, load.at), load.torque)


def reaction_forces(case: Case, pose: Pose, sketches: Mapping[str, JointDrawing],
                    reactions: Solution) -> Iterator[Force]:
    """Each joint's ``F_<joint>`` (by its first link on its second) where it acts."""
    values = linkage_values(case, reactions)
    for joint in case.linkage.joints:
        fx, fy = values.get(f"F_{joint.name}_x"), values.get(f"F_{joint.name}_y")
        if fx is None or fy is None or not (math.isfinite(fx) and math.isfinite(fy)):
            continue
        yield Force(newtons(f"F_{joint.name}", (fx, fy)), sketches[joint.name].acts_at,
                    (fx, fy), "reaction")


def newtons(name: str, force: Vec2) -> str:
    """A force's label: its name and magnitude (N), to three digits below 1000 N."""
    size = math.hypot(*force)
    text = f"{size:.0f}" if size >= 1000.0 else f"{size:.3g}"
    return f"{name} {text} N".strip()


def extent_of(pose: Pose, sketches: Sequence[JointDrawing]) -> float:
    """The drawing's size: the larger side of the box round its points and pitch circles."""
    xs, ys = reach(list(pose.points.values()), sketches)
    return max(max(xs) - min(xs), max(ys) - min(ys))


def largest_force(forces: Sequence[Force]) -> float:
    return max((math.hypot(*f.force) for f in forces), default=0.0)


def scene_of(case: Case, solution: Solution | None = None, *, reactions: Solution | None = None,
             force_scale: float | None = None, title: str | None = None) -> Scene:
    """The scene of ``case`` at the pose ``solution`` reports (None: as its file draws it),
    with the reactions of ``reactions`` (default: ``solution``'s own; None and no solution:
    none).

    ``force_scale`` (m of arrow per N) is, by default, what makes the largest force
    :data:`ARROW_FRACTION` of the extent; drawings meant to be compared pass one scale.
    ValueError when ``solution`` reports no pose (:func:`solved_pose`).
    """
    linkage = case.linkage
    pose = drawn_pose(linkage) if solution is None else solved_pose(case, solution)
    sketches = {j.name: j.kind.drawing(j, pose) for j in linkage.joints}
    forces = list(load_forces(pose, linkage.gravity))
    source = reactions if reactions is not None else solution
    if source is not None:
        forces += reaction_forces(case, pose, sketches, source)
    extent = extent_of(pose, list(sketches.values()))
    largest = largest_force(forces)
    forces = [f for f in forces if math.hypot(*f.force) > NEGLIGIBLE_FORCE * largest]
    scale = force_scale if force_scale is not None else \
        (ARROW_FRACTION * extent / largest if largest > 0.0 else 0.0)
    arrows = tuple(Arrow(f.label, f.at, f.force, (f.force[0] * scale, f.force[1] * scale), f.role)
                   for f in forces)
    return Scene(
        title=title if title is not None else scene_title(case, solution, source),
        bars=tuple(bars(pose)), joints=tuple(sketches.values()),
        grounds=tuple(pose.point(p) for p in ground_points(linkage)),
        zigzags=tuple(zigzags(pose)), coils=tuple(coils(pose)), arrows=arrows,
        couples=tuple(couples(pose)), points=dict(pose.points), extent=extent,
        force_scale=scale, caption=caption(arrows, source))


def scene_title(case: Case, solution: Solution | None, reactions: Solution | None) -> str:
    pose = "as drawn in its file" if solution is None else f"pose by {solution.backend}"
    forces = f", reactions by {reactions.backend}" if reactions is not None else ""
    return f"{case.name}: {pose}{forces}"


def caption(arrows: Sequence[Arrow], reactions: Solution | None) -> str:
    """What the arrows mean: loads in blue, reactions in red (F_<joint>: by the joint's
    first link on its second), one scale."""
    parts = ["blue: loads"]
    if reactions is not None:
        parts.append("red: F_<joint>, by the joint's first link on its second")
    if arrows:
        largest = max(arrows, key=lambda a: math.hypot(*a.force))
        parts.append(f"arrows to one scale (longest: {largest.label})")
    return "; ".join(parts)


# -- the command line -----------------------------------------------------------------------
class DrawingError(ValueError):
    """A drawing that cannot be made as asked: the command line's one line."""


#: What ``mechcheck draw`` writes, by the output's suffix.
FORMATS: dict[str, Literal["png", "svg"]] = {".svg": "svg", ".png": "png"}


def pick_case(path: Path, name: str | None) -> Case:
    """The case called ``name`` in the file at ``path``, or its only case; a
    :class:`~mechcheck.analytic.values.CaseError` naming the file otherwise."""
    from mechcheck.casefile import load_cases

    cases = load_cases(path)
    names = ", ".join(c.name for c in cases)
    if name is None:
        if len(cases) > 1:
            raise CaseError(f"holds {len(cases)} cases; choose one with --case: {names}",
                            file=str(path))
        return cases[0]
    for case in cases:
        if case.name == name:
            return case
    raise CaseError(f"no case {name!r}; its cases: {names}", file=str(path))


def output_format(target: Path) -> Literal["png", "svg"]:
    """The format a file name asks for; DrawingError for any other suffix."""
    fmt = FORMATS.get(target.suffix.lower())
    if fmt is None:
        raise DrawingError(f"--out {target}: must end in .svg or .png")
    return fmt


def drawing_file(case: Case, fmt: Literal["png", "svg"], *, drawn: bool = False,
                 backend: str = "analytic") -> bytes:
    """The drawing ``mechcheck draw`` writes: ``case`` at analytic's pose with ``backend``'s
    reactions, or (``drawn``) as its file draws it. DrawingError when a solve gives nothing
    to draw, saying why."""
    if case.geometry is None:
        raise CaseError("does not assemble at its theta12: there is no pose to draw",
                        case=case.name, file=case.source)
    if drawn:
        return saved(draw_case(case), fmt)
    from mechcheck.run import solve_gated

    pose = solve_gated("analytic", case)
    forces = pose if backend == "analytic" else solve_gated(backend, case)
    if not any(q.startswith("F_") and math.isfinite(v)
               for q, v in linkage_values(case, forces).items()):
        why = f"{forces.status}: {forces.message}" if forces.status != "ok" else \
            "it reports no joint forces"
        raise CaseError(f"backend {backend} gives no reactions to draw ({why})",
                        case=case.name, file=case.source)
    try:
        return saved(draw_case(case, pose, reactions=forces), fmt)
    except ValueError as error:   # analytic found no pose
        raise CaseError(str(error), case=case.name, file=case.source) from None


# -- rendering ----------------------------------------------------------------------------
def draw_case(case: Case, solution: Solution | None = None, *,
              reactions: Solution | None = None, size: tuple[float, float] = FIGURE_SIZE) -> Figure:
    """A matplotlib Figure of ``case`` at the pose ``solution`` reports (None: as drawn in
    its file) with ``reactions``' joint forces (default: ``solution``'s). ValueError when
    ``solution`` reports no pose."""
    return render(scene_of(case, solution, reactions=reactions), size=size)


def drawing_png(case: Case, solution: Solution | None = None, *,
                reactions: Solution | None = None) -> bytes:
    """PNG bytes of :func:`draw_case` at the default size: what a report inlines."""
    return saved(draw_case(case, solution, reactions=reactions), "png")


def drawing_svg(case: Case, solution: Solution | None = None, *,
                reactions: Solution | None = None) -> str:
    """SVG text of :func:`draw_case` at the default size."""
    return saved(draw_case(case, solution, reactions=reactions), "svg").decode()


def saved(fig: Figure, fmt: Literal["png", "svg"]) -> bytes:
    """The figure as a PNG or SVG file's bytes. Without a date or software stamp and with a
    fixed SVG id salt: the same drawing gives the same bytes."""
    import matplotlib

    buffer = io.BytesIO()
    stamp = {"Software": None} if fmt == "png" else {"Date": None}
    with matplotlib.rc_context({"svg.hashsalt": "mechcheck"}):
        fig.savefig(buffer, format=fmt, dpi=DPI, bbox_inches="tight", metadata=stamp)
    return buffer.getvalue()


#: The width (inches) of one panel of :func:`panels_png`, and the range of its height: as
#: tall as the poses' common window needs at that width, within these bounds.
PANEL_WIDTH = 4.6
PANEL_HEIGHTS = (2.0, 5.0)


def panels_png(panels: Sequence[tuple[Case, Solution, str]]) -> bytes:
    """PNG bytes of several poses side by side (a sweep's cycle), each ``(case at the pose,
    its solution, panel title)``: one force scale, one window, so that the panels compare.
    A panel whose solution has no pose is left out."""
    drawable = []
    for case, solution, title in panels:
        try:
            drawable.append((case, solution, title, scene_of(case, solution, title=title)))
        except ValueError:
            continue
    if not drawable:
        return b""
    extent = max(s.extent for *_, s in drawable)
    largest = max((math.hypot(*a.force) for *_, s in drawable for a in s.arrows), default=0.0)
    scale = ARROW_FRACTION * extent / largest if largest > 0.0 else 0.0
    scenes = [scene_of(c, sol, force_scale=scale, title=t) for c, sol, t, _ in drawable]
    limits = [s.limits() for s in scenes]
    window = ((min(x[0] for x, _ in limits), max(x[1] for x, _ in limits)),
              (min(y[0] for _, y in limits), max(y[1] for _, y in limits)))
    (x0, x1), (y0, y1) = window
    height = min(max(PANEL_WIDTH * (y1 - y0) / (x1 - x0), PANEL_HEIGHTS[0]), PANEL_HEIGHTS[1])
    fig, axes = new_figure((PANEL_WIDTH * len(scenes), height), panels=len(scenes))
    placer = LabelPlacer(fig)
    placer.block(fig.suptitle("blue: loads; red: F_<joint>, by the joint's first link on its "
                              "second; arrows to one scale in every panel",
                              fontsize=FONT_SIZE + 1, y=1.0, va="top"))
    for ax, scene in zip(axes, scenes, strict=True):
        draw_scene(ax, replace(scene, caption=""), placer, window)
    return saved(fig, "png")


def new_figure(size: tuple[float, float], panels: int = 1) -> tuple[Figure, list[Axes]]:
    """A figure of ``panels`` side by side, each without ticks or frame, below a band of
    :data:`TITLE_BAND` inches for the titles. Not pyplot's: no display, and nothing global
    holds it once it is dropped."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.ticker import NullLocator

    fig = Figure(figsize=(size[0], size[1] + TITLE_BAND), dpi=DPI)
    FigureCanvasAgg(fig)
    width, top = 1.0 / panels, size[1] / (size[1] + TITLE_BAND)
    axes = [fig.add_axes((k * width + 0.01, 0.0, width - 0.02, top)) for k in range(panels)]
    for ax in axes:
        ax.set_axis_off()
        # No ticks at all: an axis off still lays its ticks out for the title's position.
        ax.xaxis.set_major_locator(NullLocator())
        ax.yaxis.set_major_locator(NullLocator())
    return fig, axes


def render(scene: Scene, *, size: tuple[float, float] = FIGURE_SIZE) -> Figure:
    """The scene drawn on a figure of ``size`` inches, its labels placed apart."""
    fig, (ax,) = new_figure(size)
    placer = LabelPlacer(fig)
    draw_scene(ax, scene, placer, scene.limits())
    return fig


def draw_scene(ax: Axes, scene: Scene, placer: LabelPlacer,
               limits: tuple[tuple[float, float], tuple[float, float]]) -> None:
    """Draw the scene into ``ax`` over ``limits`` (x, y ranges; equal scales), then its
    labels through ``placer``."""
    ax.set_xlim(*limits[0])
    ax.set_ylim(*limits[1])
    ax.set_aspect("equal", adjustable="box")
    ax.set_anchor("N")   # under the title band, whatever the drawing's shape
    ax.apply_aspect()
    ax.set_autoscale_on(False)
    unit = scene.extent
    colours = link_colours(scene)
    for bar in scene.bars:
        draw_bar(ax, bar, colours[bar.link])
    for z in scene.zigzags:
        draw_zigzag(ax, z, unit)
    for c in scene.coils:
        draw_coil(ax, c, unit)
    for at in scene.grounds:
        draw_ground(ax, at, unit)
    for sketch in scene.joints:
        for mark in sketch.marks:
            draw_mark(ax, mark, unit)
    for a in scene.arrows:
        draw_arrow(ax, a)
    for couple in scene.couples:
        draw_couple(ax, couple, unit)
    title = ax.set_title(scene.title + ("\n" + scene.caption if scene.caption else ""),
                         fontsize=FONT_SIZE + 1)
    placer.block(title)
    placer.block_points(ax, scene)
    for name, at in scene.points.items():
        placer.place(ax, name, at, colour="black")
    for z in scene.zigzags:
        placer.place(ax, z.name, midpoint(*z.ends), colour=SPRING_COLOUR)
    for c in scene.coils:
        placer.place(ax, c.name, c.at, colour=SPRING_COLOUR)
    for couple in scene.couples:
        placer.place(ax, couple.label, couple.at, colour=LOAD_COLOUR)
    for a in scene.arrows:
        placer.place(ax, a.label, (a.at[0] + a.vector[0], a.at[1] + a.vector[1]),
                     colour=REACTION_COLOUR if a.role == "reaction" else LOAD_COLOUR)


def link_colours(scene: Scene) -> dict[str, str]:
    palette = ["tab:blue", "tab:orange", "tab:green", "tab:purple", "tab:brown", "tab:olive",
               "tab:cyan", "tab:pink", "tab:gray"]
    return {bar.link: palette[k % len(palette)] for k, bar in enumerate(scene.bars)}


def line(ax: Axes, xs: Any, ys: Any, **style: Any) -> None:
    """A line on ``ax`` (Axes.plot's colour cycle and argument parsing took a third of a
    drawing's time)."""
    from matplotlib.lines import Line2D

    ax.add_line(Line2D(xs, ys, **style))


def midpoint(a: Vec2, b: Vec2) -> Vec2:
    return ((a[0] + b[0]) / 2, (a[1] + b[1]) / 2)


def draw_bar(ax: Axes, bar: Bar, colour: str) -> None:
    from matplotlib.patches import Polygon

    xs, ys = zip(*bar.corners, strict=True)
    if len(bar.corners) == 2:
        line(ax, xs, ys, color=colour, lw=5, solid_capstyle="round", alpha=0.85, zorder=2)
        return
    ax.add_patch(Polygon(bar.corners, closed=True, facecolor=colour, edgecolor=colour,
                         alpha=0.35, lw=2, zorder=1))


def draw_zigzag(ax: Axes, z: Zigzag, unit: float) -> None:
    (x0, y0), (x1, y1) = z.ends
    length = math.hypot(x1 - x0, y1 - y0)
    if length == 0.0:
        return
    ux, uy = (x1 - x0) / length, (y1 - y0) / length
    amp = ZIGZAG_AMPLITUDE * unit
    teeth = 10
    # Straight leads at both ends, the zigzag between them.
    ts = [0.0, 0.15] + [0.15 + 0.7 * (k + 0.5) / teeth for k in range(teeth)] + [0.85, 1.0]
    offsets = [0.0, 0.0] + [amp * (1 if k % 2 == 0 else -1) for k in range(teeth)] + [0.0, 0.0]
    xs = [x0 + t * length * ux - o * uy for t, o in zip(ts, offsets, strict=True)]
    ys = [y0 + t * length * uy + o * ux for t, o in zip(ts, offsets, strict=True)]
    line(ax, xs, ys, color=SPRING_COLOUR, lw=1.2, zorder=3)


def draw_coil(ax: Axes, c: Coil, unit: float) -> None:
    import numpy as np

    turn = np.linspace(0.0, 3.5 * math.pi, 80)
    radius = COIL_RADIUS * unit * (0.35 + 0.65 * turn / turn[-1])
    line(ax, c.at[0] + radius * np.cos(turn), c.at[1] + radius * np.sin(turn),
            color=SPRING_COLOUR, lw=1.0, zorder=3)


def draw_ground(ax: Axes, at: Vec2, unit: float) -> None:
    """A fixed pivot: a triangle under the point on a hatched base."""
    from matplotlib.patches import Polygon, Rectangle

    w = GROUND_WIDTH * unit
    x, y = at
    ax.add_patch(Polygon([(x, y), (x - w / 2, y - 0.7 * w), (x + w / 2, y - 0.7 * w)],
                         closed=True, facecolor="white", edgecolor=GROUND_COLOUR, lw=1, zorder=3))
    ax.add_patch(Rectangle((x - 0.7 * w, y - w), 1.4 * w, 0.3 * w, hatch="////",
                           facecolor="none", edgecolor=GROUND_COLOUR, lw=0, zorder=3))
    line(ax, [x - 0.7 * w, x + 0.7 * w], [y - 0.7 * w] * 2, color=GROUND_COLOUR, lw=1.2, zorder=3)


def draw_mark(ax: Axes, mark: Pin | Slide | PitchCircle, unit: float) -> None:
    if isinstance(mark, Pin):
        draw_pin(ax, mark.at)
    elif isinstance(mark, Slide):
        draw_slide(ax, mark, unit)
    else:
        from matplotlib.patches import Circle

        ax.add_patch(Circle(mark.centre, mark.radius, fill=False, ls="--", lw=1.2,
                            edgecolor="0.2", zorder=2))


def draw_pin(ax: Axes, at: Vec2) -> None:
    line(ax, [at[0]], [at[1]], ls="none", marker="o", ms=7, mfc="white", mec="black", mew=1.3,
         zorder=6)


def draw_slide(ax: Axes, mark: Slide, unit: float) -> None:
    """The guide along the axis (hatched on one side where it is the ground), and a block,
    or a pin in a slot, at the point."""
    from matplotlib.patches import Polygon

    (x, y), (ux, uy) = mark.at, mark.axis
    nx, ny = -uy, ux
    half = RAIL_HALF_LENGTH * unit

    def along(t: float, s: float) -> Vec2:
        return (x + t * ux + s * nx, y + t * uy + s * ny)

    if mark.turns:
        gap = SLOT_HALF_WIDTH * unit
        for side in (-gap, gap):
            (x0, y0), (x1, y1) = along(-half, side), along(half, side)
            line(ax, [x0, x1], [y0, y1], color="black", lw=1.0, zorder=4)
        draw_pin(ax, mark.at)
        return
    bl, bh = BLOCK_SIZE[0] * unit, BLOCK_SIZE[1] * unit
    rail = -bh / 2
    (rx0, ry0), (rx1, ry1) = along(-half, rail), along(half, rail)
    line(ax, [rx0, rx1], [ry0, ry1], color=GROUND_COLOUR if mark.grounded else "black", lw=1.5,
         zorder=3)
    if mark.grounded:   # hatch ticks under the rail, one line broken by NaNs
        xs, ys = [], []
        for k in range(13):
            t = -half + 2 * half * k / 12
            (tx0, ty0), (tx1, ty1) = along(t, rail), along(t - 0.25 * bh, rail - 0.45 * bh)
            xs += [tx0, tx1, math.nan]
            ys += [ty0, ty1, math.nan]
        line(ax, xs, ys, color=GROUND_COLOUR, lw=0.8, zorder=3)
    corners = [along(-bl / 2, -bh / 2), along(bl / 2, -bh / 2), along(bl / 2, bh / 2),
               along(-bl / 2, bh / 2)]
    ax.add_patch(Polygon(corners, closed=True, facecolor="0.85", edgecolor="black", lw=1.2,
                         zorder=5))
    draw_pin(ax, mark.at)


def draw_arrow(ax: Axes, a: Arrow) -> None:
    from matplotlib.patches import FancyArrowPatch

    colour = REACTION_COLOUR if a.role == "reaction" else LOAD_COLOUR
    tip = (a.at[0] + a.vector[0], a.at[1] + a.vector[1])
    ax.add_patch(FancyArrowPatch(a.at, tip, arrowstyle="-|>", mutation_scale=12, color=colour,
                                 lw=1.6, shrinkA=0, shrinkB=0, zorder=7))


def draw_couple(ax: Axes, c: Couple, unit: float) -> None:
    """A three-quarter circle round the point, its head showing the sense."""
    from matplotlib.patches import FancyArrowPatch

    r = 2 * COIL_RADIUS * unit
    start, end = (c.at[0] + r, c.at[1]), (c.at[0], c.at[1] - r)
    if c.torque < 0:
        start, end = end, start
    ax.add_patch(FancyArrowPatch(start, end, connectionstyle="arc3,rad=-1.2" if c.torque > 0
                                 else "arc3,rad=1.2", arrowstyle="-|>", mutation_scale=10,
                                 color=LOAD_COLOUR, lw=1.2, zorder=7))


class LabelPlacer:
    """Places labels on a figure so that no two boxes overlap.

    Each label is tried at rings of positions round its anchor, nearest first, and goes to
    the first where its box (measured with the figure's renderer) meets no label placed
    before, no blocked box (titles) and, within :data:`NEAR_RINGS` rings, no marker or
    drawn line either; further out only the labels and blocked boxes count, so a place is
    always found. Boxes are held as rows (x0, y0, x1, y1) in display pixels.
    """

    def __init__(self, fig: Figure) -> None:
        import numpy as np

        self.renderer = fig.canvas.get_renderer()   # type: ignore[attr-defined]
        self.labels = np.empty((0, 4))
        self.obstacles = np.empty((0, 4))

    def block(self, artist: Text) -> None:
        """Keep labels off an artist (a title)."""
        import numpy as np

        if artist.get_text():
            box = artist.get_window_extent(self.renderer).padded(LABEL_PAD)
            self.labels = np.vstack([self.labels, box.extents])

    def block_points(self, ax: Axes, scene: Scene) -> None:
        """Keep labels off the points' markers and, near their anchors, off bars and arrows
        (sampled along their length)."""
        import numpy as np

        marks: list[tuple[Vec2, float]] = [(p, 6.0) for p in scene.points.values()]
        # The ground's marks hang below their points: a box of their size, as samples.
        w = GROUND_WIDTH * scene.extent
        marks += [((x + dx * w, y - dy * w), 4.0) for x, y in scene.grounds
                  for dx in (-0.6, -0.3, 0.0, 0.3, 0.6) for dy in (0.3, 0.6, 0.9)]
        segments = [(a.at, (a.at[0] + a.vector[0], a.at[1] + a.vector[1])) for a in scene.arrows]
        for bar in scene.bars:
            segments += list(zip(bar.corners, bar.corners[1:] + bar.corners[:1], strict=True))
        for (x0, y0), (x1, y1) in segments:
            marks += [((x0 + t * (x1 - x0), y0 + t * (y1 - y0)), 2.5)
                      for t in np.linspace(0.0, 1.0, 13)[1:-1]]
        if marks:
            centres = ax.transData.transform([p for p, _ in marks])
            half = np.array([h for _, h in marks])[:, None]
            self.obstacles = np.vstack([self.obstacles,
                                        np.hstack([centres - half, centres + half])])

    def place(self, ax: Axes, text: str, anchor: Vec2, *, colour: str) -> Text:
        import numpy as np

        label = ax.text(*anchor, text, ha="center", va="center", fontsize=FONT_SIZE,
                        color=colour, zorder=9, gid=LABEL_GID,
                        bbox={"boxstyle": "square,pad=0.05", "fc": "white", "ec": "none",
                              "alpha": 0.75})
        box = label.get_window_extent(self.renderer)
        w, h = box.width + 2 * LABEL_PAD, box.height + 2 * LABEL_PAD
        ax_x, ax_y = ax.transData.transform(anchor)
        for ring, (cx, cy) in candidates(ax_x, ax_y, w, h):
            candidate = np.array([cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2])
            if overlaps(candidate, self.labels) or \
                    (ring < NEAR_RINGS and overlaps(candidate, self.obstacles)):
                continue
            break
        label.set_position(tuple(ax.transData.inverted().transform((cx, cy))))
        if math.hypot(cx - ax_x, cy - ax_y) > LEADER_DISTANCE + max(w, h) / 2:
            x, y = label.get_position()
            line(ax, [anchor[0], x], [anchor[1], y], color="0.6", lw=0.6, zorder=8)
        self.labels = np.vstack([self.labels, candidate])
        return label


def overlaps(box: Any, boxes: Any) -> bool:
    """Whether the box (x0, y0, x1, y1) overlaps any row of ``boxes`` (touching is not)."""
    return bool(((box[0] < boxes[:, 2]) & (boxes[:, 0] < box[2])
                 & (box[1] < boxes[:, 3]) & (boxes[:, 1] < box[3])).any())


def candidates(x: float, y: float, w: float, h: float) -> Iterator[tuple[int, Vec2]]:
    """(ring, centre) of a w × h box round (x, y), ring by ring outward: the box's edge
    ``ring`` steps from the anchor, upper right first. The last ring is beyond any label."""
    for ring in range(FAR_RINGS):
        gap = 2.0 + ring * RING_STEP
        for k in range(DIRECTIONS):
            angle = math.pi / 4 + 2 * math.pi * k / DIRECTIONS
            c, s = math.cos(angle), math.sin(angle)
            yield ring, (x + c * (gap + w / 2), y + s * (gap + h / 2))
