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
from concurrent.futures import Executor, ProcessPoolExecutor
from contextlib import contextmanager

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


@contextmanager
def executor_for(workers: int | None = None, dask_address: str | None = None) -> Iterator[Executor]:
    """An executor: Dask's when an address is given, else ``workers`` local processes
    (default: one per core), or the calling process itself for ``workers = 0``."""
    if dask_address:
        from distributed import Client  # optional dependency: only for --dask

        with Client(dask_address) as client:
            yield client.get_executor()
        return
    if workers == 0:
        from mechcheck.sweep import LocalExecutor

        yield LocalExecutor()
        return
    pool = ProcessPoolExecutor(max_workers=workers or os.cpu_count() or 1,
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
