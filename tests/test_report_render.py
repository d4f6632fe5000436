"""The HTML report as a person sees it: headless Chromium renders it with its figures.

The screenshot is written to pytest's temporary directory and not shipped.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import matplotlib.image as mpimg
import pytest
from typer.testing import CliRunner

from mechcheck.cli import app

#: Chromium flags for a closed network and a root user (see the machine notes).
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--hide-scrollbars"]
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
    subprocess.run([browser, *FLAGS, f"--user-data-dir={tmp_path / 'profile'}",
                    f"--screenshot={shot}", "--window-size=1280,4000", page.as_uri()],
                   check=True, capture_output=True, timeout=120)
    image = mpimg.imread(shot)[..., :3]
    return int(((image.max(axis=-1) - image.min(axis=-1)) > SATURATION).sum())
