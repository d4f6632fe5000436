"""One backend contract (issue 12): a simulator is a package under ``mechcheck.sim_models`` that
declares its ``BACKENDS``; nothing in the harness names it.

The test writes a fake simulator package into a temporary directory that joins
``mechcheck.sim_models``'s search path, as a new folder there would, and runs the CLI: the
fake backends are listed, run, swept, compared and judged with no edit anywhere in
mechcheck. One fake is right and one is 1 % off in one force, so the
comparison is seen to be real.
"""

from __future__ import annotations

import math
import pickle
import re
import sys
import textwrap
from collections.abc import Iterator
from pathlib import Path

import pandas as pd
import pytest
from click.testing import Result
from typer.testing import CliRunner

import mechcheck
import mechcheck.sim_models as simulators
from mechcheck import backends as registry
from mechcheck.analytic.contract import Backend
from mechcheck.analytic.solution import quantity_kind
from mechcheck.cli import app
from mechcheck.sim_models.diagnostics import COMMON_KEYS
from mechcheck.tolerance import rule

from .builtin import builtin, rocker_load_case

FAKE_SIMULATOR = '''
"""A fake simulator: the analytic answer under another name (and one 1 % off)."""
from dataclasses import replace

from mechcheck.analytic.contract import Backend
from mechcheck.sim_models.protocol import Simulator, StiffnessStudy

BACKENDS = (
    Backend("fakesim", f"{__name__}:solve", "settled", "a fake simulator",
            sweep=f"{__name__}:sweep", requires="json"),
    Backend("fakesim_off", f"{__name__}:solve_off", "settled", "a fake simulator, 1 % off"),
    Backend("fakesim_absent", f"{__name__}:solve", "settled", "needs a package not installed",
            requires="no_such_package_for_mechcheck"),
)
SIMULATOR = Simulator("fakesim", BACKENDS[:1], f"{__name__}:stiffness", requires="json")


def stiffness(case, driven, quick, error_of):
    """The fake's stiffness experiment: its one setting is 1 % off in F_A0_x."""
    from mechcheck.analytic.presets import solve_preset
    answer = solve_preset(case, solve_off, "fakesim")
    row = {"simulator": "fakesim", "setting": "off", "parameter": "none", "value": 1.0,
           "reading": "settled", "error": error_of(case, answer.values)}
    return StiffnessStudy([row], lambda ax, data: ax.loglog(data["value"], data["error"]),
                          lambda data: f"fakesim errs by {data['error'].max():.3f}.")


def solve(case):
    from mechcheck.analytic import linkage_backends
    return replace(linkage_backends.solve(case), backend="fakesim", diagnostics={"method": "fake"})


def solve_off(case):
    answer = solve(case)
    values = dict(answer.values, F_A0_x=answer.values["F_A0_x"] * 1.01 + 1.0)
    return replace(answer, backend="fakesim_off", values=values)


def sweep(case, values, backend):
    from mechcheck.analytic.linkage_backends import analytic_results, solution_from
    results = analytic_results(case, values)
    return [replace(solution_from(case, "fakesim", results, method="fake", elapsed=0.0, index=i),
                    diagnostics={"method": "fake"}) for i in range(len(values))]
'''


@pytest.fixture
def fake_simulator(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """The fake package ``fakesim`` put under ``mechcheck.sim_models`` (its search path
    extended to a temporary directory, as a package in the folder would be), and the
    registry discovered again; a case file to run. Undone afterwards."""
    package = tmp_path / "sim_models" / "fakesim"
    package.mkdir(parents=True)
    (package / "__init__.py").write_text(textwrap.dedent(FAKE_SIMULATOR))
    monkeypatch.setattr(simulators, "__path__", [*simulators.__path__, str(package.parent)])
    monkeypatch.setattr(registry, "REGISTRY", registry.discovered())
    monkeypatch.chdir(tmp_path)
    (tmp_path / "arm.toml").write_text(rocker_load_case("arm"))
    yield tmp_path
    sys.modules.pop(f"{simulators.__name__}.fakesim", None)


def cli(*args: str) -> Result:
    return CliRunner().invoke(app, list(args))


def test_a_new_simulator_package_is_listed_run_and_compared(fake_simulator: Path) -> None:
    listing = cli("backends")
    assert listing.exit_code == 0, listing.output
    assert re.search(r"^fakesim +available +settled +a fake simulator$", listing.output, re.M)
    assert re.search(r"^fakesim_absent +unavailable \(no_such_package_for_mechcheck is not "
                     r"installed\)", listing.output, re.M)

    good = cli("run", "arm.toml", "-b", "fakesim", "-o", "good", "-q")
    assert good.exit_code == 0, good.output
    table = pd.read_csv(fake_simulator / "good" / "comparison.csv")
    fake = table[table["backend"] == "fakesim"]
    assert len(fake) > 0 and fake["passed"].all()
    # Judged by its declared family's row of the tolerance policy, as any simulation:
    assert all(row.tolerance == rule("mujoco", quantity_kind(row.quantity), "static").rtol
               for row in fake.itertuples())

    off = cli("run", "arm.toml", "-b", "fakesim_off", "-o", "off", "-q")
    assert off.exit_code == 1, off.output
    table = pd.read_csv(fake_simulator / "off" / "comparison.csv")
    failed = table[(table["backend"] == "fakesim_off") & ~table["passed"].astype(bool)]
    assert list(failed["quantity"]) == ["F12_x"]

    swept = cli("sweep", "arm.toml", "-b", "fakesim", "--theta12", "0:60:20", "--workers", "0",
                "-o", "sweep", "-q")
    assert swept.exit_code == 0, swept.output
    assert ", 0 poses outside tolerance" in swept.output
    swept_table = pd.read_parquet(fake_simulator / "sweep" / "comparison.parquet")
    assert len(swept_table[swept_table["backend"] == "fakesim"]) > 0


def test_a_backend_needing_an_absent_package_says_so(fake_simulator: Path) -> None:
    result = cli("run", "arm.toml", "-b", "fakesim_absent", "-o", "absent", "-q")
    assert result.exit_code == 2 and not (fake_simulator / "absent").exists()
    assert result.output.strip().count("\n") == 0
    assert "no_such_package_for_mechcheck is not installed" in result.output


def test_every_declared_backend_meets_the_contract() -> None:
    """Each registered backend's functions exist where its declaration says (imported here:
    a typo in a ``"module:function"`` would otherwise surface only when a user runs it)."""
    for name, backend in registry.REGISTRY.items():
        assert isinstance(backend, Backend) and backend.name == name
        if backend.missing_requirement() is not None:
            continue
        assert callable(backend.solver())
        sweeper = backend.sweeper()
        assert sweeper is None or callable(sweeper)
        assert backend.family in ("reference", "analytic", "exact_solve", "settled")
    assert [n for n, b in registry.REGISTRY.items() if b.family == "reference"] == [registry.REFERENCE]


#: One case of each way a simulator gets its numbers: settled, driven, exact solve; a
#: four-bar, a slider-crank with friction and linkages (held, with free coordinates).
DIAGNOSED = ("seed-E1-as-stated", "seed-exam-Q3", "slidercrank-friction-slide", "bonnet-hold",
             "bonnet-free", "e2-linkage-friction")


@pytest.mark.parametrize("name", DIAGNOSED)
def test_both_simulators_report_the_same_diagnostics(name: str) -> None:
    """Typed diagnostics (issue 12): every simulator solution that has numbers says how it got
    them under the same keys (RunDiagnostics), each a finite number or a method name."""
    case = builtin(name)
    for backend in registry.names_of_family("settled") + registry.names_of_family("exact_solve"):
        solution = mechcheck.solve(case, backend)
        if solution.status == "not_applicable":
            continue
        assert solution.status == "ok", (backend, solution.message)
        missing = [k for k in COMMON_KEYS if k not in solution.diagnostics]
        assert not missing, (backend, missing)
        assert solution.diagnostics["method"] in ("settle", "driven", "constraint_solve")
        assert all(math.isfinite(float(solution.diagnostics[k])) for k in COMMON_KEYS[1:])
        assert float(solution.diagnostics["loop_violation"]) < 1e-6 * case.scale


def test_a_solution_is_read_only() -> None:
    solution = mechcheck.solve(builtin("seed-E1-as-stated"), "analytic")
    with pytest.raises(TypeError):
        solution.values["T12"] = 0.0  # type: ignore[index]
    with pytest.raises(TypeError):
        solution.diagnostics["method"] = "other"  # type: ignore[index]
    assert pickle.loads(pickle.dumps(solution)) == solution


def test_a_new_simulator_takes_part_in_the_rigid_joints_study(fake_simulator: Path) -> None:
    """The rigid-joints study runs every installed simulator's stiffness experiment
    (``SIMULATOR``), the fake one included, with no edit to the study: its rows, its panel
    and its sentence. The fake is 1 % + 1 N off in F12_x: its one row has a positive error
    (where the analytic answer itself would have none)."""
    from mechcheck.studies import rigid_joints

    assert [s.name for s in registry.simulators()] == ["fakesim", "mujoco", "pymunk"]
    result = rigid_joints.run(quick=True)
    fake = result.data[result.data["simulator"] == "fakesim"]
    assert len(fake) == 1 and set(result.data["simulator"]) == {"fakesim", "mujoco", "pymunk"}
    assert 0.0 < float(fake["error"].iloc[0]) < 1.0
    assert "fakesim errs by" in result.conclusion and "MuJoCo" in result.conclusion
