"""Public assertion helpers: compare a Solution with the analytic reference under
the one tolerance policy, exactly as ``mechcheck run`` does.

Examples
--------
>>> import mechcheck
>>> case = mechcheck.load_cases()[0]
>>> assert_solution_close(case, mechcheck.solve(case, "virtual_work"))
"""

from __future__ import annotations

from mechcheck import backends
from mechcheck.analytic.case import Case
from mechcheck.analytic.solution import Solution
from mechcheck.tables import comparison_rows


def assert_solution_close(case: Case, solution: Solution, reference: Solution | None = None, *,
                          complete: bool = False) -> None:
    """Every quantity ``solution`` reports is within the policy's tolerance of ``reference``.

    ``reference`` defaults to the ``analytic`` backend. With ``complete``, the
    solution must also report every quantity the reference does. The failure
    message names the case, the backend, each quantity, both values with their
    unit, the relative error, the tolerance and the reason for it.
    """
    reference = backends.load(backends.REFERENCE)(case) if reference is None else reference
    where = f"{case.name} [{solution.backend}]"
    if solution.status != "ok":
        raise AssertionError(f"{where}: verdict {solution.status}: {solution.message}")
    missing = set(reference.values) - set(solution.values)
    if complete and missing:
        raise AssertionError(f"{where}: missing quantities {sorted(missing)}")
    rows = comparison_rows(case, reference, solution)
    if not rows:
        raise AssertionError(f"{where}: no quantity in common with the reference")
    bad = [r for r in rows if not r["passed"]]
    if bad:
        lines = [f"{where}: {len(bad)} of {len(rows)} quantities outside tolerance"]
        for r in bad:
            unit = reference.unit(str(r["quantity"]))
            lines.append(
                f"  {r['quantity']}: {r['value']:.12g} {unit} vs analytic {r['reference']:.12g} "
                f"{unit}; relative error {r['rel_err']:.2e} > tolerance {r['tolerance']:.1e} "
                f"({r['case_kind']}: {r['reason']})")
        raise AssertionError("\n".join(lines))
