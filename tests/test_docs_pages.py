"""The user's pages (README.md, docs/*.md) describe the current mechcheck from inside the
clone: every link, anchor, file and test they name exists, and none narrates the
development (issue numbers, dated findings, what an earlier version did)."""

from __future__ import annotations

import re
from itertools import pairwise
from pathlib import Path

import pytest
from markdown_it import MarkdownIt

ROOT = Path(__file__).resolve().parents[1]
#: What a user reads: the front page and the reference pages.
USER_PAGES = sorted([ROOT / "README.md", *(ROOT / "docs").glob("*.md")])
#: Every page of the clone whose links and file names must resolve (the developers' too).
ALL_PAGES = sorted([*USER_PAGES, ROOT / "CHANGELOG.md",
                    *(path for path in ROOT.glob("*/**/README.md")
                      if not any(part.startswith(".") for part in path.relative_to(ROOT).parts))])

#: Development narration a user page must not carry, each with why.
NARRATION = {
    r"\bissues? \d+|(?<![\w&/])#\d+\b": "an issue number",
    r"(?<!test )\bsessions?\b": "a work session (a pytest session is named so)",
    r"\b20\d\d-\d\d-\d\d\b": "a date (a dated finding or measurement belongs in CHANGELOG.md)",
    r"\bretired\b|\bno longer\b|\bused to\b|\bearlier (?:version|release|choice|closed form)s?\b"
    r"|\bthe run before\b|\(before,|\bbefore:|\bBefore,|\bit was \d|\bwas \d[\d.,]* ?(?:ms|s|µs)\b"
    r"|\bwas once\b|\bdraw of README|\bfound by (?:a|the) random\b|\bTraced and fixed\b":
        "what an earlier version did, or how a finding was made",
}


def page_id(path: Path) -> str:
    return str(path.relative_to(ROOT))


def github_slug(heading: str) -> str:
    """The anchor GitHub gives a heading (and mkdocs, for the headings these pages use)."""
    text = re.sub(r"`([^`]*)`", r"\1", heading.strip()).lower()
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", text)
    return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")


def anchors(page: Path) -> set[str]:
    """Every heading anchor of a Markdown page, repeated headings numbered as GitHub does."""
    found: set[str] = set()
    tokens = MarkdownIt().parse(page.read_text(encoding="utf-8"))
    for opening, inline in pairwise(tokens):
        if opening.type == "heading_open":
            slug = base = github_slug(inline.content)
            count = 0
            while slug in found:
                count += 1
                slug = f"{base}-{count}"
            found.add(slug)
    return found


def links(page: Path) -> list[str]:
    """The targets of a page's Markdown links and images (code spans and blocks left out)."""
    targets: list[str] = []
    stack = list(MarkdownIt().parse(page.read_text(encoding="utf-8")))
    while stack:
        token = stack.pop()
        stack.extend(token.children or [])
        if token.type == "link_open":
            targets.append(str(token.attrs["href"]))
        elif token.type == "image":
            targets.append(str(token.attrs["src"]))
    return targets


def prose(page: Path) -> str:
    """A page's text outside fenced code blocks (a block quotes output, not the page)."""
    return re.sub(r"^\s*```.*?^\s*```", "", page.read_text(encoding="utf-8"), flags=re.S | re.M)


@pytest.mark.parametrize("page", ALL_PAGES, ids=page_id)
def test_every_link_reaches_a_file_and_heading_of_the_clone(page: Path) -> None:
    """A relative link names a file the clone has and, with #, a heading of that page."""
    broken = []
    for target in links(page):
        if re.match(r"[a-z]+:", target):
            continue  # a web address: not the clone's to keep
        path, _, anchor = target.partition("#")
        resolved = (page.parent / path).resolve() if path else page
        if not resolved.exists():
            broken.append(f"{target}: no such file")
        elif anchor and resolved.suffix == ".md" and anchor not in anchors(resolved):
            broken.append(f"{target}: no heading with that anchor")
    assert not broken, broken


#: A file path of the repository written in a code span: a source folder, then a path.
REPO_PATH = re.compile(r"`((?:analytic|compare|sim_models|tests|benchmarks|reports|docs)/[\w./-]+)"
                       r"(?:::(\w+))?(?:\[[^\]`]*\])?`")


@pytest.mark.parametrize("page", ALL_PAGES, ids=page_id)
def test_every_file_and_test_a_page_names_exists(page: Path) -> None:
    """A path in a code span (`tests/test_x.py::test_y` included) is a file, folder or test
    of the clone."""
    missing = []
    for path, test in REPO_PATH.findall(prose(page)):
        target = ROOT / path
        if not target.exists():
            missing.append(path)
        elif test and not re.search(rf"^\s*(?:async )?def {test}\(", target.read_text(encoding="utf-8"),
                                    flags=re.M):
            missing.append(f"{path}::{test}")
    assert not missing, missing


@pytest.mark.parametrize("page", USER_PAGES, ids=page_id)
def test_no_user_page_narrates_the_development(page: Path) -> None:
    """A user page describes what mechcheck does now; history goes into CHANGELOG.md."""
    text = prose(page)
    found = [f"line {text.count(chr(10), 0, hit.start()) + 1}: {hit.group(0)!r} ({why})"
             for pattern, why in NARRATION.items() for hit in re.finditer(pattern, text)]
    assert not found, "\n".join(found)


#: The project's planning documents, which live outside the repository.
ABSENT_DOCUMENTS = re.compile(r"\b(?:LINKAGES|SIMULATORS|SEEDS|DESIGN|CONVENTIONS|STYLE)\.md\b|\.\./shared\b")


@pytest.mark.parametrize("page", ALL_PAGES, ids=page_id)
def test_no_page_sends_the_reader_to_a_document_the_clone_lacks(page: Path) -> None:
    """No page, a developer's README included, names a planning document kept outside."""
    assert not ABSENT_DOCUMENTS.findall(page.read_text(encoding="utf-8"))


def test_changelog_names_no_issue_or_session() -> None:
    """CHANGELOG.md speaks of versions, not of issues or work sessions."""
    text = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    assert not re.search(r"\bissues? \d+|(?<![\w&/])#\d+\b|\bsessions?\b", text)


def test_readme_fits_on_a_newcomers_screen_and_a_half() -> None:
    """README.md stays the door, not the manual: at most 15 KB."""
    assert (ROOT / "README.md").stat().st_size <= 15_000
