"""Where sweeps run: in-process, local processes, or an existing Dask cluster.

All three are ``concurrent.futures.Executor`` s, so :func:`mechcheck.sweep.run_sweep`
does not know which it got.

Local worker processes never outlive the sweep: an interrupted sweep (Ctrl-C,
SIGTERM, an error) terminates them at once, and each worker watches its parent
and exits when the parent is gone, however it died (SIGKILL included).
"""

from __future__ import annotations

import os
import signal
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the command line imports this module; the pool only when it sweeps
    from concurrent.futures import Executor

#: How often a worker checks that the sweep that started it still runs, s.
PARENT_POLL_S = 0.5


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by someone else: pid reused; treat as gone
        return False
    return True


def _watch_parent(parent: int) -> None:
    """Worker initializer: a daemon thread that ends the worker once ``parent`` is gone.

    A killed parent cannot shut its pool down, so the worker must notice by itself:
    it is re-parented (its parent pid changes) or the parent pid no longer exists.
    """
    # A forked worker inherits the sweep's signal handlers: it must die of the SIGTERM
    # its pool sends, and leave Ctrl-C to the parent, which then terminates it.
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    original = os.getppid()

    def watch() -> None:
        while True:
            time.sleep(PARENT_POLL_S)
            if os.getppid() != original or not _alive(parent):
                os._exit(1)

    threading.Thread(target=watch, name="mechcheck-parent-watch", daemon=True).start()


#: The most local worker processes a sweep may ask for, per core: beyond a few per core
#: they only queue for the cores, each holding its own simulators in memory, so a larger
#: ``--workers`` is far more likely a typo than a plan.
MAX_WORKERS_PER_CORE = 4

#: How long a sweep waits for the ``--dask`` scheduler to answer, s: long enough for a
#: scheduler across a network, short enough that a wrong address is reported promptly.
DASK_CONNECT_TIMEOUT_S = 5.0


class ExecutorUnavailable(Exception):
    """``--workers`` or ``--dask`` cannot be used: one line naming the option and value."""


def max_workers() -> int:
    """The largest ``--workers`` this machine accepts."""
    return MAX_WORKERS_PER_CORE * (os.cpu_count() or 1)


def check_workers(workers: int | None) -> None:
    """Raise :class:`ExecutorUnavailable` unless ``workers`` is None (one per core) or
    0 … :func:`max_workers`."""
    if workers is not None and not 0 <= workers <= max_workers():
        raise ExecutorUnavailable(
            f"--workers {workers}: must be 0 (in this process) to {max_workers()} "
            f"({MAX_WORKERS_PER_CORE} per core of this machine)")


@contextmanager
def _dask_executor(address: str) -> Iterator[Executor]:
    try:
        from distributed import Client  # optional dependency: only for --dask
    except ImportError:
        raise ExecutorUnavailable(f"--dask {address}: needs the 'distributed' package "
                                  "(pip install 'mechcheck[dask]')") from None
    try:
        client = Client(address, timeout=DASK_CONNECT_TIMEOUT_S)
    except OSError as error:  # nothing answers there, or not in time
        raise ExecutorUnavailable(f"--dask {address}: cannot connect to a scheduler within "
                                  f"{DASK_CONNECT_TIMEOUT_S:g} s ({error})") from None
    except (ValueError, TypeError) as error:
        raise ExecutorUnavailable(f"--dask {address}: not a scheduler address ({error})") from None
    with client:
        yield client.get_executor()


@contextmanager
def executor_for(workers: int | None = None, dask_address: str | None = None,
                 tasks: int | None = None) -> Iterator[Executor]:
    """An executor: Dask's when an address is given, else ``workers`` local processes
    (default: one per core; never more than ``tasks``), or the calling process itself for
    ``workers = 0``. :class:`ExecutorUnavailable` for a scheduler that does not answer
    within :data:`DASK_CONNECT_TIMEOUT_S`."""
    if dask_address:
        with _dask_executor(dask_address) as executor:
            yield executor
        return
    if workers == 0:
        from mechcheck.sweep import LocalExecutor

        yield LocalExecutor()
        return
    from concurrent.futures import ProcessPoolExecutor

    count = workers or os.cpu_count() or 1
    if tasks is not None:
        count = max(1, min(count, tasks))
    pool = ProcessPoolExecutor(max_workers=count,
                               initializer=_watch_parent, initargs=(os.getpid(),))
    try:
        yield pool
    except BaseException:
        # Interrupted or failed: stop now rather than after the queued and running tasks.
        # (The pool forgets its processes on shutdown: take them first. Python 3.14 has
        # terminate_workers(); 3.11 needs the attribute.)
        processes = list((getattr(pool, "_processes", None) or {}).values())
        pool.shutdown(wait=False, cancel_futures=True)
        for process in processes:
            process.terminate()
        raise
    pool.shutdown(wait=True)
