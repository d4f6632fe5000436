"""One case's analytic statics, against Exudyn (an open multibody code with Lagrange
multipliers) building and solving the same model, one case at a time in one process.

Usage:  python benchmarks/bench_exudyn.py [--repeats 7] [--cpu]

``--cpu`` times with the process's CPU time instead of the wall clock: on a machine shared
with other work, a run of a millisecond or more is often preempted for several (the wall
clock counts that; the CPU time does not), which penalises the longer of two timed calls.

Cases: every built-in linkage case, the four-bar and slider-crank cases as linkages
(:func:`mechcheck.analytic.presets.as_linkage`), and the user mechanisms in
``/work/shared/cases/users`` (Whitworth, toggle press, scissor lift) where present.

Exudyn's model is built at the pose mechcheck solves, taken from mechcheck's own answer
(x_<point>, y_<point>, phi_<link>): each moving link a ``NodeRigidBody2D`` whose reference
is its rigid displacement from the drawn pose (so its local frame is the drawing's), the
revolute joints ``ObjectJointRevolute2D``, the prismatic ones ``ObjectJointPrismatic2D``
with the rotation held. A driven revolute joint adds an ``ObjectConnectorCoordinate`` on
the two links' rotations; a driven prismatic joint becomes a revolute joint at its point
moved by the travel, plus that coordinate constraint, its effort the force along the axis.
Loads are ``LoadForceVector`` / ``LoadTorqueVector``, weights a ``LoadForceVector`` at each
centre of mass; ``SolveStatic`` then gives the multipliers, and the driver's effort is read
from them and compared with mechcheck's ``Q_<joint>``. Cases Exudyn cannot take as plainly
(springs, friction, free coordinates, motion, redundant joints, no forces from mechcheck)
are listed with the reason.

Times per case, median (min, max) of the repeats, in ms: Exudyn's build and static solve;
``mechcheck.solve(case, "analytic")`` on a Linkage built just before the call (nothing it
caches per Linkage is there yet: "first"; what the engine keeps by content rather than per
Linkage, a mechanism's walked path and a matrix's entry places, is there from the calls
before, as in any process that solves one mechanism again) and called again on the same
one ("repeat"), the three timed in turn (:func:`interleaved`); the ratios mechcheck/Exudyn;
last, the median over the cases.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import statistics
import sys
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from functools import partial
from pathlib import Path
from types import ModuleType
from typing import Any

import mechcheck
from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage import Joint, Linkage
from mechcheck.analytic.presets import as_linkage
from mechcheck.analytic.solution import Solution

USER_CASES = Path("/work/shared/cases/users")
USER_FILES = ("whitworth.toml", "toggle_press.toml", "scissor_lift.toml")
GROUND = "ground"
#: The clock every time is read from (``--cpu``: the process's CPU time).
CLOCK: list[Callable[[], float]] = [time.perf_counter]


@dataclass
class Row:
    name: str
    joints: str
    q_mechcheck: float
    q_exudyn: float
    exudyn: list[float]
    first: list[float]
    repeat: list[float]


def import_exudyn() -> tuple[ModuleType, ModuleType]:
    try:
        import exudyn
        import exudyn.itemInterface as items
    except ImportError:
        print("bench_exudyn.py: Exudyn is not installed (it is not a dependency of mechcheck): "
              "pip install exudyn", file=sys.stderr)
        raise SystemExit(2) from None
    return exudyn, items


def all_cases() -> list[Case]:
    """The built-in suite (four-bars and slider-cranks as linkages), then the user files."""
    files = [USER_CASES / name for name in USER_FILES if (USER_CASES / name).is_file()]
    cases = mechcheck.load_cases() + (mechcheck.load_cases(*files) if files else [])
    return [c if c.mechanism == "linkage" else as_linkage(c) for c in cases]


def skip_reason(case: Case, solution: Solution) -> str:
    """Why Exudyn's plain static model is not the same problem, or ""."""
    linkage = case.linkage
    reasons = [
        (solution.status != "ok", f"mechcheck gives no forces ({solution.status})"),
        (bool(linkage.springs), "springs"),
        (linkage.friction is not None and (linkage.has_coulomb_friction or
                                           any(linkage.friction.viscous.values())), "friction"),
        (linkage.is_moving, "moving (inertia forces)"),
        (linkage.dof > len(linkage.drivers), "free coordinates"),
        (linkage.redundant, "redundant joints"),
    ]
    return ", ".join(text for holds, text in reasons if holds)


def link_poses(linkage: Linkage, values: Mapping[str, float]) -> dict[str, tuple[float, float, float]]:
    """Each moving link's rigid displacement (tx, ty, φ) from the drawn pose, from the
    positions and rotations of mechcheck's answer: p = R(φ)·P0 + t at one point it carries."""
    carried = {link.name: link.points[0] for link in linkage.links}
    ox, oy = linkage.offset
    poses = {}
    for name in linkage.moving_links:
        phi = values[f"phi_{name}"]
        point = carried[name]
        x0, y0 = linkage.points[point]
        c, s = math.cos(phi), math.sin(phi)
        px, py = values[f"x_{point}"] - ox, values[f"y_{point}"] - oy
        poses[name] = (px - (c * x0 - s * y0), py - (s * x0 + c * y0), phi)
    return poses


class ExudynModel:
    """The linkage as an Exudyn system at one pose; :meth:`efforts` solves its statics."""

    def __init__(self, exu: ModuleType, items: ModuleType, linkage: Linkage,
                 values: Mapping[str, float]) -> None:
        self.exu, self.items, self.linkage = exu, items, linkage
        self.system = exu.SystemContainer()
        self.mbs = self.system.AddSystem()
        it = items
        self.bodies = {GROUND: self.mbs.AddObject(it.ObjectGround())}
        ground_node = self.mbs.AddNode(it.NodePointGround())
        self.rotations = {GROUND: self.mbs.AddMarker(it.MarkerNodeCoordinate(nodeNumber=ground_node,
                                                                             coordinate=0))}
        self.phi = {GROUND: 0.0}
        for name, (tx, ty, phi) in link_poses(linkage, values).items():
            node = self.mbs.AddNode(it.NodeRigidBody2D(referenceCoordinates=[tx, ty, phi]))
            # Mass and inertia do not enter statics; the weights are loads (add_loads).
            self.bodies[name] = self.mbs.AddObject(it.ObjectRigidBody2D(nodeNumber=node, mass=1.0,
                                                                        inertia=1.0))
            self.rotations[name] = self.mbs.AddMarker(it.MarkerNodeCoordinate(nodeNumber=node,
                                                                              coordinate=2))
            self.phi[name] = phi
        driven = {d.joint: d for d in linkage.drivers}
        self.drivers: dict[str, tuple[Any, Joint]] = {}
        for joint in linkage.joints:
            self.add_joint(joint, joint.name in driven, values.get(f"q_{joint.name}", 0.0))
        self.add_loads()

    def marker(self, link: str, at: tuple[float, float], rigid: bool = False) -> Any:
        kind = self.items.MarkerBodyRigid if rigid else self.items.MarkerBodyPosition
        return self.mbs.AddMarker(kind(bodyNumber=self.bodies[link], localPosition=[at[0], at[1], 0.0]))

    def add_joint(self, joint: Joint, driven: bool, travel: float) -> None:
        it, (first, second) = self.items, joint.links
        x, y = self.linkage.points[joint.at]
        if joint.kind.name == "revolute":
            pin = [self.marker(first, (x, y)), self.marker(second, (x, y))]
            self.mbs.AddObject(it.ObjectJointRevolute2D(markerNumbers=pin))
            if driven:
                self.drivers[joint.name] = (self.hold_rotation(first, second), joint)
            return
        ux, uy = joint.axis or (1.0, 0.0)
        if driven:
            # The slide held at its travel: the point, moved along the axis on links[0],
            # pinned to links[1], and the rotation held; the pin's force along the axis is
            # the driver's effort.
            pin = [self.marker(first, (x + travel * ux, y + travel * uy)), self.marker(second, (x, y))]
            force = self.mbs.AddObject(it.ObjectJointRevolute2D(markerNumbers=pin))
            self.hold_rotation(first, second)
            self.drivers[joint.name] = (force, joint)
            return
        slide = [self.marker(first, (x, y), rigid=True), self.marker(second, (x, y), rigid=True)]
        self.mbs.AddObject(it.ObjectJointPrismatic2D(markerNumbers=slide, axisMarker0=[ux, uy, 0.0],
                                                     normalMarker1=[-uy, ux, 0.0],
                                                     constrainRotation=True))

    def hold_rotation(self, first: str, second: str) -> Any:
        """φ(second) − φ(first) held at its value: the coordinates are displacements from
        the reference pose, so both are zero there. Exudyn's multiplier is the couple on
        the second marker's body."""
        markers = [self.rotations[first], self.rotations[second]]
        return self.mbs.AddObject(self.items.ObjectConnectorCoordinate(markerNumbers=markers))

    def add_loads(self) -> None:
        it = self.items
        gx, gy = self.linkage.gravity
        for load in self.linkage.loads:
            if load.link == GROUND:
                continue
            if load.force != (0.0, 0.0):
                self.mbs.AddLoad(it.LoadForceVector(markerNumber=self.marker(load.link, load.at),
                                                    loadVector=[load.force[0], load.force[1], 0.0]))
            if load.torque:
                self.mbs.AddLoad(it.LoadTorqueVector(markerNumber=self.marker(load.link, load.at, True),
                                                     loadVector=[0.0, 0.0, load.torque]))
        for mass in self.linkage.masses:
            if mass.link != GROUND and (gx or gy):
                self.mbs.AddLoad(it.LoadForceVector(markerNumber=self.marker(mass.link, mass.com),
                                                    loadVector=[mass.mass * gx, mass.mass * gy, 0.0]))

    def efforts(self) -> dict[str, float]:
        """Static solve; each driver's effort on links[1] by links[0] (N·m or N)."""
        exu = self.exu
        self.mbs.Assemble()
        settings = exu.SimulationSettings()
        settings.solution.file.write = False
        settings.staticSolver.verboseMode = 0
        if not self.mbs.SolveStatic(settings, storeSolver=False):
            raise RuntimeError("Exudyn's static solver did not converge")
        out = {}
        for name, (item, joint) in self.drivers.items():
            value = self.mbs.GetObjectOutput(item, exu.OutputVariableType.Force)
            if joint.kind.name == "revolute":
                out[name] = float(value)
            else:
                ux, uy = joint.axis or (1.0, 0.0)
                phi = self.phi[joint.links[0]]
                c, s = math.cos(phi), math.sin(phi)
                out[name] = float(value[0] * (c * ux - s * uy) + value[1] * (s * ux + c * uy))
        return out


def exudyn_effort(exu: ModuleType, items: ModuleType, case: Case, values: Mapping[str, float]) -> float:
    """Build and solve the Exudyn model; the first driver's effort."""
    model = ExudynModel(exu, items, case.linkage, values)
    return model.efforts()[case.linkage.drivers[0].joint]


def fresh(case: Case) -> Case:
    """The same Case on a Linkage built anew: none of its per-Linkage caches filled."""
    return Case(name=case.name, geometry=replace(case.linkage),
                tolerance=case.tolerance, source=case.source)


def clocked(fn: Callable[[], object]) -> float:
    clock = CLOCK[0]
    start = clock()
    fn()
    return clock() - start


def interleaved(exudyn_run: Callable[[], object], case: Case,
                repeats: int) -> tuple[list[float], list[float], list[float]]:
    """Exudyn's build and solve, mechcheck's first call on a new Linkage (built and checked
    outside the timer) and its next call on the same one, timed in turn ``repeats`` times:
    a burst of other work on a shared machine lengthens all three alike, so their ratios
    hold where their times do not. Exudyn runs once untimed just before its timed run, so
    that it is timed as warm as mechcheck's next call."""
    exudyn, first, repeat = [], [], []
    for _ in range(repeats):
        exudyn_run()
        exudyn.append(clocked(exudyn_run))
        solve = partial(mechcheck.solve, fresh(case), "analytic")
        first.append(clocked(solve))
        repeat.append(clocked(solve))
    return exudyn, first, repeat


def spread(times: list[float]) -> str:
    ms = [1e3 * t for t in times]
    return f"{statistics.median(ms):.3g} ({min(ms):.3g}–{max(ms):.3g})"


def joint_kinds(linkage: Linkage) -> str:
    kinds = [j.kind.name for j in linkage.joints]
    return f"{kinds.count('revolute')}R {kinds.count('prismatic')}P"


def measure(exu: ModuleType, items: ModuleType, case: Case, repeats: int) -> Row | str:
    """One case compared and timed, or the reason it is skipped."""
    solution = mechcheck.solve(case, "analytic")
    reason = skip_reason(case, solution)
    if reason:
        return reason
    joint = case.linkage.drivers[0].joint
    effort = exudyn_effort(exu, items, case, solution.values)
    exudyn, first, repeat = interleaved(
        lambda: exudyn_effort(exu, items, case, solution.values), case, repeats)
    return Row(case.name, joint_kinds(case.linkage), solution.values[f"Q_{joint}"], effort,
               exudyn=exudyn, first=first, repeat=repeat)


def relative(a: float, b: float) -> float:
    return abs(a - b) / max(abs(a), abs(b), 1e-300)


def print_table(rows: list[Row]) -> None:
    print("| case | joints | Q mechcheck | Q Exudyn | rel. diff | Exudyn build+solve ms | "
          "mechcheck first ms | mechcheck repeat ms | first/Exudyn | repeat/Exudyn |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        exu, first, rep = (statistics.median(t) for t in (r.exudyn, r.first, r.repeat))
        print(f"| {r.name} | {r.joints} | {r.q_mechcheck:.6g} | {r.q_exudyn:.6g} | "
              f"{relative(r.q_mechcheck, r.q_exudyn):.1e} | {spread(r.exudyn)} | {spread(r.first)} | "
              f"{spread(r.repeat)} | {first / exu:.3f} | {rep / exu:.3f} |")

    def over(key: Callable[[Row], float]) -> float:
        return statistics.median(key(r) for r in rows)

    med = statistics.median
    print(f"| **median of {len(rows)} cases** | | | | "
          f"{over(lambda r: relative(r.q_mechcheck, r.q_exudyn)):.1e} | "
          f"{1e3 * over(lambda r: med(r.exudyn)):.3g} | {1e3 * over(lambda r: med(r.first)):.3g} | "
          f"{1e3 * over(lambda r: med(r.repeat)):.3g} | "
          f"{over(lambda r: med(r.first) / med(r.exudyn)):.3f} | "
          f"{over(lambda r: med(r.repeat) / med(r.exudyn)):.3f} |")
    worst = max(rows, key=lambda r: relative(r.q_mechcheck, r.q_exudyn))
    print(f"\nlargest relative difference: {relative(worst.q_mechcheck, worst.q_exudyn):.1e} "
          f"({worst.name})")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--cpu", action="store_true",
                        help="time with the process's CPU time (a shared machine's other load "
                             "does not count), not the wall clock")
    args = parser.parse_args()
    if args.cpu:
        CLOCK[0] = time.process_time
    if args.repeats < 1:
        parser.error("--repeats must be at least 1")
    exu, items = import_exudyn()
    print(f"machine: {platform.machine()}, {os.cpu_count()} cores, Python "
          f"{platform.python_version()}, Exudyn {exu.__version__}; {args.repeats} repeats, "
          f"{'CPU time' if args.cpu else 'wall clock'}\n")
    rows, skipped = [], []
    for case in all_cases():
        found = measure(exu, items, case, args.repeats)
        if isinstance(found, Row):
            rows.append(found)
        else:
            skipped.append((case.name, found))
    print_table(rows)
    print("\nskipped:")
    for name, reason in skipped:
        print(f"- {name}: {reason}")


if __name__ == "__main__":
    main()
