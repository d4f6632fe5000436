"""JUnit XML for CI dashboards: one test case per comparison, one per non-ok verdict.

A comparison outside tolerance is a ``<failure>``; a verdict listed in
``--fail-on`` (e.g. ``not_settled``) is a ``<failure>`` too; other verdicts
(``singular``, ``not_applicable`` …) are ``<skipped>`` with their message.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Iterable

import pandas as pd

from mechcheck.run import RunResult

#: (case, backend, θ12 in degrees or NaN, status, message)
Verdict = tuple[str, str, float, str, str]


def _label(name: str, theta: float) -> str:
    return name if math.isnan(theta) else f"{name}@{theta:g}deg"


def junit_document(comparison: pd.DataFrame, verdicts: Iterable[Verdict],
                   fail_on: tuple[str, ...], seconds: float, suite_name: str = "mechcheck") -> str:
    """The JUnit XML text for comparison rows and backend verdicts."""
    suite = ET.Element("testsuite", name=suite_name)
    failures = skipped = tests = 0
    for row in comparison.to_dict("records"):
        tests += 1
        theta = float(row["theta12"]) if "theta12" in row else math.nan
        case = ET.SubElement(suite, "testcase", classname=_label(str(row["case"]), theta),
                             name=f"{row['backend']}:{row['quantity']}")
        if not row["passed"]:
            failures += 1
            ET.SubElement(case, "failure", message=(
                f"{row['quantity']} = {row['value']:.9g}, analytic {row['reference']:.9g}: "
                f"relative error {row['rel_err']:.2e} > tolerance {row['tolerance']:.1e}"))
    for case_name, backend, theta, status, message in verdicts:
        tests += 1
        case = ET.SubElement(suite, "testcase", classname=_label(case_name, theta),
                             name=f"{backend}:verdict")
        failing = status in fail_on
        failures += failing
        skipped += not failing
        ET.SubElement(case, "failure" if failing else "skipped", message=f"{status}: {message}")
    suite.set("tests", str(tests))
    suite.set("failures", str(failures))
    suite.set("skipped", str(skipped))
    suite.set("time", f"{seconds:.3f}")
    ET.indent(suite)
    return '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(suite, encoding="unicode") + "\n"


def junit_xml(result: RunResult) -> str:
    """A ``mechcheck run`` as JUnit XML."""
    verdicts = [(s.case, s.backend, math.nan, s.status, s.message)
                for s in result.solutions if s.status != "ok"]
    return junit_document(result.detail, verdicts, result.fail_on, result.wall_time_s)


def junit_sweep_xml(comparison: pd.DataFrame, statuses: pd.DataFrame, fail_on: tuple[str, ...],
                    seconds: float) -> str:
    """A ``mechcheck sweep`` as JUnit XML (test cases named case@θ12)."""
    bad = statuses[statuses["status"] != "ok"]
    verdicts = [(str(c), str(b), float(t), str(s), "") for c, b, t, s in zip(
        bad["case"], bad["backend"], bad["theta12"].to_numpy(dtype=float), bad["status"],
        strict=True)]
    return junit_document(comparison, verdicts, fail_on, seconds, "mechcheck-sweep")
