"""The examples in the installed package's docstrings run and print what they show."""

from __future__ import annotations

import doctest
import importlib
import importlib.util
import pkgutil
from pathlib import Path

import pytest

import mechcheck


def modules_with_examples() -> list[str]:
    names = [m.name for m in pkgutil.walk_packages(mechcheck.__path__, "mechcheck.")]
    out = []
    for name in ["mechcheck", *names]:
        spec = importlib.util.find_spec(name)
        if spec and spec.origin and ">>>" in Path(spec.origin).read_text(encoding="utf-8"):
            out.append(name)
    return out


@pytest.mark.parametrize("name", modules_with_examples())
def test_docstring_examples(name: str) -> None:
    """Every ``>>>`` example in the module's docstrings gives the output written under it."""
    result = doctest.testmod(importlib.import_module(name), optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0
