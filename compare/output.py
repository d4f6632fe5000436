"""Writing outputs: atomically, with the user's permissions, to places checked before any
computing, under file names that are safe whatever a case is called."""

from __future__ import annotations

import hashlib
import os
import tempfile
from collections.abc import Mapping
from pathlib import Path

#: The longest file-name stem derived from a case name. File systems allow 255 bytes;
#: the stem shares a name with a backend, a chunk number and a digest.
MAX_STEM = 80


class OutputError(OSError):
    """An output path that cannot be written: one line naming the option and the path."""


def _umask() -> int:
    # The only portable way to read the umask is to set it; set it straight back.
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_all(directory: Path, files: Mapping[str, str | bytes]) -> None:
    """Write every file to a temporary name first, then rename them all into place.

    Each rename is atomic, and all renames happen only after every file has
    been written completely, so an error while rendering or writing leaves
    the previous outputs (if any) untouched. The files get the mode an ordinary
    ``open`` would give them (0666 less the umask), not mkstemp's private 0600.
    """
    directory.mkdir(parents=True, exist_ok=True)
    mode = 0o666 & ~_umask()
    staged: list[tuple[str, Path]] = []
    try:
        for name, content in files.items():
            fd, tmp = tempfile.mkstemp(prefix=f".{name[:MAX_STEM]}.", dir=directory)
            staged.append((tmp, directory / name))
            with os.fdopen(fd, "wb") as handle:
                handle.write(content.encode() if isinstance(content, str) else content)
            os.chmod(tmp, mode)
    except BaseException:
        for tmp, _ in staged:
            os.unlink(tmp)
        raise
    for tmp, final in staged:
        os.replace(tmp, final)


def check_writable_directory(path: Path, option: str) -> None:
    """Raise :class:`OutputError` unless files can be written in ``path`` (made if missing).

    Called before any computing, so that an unusable ``--out`` costs nothing.
    """
    if path.exists() and not path.is_dir():
        raise OutputError(f"{option} {path}: exists and is not a directory")
    try:
        path.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=path):
            pass
    except OSError as error:
        raise OutputError(f"{option} {path}: cannot write there: "
                          f"{error.strerror or error}") from None


def check_writable_file(path: Path, option: str) -> None:
    """Raise :class:`OutputError` unless a file can be written at ``path``."""
    if path.is_dir():
        raise OutputError(f"{option} {path}: is a directory; give a file name")
    check_writable_directory(path.parent, option)


def file_stem(name: str) -> str:
    """A file-name stem for a case name: the name itself when short, else its head and a
    digest of the whole, so that it stays unique and within any file system's limit.
    (Case names hold only letters, digits, ``-`` and ``_``.)"""
    if len(name) <= MAX_STEM:
        return name
    return f"{name[:MAX_STEM - 17]}-{hashlib.sha256(name.encode()).hexdigest()[:16]}"
