"""What the console says (docs/cli.md): the one-line summary names every verdict that gave
no number, the help speaks of linkages and drivers, `new` lists its templates, `validate`
checks files without solving them with `run`'s own refusals, and messages quote lengths in
the file's unit."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from mechcheck import load_cases, solve
from mechcheck.casefile import builtin_case_files, catalogue_case_files
from mechcheck.cli import EXAMPLES, app, example_path

from .builtin import rocker_load_case
from .test_casefile import BAD_INPUTS, GOOD as GOOD_FOUR_BAR
from .test_linkage_file import BAD as BAD_LINKAGES


def invoke(args: list[str]) -> tuple[int, str, str]:
    result = CliRunner().invoke(app, args)
    return result.exit_code, result.stdout, result.stderr


def slide_driven() -> str:
    """Seed E2's slider-crank drawn as a linkage (crank a2 = 200, rod a3 = 800 mm, the slider
    drawn at s14 = 897.76036716 mm; compare/cases/linkages/seed_e2_slider_crank.toml), driven
    by its slide instead of its crank, 150 mm outward. It locks where crank and rod lie in
    line, s = a2 + a3 = 1000 mm: a displacement of 1000 − 897.76036716 = 102.23963284 mm
    from the drawing (inward: s = a3 − a2 = 600 mm, −297.76036716 mm)."""
    path = next(p for p in builtin_case_files() if p.name == "seed_e2_slider_crank.toml")
    # The first case, without its printed answer (Q_A0: A0 is no longer driven).
    first = "[[case]]" + path.read_text(encoding="utf-8").split("[[case]]")[1].split("[case.seed]")[0]
    return (first.replace('name = "e2-linkage-frictionless"', 'name = "slide-driven"')
            .replace('joint = "A0"\nrotation = 0.0', 'joint = "slide"\ndisplacement = 150.0'))


SLIDE_DRIVEN = slide_driven()


# -- the one-line summary -------------------------------------------------------------------

def test_a_run_driven_past_a_lock_says_so_in_its_summary(tmp_path: Path) -> None:
    """Driven past its lock, a case has no number to compare: the PASS line names the
    verdict, how many backends gave it and the case."""
    path = tmp_path / "slide.toml"
    path.write_text(SLIDE_DRIVEN)
    code, out, _ = invoke(["run", str(path), "-q", "-b", "analytic", "-b", "virtual_work",
                           "--out", str(tmp_path / "o")])
    assert code == 0
    line = out.strip().splitlines()[-1]
    assert "no_solution ×2 (slide-driven)" in line and "(PASS)" in line, line


def test_not_applicable_is_named_in_the_summary(tmp_path: Path) -> None:
    """Superposition does not apply with Coulomb friction: the summary names the verdict and
    the case rather than printing a bare PASS."""
    seeds = next(p for p in builtin_case_files() if p.name == "seeds.toml")
    code, out, _ = invoke(["run", str(seeds), "-q", "-b", "superposition",
                           "--out", str(tmp_path / "o")])
    assert code == 0
    assert "not_applicable ×1 (seed-E2-friction)" in out.strip().splitlines()[-1], out


# -- help -----------------------------------------------------------------------------------

@pytest.mark.parametrize("command", [[], ["run"], ["sweep"], ["validate"], ["theory"],
                                     ["theory", "case"], ["reports"]])
def test_the_help_speaks_of_linkages(command: list[str]) -> None:
    """`--help` and the subcommands' help name linkages, not only the four-bar's θ12."""
    code, out, _ = invoke([*command, "--help"])
    assert code == 0 and "linkage" in out, out


def test_the_sweep_help_speaks_of_drivers() -> None:
    """A sweep moves each case's driver; θ12 is the four-bar's and slider-crank's."""
    code, out, _ = invoke(["sweep", "--help"])
    assert code == 0 and "driver" in out.split("Options")[0], out


# -- new ------------------------------------------------------------------------------------

def test_new_without_a_template_lists_every_template() -> None:
    """`mechcheck new` lists the templates, one a line, each one `new NAME` prints."""
    code, out, _ = invoke(["new"])
    assert code == 0
    listed = [line.split()[0] for line in out.strip().splitlines()]
    assert listed == list(EXAMPLES)
    for name in listed:
        code, text, _ = invoke(["new", name])
        assert code == 0 and text == example_path(name).read_text(encoding="utf-8")


# -- validate -------------------------------------------------------------------------------

@pytest.mark.parametrize("path", [*builtin_case_files(), *catalogue_case_files(),
                                  *(example_path(name) for name in EXAMPLES)],
                         ids=lambda p: p.name)
def test_validate_accepts_every_built_in_file(path: Path) -> None:
    """Every case file shipped with mechcheck validates: exit 0, the count on stdout."""
    code, out, err = invoke(["validate", str(path)])
    assert code == 0 and out.strip().endswith("valid") and not err, (out, err)


def test_validate_without_files_checks_the_built_in_suite() -> None:
    """No file: the built-in suite, as `run` would read it."""
    code, out, _ = invoke(["validate"])
    assert code == 0 and f"in {len(builtin_case_files())} files: valid" in out


REFUSED = [(f"four-bar-{b[0]}", GOOD_FOUR_BAR + b[1]) for b in BAD_INPUTS[::4]] + [
    (f"linkage-{b[0]}", b[1]) for b in BAD_LINKAGES[::4]]


@pytest.mark.parametrize("text", [t for _, t in REFUSED], ids=[i for i, _ in REFUSED])
def test_validate_refuses_as_run_does(tmp_path: Path, text: str) -> None:
    """A bad file is refused by `validate` with exit 2 and exactly the one line `run` gives
    (one reader, one set of checks), and nothing is written."""
    path = tmp_path / "bad.toml"
    path.write_text(text)
    code, out, err = invoke(["validate", str(path)])
    run_code, _, run_err = invoke(["run", str(path), "-q", "--out", str(tmp_path / "o")])
    assert code == run_code == 2
    assert len(err.strip().splitlines()) == 1 and err == run_err, (err, run_err)
    assert str(path) in err and not out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml"]


# -- lengths in the file's unit -------------------------------------------------------------

def test_a_lock_is_quoted_in_the_files_millimetres(tmp_path: Path) -> None:
    """The lock of a slide driven past crank and rod in line is quoted in mm, at the hand
    value 102.239633 mm (slide_driven), not as 0.102240 m."""
    path = tmp_path / "slide.toml"
    path.write_text(SLIDE_DRIVEN)
    solution = solve(load_cases(path)[0])
    assert solution.status == "no_solution"
    assert "locks at displacement 102.2396" in solution.message, solution.message
    assert " mm of slide" in solution.message
    code, out, _ = invoke(["theory", "case", str(path)])
    assert code == 0 and "increasing: locks at +102.2396" in out, out
    assert "decreasing: locks at -297.7603" in out, out


def test_a_length_error_quotes_the_files_unit(tmp_path: Path) -> None:
    """A negative link length in a mm file is quoted as written, in mm."""
    path = tmp_path / "bad.toml"
    path.write_text(rocker_load_case("neg").replace("a1 = 140.0", "a1 = -140.0"))
    code, _, err = invoke(["validate", str(path)])
    assert code == 2 and "got -140 mm" in err, err
