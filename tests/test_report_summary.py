"""The accuracy report's first screen and its case sections, in Markdown and HTML: the
verdict, one line per backend, the matrix of cases × backends, drawings and file paths."""

from __future__ import annotations

import base64
import math
import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

from mechcheck import report
from mechcheck.casefile import builtin_case_files
from mechcheck.cli import app
from mechcheck.report import shown_path
from mechcheck.tolerance import of_tolerance

from .builtin import rocker_load_case
from .test_cli import TIGHTENED


def run(args: list[str]) -> int:
    result = CliRunner().invoke(app, args)
    return result.exit_code


def test_a_comparisons_share_of_its_tolerance_by_hand() -> None:
    """The share of the tolerance used is the smaller of rel/rtol and abs/atol: a comparison
    passes when either error is within its limit, so it passes exactly when this is ≤ 1."""
    assert of_tolerance(2e-7, 5.0, 1e-6, 0.0) == pytest.approx(0.2)  # 2e-7 / 1e-6
    # 3× its rtol, but its 1e-4 absolute error is a tenth of the atol of 1e-3: passes at 0.1.
    assert of_tolerance(3e-6, 1e-4, 1e-6, 1e-3) == pytest.approx(0.1)
    assert of_tolerance(3e-6, 1e-2, 1e-6, 1e-3) == pytest.approx(3.0)  # fails on both
    # A zero limit allows only a zero error.
    assert of_tolerance(0.0, 0.0, 0.0, 0.0) == 0.0
    assert of_tolerance(1e-300, 1e-300, 0.0, 0.0) == math.inf


def matrix_row(markdown: str, case: str) -> list[str]:
    """The cells of ``case``'s row of the Markdown matrix, after the case's name."""
    line = next(x for x in markdown.splitlines() if x.startswith(f"| [{case}](#case-{case}) |"))
    return [cell.strip() for cell in line.strip("|").split("|")][1:]


def backend_line(markdown: str, backend: str) -> str:
    return next(x for x in markdown.splitlines() if x.startswith(f"| `{backend}` |"))


def test_an_injected_failure_is_red_in_its_cell_and_named_in_its_backends_line(
        tmp_path: Path) -> None:
    """A tolerance of 1e-30 on virtual_work's T12 (no method meets it unless bit-identical)
    fails exactly that backend on that case: its matrix cell alone is marked failed, in both
    formats, and its backend's line counts one failure and names T12 and the case."""
    path = tmp_path / "tight.toml"
    path.write_text(TIGHTENED + rocker_load_case("e1b"))
    out = tmp_path / "o"
    assert run(["run", str(path), "-q", "-b", "superposition", "-b", "virtual_work",
                "--out", str(out)]) == 1
    markdown = (out / "report.md").read_text()
    assert markdown.index("## Backends") < markdown.index("## Worst error per case and backend")
    assert markdown.index("## Worst error per case and backend") < markdown.index("## Cases")
    superposition, virtual_work = matrix_row(markdown, "e1")
    assert virtual_work.startswith("**") and "●" in virtual_work
    assert "●" not in superposition and "**" not in superposition
    assert all("●" not in cell for cell in matrix_row(markdown, "e1b"))
    line = backend_line(markdown, "virtual_work")
    assert "| 1 **FAIL** |" in line and "T12 on [e1](#case-e1)" in line
    assert "| 0 |" in backend_line(markdown, "superposition")
    page = (out / "report.html").read_text()
    matrix = page[page.index('<table class="matrix">'):]
    matrix = matrix[:matrix.index("</table>")]
    rows = {m.group(1): m.group(2) for m in re.finditer(r'href="#case-([^"]+)">.*?</a></td>(.*?)</tr>',
                                                       matrix)}
    assert rows["e1"].count("band-fail") == 1 and "band-fail" not in rows["e1b"]


def test_markdown_and_html_have_the_same_sections(tmp_path: Path) -> None:
    """The two formats tell the same story in the same order: their section headings match."""
    path = tmp_path / "c.toml"
    path.write_text(rocker_load_case("e1") + rocker_load_case("e1-again"))
    out = tmp_path / "o"
    assert run(["run", str(path), "-q", "-b", "virtual_work", "--out", str(out)]) == 0
    markdown = (out / "report.md").read_text()
    page = (out / "report.html").read_text()
    for level in (2, 3):
        in_markdown = re.findall(rf"^{'#' * level} (.+)$", markdown, flags=re.MULTILINE)
        in_html = re.findall(rf"<h{level}>(.+?)</h{level}>", page)
        assert in_markdown == in_html and len(in_markdown) >= 2, level


def test_a_case_files_path_is_shown_relative(tmp_path: Path,
                                             monkeypatch: pytest.MonkeyPatch) -> None:
    """A report names a case file relative to the current directory, or inside the package
    as mechcheck/…, never where the clone or the installation sits."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "sub").mkdir()
    path = tmp_path / "sub" / "c.toml"
    path.write_text(rocker_load_case("e1"))
    assert run(["run", str(path), "-q", "-b", "virtual_work", "--out", "o"]) == 0
    markdown = (tmp_path / "o" / "report.md").read_text()
    assert "from `sub/c.toml`" in markdown and str(tmp_path) not in markdown
    seeds = builtin_case_files()[0]
    assert shown_path(str(seeds)) == f"mechcheck/cases/{seeds.name}"


def test_a_cases_drawing_is_inline_in_html_and_a_file_beside_the_markdown(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Whatever ``case_drawing`` draws is written to drawings/, linked from the Markdown and
    held by the HTML (the page stays one self-contained file)."""
    png = b"\x89PNG\r\n\x1a\n stand-in for a drawing"
    monkeypatch.setattr(report, "case_drawing", lambda case, solution: png + case.name.encode())
    path = tmp_path / "c.toml"
    path.write_text(rocker_load_case("e1"))
    out = tmp_path / "o"
    assert run(["run", str(path), "-q", "-b", "virtual_work", "--out", str(out)]) == 0
    assert (out / "drawings" / "e1.png").read_bytes() == png + b"e1"
    assert "](drawings/e1.png)" in (out / "report.md").read_text()
    inline = base64.b64encode(png + b"e1").decode()
    assert f'<img class="case-drawing" src="data:image/png;base64,{inline}"' in \
        (out / "report.html").read_text()
