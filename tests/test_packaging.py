"""What installs: one import namespace, a fast command line, software versions looked up once."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
import sysconfig
import tomllib
from pathlib import Path

import pytest

import mechcheck
from mechcheck.sweep import software_versions

REPO = Path(__file__).resolve().parents[1]


def test_one_top_level_package_from_the_installation() -> None:
    """The tests import the installed ``mechcheck`` (from the interpreter's site-packages,
    wherever its environment lives: README's commands put ``.venv`` inside the clone);
    the repository's folders are not packages."""
    installed = Path(sysconfig.get_paths()["purelib"]).resolve()
    assert installed in Path(mechcheck.__file__).resolve().parents
    assert Path(mechcheck.__file__).resolve().parent != REPO / "compare"
    for folder in ("analytic", "compare", "sim_models", "builtin", "strategies", "reference_solver"):
        assert importlib.util.find_spec(folder) is None, folder


def test_every_source_package_is_packaged() -> None:
    """Each folder with an ``__init__.py`` is listed in pyproject's ``packages``, under its
    mapped name, so that a plain ``pip install .`` ships it."""
    tool = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]
    folders = {folder: package for package, folder in tool["package-dir"].items()}
    found = set()
    for root, package in folders.items():
        for init in (REPO / root).rglob("__init__.py"):
            parts = init.parent.relative_to(REPO / root).parts
            found.add(".".join((package, *parts)))
    assert found == set(tool["packages"])


@pytest.mark.parametrize("args", [["--help"], ["backends"]])
def test_fast_commands_import_nothing_heavy(args: list[str]) -> None:
    """`mechcheck --help` and `mechcheck backends` import neither numpy, pandas, matplotlib,
    mujoco nor pymunk (benchmarks/bench_startup.py times them)."""
    probe = ("import sys\nfrom mechcheck.cli import app\n"
             f"app({args!r}, standalone_mode=False)\n"
             "print('heavy:' + ','.join(m for m in ('numpy', 'pandas', 'matplotlib', 'mujoco', 'pymunk') "
             "if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    assert done.stdout.splitlines()[-1] == "heavy:", done.stdout


def test_python_m_mechcheck_is_the_command_line() -> None:
    """`python -m mechcheck` runs the same command line as the console script."""
    done = subprocess.run([sys.executable, "-m", "mechcheck", "backends"], capture_output=True,
                          text=True, check=True)
    assert done.stdout.startswith("analytic")


def test_software_versions_are_looked_up_once() -> None:
    """Every sweep task's digest reuses one look-up of the installed versions."""
    assert software_versions() is software_versions()
    assert any(v.startswith("mechcheck=") for v in software_versions())
