"""``mechcheck study``: run studies, write their data, figures and report."""

from __future__ import annotations

import base64
import sys
import time
from collections.abc import Iterator
from pathlib import Path

from mechcheck.output import write_all
from mechcheck.report import _ENV
from mechcheck.studies import run_study


def run_studies(names: list[str], out: Path, *, quick: bool = False) -> Iterator[str]:
    """Run each study, then write everything at once; yields a line per study."""
    views, figures, data = [], {}, {}
    for name in names:
        start = time.perf_counter()
        print(f"running study {name} …", file=sys.stderr)
        result = run_study(name, quick)
        seconds = time.perf_counter() - start
        figures[f"{name}.png"] = result.figure
        data[f"{name}.csv"] = result.data.to_csv(index=False)
        views.append({"name": name, "title": result.title, "question": result.question,
                      "conclusion": result.conclusion, "method": result.method,
                      "seconds": seconds,
                      "figure_b64": base64.b64encode(result.figure).decode()})
        yield f"{result.title} ({seconds:.1f} s): {result.conclusion}"
    model = {"title": "mechcheck assumption studies", "studies": views}
    write_all(out / "figures", figures)
    write_all(out / "data", data)
    write_all(out, {"studies.md": _ENV.get_template("studies.md.j2").render(**model),
                    "studies.html": _ENV.get_template("studies.html.j2").render(**model)})
