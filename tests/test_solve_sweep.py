"""``mujoco_solve`` over a sweep (issue 13): the batch is the pose-by-pose solve, the model
kept for the next sweep carries nothing over, and the preset path's shortcuts (the branch
check on the sweep's own analysis, renaming as columns, Solutions made as a batch) give what
the one-by-one path gives; a stretch's analysis cut from a longer one is its own.

Expected values come from another path doing the same work (the pose-by-pose solve, the
generic engine's continuation, one Solution at a time): identities, judged exactly or
by the one tolerance policy (:func:`mechcheck.testing.assert_solution_close`, the exact
solve's 1e-9).
"""

from __future__ import annotations

import math
from types import MappingProxyType

import numpy as np
import pytest

from mechcheck.analytic.case import Case
from mechcheck.analytic.kinematics import pose_of
from mechcheck.analytic.linkage_backends import analytic_results
from mechcheck.analytic.linkage_forces import coulomb_terms
from mechcheck.analytic.linkage_kinematics import LinkagePose, solve_pose
from mechcheck.analytic.presets import (
    Renaming,
    as_linkage,
    driver_offsets,
    follows_branch,
    redrawn,
    stretch_results,
)
from mechcheck.analytic.solution import Solution
from mechcheck.sim_models.mujoco.linkage import (
    solve_linkage_at_pose,
    sweep_linkage,
    sweep_rig,
    unbuildable,
)
from mechcheck.testing import assert_solution_close

from .builtin import builtin_cases


def linkage_cases() -> dict[str, Case]:
    return {n: c for n, c in builtin_cases().items() if c.mechanism == "linkage"}


def exact_sweepable(case: Case) -> bool:
    """A linkage the batch solves: buildable, driven, without Coulomb friction, with forces
    at its drawn pose."""
    return (bool(case.linkage.drivers) and unbuildable(case) is None
            and not case.has_coulomb_friction and not analytic_results(case).withheld[0])


def around(case: Case) -> np.ndarray:
    """The first driver at its value and a little either side (rad, or m)."""
    driver = case.linkage.drivers[0]
    revolute = case.linkage.joint(driver.joint).kind == "revolute"
    step = 0.01 if revolute else 0.01 * case.linkage.scale
    return driver.value + np.array([-step, 0.0, step])


@pytest.mark.parametrize("name", sorted(n for n, c in linkage_cases().items()
                                        if exact_sweepable(c)))
def test_the_batch_is_the_pose_by_pose_solve(name: str) -> None:
    """Every built-in linkage the batch solves: each pose of the batch agrees with the exact
    solve of that pose alone (its own forward pass and solve), every quantity, within the
    policy's tolerance for the exact solve."""
    case = linkage_cases()[name]
    first = around(case)
    # Only poses with forces, as the pose gate lets through (:func:`mechcheck.sweep.gated_poses`).
    first = first[~analytic_results(case, first).withheld]
    results = analytic_results(case, first)
    batch = sweep_linkage(case, first, "mujoco_solve", results)
    assert len(batch) == first.size
    for i, solved in enumerate(batch):
        assert_solution_close(case, solved, solve_linkage_at_pose(case, results=results, index=i),
                              complete=True)


def test_a_kept_model_carries_nothing_into_the_next_sweep() -> None:
    """The Watt six-bar swept twice with its model kept, then with it built anew: the same
    numbers and diagnostics (but the wall time), and the drivers' targets left at the last
    pose's, as set pose by pose."""
    case = linkage_cases()["watt-ii-demo"]
    assert not coulomb_terms(analytic_results(case).pose)
    first = np.radians(np.linspace(-20.0, 20.0, 9))
    results = analytic_results(case, first)
    sweep_rig.cache_clear()
    runs = [sweep_linkage(case, first, "mujoco_solve", results) for _ in range(2)]
    assert sweep_rig.cache_info().hits == 1
    sweep_rig.cache_clear()
    runs.append(sweep_linkage(case, first, "mujoco_solve", results))

    def without_time(s: Solution) -> tuple[dict[str, float], dict[str, object]]:
        return dict(s.values), {k: v for k, v in s.diagnostics.items() if k != "wall_time_s"}

    assert [without_time(s) for s in runs[1]] == [without_time(s) for s in runs[0]]
    assert [without_time(s) for s in runs[2]] == [without_time(s) for s in runs[0]]
    rig = sweep_rig(case)
    assert rig.model.eq_data[rig.driver_eqs, 0].tolist() == results.pose.drivers[-1].tolist()


def test_batch_solutions_are_made_as_one_by_one() -> None:
    """Solution.batch: equal to Solutions made one at a time, read-only, and refusing a name
    that is no quantity, as one by one."""
    names = ("F_A_x", "F_A_y", "phi_crank")
    units = {"F_A_x": "N", "F_A_y": "N", "phi_crank": "deg"}
    rows = [(1.0, 2.0, 0.5), (3.0, -4.0, 0.25)]
    diagnostics = [{"loop_violation": 0.0}, {"loop_violation": 1e-17}]
    batch = Solution.batch("c", "mujoco_solve", names, rows,
                           (dict(d) for d in diagnostics), units)
    one_by_one = [Solution("c", "mujoco_solve", dict(zip(names, r, strict=True)),
                           diagnostics=d, units=units) for r, d in zip(rows, diagnostics,
                                                                       strict=True)]
    assert batch == one_by_one
    assert all(isinstance(getattr(s, f), MappingProxyType) for s in batch
               for f in ("values", "diagnostics", "units"))
    with pytest.raises(TypeError):
        batch[0].values["F_A_x"] = 0.0  # type: ignore[index]
    with pytest.raises(ValueError, match="unknown quantities"):
        Solution.batch("c", "mujoco_solve", ("F_A_x", "bogus"), [(1.0, 2.0)], [{}], units)


def preset_stretches() -> list[tuple[Case, np.ndarray]]:
    """Seed E1 from 1° over a whole turn (its linkage leaves the preset's branch at the
    change point) and every built-in slider-crank swept as held statics (the others are
    driven pose by pose), each from its own pose."""
    cases = builtin_cases()
    e1 = cases["seed-E1-as-stated"]
    grid = np.radians(np.arange(1.0, 360.0))
    out = [(redrawn(e1, theta12=float(grid[0])), grid)]
    out += [(c, c.preset.theta12 + np.radians(np.arange(0.0, 360.0, 3.0)))
            for c in cases.values() if c.mechanism == "slider_crank" and c.kind == "static"]
    return out


def closed_form_branch_end(case: Case, grid: np.ndarray, pose: LinkagePose) -> int:
    """The first pose where the linkage's continued angles (or slide) leave the preset's
    closed-form ones by more than 1e-6 (rad, or per unit of size): both are exact, so on the
    same branch they agree to rounding, and on the other one differ by a finite amount."""
    closed = pose_of(case, grid)
    gap = np.zeros(grid.size)
    links = {3: "coupler", 4: "rocker"} if case.mechanism == "four_bar" else {3: "coupler"}
    for link, name in links.items():
        turned = closed.links[link].angle - closed.links[link].angle[0]
        gap = np.maximum(gap, np.abs(np.sin(0.5 * (turned - pose.angle(name)[0]))))
    if case.mechanism == "slider_crank":
        u = np.array([math.cos(case.preset.ground_angle), math.sin(case.preset.ground_angle)])
        s14 = closed.joints["B"] @ u
        slide = pose.joint_coordinate(pose.linkage.joint("slide"))[0]
        gap = np.maximum(gap, np.abs(s14 - s14[0] - slide) / pose.linkage.scale)
    off = np.flatnonzero(~(gap <= 1e-6))
    return int(off[0]) if off.size else grid.size


@pytest.mark.parametrize("index", range(len(preset_stretches())))
def test_the_branch_ends_where_the_closed_form_leaves_it(index: int) -> None:
    """follows_branch (which side of the line A→B0 B is on, or of A along the slide, from the
    linkage's own points) ends a stretch where its continuation leaves the preset's closed-form
    branch, by the Assur path and by Newton's continuation
    (:func:`mechcheck.analytic.linkage_kinematics.solve_pose`); seed E1 leaves it at its
    change point, half a turn on."""
    case, grid = preset_stretches()[index]
    offsets = driver_offsets(case, grid)
    linkage = as_linkage(case)
    results = analytic_results(linkage, offsets)
    end = follows_branch(case, results)
    assert end == closed_form_branch_end(case, grid, results.pose)
    assert end == closed_form_branch_end(case, grid, solve_pose(linkage.linkage, offsets[:, None]))
    if index == 0:
        assert 0 < end < grid.size


@pytest.mark.parametrize("index", range(len(preset_stretches())))
def test_a_renamed_sweep_is_each_solution_renamed(index: int) -> None:
    """Renaming.solutions (columns, one batch) equals Renaming.solution of each, exactly."""
    case, grid = preset_stretches()[index]
    linkage = as_linkage(case)
    offsets = driver_offsets(case, grid)
    n = max(1, follows_branch(case, analytic_results(linkage, offsets)))
    solutions = sweep_linkage(linkage, offsets[:n], "mujoco_solve")
    renaming = Renaming.of(case.preset)
    assert renaming.solutions(solutions, case.name) == [renaming.solution(s, case.name)
                                                        for s in solutions]


@pytest.mark.parametrize("index", range(len(preset_stretches())))
def test_a_cut_stretch_is_analysed_as_its_own_sweep(index: int) -> None:
    """stretch_results: a stretch's analysis, cut from a longer one with an Assur plan or
    made anew without, is the stretch's own analysis, bit for bit (cut at the branch's
    end, or halfway where the preset's branch never ends)."""
    case, grid = preset_stretches()[index]
    linkage = as_linkage(case)
    offsets = driver_offsets(case, grid)
    longer = analytic_results(linkage, offsets)
    n = follows_branch(case, longer)
    n = n if n < grid.size else grid.size // 2
    cut, own = stretch_results(linkage, offsets[:n], longer), analytic_results(linkage, offsets[:n])
    assert cut.values.keys() == own.values.keys()
    for name, column in own.values.items():
        np.testing.assert_array_equal(cut.values[name], column, err_msg=name, strict=True)
    for field in ("drivers", "q", "qdot", "qddot", "locked_at"):
        np.testing.assert_array_equal(getattr(cut.pose, field), getattr(own.pose, field),
                                      err_msg=field, strict=True)
    for field in ("condition", "ill_conditioned", "converged", "reversing"):
        np.testing.assert_array_equal(getattr(cut, field), getattr(own, field), err_msg=field,
                                      strict=True)
    assert (cut.stable is None) == (own.stable is None)
