"""The packages' layering: ``analytic`` imports neither the harness nor a simulator, and its
modules import each other without a cycle (no module needs another that needs it back)."""

from __future__ import annotations

import ast
from pathlib import Path

import mechcheck
import mechcheck.analytic

ANALYTIC = Path(mechcheck.analytic.__file__).parent


def graph() -> dict[str, set[str]]:
    modules = {f"mechcheck.analytic.{p.stem}": p for p in ANALYTIC.glob("*.py") if p.stem != "__init__"}
    out = {}
    for name, path in modules.items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        typing_only = {id(n) for node in ast.walk(tree) if isinstance(node, ast.If)
                       and "TYPE_CHECKING" in ast.unparse(node.test) for n in ast.walk(node)}
        deps = set()
        for node in ast.walk(tree):
            if id(node) in typing_only:
                continue
            if isinstance(node, ast.ImportFrom) and node.module:
                deps.add(node.module)
                deps.update(f"{node.module}.{a.name}" for a in node.names)
        out[name] = {d for d in deps if d in modules}
    return out


def test_analytic_imports_nothing_outside_itself() -> None:
    """``sim_models`` and the harness depend on ``analytic``, never the reverse."""
    for path in ANALYTIC.glob("*.py"):
        text = path.read_text(encoding="utf-8")
        for banned in ("mechcheck.sim_models", "import mujoco", "import pymunk",
                       "from mechcheck.casefile", "from mechcheck.tables", "from mechcheck.run"):
            assert banned not in text, (path.name, banned)


def test_analytic_modules_import_each_other_without_a_cycle() -> None:
    """No chain of imports (at run time, late imports included) leads back to its start:
    the old circle case → assembly → kinematics → case is gone."""
    deps = graph()
    state: dict[str, int] = {}

    def visit(node: str, path: list[str]) -> None:
        state[node] = 1
        for nxt in sorted(deps[node]):
            assert state.get(nxt) != 1, " → ".join([*path, node, nxt])
            if nxt not in state:
                visit(nxt, [*path, node])
        state[node] = 2

    for module in sorted(deps):
        if module not in state:
            visit(module, [])


def test_the_harness_reaches_simulators_only_through_sim_models() -> None:
    """No module of the harness (``compare/``, the studies included) imports a simulator:
    it reaches MuJoCo and pymunk through ``mechcheck.sim_models`` (issue 12), so a simulator
    is one package there."""
    harness = Path(mechcheck.__file__).parent
    for path in harness.rglob("*.py"):
        if path.relative_to(harness).parts[0] == "sim_models":  # installed: a subfolder
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import)
                     else [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            for name in names:
                assert name.split(".")[0] not in ("mujoco", "pymunk"), (path.name, name)
