"""Random case files through the command line (issue 10): valid ones never crash it or leave a
non-finite number in a table; malformed ones always get exit 2 and one line."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pandas as pd
from hypothesis import HealthCheck, assume, given, settings, strategies as st
from typer.testing import CliRunner

from mechcheck.cli import app

SETTINGS = settings(max_examples=int(__import__("os").environ.get("MC_EXAMPLES", "40")), deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])

number = st.floats(-500.0, 500.0, allow_nan=False)
positive = st.floats(1.0, 500.0)


def toml_pair(x: float, y: float) -> str:
    return f"[{x!r}, {y!r}]"


@st.composite
def geometry_lines(draw: st.DrawFn, mechanism: str) -> str:
    if mechanism == "four_bar":
        lengths = [draw(positive) for _ in range(4)]
        assume(max(lengths) < 0.98 * (sum(lengths) - max(lengths)))  # some θ12 assembles
        return "".join(f"a{i + 1} = {v!r}\n" for i, v in enumerate(lengths))
    a2, a3 = draw(positive), draw(positive)
    offset = draw(st.floats(-0.9, 0.9)) * (a2 + a3)
    return f"a2 = {a2!r}\na3 = {a3!r}\noffset = {offset!r}\n"


@st.composite
def load_table(draw: st.DrawFn) -> str:
    force = (f"{{ magnitude = {draw(st.floats(0.0, 1e4))!r}, angle = {draw(number)!r} }}"
             if draw(st.booleans()) else f"{{ x = {draw(number)!r}, y = {draw(number)!r} }}")
    return (f"[[case.loads]]\nlink = {draw(st.sampled_from([2, 3, 4]))}\n"
            f"at = {toml_pair(draw(number), draw(number))}\nforce = {force}\n"
            f"torque = {draw(number)!r}\n")


@st.composite
def valid_case_files(draw: st.DrawFn) -> str:
    """A case file CONVENTIONS.md accepts: either mechanism, any pose (assembled or not),
    loads, masses, gravity, motion and friction, in mm or m."""
    mechanism = draw(st.sampled_from(["four_bar", "slider_crank"]))
    branches = ["open", "crossed"] if mechanism == "four_bar" else ["right", "left"]
    omega = draw(st.sampled_from([0.0, draw(st.floats(-40.0, 40.0))]))
    lines = [
        "[[case]]", 'name = "random-case"', f'mechanism = "{mechanism}"',
        f'length_unit = "{draw(st.sampled_from(["m", "mm"]))}"',
        f"theta12 = {draw(st.floats(-720.0, 720.0))!r}",
        f'branch = "{draw(st.sampled_from(branches))}"',
        f"ground_angle = {draw(st.floats(-180.0, 180.0))!r}",
        f"gravity = {toml_pair(draw(st.floats(-20, 20)), draw(st.floats(-20, 20)))}",
    ]
    if mechanism == "four_bar":
        lines.append(f"drive_link = {draw(st.sampled_from([2, 4]))}")
    text = "\n".join(lines) + "\n[case.geometry]\n" + draw(geometry_lines(mechanism))
    for _ in range(draw(st.integers(0, 3))):
        text += draw(load_table())
    for link in draw(st.sets(st.sampled_from([2, 3, 4]))):
        text += (f"[[case.masses]]\nlink = {link}\nmass = {draw(st.floats(0.01, 50.0))!r}\n"
                 f"com = {toml_pair(draw(number), draw(number))}\n"
                 f"inertia = {draw(st.floats(0.0, 1.0))!r}\n")
    text += f"[case.motion]\nomega = {omega!r}\nalpha = {draw(st.floats(-300.0, 300.0))!r}\n"
    if draw(st.booleans()):
        pins = ["A0", "A", "B", "B0"] if mechanism == "four_bar" else ["A0", "A", "B"]
        radii = ", ".join(f"{p} = {draw(st.floats(0.0, 20.0))!r}"
                          # sorted: a set of names walks in PYTHONHASHSEED's order
                          for p in sorted(draw(st.sets(st.sampled_from(pins), min_size=1))))
        sense = "ccw" if omega > 0 else "cw" if omega < 0 else draw(st.sampled_from(["cw", "ccw"]))
        text += (f"[case.friction]\nmu = {draw(st.floats(0.0, 0.4))!r}\npin_radius = {{ {radii} }}\n"
                 f'direction = "{sense}"\n')
    return text


def run_file(path: Path, text: str | bytes, args: list[str]) -> tuple[int, str, list[str]]:
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = CliRunner().invoke(app, ["run", str(path), "-q", *args])
    return result.exit_code, result.stderr, [str(w.message) for w in caught]


@SETTINGS
@given(text=valid_case_files())
def test_random_valid_case_files_never_crash_or_write_a_non_finite_number(
        tmp_path: Path, text: str) -> None:
    """Any valid case file through the analytic backends: exit 0 or 1, nothing on stderr (no
    traceback, no RuntimeWarning), and every number in every table finite."""
    out = tmp_path / "out"
    code, err, caught = run_file(tmp_path / "case.toml", text,
                                 ["-b", "superposition", "-b", "virtual_work", "--out", str(out)])
    assert code in (0, 1), err
    assert err == "" and caught == [], (err, caught)
    for table in ("results.csv", "comparison.csv"):
        numbers = pd.read_csv(out / table).select_dtypes("number").to_numpy(dtype=float)
        assert np.isfinite(numbers).all(), table
    diagnostics = pd.read_csv(out / "diagnostics.csv")
    values = pd.to_numeric(diagnostics["value"], errors="coerce")
    numeric = values[diagnostics["key"] != "message"].dropna()
    # The condition number of a pose with no position is infinite by definition; nothing else.
    others = numeric[diagnostics.loc[numeric.index, "key"] != "condition_number"]
    assert np.isfinite(others.to_numpy(dtype=float)).all()


#: pydantic's own wording, which means nothing to someone writing a case file.
PYDANTIC_PHRASES = ("Input should", "instance of", "after validation", "Field required",
                    "Extra inputs", "valid dictionary")

REQUIRED = ["name", "mechanism", "theta12", "a1", "a2", "a3", "a4"]


@st.composite
def malformed_case_files(draw: st.DrawFn) -> str | bytes:
    """A valid four-bar file with one thing made certainly wrong."""
    base = (
        '[[case]]\nname = "broken"\nmechanism = "four_bar"\ntheta12 = 60.0\n'
        "[case.geometry]\na1 = 140.0\na2 = 80.0\na3 = 100.0\na4 = 120.0\n"
        "[[case.loads]]\nlink = 4\nat = [90.0, 0.0]\nforce = { magnitude = 100.0, angle = 20.0 }\n"
    )
    flaw = draw(st.sampled_from(["drop", "unknown", "value", "syntax", "bytes", "link"]))
    if flaw == "drop":
        key = draw(st.sampled_from(REQUIRED))
        return "\n".join(line for line in base.splitlines() if not line.startswith(f"{key} ="))
    if flaw == "unknown":
        key = draw(st.from_regex(r"[a-z][a-z_]{2,10}", fullmatch=True))
        assume(key not in {"name", "mechanism", "theta12", "branch", "description", "gravity",
                           "drive_link", "length_unit", "ground_angle", "link", "at", "force",
                           "torque"} | set(REQUIRED))
        return base.replace("theta12 = 60.0", f"theta12 = 60.0\n{key} = 1")
    if flaw == "value":
        key = draw(st.sampled_from(["theta12", "a1", "a3", "magnitude"]))
        bad = draw(st.sampled_from(['"sixty"', "true", "[1.0]", "nan", "inf", "-inf", "1e300",
                                    "-5.0", "{ x = 1 }"]))
        if key == "theta12":
            assume(bad != "-5.0")  # a negative angle is fine
        return base.replace(f"{key} = ", f"{key} = {bad} #", 1)
    if flaw == "syntax":
        lines = base.splitlines()
        where = draw(st.integers(0, len(lines) - 1))
        lines.insert(where, draw(st.sampled_from(["[[case", "= 3", "a = = 1", "[case.geometry"])))
        return "\n".join(lines)
    if flaw == "link":
        link = draw(st.sampled_from(["1", "5", "0", "-2", '"x"', "2.5"]))
        return base.replace("link = 4", f"link = {link}")
    junk = draw(st.binary(min_size=1, max_size=8).filter(lambda b: _not_utf8(b)))
    return base.encode()[:40] + junk + base.encode()[40:]


def _not_utf8(data: bytes) -> bool:
    try:
        data.decode("utf-8")
    except UnicodeDecodeError:
        return True
    return False


@SETTINGS
@given(text=malformed_case_files())
def test_random_malformed_case_files_exit_2_with_one_line(tmp_path: Path, text: str | bytes) -> None:
    """Any certainly-broken case file: exit 2, one line naming the file, nothing written."""
    path = tmp_path / "broken.toml"
    out = tmp_path / "out"
    code, err, _ = run_file(path, text, ["--out", str(out)])
    lines = err.strip().splitlines()
    assert code == 2, (code, err)
    assert len(lines) == 1 and lines[0].startswith(f"mechcheck: error: {path}"), err
    assert not any(phrase in lines[0] for phrase in PYDANTIC_PHRASES), lines[0]
    assert not out.exists()
