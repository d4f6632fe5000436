"""The trajectory report as a person sees it: headless Chromium paints ``mechcheck
simulate``'s HTML (on the fake backends of :mod:`tests.fake_trajectories`), and its first
screen holds the verdict and the matrix of cases × backends, as ``run``'s does; each case's
figure paints. ``MECHCHECK_SCREENSHOTS=DIR`` keeps the screenshot (test_report_render.py).
"""

from __future__ import annotations

import re
from pathlib import Path

from . import fake_trajectories as fake
from .test_report_render import (
    CELL_COLOURS,
    CELL_PIXELS_PER_BACKEND,
    FIRST_SCREEN,
    MIN_BANNER_PIXELS,
    MIN_PIXELS_PER_FIGURE,
    PASS_BANNER,
    chromium,
    coloured_pixels,
    keep,
    matching,
    runs,
    screenshot,
)
from .test_simulate_cli import fakes, simulate

__all__ = ["fakes"]   # the fixture, used by name

#: The trajectory cases the page shows: the block twice, under two names.
CASES = ("block-springs", "block-again")
#: The backends of its matrix: one that converges, one with no number, one that does not
#: simulate. (Three: the legend's six swatches, 72 px in a pixel row, stay below the cells.)
BACKENDS = ("fakesim", "fakesim_none", "virtual_work")


def written_report(folder: Path) -> Path:
    (folder / "again.toml").write_text(fake.block_case(CASES[1]))
    code, _, err = simulate("block.toml", "again.toml", *(f"-b{b}" for b in BACKENDS),
                            "-o", "out")
    assert code == 0, err
    return folder / "out" / "report.html"


def test_the_first_screen_holds_the_verdict_and_the_matrix(fakes: Path, tmp_path: Path) -> None:
    """At 1400 × 900: the passing banner, and one band of cell colours per case, each as wide
    as the backends' cells."""
    browser = chromium()
    page = written_report(fakes)
    shot = tmp_path / "trajectories_first_screen.png"
    image = screenshot(browser, page, shot, tmp_path, FIRST_SCREEN)
    keep(shot, "trajectories_first_screen.png")
    cells = matching(image, CELL_COLOURS).sum(axis=1)
    assert runs(cells >= CELL_PIXELS_PER_BACKEND * len(BACKENDS)) == len(CASES)
    assert matching(image, (PASS_BANNER,)).sum() >= MIN_BANNER_PIXELS


def test_each_case_figure_paints(fakes: Path, tmp_path: Path) -> None:
    """The self-contained page, moved away from its figures folder, paints each case's figure:
    more coloured pixels than the same page with its images removed."""
    browser = chromium()
    html = written_report(fakes).read_text()
    alone, bare = tmp_path / "alone.html", tmp_path / "bare.html"
    alone.write_text(html)
    bare.write_text(re.sub(r'src="data:image/png;base64,[^"]*"', 'src=""', html))
    figures = html.count('class="trajectory-figure"')
    assert figures == len(CASES)
    painted = coloured_pixels(browser, alone, tmp_path / "alone.png", tmp_path)
    without = coloured_pixels(browser, bare, tmp_path / "bare.png", tmp_path)
    assert painted - without > figures * MIN_PIXELS_PER_FIGURE, (painted, without)
