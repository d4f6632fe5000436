"""The reference pages build with `mkdocs build --strict`: no broken link or anchor."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_the_reference_pages_build_strictly(tmp_path: Path) -> None:
    """mkdocs builds docs/ in strict mode: every page, link and anchor resolves (mkdocs.yml)."""
    built = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
        cwd=ROOT, capture_output=True, text=True, timeout=120, check=False,
    )
    assert built.returncode == 0, built.stderr
    assert (tmp_path / "site" / "case-files" / "index.html").is_file()
