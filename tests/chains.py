"""Chains of four-bar loops of any length, for scale tests and benchmarks.

Loop k is seed E1's four-bar (SEEDS.md; a1 = 140, a2 = 80, a3 = 100, a4 = 120 mm, drawn at
θ12 = 60°, open branch) moved 140·k mm along x: its input link is the rocker of loop k − 1
(the first loop's is the crank), which carries the next loop's crank pin as E1's crank
carries A. Every loop is in E1's drawn configuration, far from its toggles, so a chain of
any length is as well conditioned as one loop; it has one degree of freedom, driven at
the first crank. Each coupler carries E1's 50 N load at C and each rocker E1's 100 N at D.
"""

from __future__ import annotations

from typing import Any

# E1 drawn at θ12 = 60° (compare/cases/linkages/seed_e1_fourbar.toml derives these).
_A = (40.0, 69.2820323)
_B = (126.62002551, 119.25173492)
_C = (49.01961837, 138.69850358)
_D = (129.96501913, 89.43880119)
PITCH = 140.0


def four_bar_chain(loops: int, *, offset: tuple[float, float] = (0.0, 0.0),
                   scale: float = 1.0, name: str = "chain") -> dict[str, Any]:
    """The ``[[case]]`` table of a chain of ``loops`` four-bar loops (mm), drawn ``scale``
    times E1's size and ``offset`` (mm) from where loop 0's ground pivot would be at the
    origin."""
    ox, oy = offset

    def at(k: int, p: tuple[float, float]) -> list[float]:
        return [scale * (PITCH * k + p[0]) + ox, scale * p[1] + oy]

    points = {"O0": at(0, (0.0, 0.0))}
    links: list[dict[str, Any]] = [{"name": "ground", "points": ["O0"]},
                                   {"name": "crank", "points": ["O0", "A1"]}]
    joints = [{"name": "J_O0", "kind": "revolute", "links": ["ground", "crank"], "at": "O0"}]
    loads = []
    for k in range(1, loops + 1):
        points[f"A{k}"] = at(k - 1, _A)
        points[f"B{k}"] = at(k - 1, _B)
        points[f"C{k}"] = at(k - 1, _C)
        points[f"D{k}"] = at(k - 1, _D)
        points[f"O{k}"] = at(k, (0.0, 0.0))
        links[0]["points"].append(f"O{k}")
        rocker_points = [f"O{k}", f"B{k}", f"D{k}"] + ([f"A{k + 1}"] if k < loops else [])
        links += [{"name": f"coupler{k}", "points": [f"A{k}", f"B{k}", f"C{k}"]},
                  {"name": f"rocker{k}", "points": rocker_points}]
        source = "crank" if k == 1 else f"rocker{k - 1}"
        joints += [
            {"name": f"J_A{k}", "kind": "revolute", "links": [source, f"coupler{k}"], "at": f"A{k}"},
            {"name": f"J_B{k}", "kind": "revolute", "links": [f"coupler{k}", f"rocker{k}"],
             "at": f"B{k}"},
            {"name": f"J_O{k}", "kind": "revolute", "links": ["ground", f"rocker{k}"], "at": f"O{k}"},
        ]
        loads += [{"link": f"coupler{k}", "at": f"C{k}", "force": {"magnitude": 50.0, "angle": 50.0}},
                  {"link": f"rocker{k}", "at": f"D{k}", "force": {"magnitude": 100.0, "angle": 20.0}}]
    return {"name": name, "mechanism": "linkage", "length_unit": "mm", "points": points,
            "links": links, "joints": joints, "drivers": [{"joint": "J_O0", "rotation": 0.0}],
            "loads": loads}


def toml_of(table: dict[str, Any]) -> str:
    """One ``[[case]]`` table as TOML text (the subset the chain uses)."""

    def value(v: Any) -> str:
        if isinstance(v, str):
            return f'"{v}"'
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, int | float):
            return repr(float(v)) if isinstance(v, float) else str(v)
        if isinstance(v, list):
            return "[" + ", ".join(value(x) for x in v) + "]"
        if isinstance(v, dict):
            return "{ " + ", ".join(f"{k} = {value(x)}" for k, x in v.items()) + " }"
        raise TypeError(type(v))

    lines = ["[[case]]"]
    for key, v in table.items():
        if not isinstance(v, dict | list) or (isinstance(v, list) and not v) or (
                isinstance(v, list) and not isinstance(v[0], dict)):
            lines.append(f"{key} = {value(v)}")
    for key, v in table.items():
        if isinstance(v, dict):
            lines.append(f"[case.{key}]")
            lines += [f"{k} = {value(x)}" for k, x in v.items()]
        elif isinstance(v, list) and v and isinstance(v[0], dict):
            for item in v:
                lines.append(f"[[case.{key}]]")
                lines += [f"{k} = {value(x)}" for k, x in item.items()]
    return "\n".join(lines) + "\n"
