"""JUnit XML for CI dashboards: one test case per comparison, one per backend verdict.

A comparison outside tolerance is a ``<failure>``; a verdict listed in
``--fail-on`` (e.g. ``not_settled``) is a ``<failure>`` too; other verdicts
(``singular``, ``not_applicable`` …) are ``<skipped>`` with their message.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

from compare.run import RunResult


def junit_xml(result: RunResult, suite_name: str = "mechcheck") -> str:
    """The run as a JUnit XML document."""
    suite = ET.Element("testsuite", name=suite_name)
    failures = skipped = tests = 0
    for row in result.detail.to_dict("records"):
        tests += 1
        case = ET.SubElement(suite, "testcase", classname=str(row["case"]),
                             name=f"{row['backend']}:{row['quantity']}")
        if not row["passed"]:
            failures += 1
            ET.SubElement(case, "failure", message=(
                f"{row['quantity']} = {row['value']:.9g}, analytic {row['reference']:.9g}: "
                f"relative error {row['rel_err']:.2e} > tolerance {row['tolerance']:.1e}"))
    for s in result.solutions:
        if s.status == "ok":
            continue
        tests += 1
        case = ET.SubElement(suite, "testcase", classname=s.case, name=f"{s.backend}:verdict")
        if s.status in result.fail_on:
            failures += 1
            ET.SubElement(case, "failure", message=f"{s.status}: {s.message}")
        else:
            skipped += 1
            ET.SubElement(case, "skipped", message=f"{s.status}: {s.message}")
    suite.set("tests", str(tests))
    suite.set("failures", str(failures))
    suite.set("skipped", str(skipped))
    suite.set("time", f"{result.wall_time_s:.3f}")
    ET.indent(suite)
    return '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(suite, encoding="unicode") + "\n"
