"""Where a linkage is drawn, how it is turned and how large it is change nothing but the
coordinates: the forces (turned with the drawing), the verdicts and the condition numbers
of the pose analysis are the same to rounding (statics is invariant under rigid motions and,
with moments scaled with the lengths, under a change of length unit)."""

from __future__ import annotations

import copy
import math
from typing import Any

import pytest
from hypothesis import HealthCheck, given, reject, settings, strategies as st

from mechcheck import CaseError, solve
from mechcheck.casefile import parse_cases
from tests.chains import four_bar_chain
from tests.strategies import linkage_tables

SETTINGS = settings(max_examples=40, deadline=None,
                    suppress_health_check=[HealthCheck.filter_too_much, HealthCheck.too_slow])
#: The analytic family's tolerance (compare/tolerance.py: the same equations, only rounding
#: separates them), plus the rounding of the drawing's own coordinates, which a drawing far
#: from the origin carries into every length: eps × (distance / size), amplified by the
#: condition number (Higham, Accuracy and Stability of Numerical Algorithms, §7.1).
BASE_RTOL = 1e-9
EPS = 2.2e-16


def transformed(table: dict[str, Any], offset: tuple[float, float], angle: float,
                scale: float) -> dict[str, Any]:
    """The case table drawn ``scale`` times as large, turned by ``angle`` about the origin and
    moved by ``offset`` (m), with every load carried along: forces turned, moments (torques,
    torsional stiffness) times ``scale``, linear stiffness and damping divided by it."""
    c, s = math.cos(angle), math.sin(angle)

    def turn(v: list[float]) -> list[float]:
        return [c * v[0] - s * v[1], s * v[0] + c * v[1]]

    def place(p: Any) -> Any:
        if isinstance(p, str):
            return p
        x, y = turn([scale * p[0], scale * p[1]])
        return [x + offset[0], y + offset[1]]

    out = copy.deepcopy(table)
    out["points"] = {n: place(p) for n, p in table["points"].items()}
    out["gravity"] = turn(table.get("gravity", [0.0, 0.0]))
    for joint in out["joints"]:
        if "axis" in joint:
            joint["axis"] = turn(joint["axis"])
    for load in out.get("loads", []):
        load["at"] = place(load["at"])
        if "force" in load:
            f = load["force"]
            load["force"] = dict(zip("xy", turn([f["x"], f["y"]]), strict=True))
        load["torque"] = load.get("torque", 0.0) * scale
    for mass in out.get("masses", []):
        mass["com"] = place(mass["com"])
        mass["inertia"] = mass.get("inertia", 0.0) * scale**2
    for spring in out.get("springs", []):
        if "ends" in spring:
            spring["ends"] = [[link, place(p)] for link, p in spring["ends"]]
            spring["stiffness"] /= scale
            spring["free_length"] *= scale
            spring["damping"] = spring.get("damping", 0.0) / scale
        else:
            spring["stiffness"] *= scale
            spring["damping"] = spring.get("damping", 0.0) * scale
    friction = out.get("friction")
    if friction:
        friction["pin_radius"] = {k: v * scale for k, v in friction.get("pin_radius", {}).items()}
    return out


def solved(table: dict[str, Any]) -> Any:
    case = parse_cases({"case": [table]}, "transformed.toml")[0][0]
    return case, solve(case)


def expected_value(name: str, unit: str, original: dict[str, float], offset: tuple[float, float],
                   angle: float, scale: float) -> float:
    """What quantity ``name`` (in SI, table unit ``unit``) of the original drawing becomes in
    the transformed one: points and joint forces turned (points scaled and moved too),
    moments and lengths times the scale, angles and scalar forces unchanged."""
    c, s = math.cos(angle), math.sin(angle)
    value = original[name]
    if name.startswith(("x_", "y_")):
        x, y = scale * original[f"x_{name[2:]}"], scale * original[f"y_{name[2:]}"]
        return c * x - s * y + offset[0] if name[0] == "x" else s * x + c * y + offset[1]
    if name.startswith("F_"):
        fx, fy = original[f"{name[:-2]}_x"], original[f"{name[:-2]}_y"]
        return c * fx - s * fy if name.endswith("_x") else s * fx + c * fy
    return value * scale if unit in ("N*m", "m") else value


def assert_same(original: Any, moved: Any, case: Any, offset: tuple[float, float], angle: float,
                scale: float) -> None:
    """The moved solution is the original's, transformed, to the tolerance above."""
    assert moved.status == original.status, (original.message, moved.message)
    cond = float(original.diagnostics["condition_number"])
    size = case.linkage.scale
    distance = math.hypot(*offset)
    rtol = BASE_RTOL + 16 * EPS * (distance / (scale * size) + 1.0) * max(cond, 1.0)
    if math.isfinite(cond):
        assert float(moved.diagnostics["condition_number"]) == pytest.approx(cond, rel=rtol)
    forces = max((abs(v) for q, v in original.values.items() if q.startswith(("F_", "S_"))),
                 default=0.0) or 1.0
    assert set(moved.values) == set(original.values)
    for name in original.values:
        unit = moved.units[name]
        want = expected_value(name, unit, dict(original.values), offset, angle, scale)
        got = moved.values[name]
        if unit == "deg":        # SI: radians, compared modulo a turn
            assert abs(math.remainder(got - want, math.tau)) <= rtol, (name, got, want)
        elif unit == "m":
            assert abs(got - want) <= rtol * scale * size + 8 * EPS * distance, (name, got, want)
        elif unit == "N*m":
            assert abs(got - want) <= rtol * forces * size * scale, (name, got, want)
        else:
            assert abs(got - want) <= rtol * forces, (name, got, want)


@SETTINGS
@given(table=linkage_tables(friction=False), data=st.data())
def test_moving_and_turning_the_drawing_changes_only_the_coordinates(table: dict[str, Any],
                                                                      data: st.DataObject) -> None:
    """A random linkage moved up to 10⁶ times its size and turned by any angle, loads carried
    along: the same verdict, condition number and forces (turned), to rounding."""
    case, original = solved(table)
    reach = data.draw(st.sampled_from([0.0, 1e2, 1e4, 1e6]), label="reach")
    direction = data.draw(st.floats(-math.pi, math.pi), label="direction")
    angle = data.draw(st.floats(-math.pi, math.pi), label="angle")
    size = case.linkage.scale
    offset = (reach * size * math.cos(direction), reach * size * math.sin(direction))
    _, moved = solved(transformed(table, offset, angle, 1.0))
    assert_same(original, moved, case, offset, angle, 1.0)


@SETTINGS
@given(table=linkage_tables(friction=False, moving=False), data=st.data())
def test_scaling_the_drawing_scales_moments_and_nothing_else(table: dict[str, Any],
                                                             data: st.DataObject) -> None:
    """A random static linkage drawn 10⁻³ to 10³ times as large (moments and stiffnesses
    scaled to match): the same verdict, condition number and forces, and moments times the
    scale."""
    case, original = solved(table)
    scale = 10.0 ** data.draw(st.sampled_from([-3, -1, 1, 3]), label="log scale")
    try:
        _, moved = solved(transformed(table, (0.0, 0.0), 0.0, scale))
    except CaseError:   # drawn smaller than a micrometre somewhere: refused, rightly
        reject()
    assert_same(original, moved, case, (0.0, 0.0), 0.0, scale)


@pytest.mark.parametrize("distance", [0.0, 5e3, 2e4, 1e8])
def test_a_crank_far_from_the_origin_keeps_its_condition_number(distance: float) -> None:
    """Seed E1's four-bar drawn 5 km, 20 km and 10⁸ m from the origin: the same verdict (ok),
    the same condition number and the same drive torque as at the origin (2.90133 N·m,
    SEEDS.md E1)."""
    table = four_bar_chain(1, offset=(distance * 1e3, 0.5 * distance * 1e3))
    case, solution = solved(table)
    _, at_origin = solved(four_bar_chain(1))
    assert solution.status == "ok", solution.message
    reach = distance / case.linkage.scale + 1.0
    rtol = BASE_RTOL + 16 * EPS * reach * 100
    assert solution.diagnostics["condition_number"] == pytest.approx(
        at_origin.diagnostics["condition_number"], rel=rtol)
    assert solution.values["Q_J_O0"] == pytest.approx(2.90133, abs=5e-6)
    assert solution.values["Q_J_O0"] == pytest.approx(at_origin.values["Q_J_O0"], rel=rtol)
    assert solution.values["x_B1"] == pytest.approx(distance + 0.12662002551, rel=1e-15, abs=1e-9)


def test_a_drawing_turned_far_from_the_origin_finds_its_equilibrium() -> None:
    """Seed 002's exam Q1 bar (a free coordinate, compare/cases/linkages/exam_q1_slider_bar.toml)
    drawn 5 km and 7 km away: its equilibrium is found, with the same angle and forces as
    where it is drawn in the file (the search's tolerances are relative to its size)."""
    from mechcheck.casefile import builtin_case_files, load_specs

    path = next(p for p in builtin_case_files() if p.name == "exam_q1_slider_bar.toml")
    (case, spec), *_ = load_specs([path])
    table = spec.model_dump(exclude_none=True)
    original = solve(case)
    for distance in (5e3, 7e3):
        scale = 1e-3 if table.get("length_unit") == "mm" else 1.0
        moved_table = transformed(table, (distance / scale, -distance / scale), 0.0, 1.0)
        moved_case = parse_cases({"case": [moved_table]}, "far.toml")[0][0]
        moved = solve(moved_case)
        assert moved.status == original.status == "ok", moved.message
        for name, value in original.values.items():
            if name.startswith(("phi_", "F_", "Q_")):
                assert moved.values[name] == pytest.approx(value, rel=1e-7, abs=1e-7), name


@pytest.mark.parametrize("backend", ["mujoco_solve", "pymunk_solve", "mujoco", "pymunk"])
def test_simulators_hold_a_linkage_drawn_far_away(backend: str) -> None:
    """Seed E1's four-bar drawn 5 km along x and 2 km along y: each simulator's model is built
    about the drawing's reference point, so it agrees with the analytic answer within the
    tolerance policy exactly as at the origin, and reports the points where the file drew
    them."""
    from mechcheck.testing import assert_solution_close

    far = parse_cases({"case": [four_bar_chain(1, offset=(5e6, 2e6))]}, "far.toml")[0][0]
    solution = solve(far, backend)
    assert solution.status == "ok", solution.message
    assert_solution_close(far, solution)
    assert solution.values["x_B1"] == pytest.approx(5000.12662002551, abs=1e-9)
