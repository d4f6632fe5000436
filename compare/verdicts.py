"""Which backend verdicts turn a run red (shared by the CLI, the API and the pytest plugin).

Kept apart from :mod:`mechcheck.run` so that reading these names imports nothing heavy.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
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


#: How many cases a verdict names in the one-line summary before it says how many more.
NAMED_CASES = 3


def without_numbers(outcomes: Iterable[tuple[str, str]]) -> str:
    """Every verdict that gave no number, as the one-line summaries name it: its count and
    the cases it came in (``no_solution ×7 (locking-fourbar)``), in the order of
    :data:`VERDICTS`; empty when every outcome is ``ok``. ``outcomes`` are (status, case)
    pairs, one per backend run (or per pose of a sweep)."""
    found: dict[str, dict[str, None]] = {}   # a dict keeps the cases in their first order
    counts: dict[str, int] = {}
    for status, case in outcomes:
        if status != "ok":
            found.setdefault(status, {})[case] = None
            counts[status] = counts.get(status, 0) + 1
    parts = []
    for status in sorted(found, key=lambda s: VERDICTS.index(s) if s in VERDICTS else len(VERDICTS)):
        cases = list(found[status])
        named = ", ".join(cases[:NAMED_CASES])
        if len(cases) > NAMED_CASES:
            named += f" and {len(cases) - NAMED_CASES} more"
        parts.append(f"{status} ×{counts[status]} ({named})")
    return ", ".join(parts)
