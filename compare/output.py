"""Writing outputs atomically: a failed run never leaves half a table."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Mapping
from pathlib import Path


def write_all(directory: Path, files: Mapping[str, str | bytes]) -> None:
    """Write every file to a temporary name first, then rename them all into place.

    Each rename is atomic, and all renames happen only after every file has
    been written completely, so an error while rendering or writing leaves
    the previous outputs (if any) untouched.
    """
    directory.mkdir(parents=True, exist_ok=True)
    staged: list[tuple[str, Path]] = []
    try:
        for name, content in files.items():
            fd, tmp = tempfile.mkstemp(prefix=f".{name}.", dir=directory)
            with os.fdopen(fd, "wb") as handle:
                handle.write(content.encode() if isinstance(content, str) else content)
            staged.append((tmp, directory / name))
    except BaseException:
        for tmp, _ in staged:
            os.unlink(tmp)
        raise
    for tmp, final in staged:
        os.replace(tmp, final)
