"""The ``mechcheck`` command line: ``run``, ``simulate``, ``validate``, ``sweep``, ``draw``, ``study``,
``theory``, ``reports``, ``new`` and ``backends`` (see docs/cli.md).

``mechcheck run FILE... [--backend NAME]... [--out DIR]`` writes
``results.csv``, ``comparison.csv``, ``diagnostics.csv``, ``report.md`` and
``report.html``. Exit status 0: every comparison within tolerance; 1: any
not (or a failing verdict); 2: unusable input, with one line on stderr that
names the file, the case and the key.
"""

from __future__ import annotations

import gc
import os
import signal
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, NoReturn

import typer

from mechcheck import backends as registry
from mechcheck.analytic.values import CaseError
from mechcheck.executors import MAX_WORKERS_PER_CORE, ExecutorUnavailable, check_workers
from mechcheck.verdicts import DEFAULT_FAIL_ON, VERDICTS, Progress

if TYPE_CHECKING:
    from mechcheck.analytic.case import Case
    from mechcheck.casefile import AnySpec
    from mechcheck.run import RunResult

# pandas, matplotlib, pydantic and the simulators are imported inside the commands
# that need them, so that `mechcheck --help` and `mechcheck backends` start fast
# (benchmarks/bench_startup.py).

#: The exit status of a crash inside mechcheck (0 agree, 1 disagree, 2 unusable input).
INTERNAL_ERROR = 3

app = typer.Typer(add_completion=False, no_args_is_help=True, pretty_exceptions_enable=False,
                  help="Validate the force analysis of planar linkages (four-bars, "
                       "slider-cranks, any linkage of revolute, prismatic, pin-in-slot and gear "
                       "joints) against MuJoCo and pymunk.")


#: The templates `mechcheck new` prints (compare/examples/<name>.toml), with what each is.
EXAMPLES = {
    "four_bar": "a four-bar at its input angle θ12: loads, masses, motion, friction",
    "slider_crank": "a slider-crank (offset, slide friction) at its input angle θ12",
    "linkage": "any planar linkage drawn as points, links and joints, moved by its drivers",
    "linkage_sketch": "a linkage sketched roughly, made exact by its lengths and angles",
    "trajectory": "a linkage released to move over time, pushed by a force (mechcheck simulate)",
}


def example_path(mechanism: str) -> Path:
    return Path(__file__).parent / "examples" / f"{mechanism}.toml"


#: The case files of `run` and `validate`.
CaseFiles = Annotated[list[Path] | None, typer.Argument(
    help="Case files (TOML). None: the built-in suite (seed examples and more).")]


#: The long table of `mechcheck simulate` (its name here: `--help` imports no pandas).
TRAJECTORIES = "trajectories.parquet"

#: The options `run` and `simulate` share.
DEFAULT_FAIL_ON_TEXT = ",".join(DEFAULT_FAIL_ON)
Backends = Annotated[list[str] | None, typer.Option(
    "--backend", "-b", help="Backend to check against analytic (repeatable). "
    f"Default: every available one of {', '.join(registry.REGISTRY)}.")]
FailOn = Annotated[str, typer.Option(
    help="Comma-separated backend verdicts that fail the run "
         f"(from {', '.join(VERDICTS)}; 'none' for none).")]
Junit = Annotated[Path | None, typer.Option(
    help="Also write a JUnit XML file: one test case per comparison.")]
Quiet = Annotated[bool, typer.Option("--quiet", "-q", help="No progress.")]


def fail_input(message: str) -> typer.Exit:
    """One clear line on stderr, exit status 2."""
    typer.echo(f"mechcheck: error: {message}", err=True)
    return typer.Exit(2)


def progress_printer() -> Progress:
    """Progress on stderr: one updating line on a terminal, a line per step otherwise (logs)."""
    tty = sys.stderr.isatty()

    def show(done: int, total: int, label: str) -> None:
        line = f"[{done}/{total}] {label}"
        if tty:
            sys.stderr.write(f"\r\x1b[K{line}{chr(10) if done == total else ''}")
            sys.stderr.flush()
        else:
            sys.stderr.write(line + "\n")
    return show


@app.command("run", help="Solve every case (four-bars, slider-cranks, linkages) through "
             "every backend and compare each number with the analytic solution; tables and a "
             "report.")
def run_command(
    files: CaseFiles = None,
    backend: Backends = None,
    out: Annotated[Path, typer.Option("--out", "-o", help="Output directory.")] =
        Path("mechcheck-out"),
    fail_on: FailOn = DEFAULT_FAIL_ON_TEXT,
    junit: Junit = None,
    quiet: Quiet = False,
) -> None:
    from mechcheck.report import drawing_file, drawings, render
    from mechcheck.run import run
    from mechcheck.tables import results_frame

    verdicts = parse_fail_on(fail_on)
    _, specs = read_case_files(files, trajectory=False)
    names = chosen_backends(backend)
    check_outputs(out, junit)
    progress = None if quiet else progress_printer()

    def work() -> Outputs:
        result = run([case for case, _ in specs], names, progress=progress, fail_on=verdicts)
        pictures = drawings(result)
        markdown, page = render(result, {c.name: s for c, s in specs}, pictures=pictures)
        tables: dict[str, str | bytes] = {
            "results.csv": results_frame(result.solutions).to_csv(index=False)}
        return (result, tables | report_files(result, markdown, page),
                ("drawings", {drawing_file(name): png for name, png in pictures.items()}))

    write_checked(out, junit, work)


#: What a command computes and writes: its result, its files (name: content) and its
#: pictures (folder, {name: PNG}).
Outputs = tuple["RunResult", dict[str, str | bytes], tuple[str, dict[str, bytes]]]


def report_files(result: RunResult, markdown: str, page: str) -> dict[str, str | bytes]:
    """What `run` and `simulate` both write: the comparison, the verdicts and diagnostics,
    the report."""
    from mechcheck.tables import diagnostics_frame

    return {"comparison.csv": result.comparison.to_csv(index=False),
            "diagnostics.csv": diagnostics_frame(result.solutions).to_csv(index=False),
            "report.md": markdown, "report.html": page}


def write_checked(out: Path, junit: Path | None,
                  work: Callable[[], Outputs]) -> NoReturn:
    """Run ``work`` holding the lock on ``out`` and write what it returns: its files in
    ``out``, its pictures in their folder (the Markdown report links to them, the HTML
    holds them) and the JUnit file; then the one-line summary and the exit status."""
    from mechcheck.junit import junit_xml
    from mechcheck.output import OutputError, locked_folder, write_all

    try:
        with locked_folder(out, "--out"):
            result, files, (folder, pictures) = work()
            write_all(out, files)
            if pictures:
                write_all(out / folder, pictures)
            if junit is not None:
                write_all(junit.parent, {junit.name: junit_xml(result)})
    except OutputError as error:
        raise fail_input(str(error)) from None
    typer.echo(f"{result.summary} -> {out}/report.md")
    raise typer.Exit(result.exit_status)


def read_case_files(files: list[Path] | None, *, trajectory: bool | None = None,
                    builtin: list[Path] | None = None) -> tuple[list[Path],
                                                            list[tuple[Case, AnySpec]]]:
    """The files read and their validated cases, as `run`, `simulate` and `validate` read
    them (no file: ``builtin``, by default the built-in suite); ``trajectory``: True, every
    case must move over time, False, none may, None: either. An unusable one is its one
    line and exit 2."""
    from mechcheck.casefile import builtin_case_files, load_specs

    paths = list(files) if files else (builtin_case_files() if builtin is None else builtin)
    try:
        return paths, load_specs(paths, trajectory=trajectory)
    except CaseError as error:
        raise fail_input(str(error)) from None


def chosen_backends(backend: list[str] | None) -> list[str]:
    """The backends of ``--backend`` (default: every available one), each importable, or the
    one line naming the one that is not and exit 2."""
    names = list(backend) if backend else registry.available()
    try:
        for name in names:
            registry.load(name)
    except registry.BackendUnavailable as error:
        raise fail_input(str(error)) from None
    return names


def check_outputs(out: Path, junit: Path | None) -> None:
    """Refuse, before any computing and before anything is created, an ``--out`` or
    ``--junit`` that cannot be written."""
    from mechcheck.output import OutputError, check_writable_directory, check_writable_file

    try:
        check_writable_directory(out, "--out")
        if junit is not None:
            check_writable_file(junit, "--junit")
    except OutputError as error:
        raise fail_input(str(error)) from None


@app.command("simulate", help="Run each trajectory case (a linkage moving freely over "
             "time, with a case.simulate table) through every backend that simulates and compare each run "
             "with the analytic reference over time; tables and a report.")
def simulate_command(
    files: Annotated[list[Path] | None, typer.Argument(
        help="Case files (TOML) of trajectory cases (each with a case.simulate table). None: the built-in "
             "trajectory cases.")] = None,
    backend: Backends = None,
    out: Annotated[Path, typer.Option("--out", "-o", help="Output directory.")] =
        Path("mechcheck-simulate"),
    fail_on: FailOn = DEFAULT_FAIL_ON_TEXT,
    junit: Junit = None,
    quiet: Quiet = False,
    trajectories: Annotated[bool, typer.Option(
        help=f"Write {TRAJECTORIES}: every run's quantities at every output time "
             "(--no-trajectories: not; a long ladder of a large linkage makes millions of "
             "rows).")] = True,
) -> None:
    from mechcheck.casefile import builtin_trajectory_files
    from mechcheck.figures import figure_file
    from mechcheck.report import drawings
    from mechcheck.simulate_report import drawn_file, figures, render_simulate
    from mechcheck.simulate_run import RUNS_FILE, simulate

    verdicts = parse_fail_on(fail_on)
    builtin = builtin_trajectory_files()
    if not files and not builtin:
        raise fail_input("mechcheck simulate: no case file given, and this installation has no "
                         "built-in trajectory cases (mechcheck/cases/trajectories/ is empty)")
    _, specs = read_case_files(files, trajectory=True, builtin=builtin)
    names = chosen_backends(backend)
    check_outputs(out, junit)
    progress = None if quiet else progress_printer()

    def work() -> Outputs:
        result = simulate([case for case, _ in specs], names, progress=progress,
                          fail_on=verdicts)
        pictures = figures(result)
        drawn = drawings(result)
        markdown, page = render_simulate(result, {c.name: s for c, s in specs},
                                         pictures=pictures, drawn=drawn)
        tables: dict[str, str | bytes] = {RUNS_FILE: result.rungs.to_csv(index=False)}
        if trajectories:
            tables[TRAJECTORIES] = result.table().to_parquet(index=False)
        return (result, tables | report_files(result, markdown, page),
                ("figures", {figure_file(name): png for name, png in pictures.items()}
                 | {drawn_file(name): png for name, png in drawn.items()}))

    write_checked(out, junit, work)


@app.command("sweep", help="Move each case's driver over a range (θ12, or a linkage's first "
             "driver) through every backend; resumable, Parquet output.")
def sweep_command(
    files: Annotated[list[Path] | None, typer.Argument(
        help="Case files (TOML); each case's driver (a four-bar's or slider-crank's θ12, a "
             "linkage's first driver) is moved over the sweep's grid. None: the built-in "
             "sweeps of the seed four-bar and slider-crank.")] = None,
    theta12: Annotated[str, typer.Option(
        help="A four-bar's or slider-crank's input angles θ12 START:STOP:STEP in degrees, "
             "STOP excluded (and a linkage's driver values unless --driver is given).")] =
        "0:360:1",
    driver: Annotated[str | None, typer.Option(
        help="For linkages: the first driver's values START:STOP:STEP from the drawn pose, "
             "in degrees (revolute) or the case file's length_unit (prismatic), STOP "
             "excluded; the other drivers keep their values. Default: the --theta12 grid.")] =
        None,
    backend: Annotated[list[str] | None, typer.Option(
        "--backend", "-b", help="Backend to sweep besides analytic (repeatable). "
        "Default: every available one.")] = None,
    out: Annotated[Path, typer.Option("--out", "-o", help="Output directory.")] =
        Path("mechcheck-sweep"),
    workers: Annotated[int | None, typer.Option(
        help="Local worker processes (default: one per core; 0: in this process; at most "
             f"{MAX_WORKERS_PER_CORE} per core, and never more than the sweep's tasks).")] = None,
    dask: Annotated[str | None, typer.Option(
        help="Address of an existing Dask scheduler to run the sweep on.")] = None,
    fail_on: Annotated[str, typer.Option(
        help="Comma-separated verdicts that fail the run ('none' for none).")] =
        ",".join(DEFAULT_FAIL_ON),
    junit: Annotated[Path | None, typer.Option(help="Also write a JUnit XML file.")] = None,
    fresh: Annotated[bool, typer.Option(
        help="Discard the parts of an earlier run in DIR instead of resuming from them.")] = False,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="No progress bar.")] = False,
    figures: Annotated[bool, typer.Option(
        help="Draw each case's figure into figures/ and the report (--no-figures: neither, "
             "and an earlier run's figures of these cases are removed).")] = True,
) -> None:
    from mechcheck.casefile import builtin_sweep_files, load_specs
    from mechcheck.output import OutputError
    from mechcheck.sweep import parse_range, plan
    from mechcheck.sweep_run import run_sweep_command

    verdicts = parse_fail_on(fail_on)
    paths = list(files) if files else builtin_sweep_files()
    try:
        specs = load_specs(paths, sweep=True, trajectory=False)
        grid = parse_range(theta12)
        driver_grid = None if driver is None else parse_range(driver, "--driver")
        names = list(backend) if backend else registry.available()
        tasks = plan([c for c, _ in specs], names, grid, driver_grid,
                     {c.name: spec.length_unit for c, spec in specs})
    except (CaseError, ValueError, registry.BackendUnavailable) as error:
        raise fail_input(str(error)) from None
    try:
        check_workers(workers)
    except ExecutorUnavailable as error:
        raise fail_input(str(error)) from None
    check_outputs(out, junit)
    # SIGTERM (a CI job cancelled, `kill`) unwinds like Ctrl-C: the pool is shut down and
    # its workers terminated on the way out, instead of being orphaned.
    signal.signal(signal.SIGTERM, lambda signum, frame: sys.exit(128 + signum))
    poses = max(len(driver_grid) if not c.is_preset and driver_grid is not None
                else len(grid) for c, _ in specs)
    try:
        status = run_sweep_command(specs, tasks, poses, out, workers=workers, dask=dask,
                                   fail_on=verdicts, junit=junit, quiet=quiet, figures=figures,
                                   fresh=fresh)
    except ExecutorUnavailable as error:
        raise fail_input(str(error)) from None
    except OutputError as error:
        raise fail_input(str(error)) from None
    raise typer.Exit(status)


def parse_fail_on(text: str) -> tuple[str, ...]:
    verdicts = tuple(v for v in text.split(",") if v and v != "none")
    unknown = [v for v in verdicts if v not in VERDICTS]
    if unknown:
        raise fail_input(f"--fail-on: unknown verdict {unknown[0]!r}; choose from "
                         f"{', '.join(VERDICTS)} or 'none'")
    return verdicts


@app.command("draw")
def draw_command(
    file: Annotated[Path, typer.Argument(help="A case file (TOML).")],
    case: Annotated[str | None, typer.Option(
        "--case", "-c", help="The case to draw (needed when the file holds several).")] = None,
    out: Annotated[Path | None, typer.Option(
        "--out", "-o", help="The drawing to write: a .svg or .png file. "
        "Default: <case>.svg in the current folder.")] = None,
    drawn: Annotated[bool, typer.Option(
        help="Draw the pose the file draws, without solving (no reactions).")] = False,
    backend: Annotated[str | None, typer.Option(
        "--backend", "-b", help="The backend whose joint reactions are drawn (default: "
        "analytic). The pose is always analytic's.")] = None,
) -> None:
    """Draw a case's mechanism at its solved pose: links, joints, ground, springs, loads
    and the joint reactions of one backend, to scale and labelled."""
    from mechcheck.drawing import DrawingError, drawing_file, output_format, pick_case
    from mechcheck.output import OutputError, check_writable_file, file_stem, write_all

    try:
        chosen = pick_case(file, case)
        target = out if out is not None else Path(f"{file_stem(chosen.name)}.svg")
        fmt = output_format(target)
        if drawn and backend is not None:
            raise DrawingError("--backend with --drawn: the drawn pose is not solved, so it "
                               "has no reactions to draw")
        if backend is not None:
            registry.load(backend)
        check_writable_file(target, "--out")
        content = drawing_file(chosen, fmt, drawn=drawn, backend=backend or "analytic")
        write_all(target.parent, {target.name: content})
    except (CaseError, DrawingError, OutputError, registry.BackendUnavailable) as error:
        raise fail_input(str(error)) from None
    typer.echo(f"{chosen.name} -> {target}")


@app.command("study")
def study_command(
    names: Annotated[list[str] | None, typer.Argument(
        help="Studies to run (default: all): quasi_static, quasi_static_motion, "
             "superposition_friction, friction_angle, massless, rigid_joints, "
             "near_toggle.")] = None,
    out: Annotated[Path, typer.Option("--out", "-o", help="Output directory.")] =
        Path("mechcheck-studies"),
    quick: Annotated[bool, typer.Option(help="Fewer points per sweep (a smoke run).")] = False,
) -> None:
    """Run the assumption studies on the simulators; figures, data and conclusions."""
    from mechcheck.studies import STUDIES
    from mechcheck.studies_report import run_studies

    chosen = list(names) if names else list(STUDIES)
    unknown = [n for n in chosen if n not in STUDIES]
    if unknown:
        raise fail_input(f"unknown study {unknown[0]!r}; studies: {', '.join(STUDIES)}")
    for line in run_studies(chosen, out, quick=quick):
        typer.echo(line)


@app.command("reports", help="Regenerate the committed reports: the built-in suite, seed "
             "001's catalogue of linkages, the whole-cycle sweeps of the seed four-bar and "
             "slider-crank through every backend, the built-in trajectory cases, and the "
             "assumption studies.")
def reports_command(
    out: Annotated[Path, typer.Option("--out", "-o", help="Output directory.")] = Path("reports"),
) -> None:
    from mechcheck.casefile import catalogue_case_files
    from mechcheck.studies import STUDIES
    from mechcheck.studies_report import run_studies

    codes = []
    catalogue = [str(path) for path in catalogue_case_files()]
    for args in (["run", "-q", "--out", str(out / "suite")],
                 ["run", "-q", *catalogue, "--out", str(out / "catalogue")],
                 ["sweep", "-q", "--fresh", "--out", str(out / "sweep")],
                 ["simulate", "-q", "--no-trajectories", "--out", str(out / "trajectories")]):
        # Without standalone mode click returns the exit status instead of exiting.
        code = app(args, standalone_mode=False)
        codes.append(int(code or 0))
    for line in run_studies(list(STUDIES), out / "studies"):
        typer.echo(line)
    raise typer.Exit(max(codes))


@app.command("new", help="Print a commented example case file to start from: "
             "mechcheck new linkage > my.toml. Without a template, list the templates.")
def new_command(
    template: Annotated[str | None, typer.Argument(
        help=f"The template: {', '.join(EXAMPLES)}. None: list them.")] = None,
) -> None:
    if template is None:
        for name, what in EXAMPLES.items():
            typer.echo(f"{name:13s} {what}")
        return
    if template not in EXAMPLES:
        raise fail_input(f"mechcheck new: unknown template {template!r}; "
                         f"choose from {', '.join(EXAMPLES)}")
    typer.echo(example_path(template).read_text(encoding="utf-8"), nl=False)


@app.command("validate", help="Check case files (four-bars, slider-cranks, linkages) without "
             "solving them: exit 0, or 2 with the one line `run` would give for the first "
             "unusable file, case and key.")
def validate_command(
    files: CaseFiles = None,
) -> None:
    paths, specs = read_case_files(files)   # as `run` and `simulate` read them
    n, m = len(specs), len(paths)
    typer.echo(f"{n} case{'s' * (n != 1)} in {m} file{'s' * (m != 1)}: valid")


@app.command("backends", help="List the backends: name, whether it is available here, the "
             "tolerance family it is judged by and what it is.")
def backends_command() -> None:
    for name, backend in registry.REGISTRY.items():
        missing = backend.missing_requirement()
        state = "available" if missing is None else f"unavailable ({missing} is not installed)"
        typer.echo(f"{name:15s} {state:12s} {backend.family:12s} {backend.summary}".rstrip())


def _add_theory() -> None:
    from mechcheck.theory_cli import app as theory_app

    app.add_typer(theory_app, name="theory")


_add_theory()


def main() -> None:
    """The console script. An exception that escapes a command is a bug in mechcheck: it
    gets one line and exit status 3, so that CI never mistakes it for a disagreement (1)
    or bad input (2). ``MECHCHECK_TRACEBACK=1`` shows the traceback instead. It ends the
    process (``SystemExit``) with the collector frozen (:func:`gc.freeze`)."""
    try:
        app()
    except KeyboardInterrupt:
        sys.exit(130)
    except Exception as error:
        from mechcheck.output import OutputError

        if isinstance(error, OutputError):  # a full disk in a command that does not say so
            sys.stderr.write(f"mechcheck: error: {error}\n")
            sys.exit(2)
        if os.environ.get("MECHCHECK_TRACEBACK"):
            raise
        sys.stderr.write(f"mechcheck: internal error: {type(error).__name__}: {error} (this is a "
                         "bug; please report it; MECHCHECK_TRACEBACK=1 shows the traceback)\n")
        sys.exit(INTERNAL_ERROR)
    finally:
        # The process ends here. Frozen, the objects pandas, pyarrow and matplotlib made are
        # not walked once more by the collector at exit: 0.13 s of a 0.9 s resumed sweep.
        gc.freeze()


if __name__ == "__main__":
    main()
