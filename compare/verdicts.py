"""Which backend verdicts turn a run red (shared by the CLI, the API and the pytest plugin).

Kept apart from :mod:`mechcheck.run` so that reading these names imports nothing heavy.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import get_args

from mechcheck.analytic.solution import Status

#: Every verdict a backend can give instead of ``ok``.
VERDICTS: tuple[str, ...] = tuple(s for s in get_args(Status) if s != "ok")

#: Backend verdicts that turn a run red unless ``--fail-on`` says otherwise:
#: a simulator that never settled, or a backend that crashed, means the check
#: did not happen. ``singular`` (an expected outcome at a change point),
#: ``indeterminate`` (friction reversing at the pose), ``not_applicable`` and
#: ``no_solution`` (self-locking) are reported only.
DEFAULT_FAIL_ON: tuple[str, ...] = ("not_settled", "error")

#: ``progress(done, total, label)``, called after each backend run.
Progress = Callable[[int, int, str], None]
