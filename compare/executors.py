"""Where sweeps run: in-process, local processes, or an existing Dask cluster.

All three are ``concurrent.futures.Executor`` s, so :func:`mechcheck.sweep.run_sweep`
does not know which it got.
"""

from __future__ import annotations

import os
from collections.abc import Iterator
from concurrent.futures import Executor, ProcessPoolExecutor
from contextlib import contextmanager


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
    with ProcessPoolExecutor(max_workers=workers or os.cpu_count() or 1) as pool:
        yield pool
