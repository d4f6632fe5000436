"""Every example of README.md and docs/*.md runs as written.

A fenced block is one of:

- a command (```bash, ```console, ```sh): each line a `mechcheck` command, run in a fresh
  folder by the command line itself (typer's runner), in page order, so that a file one
  command writes (`mechcheck new four_bar > my.toml`) is there for the next; it must exit 0;
- a case file (```toml holding `[[case]]`): read by `mechcheck.load_cases`, solved by the
  reference and compared with the fast analytic backends; a `<!-- expect: Q_O2 = -6.0 -->`
  comment just above it states hand values the page derives, checked to the precision
  printed;
- Python (```python): a doctest; README's is collected by pytest itself
  (`--doctest-glob=README.md`), the pages' here;
- output (``` or ```text): what a command prints; with a `<!-- output-of: mechcheck ... -->`
  comment just above it, that command runs too and prints every line the block shows.

A block that is not run (an install, the whole test suite, a Dask cluster) says why in a
`<!-- not-run: REASON -->` comment just above it, visible in the page's source.
"""

from __future__ import annotations

import doctest
import os
import re
import shlex
from collections.abc import Iterator
from dataclasses import dataclass
from decimal import Decimal
from itertools import pairwise
from pathlib import Path

import pytest
from markdown_it import MarkdownIt
from typer.testing import CliRunner

import mechcheck
from mechcheck.cli import app

ROOT = Path(__file__).resolve().parents[1]
PAGES = sorted([ROOT / "README.md", *(ROOT / "docs").glob("*.md")])
COMMAND = {"bash", "console", "sh", "shell"}
OUTPUT = {"", "text"}
NOT_RUN = re.compile(r"<!--\s*not-run:\s*(\S.*?)\s*-->", re.S)
EXPECT = re.compile(r"<!--\s*expect:\s*(.*?)\s*-->", re.S)
OUTPUT_OF = re.compile(r"<!--\s*output-of:\s*(mechcheck\b.*?)\s*-->", re.S)
#: The analytic backends other than the reference: fast, and exact to rounding.
FAST_BACKENDS = ["superposition", "virtual_work"]


@dataclass(frozen=True)
class Block:
    """One fenced block of a page, with the HTML comment just above it (or "")."""

    page: Path
    line: int
    lang: str
    text: str
    comment: str

    @property
    def where(self) -> str:
        return f"{self.page.relative_to(ROOT)}:{self.line}"

    @property
    def runs(self) -> bool:
        return not NOT_RUN.search(self.comment)


def blocks(page: Path) -> Iterator[Block]:
    """The fenced blocks of a page, in order."""
    tokens = MarkdownIt().parse(page.read_text(encoding="utf-8"))
    for before, token in pairwise([None, *tokens]):
        if token.type == "fence" and token.map is not None:
            comment = before.content if before is not None and before.type == "html_block" else ""
            yield Block(page, token.map[0] + 1, token.info.strip().split(" ")[0], token.content, comment)


ALL_BLOCKS = [block for page in PAGES for block in blocks(page)]


def command_lines(block: Block) -> list[list[str]]:
    """The commands of a command block, split as a shell would (comments and `$ ` dropped)."""
    lines = (re.sub(r"^\$\s+", "", line) for line in block.text.splitlines())
    return [words for words in (shlex.split(line, comments=True) for line in lines) if words]


def test_every_block_runs_or_says_why() -> None:
    """Each block is a command of mechcheck, a whole case file, a doctest or output; any
    other runs nowhere, so it must carry a not-run comment with its reason."""
    unrun = []
    for block in ALL_BLOCKS:
        if not block.runs or block.lang in OUTPUT:
            continue
        if block.lang in COMMAND:
            strays = [" ".join(words) for words in command_lines(block) if words[0] != "mechcheck"]
            if strays:
                unrun.append(f"{block.where}: not a mechcheck command: {strays}")
        elif block.lang == "toml" and "[[case]]" not in block.text:
            unrun.append(f"{block.where}: a case-file fragment, not a whole case file")
        elif block.lang == "python" and ">>>" not in block.text:
            unrun.append(f"{block.where}: Python without >>> is not a doctest")
        elif block.lang not in {"toml", "python"}:
            unrun.append(f"{block.where}: a ```{block.lang} block runs nowhere")
    assert not unrun, "\n".join(unrun)


def run_command(words: list[str], folder: Path) -> str:
    """One `mechcheck ...` line through the command line in ``folder``; `> FILE` is kept."""
    target = None
    if ">" in words:
        words, target = words[: words.index(">")], words[words.index(">") + 1]
    result = CliRunner().invoke(app, words[1:])
    assert result.exit_code == 0, f"{' '.join(words)} exited {result.exit_code}:\n{result.output}"
    if target is not None:
        (folder / target).write_text(result.stdout, encoding="utf-8")
    return result.stdout


@pytest.fixture
def in_tmp(tmp_path: Path) -> Iterator[Path]:
    before = Path.cwd()
    os.chdir(tmp_path)
    try:
        yield tmp_path
    finally:
        os.chdir(before)


def shown_output(block: Block) -> tuple[list[str], list[str]]:
    """The command an output block shows the output of (or none), and the lines it shows."""
    match = OUTPUT_OF.search(block.comment) if block.lang in OUTPUT else None
    shown = [line.rstrip() for line in block.text.splitlines() if line.strip()]
    return (shlex.split(match.group(1)) if match else []), shown


COMMAND_PAGES = sorted({b.page for b in ALL_BLOCKS
                        if (b.lang in COMMAND and b.runs and command_lines(b)) or shown_output(b)[0]})


@pytest.mark.parametrize("page", COMMAND_PAGES, ids=lambda page: str(page.relative_to(ROOT)))
def test_the_commands_of_a_page_run(page: Path, in_tmp: Path) -> None:
    """Each mechcheck command of the page, in page order in one fresh folder, exits 0, and
    prints every line of the output the page shows for it."""
    for block in blocks(page):
        if block.lang in COMMAND and block.runs:
            for words in command_lines(block):
                run_command(words, in_tmp)
        command, shown = shown_output(block)
        if command:
            printed = {line.rstrip() for line in run_command(command, in_tmp).splitlines()}
            assert not [line for line in shown if line not in printed], (block.where, printed)


CASE_BLOCKS = [b for b in ALL_BLOCKS if b.lang == "toml" and b.runs]


def expected_values(comment: str) -> dict[str, Decimal]:
    """`<!-- expect: Q_O2 = -6.0, F_A_x = -180.0 -->` as names and printed values."""
    match = EXPECT.search(comment)
    pairs = (item.split("=") for item in match.group(1).split(",")) if match else ()
    return {name.strip(): Decimal(value.strip().replace("−", "-")) for name, value in pairs}


def within_printed_precision(value: float, printed: Decimal) -> bool:
    """A hand value printed to n decimals holds the exact one to half a unit of its last digit."""
    exponent = printed.as_tuple().exponent
    assert isinstance(exponent, int)
    return abs(value - float(printed)) <= 0.5 * 10.0**exponent


@pytest.mark.parametrize("block", CASE_BLOCKS, ids=lambda block: block.where)
def test_a_case_file_of_the_pages_reads_and_solves(block: Block, tmp_path: Path) -> None:
    """The case file reads, the reference solves every case, the fast analytic backends agree
    with it under the tolerance policy, and the hand values the page states hold (a
    trajectory's: the reference's at its last output time)."""
    path = tmp_path / "example.toml"
    path.write_text(block.text, encoding="utf-8")
    cases = mechcheck.load_cases(path)
    if cases[0].is_trajectory:
        check_trajectory_example(cases, expected_values(block.comment))
        return
    solutions = [mechcheck.solve(case) for case in cases]
    assert [s.status for s in solutions] == ["ok"] * len(cases), [s.message for s in solutions]
    assert mechcheck.check(cases, FAST_BACKENDS).exit_status == 0
    expected = expected_values(block.comment)
    values = solutions[0].values
    wrong = {name: (values.get(name), str(printed)) for name, printed in expected.items()
             if name not in values or not within_printed_precision(values[name], printed)}
    assert not wrong, wrong


def check_trajectory_example(cases: list[mechcheck.Case], expected: dict[str, Decimal]) -> None:
    """The reference runs every trajectory case, its energy balance holds, and the hand values
    the page states hold at the last output time."""
    result = mechcheck.simulate(cases, backends=[])
    assert result.exit_status == 0, result.summary
    case = cases[0]
    (run,) = result.trajectories[case.name]["analytic"]
    values = {q: float(v[-1]) for q, v in run.quantities(case.linkage).items()}
    wrong = {name: (values.get(name), str(printed)) for name, printed in expected.items()
             if name not in values or not within_printed_precision(values[name], printed)}
    assert not wrong, wrong


def test_the_python_examples_of_the_pages_pass_as_doctests() -> None:
    """Each ```python block of docs/ runs as a doctest (README's is collected by pytest)."""
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    parser = doctest.DocTestParser()
    for block in ALL_BLOCKS:
        if block.lang == "python" and block.runs and block.page.name != "README.md":
            runner.run(parser.get_doctest(block.text, {}, block.where, str(block.page), block.line))
    assert runner.summarize(verbose=False).failed == 0


def test_most_examples_run() -> None:
    """A block left unrun is the exception: most examples run."""
    skipped = [b for b in ALL_BLOCKS if not b.runs]
    runnable = [b for b in ALL_BLOCKS if b.lang not in OUTPUT]
    assert len(skipped) < len(runnable) / 2, [b.where for b in skipped]
