"""The four-bar and the slider-crank in the simulators: each is built, held, driven and swept
as its linkage (:func:`mechcheck.analytic.presets.linkage_of`, LINKAGES.md "The four-bar and
slider-crank as linkages"), through the same builders as any linkage, and its numbers are
renamed back to the contract's names (CONVENTIONS.md: ``F12`` … ``F14``, ``T12`` or ``T14``,
``M14``, ``theta13``, ``theta14``, ``s14``).

There is no four-bar or slider-crank model of its own in either simulator: what a preset
adds is only this translation, in both directions.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TypeVar

import numpy as np

from mechcheck.analytic.case import Case, Load
from mechcheck.analytic.forces import solve_poses, verdict_at
from mechcheck.analytic.kinematics import pose_of
from mechcheck.analytic.linkage_backends import analytic_results
from mechcheck.analytic.linkage_forces import LinkageResults
from mechcheck.analytic.linkage_kinematics import LinkagePose
from mechcheck.analytic.presets import link_name, linkage_of, names_of
from mechcheck.analytic.solution import Solution

#: A value or a column of values (:meth:`Renaming.columns`).
T = TypeVar("T", float, np.ndarray)


def as_linkage(case: Case) -> Case:
    """The preset ``case`` as a ``mechanism = "linkage"`` case drawn at its pose; the last
    few are kept (:func:`kept_linkage`), as every backend of a sweep translates the same
    stretches again and building a Linkage checks it whole (0.5 ms for a four-bar)."""
    try:
        return kept_linkage(case)
    except TypeError:  # should a Case ever hold an unhashable value: translated each time
        return translated(case)


def translated(case: Case) -> Case:
    """:func:`as_linkage`, built anew."""
    return Case(name=case.name, geometry=linkage_of(case), theta12=0.0,
                tolerance=case.tolerance, source=case.source)


#: :func:`translated`, kept for the same Case (immutable, and so is its translation).
kept_linkage = functools.lru_cache(maxsize=16)(translated)


@dataclass(frozen=True)
class Renaming:
    """How a linkage solution of the preset ``case`` reads under the preset's names: the
    quantity names, and the pose the linkage is drawn at (θ13, θ14 or s14), which the
    simulator's rotations φ and slide displacement q move."""

    names: dict[str, str]
    coupler: str
    rocker: str
    drawn: dict[str, float]

    @classmethod
    def of(cls, case: Case) -> Renaming:
        pose = pose_of(case)
        drawn = {"theta13": float(pose.links[3].angle[0])}
        if case.mechanism == "four_bar":
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
    return Renaming.of(case).values(values)


def through_linkage(case: Case, solve: Callable[[Case], Solution], backend: str = "") -> Solution:
    """``solve`` (a linkage backend) run on the preset ``case``, read under its names; the
    preset's own verdict instead where it has one (:func:`verdicts`: ``backend`` names it)."""
    verdict = verdicts(case, np.array([case.theta12]), backend)[0] if backend else None
    return verdict or Renaming.of(case).solution(solve(as_linkage(case)), case.name)


def driver_offsets(case: Case, theta12: Sequence[float] | np.ndarray) -> np.ndarray:
    """The linkage driver's coordinate (rad from the drawn pose) at each θ12 of a preset
    sweep: θ12 itself for a drive at A0, the rocker's θ14 for a drive at B0."""
    grid = np.asarray(theta12, dtype=float)
    if case.drive_link == 2:
        return grid - case.theta12
    rocker = pose_of(case, grid).links[4].angle - pose_of(case).links[4].angle[0]
    return np.arctan2(np.sin(rocker), np.cos(rocker))


#: rad (or m per unit of the mechanism's size): the linkage's continued pose and the preset's
#: closed form are the same branch when they agree this closely (both are exact: they agree
#: to rounding on the same branch, and differ by a finite angle on another).
SAME_BRANCH = 1e-6


def follows_branch(case: Case, theta12: np.ndarray, pose: LinkagePose) -> int:
    """How many poses of ``theta12`` (the first is ``case``'s own) the linkage drawn at the
    first one reaches on the preset's branch, by continuation from its drawn pose
    (``pose``: the linkage's pose analysis at those poses, the one its sweep runs at).

    The closed form keeps its branch by definition (``open``/``crossed``, ``right``/``left``),
    also through a change point, where the two branches meet; continuation goes straight on
    and ends on the other one, as it does after poses that do not assemble."""
    closed = pose_of(case, theta12)
    phi = {3: link_name(case, 3), 4: link_name(case, 4)}
    gap = np.zeros(theta12.size)
    for link in (3, 4) if case.mechanism == "four_bar" else (3,):
        turned = closed.links[link].angle - closed.links[link].angle[0]
        gap = np.maximum(gap, np.abs(np.sin(0.5 * (turned - pose.angle(phi[link])[0]))))
    if case.mechanism == "slider_crank":
        u = np.array([math.cos(case.ground_angle), math.sin(case.ground_angle)])
        s14 = closed.joints["B"] @ u
        slide = pose.joint_coordinate(pose.linkage.joint("slide"))[0]
        gap = np.maximum(gap, np.abs(s14 - s14[0] - slide) / pose.linkage.scale)
    off = np.flatnonzero(~(gap <= SAME_BRANCH))
    return int(off[0]) if off.size else theta12.size


def verdicts(case: Case, theta12: np.ndarray, backend: str) -> list[Solution | None]:
    """The preset's own verdict at each pose (does not assemble, singular, friction
    reversing or self-locking: :func:`mechcheck.analytic.forces.verdict_at`) as ``backend``'s
    Solution, None where it has forces. A linkage drawn at such a pose is degenerate (at a
    change point its pins are collinear and its constraints redundant), so none is built."""
    results = solve_poses(case, theta12)
    # verdict_at's tests at every pose at once: it is asked only where one holds.
    flagged = ~results.assembled | results.singular | results.indeterminate | ~results.converged
    out: list[Solution | None] = [None] * len(theta12)
    for i in np.flatnonzero(flagged).tolist():
        verdict = verdict_at(case, results, i)
        out[i] = None if verdict is None else Solution(
            case.name, backend, {}, status=verdict.status, message=verdict.message,
            diagnostics={"condition_number": verdict.condition, "theta12": float(theta12[i])})
    return out


@dataclass(frozen=True)
class Stretch:
    """A stretch of a preset sweep, for a linkage backend's sweep: the ``linkage`` drawn at
    its first pose, the driver's values (``offsets``) and their analytic pose analysis
    (``results``), and how its Solutions read under the preset's names, as case ``name``."""

    linkage: Case
    offsets: np.ndarray
    results: LinkageResults
    renaming: Renaming
    name: str

    def rename(self, solutions: list[Solution]) -> list[Solution]:
        """The linkage's Solutions under the preset's names (:meth:`Renaming.solutions`)."""
        return self.renaming.solutions(solutions, self.name)


def sweep_through_linkage(case: Case, theta12: Sequence[float] | np.ndarray, backend: str,
                          sweep: Callable[[Stretch], list[Solution]],
                          solve: Callable[[Case], Solution]) -> list[Solution]:
    """A preset θ12 sweep through a linkage backend, each pose read under the preset's
    names.

    Poses with a verdict of their own get it (:func:`verdicts`). Held statics run as the
    linkage's driver sweep (``sweep``: a :class:`Stretch`, its analytic pose analysis done
    once here, to its Solutions under the preset's names; continuation from pose to pose),
    in stretches on the preset's branch (:func:`follows_branch`) between verdicts, each
    drawn at its first pose. A moving or friction case is driven pose by pose (``solve``):
    with a drive on the rocker, each pose has its own rocker rates."""
    grid = np.asarray(theta12, dtype=float)

    def pose(i: int) -> Case:
        return dataclasses.replace(case, theta12=float(grid[i]))

    given = verdicts(case, grid, backend)
    out: list[Solution] = []
    i = 0
    while i < grid.size:
        verdict = given[i]
        if verdict is not None or through_drive(case):
            out.append(verdict or through_linkage(pose(i), solve))
            i += 1
            continue
        stop = i + 1
        while stop < grid.size and given[stop] is None:
            stop += 1
        first = pose(i)
        linkage = as_linkage(first)
        offsets = driver_offsets(first, grid[i:stop])
        results = analytic_results(linkage, offsets)
        n = max(1, follows_branch(first, grid[i:stop], results.pose))
        if n < offsets.size:
            results = stretch_results(linkage, offsets[:n], results)
        out += sweep(Stretch(linkage, offsets[:n], results, Renaming.of(first), case.name))
        i += n
    return out


def stretch_results(linkage: Case, offsets: np.ndarray, longer: LinkageResults) -> LinkageResults:
    """The analysis of a stretch's ``offsets``, as its own sweep would make it, given that of
    a longer sweep starting with them (``longer``).

    With an Assur plan each pose is placed in closed form and its branch carried from the
    poses before it, so the first poses' results are the same, bit for bit, whatever
    follows (``tests/test_solve_sweep.py``): they are cut from ``longer``. The Newton path's
    rounding at a pose depends on the poses iterated with it: analysed anew."""
    if linkage.linkage.assur_plan is not None:
        return longer.head(offsets.size)
    return analytic_results(linkage, offsets)


def through_drive(case: Case) -> bool:
    """The simulators drive the case (it moves, or has Coulomb friction)."""
    return not case.motion.is_static or case.has_coulomb_friction


def output_load(case: Case, load: float) -> Load:
    """The output load of the turning experiments' holding runs: a pure couple ``load`` on
    the rocker, or a force ``load`` on the slider along the slide direction u through B (no
    moment)."""
    if case.mechanism == "four_bar":
        return Load(4, at=(0.0, 0.0), force=(0.0, 0.0), torque=load)
    g = case.ground_angle
    return Load(4, at=(0.0, 0.0), force=(load * math.cos(g), load * math.sin(g)))
