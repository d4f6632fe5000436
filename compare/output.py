"""Writing outputs: atomically, with the user's permissions, to places checked before any
computing, under file names that are safe whatever a case is called; one command at a time
in a folder (:func:`locked_folder`)."""

from __future__ import annotations

import contextlib
import errno
import fcntl
import hashlib
import os
import secrets
import tempfile
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path

#: The longest file-name stem derived from a case name. File systems allow 255 bytes;
#: the stem shares a name with a backend, a chunk number and a digest.
MAX_STEM = 80

#: The file inside an output folder that a running ``mechcheck run`` or ``sweep`` holds an
#: exclusive lock on (``flock``): a second command into the folder is refused, not mixed in.
#: It is empty and stays after the command ends (deleting it would let two commands lock two
#: different files of one name).
LOCK_FILE = ".mechcheck.lock"


#: What ``link`` answers on a file system without hard links (FAT, some network shares).
_NO_HARD_LINKS = frozenset({errno.EPERM, errno.ENOTSUP, errno.EOPNOTSUPP, errno.EMLINK})


class OutputError(OSError):
    """An output path that cannot be written: one line naming the option and the path."""


def _umask() -> int:
    # The only portable way to read the umask is to set it; set it straight back.
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _reason(error: OSError) -> str:
    return error.strerror or str(error)


def _remove(paths: Iterable[Path]) -> None:
    """Delete what can be deleted: a cleanup must not hide the error that called it."""
    for path in paths:
        with contextlib.suppress(OSError):
            path.unlink(missing_ok=True)


def _write_file(fd: int, content: bytes) -> None:
    """Write ``content`` to the open descriptor ``fd`` and close it. Every output byte goes
    through here, so tests make it fail the way a full disk does."""
    with os.fdopen(fd, "wb") as handle:
        handle.write(content)


def _stage(directory: Path, files: Mapping[str, str | bytes]) -> list[tuple[Path, Path]]:
    """Each file written completely under a temporary name: (temporary, final) pairs. On
    failure none of the temporary files is left."""
    mode = 0o666 & ~_umask()
    staged: list[tuple[Path, Path]] = []
    try:
        for name, content in files.items():
            fd, tmp = tempfile.mkstemp(prefix=f".{name[:MAX_STEM]}.", dir=directory)
            staged.append((Path(tmp), directory / name))
            _write_file(fd, content.encode() if isinstance(content, str) else content)
            os.chmod(tmp, mode)
    except BaseException:
        _remove(tmp for tmp, _ in staged)
        raise
    return staged


def _keep_previous(final: Path) -> Path | None:
    """A hard link to the file ``final`` is about to replace, so that it can be put back;
    None where the file system has no hard links (that rename is then not undone)."""
    backup = final.with_name(f".{final.name[:MAX_STEM]}.{secrets.token_hex(4)}.old")
    try:
        os.link(final, backup)
    except OSError as error:
        if error.errno in _NO_HARD_LINKS:
            return None
        raise
    return backup


def _commit(staged: list[tuple[Path, Path]]) -> None:
    """Rename every staged file into place. A rename that fails undoes the ones before it:
    replaced files get their previous version back, new ones are removed, so the folder
    holds the whole previous set and no temporary file."""
    absent = {final for _, final in staged if not os.path.lexists(final)}
    backups: dict[Path, Path] = {}
    renamed: list[Path] = []
    try:
        for _, final in staged:
            if final not in absent and (backup := _keep_previous(final)) is not None:
                backups[final] = backup
        for tmp, final in staged:
            os.replace(tmp, final)
            renamed.append(final)
    except BaseException:
        for final in reversed(renamed):
            with contextlib.suppress(OSError):
                if final in backups:
                    os.replace(backups.pop(final), final)
                elif final in absent:
                    final.unlink()
        raise
    finally:
        _remove([tmp for tmp, _ in staged] + list(backups.values()))


def _made_folders(directory: Path) -> list[Path]:
    """The folders ``directory.mkdir(parents=True)`` would create, deepest first."""
    missing = []
    while not os.path.lexists(directory) and directory != directory.parent:
        missing.append(directory)
        directory = directory.parent
    return missing


def write_all(directory: Path, files: Mapping[str, str | bytes]) -> None:
    """Write every file to a temporary name first, then rename them all into place.

    Each rename is atomic, and all renames happen only after every file has
    been written completely, so an error while rendering or writing leaves
    the previous outputs (if any) untouched; a rename that fails puts back the
    ones before it. A failure (a full disk, a quota, a folder turned read-only)
    raises :class:`OutputError` naming ``directory`` and leaves no temporary file
    and no folder it made. The files get the mode an ordinary ``open`` would give
    them (0666 less the umask), not mkstemp's private 0600.
    """
    made = _made_folders(directory)
    try:
        directory.mkdir(parents=True, exist_ok=True)
        _commit(_stage(directory, files))
    except OSError as error:
        for folder in made:
            with contextlib.suppress(OSError):
                folder.rmdir()
        raise OutputError(f"cannot write in {directory}: {_reason(error)}") from None


def _nearest_existing(path: Path) -> Path:
    while not os.path.lexists(path) and path != path.parent:
        path = path.parent
    return path


def check_writable_directory(path: Path, option: str) -> None:
    """Raise :class:`OutputError` unless files can be written in ``path``, or ``path`` can be
    made. Nothing is created: its nearest existing ancestor must be a directory this process
    can write in (probed with an anonymous temporary file, which leaves no name behind).

    Called before any computing, so that an unusable ``--out`` costs nothing.
    """
    if path.exists() and not path.is_dir():
        raise OutputError(f"{option} {path}: exists and is not a directory")
    base = _nearest_existing(path.absolute())
    if not base.is_dir():
        raise OutputError(f"{option} {path}: cannot write there: {base} is not a directory")
    try:
        with tempfile.TemporaryFile(dir=base):
            pass
    except OSError as error:
        raise OutputError(f"{option} {path}: cannot write there: {_reason(error)}") from None


def check_writable_file(path: Path, option: str) -> None:
    """Raise :class:`OutputError` unless a file can be written at ``path``: a device or FIFO
    would be replaced by a regular file, so only a regular file (or none) is accepted."""
    if path.is_dir():
        raise OutputError(f"{option} {path}: is a directory; give a file name")
    if path.exists() and not path.is_file():
        raise OutputError(f"{option} {path}: exists and is not a regular file; give a file name")
    check_writable_directory(path.parent, option)


@contextlib.contextmanager
def locked_folder(path: Path, option: str) -> Iterator[None]:
    """Hold an exclusive lock on the output folder ``path`` (made if missing) while the
    block runs; :class:`OutputError` at once if another command holds it."""
    lock = path / LOCK_FILE
    try:
        path.mkdir(parents=True, exist_ok=True)
        fd = os.open(lock, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o666 & ~_umask())
    except OSError as error:
        raise OutputError(f"{option} {path}: cannot write there: {_reason(error)}") from None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise OutputError(f"{option} {path}: another mechcheck command is writing there "
                              f"(it holds {lock}); wait for it to end or choose another "
                              "folder") from None
        try:
            yield
        finally:
            # Forked sweep workers share this descriptor: unlock explicitly, or the lock
            # would last until the last of them exits.
            fcntl.flock(fd, fcntl.LOCK_UN)
    finally:
        os.close(fd)


def file_stem(name: str) -> str:
    """A file-name stem for a case name: the name itself when short, else its head and a
    digest of the whole, so that it stays unique and within any file system's limit.
    (Case names hold only letters, digits, ``-`` and ``_``.)"""
    if len(name) <= MAX_STEM:
        return name
    return f"{name[:MAX_STEM - 17]}-{hashlib.sha256(name.encode()).hexdigest()[:16]}"
