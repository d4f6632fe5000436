"""Large linkages: a chain of hundreds of four-bar loops is solved by the sparse path of the
engine to the same answer as one loop's closed form predicts, and the sparse and dense paths
of the linear algebra agree wherever both apply."""

from __future__ import annotations

import math
import warnings
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from typer.testing import CliRunner

from mechcheck import solve
from mechcheck.analytic import linalg
from mechcheck.analytic.linkage_forces import solve_linkage
from mechcheck.analytic.rigid import force_layout
from mechcheck.casefile import parse_cases
from mechcheck.cli import app
from tests.builtin import builtin
from tests.chains import four_bar_chain, toml_of
from tests.strategies import linkage_tables

#: The analytic family's tolerance (compare/tolerance.py): the same equations solved another
#: way, only rounding between them.
RTOL = 1e-9


def chain_case(loops: int) -> Any:
    return parse_cases({"case": [four_bar_chain(loops)]}, "chain.toml")[0][0]


def one_loop() -> tuple[float, float, dict[str, float]]:
    """Seed E1 by the four-bar's closed form (an engine of its own): the drive torque, the
    rocker's speed per unit crank speed ω4/ω2 = a2·sin(θ2 − θ3) / (a4·sin(θ4 − θ3)) (the
    velocity loop, differentiated by hand), and the reactions F34, F14."""
    e1 = solve(builtin("seed-E1-as-stated"))
    t2, t3, t4 = math.radians(60.0), e1.values["theta13"], e1.values["theta14"]
    ratio = 80.0 * math.sin(t2 - t3) / (120.0 * math.sin(t4 - t3))
    return e1.values["T12"], ratio, dict(e1.values)


@pytest.mark.parametrize("loops", [1, 3, 256])
def test_a_chain_of_loops_needs_the_geometric_sum_of_one_loops_torque(loops: int) -> None:
    """Every loop of the chain is E1 at its drawn pose with E1's loads, driven by the loop
    before: by virtual work loop k adds E1's torque times the (k − 1)th power of the speed
    ratio, so Q = T12·(1 − rⁿ)/(1 − r); the last loop carries E1's own F34 and F14 (nothing
    hangs on it). 256 loops (770 joints) go through the sparse factorisation."""
    torque, r, e1 = one_loop()
    solution = solve(chain_case(loops))
    assert solution.status == "ok", solution.message
    assert solution.values["Q_J_O0"] == pytest.approx(torque * (1 - r**loops) / (1 - r), rel=RTOL)
    force = math.hypot(e1["F34_x"], e1["F34_y"])
    for mine, seed in ((f"F_J_B{loops}", "F34"), (f"F_J_O{loops}", "F14")):
        for axis in "xy":
            assert solution.values[f"{mine}_{axis}"] == pytest.approx(e1[f"{seed}_{axis}"],
                                                                      abs=RTOL * force)
    # Its condition number grows with the chain, linearly, never past the near-singular line
    # for these lengths (an exact number, from the sparse Lanczos estimate).
    assert 1.0 < solution.diagnostics["condition_number"] < 20.0 * (loops + 1)


def test_a_long_chain_is_solved_without_a_warning() -> None:
    """A valid 64-loop chain: no RuntimeWarning (overflow) reaches the user (the condition
    bound compounds past float range on long chains and is not used there)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert solve(chain_case(64)).status == "ok"


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.filter_too_much,
                                                                  HealthCheck.too_slow])
@given(table=linkage_tables(friction=False))
def test_the_sparse_path_agrees_with_the_dense_one(table: dict[str, Any]) -> None:
    """Random linkages solved with every system forced through the sparse path (SuperLU,
    LSMR, Lanczos) and through the dense one (LAPACK): the same verdict, forces and condition
    number."""
    sparse_and_dense_agree(table)


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.filter_too_much,
                                                                  HealthCheck.too_slow])
@given(table=linkage_tables(friction=True))
def test_the_sparse_path_agrees_with_the_dense_one_with_friction(table: dict[str, Any]) -> None:
    """The same with Coulomb and viscous friction: Newton's iteration on sparse matrices
    gives the dense iteration's verdict and forces."""
    sparse_and_dense_agree(table)


def sparse_and_dense_agree(table: dict[str, Any]) -> None:
    case = parse_cases({"case": [table]}, "random.toml")[0][0]
    dense = solve(case)
    saved = linalg.DENSE_COLUMNS
    try:
        linalg.DENSE_COLUMNS = 0
        sparse_case = parse_cases({"case": [table]}, "random.toml")[0][0]  # its own caches
        sparse = solve(sparse_case)
    finally:
        linalg.DENSE_COLUMNS = saved
    assert sparse.status == dense.status, (dense.message, sparse.message)
    cond = float(dense.diagnostics["condition_number"])
    assert float(sparse.diagnostics["condition_number"]) == pytest.approx(cond, rel=1e-8)
    forces = max((abs(v) for q, v in dense.values.items() if q.startswith("F_")), default=1.0)
    for name, value in dense.values.items():
        scale = forces * case.linkage.scale if name.startswith("Q_") else max(forces, 1.0)
        assert sparse.values[name] == pytest.approx(value, abs=RTOL * cond * scale), name


def friction_chain(loops: int) -> Any:
    """A chain with friction circles (μ = 0.2, r = 5 mm) at every pin, driven forwards."""
    table = four_bar_chain(loops)
    table["friction"] = {"mu": 0.2, "pin_radius": {j["name"]: 5.0 for j in table["joints"]}}
    table["drivers"][0]["sense"] = "increasing"
    return parse_cases({"case": [table]}, "chain.toml")[0][0]


def test_coulomb_friction_on_a_large_linkage_is_solved_without_a_dense_matrix(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """A 20-loop chain with friction circles at all 61 pins (123 unknowns, past the dense
    limit): Newton's iteration and the friction loop's gain go through sparse matrices (a
    dense one is refused), and give what the dense path (LAPACK) gives for the same
    equations: reactions within the analytic rule, the gain to 1e-9 (it is exact both ways,
    only rounding between them)."""
    saved = linalg.DENSE_COLUMNS
    try:
        linalg.DENSE_COLUMNS = 10**9
        dense = solve_linkage(friction_chain(20).linkage)
        assert dense.friction_gain is not None
        dense_gain = float(dense.friction_gain[0])   # computed when first read
    finally:
        linalg.DENSE_COLUMNS = saved
    linkage = friction_chain(20).linkage
    assert force_layout(linkage).columns > linalg.DENSE_COLUMNS
    small_only = linalg.Batched.dense

    def refuse_large(self: linalg.Batched) -> Any:
        assert self.small, f"a dense {self.rows} × {self.cols} matrix"
        return small_only(self)

    monkeypatch.setattr(linalg.Batched, "dense", refuse_large)
    sparse = solve_linkage(linkage)
    assert sparse.converged.all() and dense.converged.all()
    forces = [q for q in dense.values if q.startswith(("F_", "Q_"))]
    scale = max(abs(float(dense.values[q][0])) for q in forces)
    for q in forces:
        assert float(sparse.values[q][0]) == pytest.approx(float(dense.values[q][0]),
                                                           abs=RTOL * scale), q
    assert sparse.friction_gain is not None
    assert float(sparse.friction_gain[0]) == pytest.approx(dense_gain, rel=1e-9)


def test_ranks_by_the_sparse_path_count_redundant_constraints() -> None:
    """The rank of a constraint Jacobian with two repeated rows and one zero singular value
    of its own (a 300 × 400 block-diagonal matrix), counted through the factorisation of the
    augmented system: 300 − 2 − 1 = 297, as the dense SVD counts."""
    rng = np.random.default_rng(1)
    blocks = [rng.standard_normal((3, 4)) for _ in range(100)]
    blocks[7][2] = blocks[7][0]                 # a repeated row
    blocks[50][1] = 2.0 * blocks[50][0]         # and another
    blocks[90][2] = blocks[90][0] + blocks[90][1]
    m = np.zeros((300, 400))
    for k, b in enumerate(blocks):
        m[3 * k:3 * k + 3, 4 * k:4 * k + 4] = b
    assert linalg.rank(m) == 297
    assert int(np.linalg.matrix_rank(m)) == 297


def test_a_sweep_grid_beyond_ten_turns_is_refused(tmp_path: Path) -> None:
    """`--driver` beyond the ±3600° a linkage's driver may turn (the case-file bound) is one
    line and exit 2, before anything is computed or written."""
    path = tmp_path / "chain.toml"
    path.write_text(toml_of(four_bar_chain(1)))
    result = CliRunner().invoke(app, ["sweep", str(path), "-q", "--workers", "0", "--driver",
                                      "0:5000:1", "--out", str(tmp_path / "o")])
    assert result.exit_code == 2
    assert "--driver" in result.output and "3600" in result.output
    assert not (tmp_path / "o").exists()
