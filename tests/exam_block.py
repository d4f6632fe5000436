"""Seed 002's exam Q2 block as a trajectory case file, for the trajectory tests.

A 2 kg block on a horizontal slide between springs k1 = 300 N/m (from the wall W1) and
k2 = 200 N/m (to the wall W2), both unstretched with the block at x = 0 (SEEDS.md;
compare/cases/linkages/exam_q2_mass_springs.toml): m ẍ + (k1 + k2) x = F.
"""

from __future__ import annotations

MASS, STIFFNESS, X0 = 2.0, 300.0 + 200.0, 0.040


def exam_block(name: str = "exam-q2", *, drawn_at: float = 40.0, drivers: str = "",
               extra: str = "", end: float | str = 1.0, outputs: int = 21,
               gravity: bool = True, description: str = "") -> str:
    """The block drawn at ``drawn_at`` mm, with ``drivers`` (TOML of its driver tables),
    ``extra`` tables after the rest, and ``[case.simulate]`` to ``end`` s at ``outputs``
    times."""
    return f"""
[[case]]
name = "{name}"
description = "{description}"
mechanism = "linkage"
length_unit = "mm"
gravity = [0.0, {-9.81 if gravity else 0.0}]
[case.points]
W1 = [-300.0, 0.0]
W2 = [300.0, 0.0]
A = [{drawn_at}, 0.0]
[[case.links]]
name = "ground"
points = ["W1", "W2"]
[[case.links]]
name = "block"
points = ["A"]
[[case.joints]]
name = "slide"
kind = "prismatic"
links = ["ground", "block"]
at = "A"
axis = [1.0, 0.0]
{drivers}
[[case.masses]]
link = "block"
mass = 2.0
com = "A"
[[case.springs]]
name = "k1"
ends = [["ground", "W1"], ["block", "A"]]
stiffness = 300.0
free_length = 300.0
[[case.springs]]
name = "k2"
ends = [["block", "A"], ["ground", "W2"]]
stiffness = 200.0
free_length = 300.0
[case.simulate]
end = {end}
outputs = {outputs}
{extra}
"""


def pushed(force: str) -> str:
    """The slide's driver table: the block 40 mm from its drawing, pushed by ``force``."""
    return f'[[case.drivers]]\njoint = "slide"\ndisplacement = 40.0\nforce = {force}'
