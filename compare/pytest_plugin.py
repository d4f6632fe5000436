"""The pytest plugin: a project's own case files checked as test items.

Registered through the ``pytest11`` entry point, so it is active wherever
mechcheck is installed. It collects

- every file whose name matches the ini option ``mechcheck_files``
  (default ``*.mechcheck.toml``), like ``test_*.py``;
- with ``--mechcheck``, also every other ``*.toml`` file that holds ``[[case]]``
  tables, in the paths pytest is given (``pytest --mechcheck cases/``).

Each case becomes one item per backend, ``cases/arm.toml::arm-static[mujoco]``,
so ``-k arm-static`` selects a case and ``-k mujoco`` a backend. The backends
are ``--mechcheck-backend NAME`` (repeatable), else the ini option
``mechcheck_backends``, else every available one. Each item compares its
backend with ``analytic`` under the tolerance policy, exactly as
``mechcheck run`` does; the ``[analytic]`` item checks that the reference
itself has an answer. A trajectory case (``[case.simulate]``) is run as ``mechcheck
simulate`` runs it: each item its backend's runs against the reference's over time.
Verdicts: ``not_settled`` and ``error`` fail;
``singular``, ``indeterminate``, ``not_applicable`` and ``no_solution`` skip
with their reason. A file that cannot be used is a collection error carrying
the CLI's one-line message.

This module is imported by every pytest run in an environment that has
mechcheck, so it imports nothing heavy until a case file is collected.
"""

from __future__ import annotations

import fnmatch
from collections.abc import Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest

from mechcheck.verdicts import DEFAULT_FAIL_ON

if TYPE_CHECKING:
    from mechcheck.analytic.case import Case
    from mechcheck.analytic.solution import Solution


class CaseCheckFailed(AssertionError):
    """A backend disagreed with the reference, or gave a failing verdict."""


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("mechcheck", "mechcheck case files")
    group.addoption("--mechcheck", action="store_true", default=False,
                    help="also collect every *.toml file holding [[case]] tables "
                         "(files matching mechcheck_files are always collected)")
    group.addoption("--mechcheck-backend", action="append", default=None, metavar="NAME",
                    help="check case files against this backend (repeatable; "
                         "default: every available one)")
    parser.addini("mechcheck_files", type="args", default=["*.mechcheck.toml"],
                  help="glob patterns of case files that are always collected")
    parser.addini("mechcheck_backends", type="args", default=[],
                  help="backends case files are checked against (default: every available one)")


def pytest_collect_file(file_path: Path, parent: pytest.Collector) -> pytest.Collector | None:
    if file_path.suffix != ".toml":
        return None
    config = parent.config
    named = any(fnmatch.fnmatch(file_path.name, glob) for glob in config.getini("mechcheck_files"))
    if named or (config.getoption("mechcheck") and _may_hold_cases(file_path)):
        collector: CaseFile = CaseFile.from_parent(parent, path=file_path)
        return collector
    return None


def _may_hold_cases(path: Path) -> bool:
    """Whether ``--mechcheck`` should treat a ``.toml`` file as a case file.

    A readable TOML file without a ``case`` key (``pyproject.toml``) is not one;
    a file that cannot be read or parsed is, so that its error is reported. It is read
    as ``mechcheck run`` reads a case file: a FIFO or device is never opened, and a
    file larger than the cap never read whole.
    """
    from mechcheck.analytic.values import CaseError
    from mechcheck.casefile import parse_toml, read_case_text

    try:
        return "case" in parse_toml(read_case_text(path), str(path))
    except CaseError:  # not a regular file, too large, unreadable, not UTF-8, not TOML
        return True


def _backends(config: pytest.Config) -> list[str]:
    from mechcheck import backends as registry

    names = config.getoption("mechcheck_backend") or config.getini("mechcheck_backends")
    if not names:
        return registry.available()
    for name in names:
        if name not in registry.REGISTRY:
            raise pytest.UsageError(f"mechcheck: unknown backend {name!r}; known backends: "
                                    f"{', '.join(registry.REGISTRY)}")
    return list(dict.fromkeys([registry.REFERENCE, *names]))


class CaseFile(pytest.File):
    """One case file: an item per case and backend."""

    def collect(self) -> Iterator[CaseItem]:
        from mechcheck.analytic.case import CaseError
        from mechcheck.casefile import load_file

        try:
            cases = [case for case, _ in load_file(self._shown_path())]
        except CaseError as error:
            # The CLI's line exactly; pytest shows a CollectError's message without a traceback.
            raise self.CollectError(f"mechcheck: error: {error}") from None
        self._references: dict[str, Solution] = {}
        for case in cases:
            for backend in _backends(self.config):
                yield CaseItem.from_parent(self, name=f"{case.name}[{backend}]", case=case,
                                           backend=backend)

    def _shown_path(self) -> Path:
        """The path as the user would type it: relative to where pytest was started, if inside."""
        try:
            return self.path.relative_to(self.config.invocation_params.dir)
        except ValueError:
            return self.path

    def reference(self, case: Case) -> Solution:
        """The analytic solution of ``case``, computed once for all its items."""
        from mechcheck.backends import REFERENCE, load
        from mechcheck.run import call_backend

        if case.name not in self._references:
            self._references[case.name] = call_backend(load(REFERENCE), REFERENCE, case)
        return self._references[case.name]


class CaseItem(pytest.Item):
    """One case through one backend, compared with the analytic reference."""

    def __init__(self, *, case: Case, backend: str, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.case = case
        self.backend = backend

    def runtest(self) -> None:
        from mechcheck.backends import REFERENCE, BackendUnavailable, load
        from mechcheck.run import call_backend
        from mechcheck.testing import assert_solution_close

        assert isinstance(self.parent, CaseFile)
        if self.case.is_trajectory:
            self._run_trajectory()
            return
        reference = self.parent.reference(self.case)
        self._judge(reference, REFERENCE)
        if self.backend == REFERENCE:
            return
        try:
            backend = load(self.backend)
        except BackendUnavailable as error:
            raise CaseCheckFailed(f"{self.case.name} [{self.backend}]: {error}") from None
        solution = call_backend(backend, self.backend, self.case)
        self._judge(solution, self.backend)
        try:
            assert_solution_close(self.case, solution, reference)
        except AssertionError as error:
            raise CaseCheckFailed(str(error)) from None

    def _run_trajectory(self) -> None:
        """A trajectory case: this backend's runs against the reference's, as
        ``mechcheck simulate`` compares them (its finest run within the policy)."""
        import mechcheck
        from mechcheck.backends import REFERENCE

        result = mechcheck.simulate([self.case], list(dict.fromkeys([REFERENCE, self.backend])))
        for solution in result.solutions:
            self._judge(solution, solution.backend)
        failed = result.failed_comparisons
        if len(failed):
            rows = failed.head(5).to_dict("records")
            raise CaseCheckFailed(f"{self.case.name} [{self.backend}]: {len(failed)} quantities "
                                  f"outside tolerance over time, e.g. {rows}")

    def _judge(self, solution: Solution, backend: str) -> None:
        """Fail on a failing verdict, skip on one that leaves nothing to compare."""
        if solution.status == "ok":
            return
        reason = f"{self.case.name} [{backend}]: {solution.status}: {solution.message}"
        # As `mechcheck run`: a check that did not happen fails; a pose with no unique
        # answer, or a method that does not apply, leaves nothing to compare.
        if solution.status in DEFAULT_FAIL_ON:
            raise CaseCheckFailed(reason)
        pytest.skip(reason)

    def repr_failure(self, excinfo: pytest.ExceptionInfo[BaseException],
                     style: Any = None) -> str | Any:
        if isinstance(excinfo.value, CaseCheckFailed):
            return str(excinfo.value)
        return super().repr_failure(excinfo, style=style)

    def reportinfo(self) -> tuple[Path, int | None, str]:
        return self.path, None, f"{self.case.name} [{self.backend}]"
