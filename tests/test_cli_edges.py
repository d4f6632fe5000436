"""Unusable inputs, options and output folders at the command line: each is refused with one
line on stderr and exit status 2, promptly, changing nothing (README, "Command line").

Whatever could hang on a regression (a FIFO, /dev/zero, an unreachable scheduler) runs in a
subprocess with a timeout, so that it fails instead of blocking the suite.
"""

from __future__ import annotations

import errno
import fcntl
import os
import socket
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest

from mechcheck import output, sweep as sweep_module
from mechcheck.casefile import MAX_CASE_FILE_BYTES
from mechcheck.executors import MAX_WORKERS_PER_CORE
from mechcheck.output import LOCK_FILE, OutputError, write_all

from .builtin import rocker_load_case
from .test_edges import case_file, one_line, run_cli

#: The quickest sweep: one analytic task of three poses.
QUICK = ["-q", "-b", "analytic", "--workers", "0", "--theta12", "0:30:10"]
#: Long enough for a cold interpreter to import mechcheck and refuse; far below a hang.
TIMEOUT_S = 60


def run_process(args: list[str], timeout: float = TIMEOUT_S) -> subprocess.CompletedProcess[str]:
    """The real command line in its own process; a hang raises TimeoutExpired (and is killed)."""
    return subprocess.run([sys.executable, "-m", "mechcheck", *args], capture_output=True,
                          text=True, timeout=timeout, check=False)


def snapshot(folder: Path) -> dict[str, bytes]:
    """Every file under ``folder`` by relative name, with its bytes."""
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file()}


# -- files that are not case files ----------------------------------------------------------

@pytest.mark.parametrize("command", ["run", "sweep"])
def test_a_fifo_is_refused_without_being_opened(tmp_path: Path, command: str) -> None:
    """A FIFO given as a case file is refused at once (opening it would wait for a writer)."""
    fifo = tmp_path / "pipe.toml"
    os.mkfifo(fifo)
    done = run_process([command, str(fifo), "-q", "--out", str(tmp_path / "o")])
    one_line(done.returncode, done.stderr, str(fifo), "FIFO")
    assert not (tmp_path / "o").exists()


def test_dev_zero_is_refused_without_being_read(tmp_path: Path) -> None:
    """/dev/zero (endless bytes) is refused as a device, not read until memory runs out."""
    done = run_process(["run", "/dev/zero", "-q", "--out", str(tmp_path / "o")])
    one_line(done.returncode, done.stderr, "/dev/zero", "character device")
    assert not (tmp_path / "o").exists()


def test_a_case_file_beyond_the_cap_is_refused_unread(tmp_path: Path) -> None:
    """A file one byte over the cap (sparse: no disk used) is refused by its size, naming the
    cap, which is 64 MiB = 67,108,864 bytes."""
    assert MAX_CASE_FILE_BYTES == 64 * 1024 * 1024
    big = tmp_path / "big.toml"
    with big.open("wb") as handle:
        handle.truncate(MAX_CASE_FILE_BYTES + 1)
    done = run_process(["run", str(big), "-q", "--out", str(tmp_path / "o")])
    one_line(done.returncode, done.stderr, str(big), "67,108,865 bytes", "67,108,864")


@pytest.mark.skipif(not Path("/proc/self/pagemap").exists(), reason="needs Linux /proc")
def test_a_pseudo_file_is_read_no_further_than_the_cap(tmp_path: Path) -> None:
    """/proc/self/pagemap says 0 bytes but reads on for hundreds of GB: the read stops one
    byte past the cap and the file is refused."""
    assert os.stat("/proc/self/pagemap").st_size == 0
    done = run_process(["run", "/proc/self/pagemap", "-q", "--out", str(tmp_path / "o")])
    one_line(done.returncode, done.stderr, "/proc/self/pagemap", "more than 67,108,864 bytes")


def test_an_unreadable_case_file_is_one_line(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A case file the user may not read is refused naming it (as root chmod 000 would not
    stop the read, so the open is made to fail as it would for another user)."""
    locked = case_file(tmp_path, name="locked.toml")
    real = os.open

    def denied(path: str | os.PathLike[str], flags: int, *args: int, **kwargs: int) -> int:
        if Path(path) == locked:
            raise PermissionError(errno.EACCES, "Permission denied", str(path))
        return real(path, flags, *args, **kwargs)

    monkeypatch.setattr(os, "open", denied)
    code, _, err = run_cli(["run", str(locked), "-q", "--out", str(tmp_path / "o")])
    one_line(code, err, str(locked), "permission denied")


def test_the_pytest_plugin_does_not_open_a_fifo(tmp_path: Path) -> None:
    """`pytest --mechcheck` asks whether a .toml holds cases without opening a FIFO: it answers
    at once that it may (so that collecting it reports the CLI's one line)."""
    fifo = tmp_path / "pipe.toml"
    os.mkfifo(fifo)
    code = ("import sys; from pathlib import Path; from mechcheck.pytest_plugin import "
            "_may_hold_cases; print(_may_hold_cases(Path(sys.argv[1])))")
    done = subprocess.run([sys.executable, "-c", code, str(fifo)], capture_output=True,
                          text=True, timeout=TIMEOUT_S, check=False)
    assert done.returncode == 0 and done.stdout.strip() == "True", done.stderr


def test_the_pytest_plugin_refuses_an_oversized_case_file(pytester: pytest.Pytester) -> None:
    """A named case file over the cap is a collection error carrying the CLI's line."""
    big = pytester.path / "big.mechcheck.toml"
    with big.open("wb") as handle:
        handle.truncate(MAX_CASE_FILE_BYTES + 1)
    result = pytester.runpytest("--mechcheck-backend", "virtual_work")
    result.assert_outcomes(errors=1)
    result.stdout.fnmatch_lines(["*mechcheck: error: big.mechcheck.toml: is 67,108,865 bytes*"])


# -- --workers ---------------------------------------------------------------------------

@pytest.mark.parametrize("excess", [False, True])
def test_workers_outside_the_bound_are_refused(tmp_path: Path, excess: bool) -> None:
    """--workers below 0 or above 4 per core is refused naming the option, before any folder
    is made."""
    assert MAX_WORKERS_PER_CORE == 4
    bound = 4 * (os.cpu_count() or 1)
    workers = bound + 1 if excess else -1
    args = ["sweep", str(case_file(tmp_path)), *QUICK[:3], "--theta12", "0:30:10",
            "--workers", str(workers), "--out", str(tmp_path / "o")]
    code, _, err = run_cli(args)
    one_line(code, err, f"--workers {workers}", f"to {bound}")
    assert not (tmp_path / "o").exists()


def test_no_more_local_workers_than_tasks(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A sweep of 2 tasks (one case × analytic and superposition × one chunk of 3 poses) asked
    for the most workers allowed starts 2 processes, not 4 per core."""
    import concurrent.futures

    started: list[int] = []
    real = concurrent.futures.ProcessPoolExecutor

    class Counting(real):  # type: ignore[misc, valid-type]
        def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
            started.append(len(self._processes or {}))
            super().shutdown(wait=wait, cancel_futures=cancel_futures)

    monkeypatch.setattr(concurrent.futures, "ProcessPoolExecutor", Counting)
    most = str(MAX_WORKERS_PER_CORE * (os.cpu_count() or 1))
    code, _, err = run_cli(["sweep", str(case_file(tmp_path)), "-q", "-b", "superposition",
                            "--theta12", "0:30:10", "--workers", most,
                            "--out", str(tmp_path / "o")])
    assert code == 0, err
    assert started == [2]


# -- --dask ------------------------------------------------------------------------------

def test_an_unreachable_dask_scheduler_is_refused_promptly(tmp_path: Path) -> None:
    """A --dask address nothing listens on (a port bound and closed) exits 2 naming the option
    and the address within the 5 s connect timeout (plus start-up), creating nothing."""
    pytest.importorskip("distributed")
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        address = f"tcp://127.0.0.1:{probe.getsockname()[1]}"
    out = tmp_path / "o"
    start = time.monotonic()
    done = run_process(["sweep", str(case_file(tmp_path)), "-q", "-b", "analytic",
                        "--dask", address, "--out", str(out)])
    elapsed = time.monotonic() - start
    one_line(done.returncode, done.stderr, f"--dask {address}")
    assert elapsed < 30, elapsed
    assert not out.exists()


# -- one command per output folder --------------------------------------------------------

@contextmanager
def held_lock(folder: Path) -> Iterator[None]:
    """Hold the folder's lock as another running command would (an open file description
    of this process conflicts with the command's own, as another process's would)."""
    folder.mkdir(parents=True, exist_ok=True)
    fd = os.open(folder / LOCK_FILE, os.O_RDWR | os.O_CREAT)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        yield
    finally:
        os.close(fd)


@pytest.mark.parametrize("command", ["run", "sweep"])
def test_a_locked_output_folder_is_refused_at_once(tmp_path: Path, command: str) -> None:
    """A run or sweep into a folder another command holds exits 2 at once, naming --out and
    the folder, and changes nothing there."""
    path = case_file(tmp_path)
    out = tmp_path / "o"
    args = [command, str(path), *(QUICK if command == "sweep" else ["-q", "-b", "analytic"]),
            "--out", str(out)]
    assert run_cli(args)[0] == 0
    before = snapshot(out)
    with held_lock(out):
        start = time.monotonic()
        code, _, err = run_cli(args + ["--fresh"] * (command == "sweep"))
        assert time.monotonic() - start < 10
    one_line(code, err, f"--out {out}", "another mechcheck command")
    assert snapshot(out) == before


#: Runs `mechcheck` with every sweep task slowed by 3 s, so that it holds its folder a while.
SLOW_SWEEP = """
import sys, time
import mechcheck.sweep as sweep
real = sweep.run_task
def slow(task):
    time.sleep(3)
    return real(task)
sweep.run_task = slow
from mechcheck.cli import main
sys.argv = ["mechcheck", *sys.argv[1:]]
main()
"""


def lock_is_held(folder: Path) -> bool:
    try:
        fd = os.open(folder / LOCK_FILE, os.O_RDWR)
    except FileNotFoundError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return True
    finally:
        os.close(fd)
    return False


def test_two_sweeps_into_one_folder_do_not_mix(tmp_path: Path) -> None:
    """While one sweep runs, a second sweep of another case into its folder is refused; the
    first then finishes (exit 0) with rows of its own case only."""
    import pandas as pd

    out = tmp_path / "o"
    first = subprocess.Popen(
        [sys.executable, "-c", SLOW_SWEEP, "sweep", str(case_file(tmp_path, name="a.toml")),
         *QUICK, "--out", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + TIMEOUT_S
        while not lock_is_held(out) and time.monotonic() < deadline and first.poll() is None:
            time.sleep(0.05)
        assert lock_is_held(out), "the first sweep never locked its folder"
        other = case_file(tmp_path, rocker_load_case("other"), name="b.toml")
        code, _, err = run_cli(["sweep", str(other), *QUICK, "--out", str(out)])
        one_line(code, err, f"--out {out}", "another mechcheck command")
        _, first_err = first.communicate(timeout=TIMEOUT_S)
    finally:
        first.kill()
        first.wait()
    assert first.returncode == 0, first_err
    assert set(pd.read_parquet(out / "results")["case"].astype(str)) == {"demo"}


# -- output paths are checked before any is made -------------------------------------------

@pytest.mark.parametrize("command", ["run", "sweep"])
def test_an_unusable_junit_path_creates_no_out_folder(tmp_path: Path, command: str) -> None:
    """--junit naming a directory, or a FIFO (which a rename would replace), exits 2 before
    --out is made, nested folders included."""
    path = case_file(tmp_path)
    out = tmp_path / "new" / "out"
    fifo = tmp_path / "pipe.xml"
    os.mkfifo(fifo)
    extra = QUICK if command == "sweep" else ["-q", "-b", "analytic"]
    for junit, fragment in ((tmp_path, "is a directory"), (fifo, "not a regular file")):
        code, _, err = run_cli([command, str(path), *extra, "--out", str(out),
                                "--junit", str(junit)])
        one_line(code, err, f"--junit {junit}", fragment)
        assert not (tmp_path / "new").exists()
    assert fifo.is_fifo()


def test_an_out_under_a_file_is_refused_without_making_folders(tmp_path: Path) -> None:
    """An --out whose nearest existing ancestor is a file is refused naming that file; the
    folders above it that did not exist are not made."""
    blocker = tmp_path / "taken"
    blocker.write_text("keep me")
    out = blocker / "a" / "b"
    code, _, err = run_cli(["run", str(case_file(tmp_path)), "-q", "--out", str(out)])
    one_line(code, err, f"--out {out}", f"{blocker} is not a directory")
    assert blocker.read_text() == "keep me"


# -- a disk that fills up or turns read-only while writing -------------------------------------

REAL_WRITE = output._write_file


def failing_writes(after: int, code: int) -> Callable[[int, bytes], None]:
    """A stand-in for the output writer that writes ``after`` files, then fails with
    ``code`` as a full disk (ENOSPC), an exhausted quota (EDQUOT) or a read-only folder does."""
    calls = {"n": 0}

    def write(fd: int, content: bytes) -> None:
        calls["n"] += 1
        if calls["n"] > after:
            os.close(fd)
            raise OSError(code, os.strerror(code))
        REAL_WRITE(fd, content)

    return write


def leftovers(folder: Path) -> list[str]:
    """Temporary or backup files of an interrupted write (the lock file is not one)."""
    return [p.name for p in folder.rglob(".*") if p.name != LOCK_FILE]


def test_a_full_disk_during_a_run_leaves_the_previous_outputs(tmp_path: Path,
                                                             monkeypatch: pytest.MonkeyPatch) -> None:
    """A run whose third output file hits a full disk exits 2 naming the folder; the five
    files of the previous run are byte-identical and no temporary file is left; into a new
    folder, none of the five appears."""
    path = case_file(tmp_path)
    out = tmp_path / "o"
    args = ["run", str(path), "-q", "-b", "virtual_work", "--out", str(out)]
    assert run_cli(args)[0] == 0
    before = snapshot(out)
    monkeypatch.setattr(output, "_write_file", failing_writes(2, errno.ENOSPC))
    code, _, err = run_cli(args)
    one_line(code, err, str(out), "No space left on device")
    assert snapshot(out) == before and leftovers(out) == []
    monkeypatch.setattr(output, "_write_file", failing_writes(2, errno.EDQUOT))
    fresh = tmp_path / "fresh"
    code, _, err = run_cli([*args[:-1], str(fresh)])
    one_line(code, err, str(fresh), "quota")
    assert [p.name for p in fresh.iterdir()] == [LOCK_FILE]


def test_a_folder_turned_read_only_between_renames_keeps_the_whole_old_set(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """If the second of three renames fails (EROFS), the first is undone: the folder holds
    its two previous files unchanged, not the new third, and neither temporary nor backup
    files."""
    write_all(tmp_path, {"a.csv": "old a", "b.csv": "old b"})
    real = os.replace
    calls = {"n": 0}

    def replace(src: str | os.PathLike[str], dst: str | os.PathLike[str]) -> None:
        if Path(dst).parent == tmp_path and Path(src).name.startswith("."):
            calls["n"] += 1
            if calls["n"] == 2:
                raise OSError(errno.EROFS, os.strerror(errno.EROFS), str(dst))
        real(src, dst)

    monkeypatch.setattr(os, "replace", replace)
    with pytest.raises(OutputError, match=f"cannot write in {tmp_path}: Read-only file system"):
        write_all(tmp_path, {"a.csv": "new a", "b.csv": "new b", "c.csv": "new c"})
    assert snapshot(tmp_path) == {"a.csv": b"old a", "b.csv": b"old b"}


def test_a_full_disk_during_a_sweep_keeps_the_finished_parts(tmp_path: Path,
                                                            monkeypatch: pytest.MonkeyPatch) -> None:
    """Ten poses in chunks of two are five tasks of two parts each: a disk full at the
    seventh part exits 2 naming the folder, keeps the three tasks done, leaves no temporary
    file, and the same command then runs the two others and reuses the three."""
    monkeypatch.setattr(sweep_module, "VECTOR_CHUNK", 2)
    out = tmp_path / "o"
    args = ["sweep", str(case_file(tmp_path)), "-q", "-b", "analytic", "--workers", "0",
            "--theta12", "0:10:1", "--no-figures", "--out", str(out)]
    monkeypatch.setattr(output, "_write_file", failing_writes(6, errno.ENOSPC))
    code, _, err = run_cli(args)
    one_line(code, err, str(out / "results"), "No space left on device", "resumes")
    assert len(list((out / "status").glob("*.parquet"))) == 3
    assert len(list((out / "results").glob("*.parquet"))) == 3
    assert leftovers(out) == [] and not (out / "report.md").exists()
    monkeypatch.undo()
    monkeypatch.setattr(sweep_module, "VECTOR_CHUNK", 2)
    code, stdout, err = run_cli(args)
    assert code == 0, err
    assert "2 tasks run, 3 reused" in stdout
