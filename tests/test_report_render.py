"""The HTML reports as a person sees them: headless Chromium renders them.

The screenshots are written to pytest's temporary directory. With
``MECHCHECK_SCREENSHOTS=DIR`` the accuracy report's are copied to DIR too: that is how
``reports/screenshots/`` is made.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import matplotlib.image as mpimg
import numpy as np
import pytest
from typer.testing import CliRunner

import mechcheck
from mechcheck.backends import REFERENCE
from mechcheck.cli import app

#: Chromium flags for a closed network and a root user (see the machine notes); sRGB, so that
#: a CSS colour is painted as the same bytes on any machine.
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--hide-scrollbars", "--force-color-profile=srgb"]
#: A pixel is "coloured" when its channels spread by more than this: text, tables and
#: the pale banner stay below it; the figures' plotted lines do not.
SATURATION = 0.3
#: Each four-panel figure paints ~5000 coloured pixels at this size (measured: three
#: figures added 16 000 over the same page without images); a broken image paints none.
MIN_PIXELS_PER_FIGURE = 3000


def chromium() -> str:
    found = shutil.which("chromium") or shutil.which("chromium-browser")
    if found is None:
        if os.environ.get("CI"):
            pytest.fail("Chromium is required in CI (.ci/run installs Debian's chromium)")
        pytest.skip("Chromium is not installed")
    return found


def test_sweep_report_renders_its_figures_in_chromium(tmp_path: Path) -> None:
    """Chromium paints the self-contained sweep report, figures included, from one HTML file."""
    browser = chromium()
    out = tmp_path / "sweep"
    result = CliRunner().invoke(app, ["sweep", "--theta12", "0:360:5", "-b", "virtual_work",
                                      "--workers", "0", "-q", "--out", str(out)])
    assert result.exit_code == 0, result.output
    page = out / "report.html"
    # Self-contained: move it away from its figures folder before opening it.
    alone = tmp_path / "alone.html"
    alone.write_text(page.read_text())
    # The same page with its images removed: what the text and tables alone paint.
    bare = tmp_path / "bare.html"
    bare.write_text(re.sub(r'src="data:image/png;base64,[^"]*"', 'src=""', page.read_text()))
    figures = page.read_text().count('class="sweep-figure"')
    assert figures == 3
    with_figures = coloured_pixels(browser, alone, tmp_path / "screenshot.png", tmp_path)
    without = coloured_pixels(browser, bare, tmp_path / "bare.png", tmp_path)
    assert with_figures - without > figures * MIN_PIXELS_PER_FIGURE, (with_figures, without)


def coloured_pixels(browser: str, page: Path, shot: Path, tmp_path: Path) -> int:
    """Screenshot ``page`` in headless Chromium; count its strongly coloured pixels."""
    image = screenshot(browser, page, shot, tmp_path, "1280,4000")
    return int(((image.max(axis=-1) - image.min(axis=-1)) > SATURATION).sum())


def screenshot(browser: str, page: Path, shot: Path, tmp_path: Path, size: str) -> np.ndarray:
    """``page`` painted by headless Chromium in a window of ``size`` ("width,height"): RGB in
    [0, 1], one row per pixel row."""
    subprocess.run([browser, *FLAGS, f"--user-data-dir={tmp_path / 'profile'}",
                    f"--screenshot={shot}", f"--window-size={size}", page.as_uri()],
                   check=True, capture_output=True, timeout=120)
    return np.asarray(mpimg.imread(shot)[..., :3])


# -- the accuracy report of the built-in suite, as a person first sees it -----------------

#: The first screen a person sees: a laptop's browser window.
FIRST_SCREEN = "1400,900"
#: The matrix's cell colours (report.html.j2, one per band: far, clear, near, fail and
#: failing verdict, verdict, none) and the passing verdict banner's, as sRGB bytes.
CELL_COLOURS = ("#1b7f3b", "#9bdcaa", "#ffc940", "#d62839", "#c9d3e3", "#f3f3f3")
PASS_BANNER = "#dff6e4"
#: A pixel row crosses a row of the matrix when this many of its pixels per backend column
#: have a cell's colour: a cell is ≥ 50 px wide and its text covers less than half of any
#: pixel row; the swatches beside the backends' lines and in the legend (12 px each) are
#: far below it.
CELL_PIXELS_PER_BACKEND = 30
#: The banner spans the page (≥ 1300 × 50 px, less its text) at this window size.
MIN_BANNER_PIXELS = 20_000


@pytest.fixture(scope="module")
def suite_report(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The built-in suite through every available backend, as ``mechcheck run`` writes it."""
    out = tmp_path_factory.mktemp("suite")
    result = CliRunner().invoke(app, ["run", "-q", "--out", str(out)])
    assert result.exit_code == 0, result.output
    return out / "report.html"


def matching(image: np.ndarray, colours: tuple[str, ...]) -> np.ndarray:
    """Where the image has one of ``colours`` (#rrggbb), within one byte per channel."""
    found = np.zeros(image.shape[:2], dtype=bool)
    for colour in colours:
        rgb = np.array([int(colour[i:i + 2], 16) for i in (1, 3, 5)]) / 255
        found |= (np.abs(image - rgb) <= 1.5 / 255).all(axis=-1)
    return found


def runs(rows: np.ndarray) -> int:
    """The number of runs of consecutive True values."""
    return int(np.count_nonzero(np.diff(rows.astype(int), prepend=0) == 1))


def keep(shot: Path, name: str) -> None:
    """Copy a screenshot to ``$MECHCHECK_SCREENSHOTS`` when it is set."""
    folder = os.environ.get("MECHCHECK_SCREENSHOTS")
    if folder:
        Path(folder).mkdir(parents=True, exist_ok=True)
        shutil.copyfile(shot, Path(folder) / name)


def test_the_first_screen_holds_the_verdict_and_every_row_of_the_matrix(
        suite_report: Path, tmp_path: Path) -> None:
    """At 1400 × 900 the built-in suite's report shows the passing verdict banner and the
    whole matrix: one band of cell colours per case, each as wide as the backends' cells."""
    browser = chromium()
    shot = tmp_path / "first_screen.png"
    image = screenshot(browser, suite_report, shot, tmp_path, FIRST_SCREEN)
    keep(shot, "first_screen.png")
    backends = [b for b in mechcheck.available_backends() if b != REFERENCE]
    cells = matching(image, CELL_COLOURS).sum(axis=1)
    matrix_rows = runs(cells >= CELL_PIXELS_PER_BACKEND * len(backends))
    assert matrix_rows == len(mechcheck.load_cases()), matrix_rows
    assert matching(image, (PASS_BANNER,)).sum() >= MIN_BANNER_PIXELS


def test_a_case_section_renders_alone_below_the_first_screen(suite_report: Path,
                                                             tmp_path: Path) -> None:
    """One case's section, the rest of the page hidden, paints its heading, inputs and its
    comparison table with a coloured swatch per compared value, and neither the banner nor
    the matrix (headless Chromium paints nothing when sent to a #fragment, hence the style)."""
    browser = chromium()
    alone = tmp_path / "case.html"
    hide = "<style>body > :not(#case-crank-shaper) { display: none !important; }</style>"
    alone.write_text(suite_report.read_text().replace("</head>", hide + "</head>", 1))
    shot = tmp_path / "case_section.png"
    image = screenshot(browser, alone, shot, tmp_path, FIRST_SCREEN)
    keep(shot, "case_section.png")
    backends = [b for b in mechcheck.available_backends() if b != REFERENCE]
    swatches = matching(image, CELL_COLOURS).sum(axis=1)
    assert matching(image, (PASS_BANNER,)).sum() == 0
    assert runs(swatches >= CELL_PIXELS_PER_BACKEND * len(backends)) == 0  # no matrix
    assert runs(swatches > 0) >= 10  # the table's rows of swatches
    assert (image.min(axis=-1) < 0.5).sum() > 10_000  # text was painted
