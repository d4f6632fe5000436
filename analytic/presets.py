"""The four-bar and the slider-crank as linkages (LINKAGES.md, "The four-bar and
slider-crank as linkages"): the same mechanism, drawn at the case's pose, solved by the one
engine and read under the preset's names.

Links ``ground``, ``crank``, ``coupler``, ``rocker`` / ``slider``; joints ``A0``
(ground, crank), ``A`` (crank, coupler), ``B`` (coupler, rocker or slider) and ``B0``
(ground, rocker) or ``slide`` (ground, slider, prismatic at B along the slide axis). The
crank's joint A0 is driven with the case's ω and α from the drawn pose (with
``drive_link = 4``, the rocker's joint B0 with the rocker's ω and α at that instant), so the
engine solves exactly the case's problem. The contract's names (CONVENTIONS.md: ``F12`` …
``F14``, ``T12`` or ``T14``, ``M14``, ``theta13``, ``theta14``, ``s14``) map one to one
(:class:`Renaming`).

Every backend, analytic or simulated, runs a preset through :func:`solve_preset` and
:func:`sweep_preset` (:class:`~mechcheck.analytic.contract.Backend` does it for them): it
sees only linkages. What the preset keeps of its own is its position analysis in closed
form, which draws the linkage, says where it does not assemble, and keeps a sweep on the
branch the file names.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, TypeVar

import numpy as np

from mechcheck.analytic.assembly import change_point_message, unassembled_verdict
from mechcheck.analytic.case import (
    Case,
    CaseError,
    FourBarGeometry,
    Friction,
    Load,
    Mass,
    Motion,
    Preset,
    PresetGeometry,
    Vec2,
    preset_of,
)
from mechcheck.analytic.joint_kinds import PRISMATIC, REVOLUTE
from mechcheck.analytic.kinematics import assembles, pose_of
from mechcheck.analytic.linkage import (
    Driver,
    Joint,
    JointFriction,
    Link,
    Linkage,
    LinkMass,
    PointLoad,
)
from mechcheck.analytic.linkage_backends import DecidedPoses, analytic_results, pose_verdicts
from mechcheck.analytic.linkage_forces import LinkageResults
from mechcheck.analytic.solution import Solution

#: A value or a column of values (:meth:`Renaming.columns`).
T = TypeVar("T", float, np.ndarray)

LINK_NAMES = {2: "crank", 3: "coupler"}

#: Legacy quantity → linkage quantity (forces, torques).
LEGACY_NAMES = {
    "F12_x": "F_A0_x", "F12_y": "F_A0_y", "F23_x": "F_A_x", "F23_y": "F_A_y",
    "F34_x": "F_B_x", "F34_y": "F_B_y", "T12": "Q_A0",
}
FOUR_BAR_NAMES = LEGACY_NAMES | {"F14_x": "F_B0_x", "F14_y": "F_B0_y"}
SLIDER_CRANK_NAMES = LEGACY_NAMES | {"F14_x": "F_slide_x", "F14_y": "F_slide_y",
                                     "M14": "M_slide"}


def names_of(preset: Preset) -> dict[str, str]:
    """Legacy quantity → linkage quantity for ``preset`` (its drive torque included)."""
    names = FOUR_BAR_NAMES if preset.geometry.rocker else SLIDER_CRANK_NAMES
    if preset.drive_link == 4:
        names = {k: v for k, v in names.items() if k != "T12"} | {"T14": "Q_B0"}
    return names


def link_name(preset: Preset, link: int) -> str:
    if link == 4:
        return "rocker" if preset.geometry.rocker else "slider"
    return LINK_NAMES[link]


def linkage_of(case: Preset) -> Linkage:
    """The preset's mechanism as a linkage drawn at its pose, driven at A0, or at B0
    for ``drive_link = 4``.

    LINKAGES.md gives ``drive_link = 4`` no direct spelling because its motion is prescribed
    through link 2; at one instant of a one-freedom linkage that motion is the rocker's
    ω14, α14 (from the crank's, by the velocity and acceleration analysis), so a driver on
    B0 with those rates is the same problem, and the same state at the reading.
    """
    pose = pose_of(case)

    def drawn(link: int, local: Vec2) -> Vec2:
        x, y = pose.point(link, local)[0][0]
        return (float(x), float(y))

    points = {name: (float(p[0][0]), float(p[0][1])) for name, p in pose.joints.items()}
    rocker = link_name(case, 4)
    links = [Link("ground", ("A0", "B0") if "B0" in points else ("A0",)),
             Link("crank", ("A0", "A")), Link("coupler", ("A", "B")),
             Link(rocker, ("B0", "B") if "B0" in points else ("B",))]
    joints = [Joint("A0", REVOLUTE, ("ground", "crank"), "A0"),
              Joint("A", REVOLUTE, ("crank", "coupler"), "A"),
              Joint("B", REVOLUTE, ("coupler", rocker), "B")]
    if isinstance(case.geometry, FourBarGeometry):
        joints.append(Joint("B0", REVOLUTE, ("ground", rocker), "B0"))
    else:
        axis = (math.cos(case.ground_angle), math.sin(case.ground_angle))
        joints.append(Joint("slide", PRISMATIC, ("ground", rocker), "B", axis))
    return Linkage(
        points=points, links=tuple(links), joints=tuple(joints),
        drivers=(_driver_of(case),),
        loads=tuple(PointLoad(link_name(case, ld.link), drawn(ld.link, ld.at), ld.force, ld.torque)
                    for ld in case.loads),
        masses=tuple(LinkMass(link_name(case, m.link), m.mass, drawn(m.link, m.com), m.inertia)
                     for m in case.masses),
        gravity=case.gravity,
        friction=_friction_of(case),
    )


def _driver_of(case: Preset) -> Driver:
    sense = case.input_sense if case.has_coulomb_friction and not case.motion.omega else 0
    if case.drive_link == 2:
        return Driver("A0", 0.0, case.motion.omega, case.motion.alpha, sense)
    rocker = pose_of(case).links[4]
    # The rocker's sense of a quasi-static motion: the crank's times dθ14/dθ12.
    ratio = float(pose_of(case, omega=1.0, alpha=0.0).links[4].omega[0])
    return Driver("B0", 0.0, float(rocker.omega[0]), float(rocker.alpha[0]),
                  sense * (1 if ratio > 0 else -1))


def _friction_of(case: Preset) -> JointFriction | None:
    f = case.friction
    if f is None:
        return None
    joint_mu = {} if case.geometry.rocker else {"slide": f.slide_coefficient()}
    return JointFriction(mu=f.mu, pin_radius=dict(f.pin_radius), joint_mu=joint_mu,
                         viscous=dict(f.viscous))


#: No prescribed motion: a preset held still.
STILL = Motion()


def preset_case(name: str, geometry: PresetGeometry, theta12: float, branch: str = "",
                ground_angle: float = 0.0, drive_link: int = 2, gravity: Vec2 = (0.0, 0.0),
                loads: tuple[Load, ...] = (), masses: tuple[Mass, ...] = (),
                motion: Motion = STILL, friction: Friction | None = None,
                tolerance: tuple[tuple[str, float, float], ...] = (), source: str = "",
                length_unit: str = "m") -> Case:
    """A four-bar or slider-crank case, its :class:`Preset` drawn as a linkage
    (:func:`drawn_case`). The arguments are the preset's (SI, radians) and the case's."""
    try:
        preset = Preset(geometry, theta12, branch, ground_angle, drive_link, gravity, loads,
                        masses, motion, friction)
    except CaseError as error:
        raise error.located(case=name, file=source) from None
    return drawn_case(preset, name, tolerance=tolerance, source=source, length_unit=length_unit)


def drawn_case(preset: Preset, name: str, *, tolerance: tuple[tuple[str, float, float], ...] = (),
               source: str = "", length_unit: str = "m") -> Case:
    """The case of ``preset``: its linkage drawn at the preset's pose (none where the closed
    form does not assemble there) and read under the preset's names."""
    if not assembles(preset, preset.theta12)[0]:
        return Case(name, None, preset, tolerance, source, length_unit=length_unit)
    return Case(name, linkage_of(preset), preset, tolerance, source, Renaming.of(preset),
                length_unit)


def redrawn(case: Case, **changes: Any) -> Case:
    """``case`` with some of its preset's fields (``theta12``, ``loads``, ``geometry`` as
    link lengths, …) or its own (``name``, ``tolerance``, ``source``) changed, its linkage
    drawn again."""
    own = {k: changes.pop(k) for k in ("name", "tolerance", "source") if k in changes}
    base = case.with_(**own)
    try:
        preset = dataclasses.replace(preset_of(base), **changes)
    except CaseError as error:
        raise error.located(case=base.name, file=base.source) from None
    return drawn_case(preset, base.name, tolerance=base.tolerance, source=base.source,
                      length_unit=base.length_unit)


def as_linkage(case: Case) -> Case:
    """``case`` as a plain linkage case: its results in the linkage's own names."""
    return Case(case.name, case.linkage, tolerance=case.tolerance, source=case.source,
                length_unit=case.length_unit)


@dataclass(frozen=True)
class Renaming:
    """How a linkage solution of the preset ``case`` reads under the preset's names: the
    quantity names, and the pose the linkage is drawn at (θ13, θ14 or s14), which the
    linkage's rotations φ and slide displacement q move."""

    names: dict[str, str]
    coupler: str
    rocker: str
    drawn: dict[str, float]

    @classmethod
    def of(cls, case: Preset) -> Renaming:
        pose = pose_of(case)
        drawn = {"theta13": float(pose.links[3].angle[0])}
        if isinstance(case.geometry, FourBarGeometry):
            drawn["theta14"] = float(pose.links[4].angle[0])
        else:
            drawn["s14"] = float(np.dot(pose.joints["B"][0], (math.cos(case.ground_angle),
                                                              math.sin(case.ground_angle))))
        return cls(names_of(case), f"phi_{link_name(case, 3)}", f"phi_{link_name(case, 4)}",
                   drawn)

    def values(self, values: Mapping[str, float]) -> dict[str, float]:
        return {q: float(v) for q, v in self.columns(values).items()}

    def columns(self, values: Mapping[str, T]) -> dict[str, T]:
        """:meth:`values` of floats or of arrays (a column per quantity, a row per pose)."""
        out = {legacy: values[name] for legacy, name in self.names.items() if name in values}
        moved = {"theta13": self.coupler, "theta14": self.rocker, "s14": "q_slide"}
        for quantity, drawn in self.drawn.items():
            if moved[quantity] in values:
                at = drawn + values[moved[quantity]]
                # wrap_angle: np.remainder is Python's %, bit for bit.
                out[quantity] = at if quantity == "s14" else (at + math.pi) % math.tau - math.pi
        return out

    def solution(self, solution: Solution, name: str) -> Solution:
        """``solution`` under the preset's names, as case ``name``."""
        return dataclasses.replace(solution, case=name, values=self.values(solution.values))

    def solutions(self, solutions: list[Solution], name: str) -> list[Solution]:
        """:meth:`solution` of each; of a sweep's (all ``ok``, the same quantities) at once:
        the quantities renamed as columns, the Solutions made as a batch
        (:meth:`Solution.batch`)."""
        given = tuple(solutions[0].values) if solutions else ()
        if not solutions or any(s.status != "ok" or tuple(s.values) != given
                                for s in solutions):
            return [self.solution(s, name) for s in solutions]
        table = np.array([tuple(s.values.values()) for s in solutions])
        columns = self.columns(dict(zip(given, table.T, strict=True)))
        return Solution.batch(name, solutions[0].backend, tuple(columns),
                              np.column_stack(list(columns.values())).tolist(),
                              (dict(s.diagnostics) for s in solutions), solutions[0].units)


def preset_values(case: Case, values: Mapping[str, float]) -> dict[str, float]:
    """A linkage solution's values under the preset's names (:class:`Renaming`), for the
    linkage drawn at ``case``'s pose."""
    return Renaming.of(preset_of(case)).values(values)


def unassembled_solution(case: Case, theta12: float, backend: str) -> Solution:
    """``backend``'s Solution at a θ12 (rad) where the preset's closed form has no position
    (:func:`~mechcheck.analytic.assembly.unassembled_verdict`)."""
    status, message = unassembled_verdict(case, theta12)
    return Solution(case.name, backend, {}, status=status, message=message,
                    diagnostics={"theta12": theta12})


def solve_preset(case: Case, solve: Callable[[Case], Solution], backend: str) -> Solution:
    """``solve`` (a backend's, on linkages) on the preset ``case``: its linkage drawn at the
    case's pose, read under the preset's names; the preset's verdict where it has no
    position."""
    theta12 = preset_of(case).theta12
    if case.names is None:
        return unassembled_solution(case, theta12, backend)
    solution = case.names.solution(solve(case), case.name)
    if case.linkage.drawn_at_change_point:   # the preset's words for the linkage's verdict
        return dataclasses.replace(solution, message=change_point_message(case, theta12))
    return solution


def driver_offsets(case: Case, theta12: Sequence[float] | np.ndarray) -> np.ndarray:
    """The linkage driver's coordinate (rad from the drawn pose) at each θ12 of a preset
    sweep: θ12 itself for a drive at A0, the rocker's θ14 for a drive at B0."""
    grid = np.asarray(theta12, dtype=float)
    if preset_of(case).drive_link == 2:
        return grid - preset_of(case).theta12
    rocker = pose_of(case, grid).links[4].angle - pose_of(case).links[4].angle[0]
    return np.arctan2(np.sin(rocker), np.cos(rocker))


def branch_side(case: Case, values: Mapping[str, np.ndarray]) -> np.ndarray:
    """Which of its two branches the preset's linkage is on at each pose, from its own points
    (``values``: x_ and y_ of A, B, B0): a four-bar's B lies on one side of the line A→B0 or
    on its mirror image (open or crossed), a slider's B ahead of A along the slide or behind
    it (right or left). Zero where the branches meet."""
    ax, ay, bx, by = values["x_A"], values["y_A"], values["x_B"], values["y_B"]
    p = preset_of(case)
    if isinstance(p.geometry, FourBarGeometry):
        return (values["x_B0"] - ax) * (by - ay) - (values["y_B0"] - ay) * (bx - ax)
    return (bx - ax) * math.cos(p.ground_angle) + (by - ay) * math.sin(p.ground_angle)


def follows_branch(case: Case, results: LinkageResults) -> int:
    """How many poses of a stretch (``results``: its linkage's analysis; the first pose is the
    drawn one, on the preset's branch) stay on that branch and assemble.

    The closed form keeps its branch by definition (``open``/``crossed``, ``right``/``left``),
    also through a change point, where the two branches meet; continuation goes straight on
    and ends on the other one, as it does after poses that do not assemble."""
    side = branch_side(case, results.values)
    off = ~results.pose.assembled | (side * side[0] < 0.0)
    return int(np.argmax(off)) if off.any() else side.size


@dataclass(frozen=True)
class Stretch:
    """A stretch of a preset sweep: the ``case`` drawn at its first pose, its linkage's
    driver values (``offsets``) and the linkage's analysis there (``results``, by the method
    that split the sweep)."""

    case: Case
    offsets: np.ndarray
    results: LinkageResults

    @property
    def names(self) -> Renaming:
        assert self.case.names is not None  # a stretch is drawn: it assembles
        return self.case.names

    def rename(self, solutions: list[Solution]) -> list[Solution]:
        """The linkage's Solutions under the preset's names (:meth:`Renaming.solutions`)."""
        return self.names.solutions(solutions, self.case.name)


def moves_pose_by_pose(case: Case) -> bool:
    """The preset's linkage changes from pose to pose beyond its driver's value: driven on
    the rocker with a motion or Coulomb friction, the rocker's rates (and the sense friction
    opposes) are the crank's times a ratio that varies along the turn."""
    p = preset_of(case)
    return p.drive_link == 4 and (p.is_moving or p.has_coulomb_friction)


def stretches(case: Case, theta12: np.ndarray, backend: str, *, one_by_one: bool,
              results_of: Callable[[Case, np.ndarray], LinkageResults],
              solve: Callable[[Case], Solution]) -> list[Stretch | Solution]:
    """A preset sweep over ``theta12`` (rad), as the linkage engine sees it, in order.

    Poses where the preset has no position get its verdict (:func:`unassembled_solution`). The
    rest run as the linkage's driver sweeps (``results_of``: its analysis at driver values),
    each drawn at its first pose and as long as the linkage stays on the preset's branch
    (:func:`follows_branch`); a pose drawn on a change point, and every pose with
    ``one_by_one`` (or :func:`moves_pose_by_pose`), is drawn and solved on its own
    (``solve``)."""
    out: list[Stretch | Solution] = []
    alone = one_by_one or moves_pose_by_pose(case)
    i = 0
    while i < theta12.size:
        first = redrawn(case, theta12=float(theta12[i]))
        if first.names is None or alone or first.linkage.drawn_at_change_point:
            out.append(solve_preset(first, solve, backend))
            i += 1
            continue
        offsets = driver_offsets(first, theta12[i:])
        results = results_of(first, offsets)
        n = max(1, follows_branch(first, results))
        if n < offsets.size:
            results = stretch_results(first, offsets[:n], results, results_of)
        out.append(Stretch(first, offsets[:n], results))
        i += n
    return out


def stretch_results(linkage: Case, offsets: np.ndarray, longer: LinkageResults,
                    results_of: Callable[[Case, np.ndarray], LinkageResults] = analytic_results
                    ) -> LinkageResults:
    """The analysis of a stretch's ``offsets``, as its own sweep would make it, given that of
    a longer sweep starting with them (``longer``).

    With an Assur plan each pose is placed in closed form and its branch carried from the
    poses before it, so the first poses' results are the same, bit for bit, whatever
    follows (``tests/test_solve_sweep.py``): they are cut from ``longer``. The Newton path's
    rounding at a pose depends on the poses iterated with it: analysed anew."""
    if linkage.linkage.assur_plan is not None:
        return longer.head(offsets.size)
    return results_of(linkage, offsets)


def sweep_preset(case: Case, theta12: np.ndarray, backend: str,
                 sweep: Callable[[Case, np.ndarray, str], list[Solution]],
                 solve: Callable[[Case], Solution], *, one_by_one: bool) -> list[Solution]:
    """A simulator's preset sweep over ``theta12`` (rad): each stretch its linkage sweep
    (``sweep``: case, driver values, backend), each pose read under the preset's names."""
    out: list[Solution] = []
    for item in stretches(case, theta12, backend, one_by_one=one_by_one,
                          results_of=analytic_results, solve=solve):
        if isinstance(item, Solution):
            out.append(item)
        else:
            out += item.rename(sweep(item.case, item.offsets, backend))
    return out


def preset_results(case: Case, theta12: np.ndarray, backend: str,
                   results_of: Callable[[Case, np.ndarray], LinkageResults],
                   solve: Callable[[Case], Solution]) -> DecidedPoses:
    """A vectorised backend's preset sweep over ``theta12`` (rad): :func:`stretches`, each
    stretch's columns renamed and its verdicts decided as the linkage's."""
    columns: list[dict[str, Any]] = []
    statuses, messages, conditions = [], [], []
    for item in stretches(case, theta12, backend, one_by_one=False, results_of=results_of,
                          solve=solve):
        if isinstance(item, Solution):
            columns.append({q: np.array([v]) for q, v in item.values.items()})
            statuses.append(np.array([item.status], dtype=object))
            messages.append(np.array([item.message], dtype=object))
            cond = float(item.diagnostics.get("condition_number", np.nan))
            conditions.append(functools.partial(np.array, [cond]))
            continue
        status, message = pose_verdicts(item.case, item.results)
        columns.append(item.names.columns(item.results.values))
        statuses.append(status)
        messages.append(message)
        conditions.append(functools.partial(getattr, item.results, "condition"))
    names = dict.fromkeys(q for c in columns for q in c)
    sizes = [s.size for s in statuses]
    values = {q: _joined([c[q] if q in c else np.full(n, np.nan)
                          for c, n in zip(columns, sizes, strict=True)], float)
              for q in names}
    return DecidedPoses(values, _joined(statuses, object), _joined(messages, object),
                         lambda: _joined([np.asarray(c(), dtype=float) for c in conditions], float))


def _joined(parts: Sequence[np.ndarray], dtype: type) -> np.ndarray:
    """The stretches' columns end to end (one stretch: its own column, not a copy)."""
    if len(parts) == 1:
        return np.asarray(parts[0], dtype=dtype)
    return np.concatenate(parts) if parts else np.array([], dtype=dtype)
