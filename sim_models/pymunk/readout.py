"""The quantity table every pymunk module passes around (:data:`Values`), and
:class:`Readout`, which reads a model's reactions.

A settling run compares the reactions of consecutive steps (:mod:`.settle`), so it reads
them every step. :class:`Readout` is compiled once per model
(:func:`.linkage_model.compile_readout`): it keeps a pointer to every accumulated impulse
(:func:`._fast.impulse_cells`), so the stop rule's reading (:meth:`Readout.impulses`) is
one cffi index per impulse component, and the named table (:meth:`Readout.values`) is made
only when a run reports.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Protocol

import pymunk

from mechcheck.sim_models.pymunk._fast import Cell, read, write

Values = dict[str, float]


def turned(axis: tuple[float, float], phi: float) -> tuple[float, float]:
    """``axis`` (a direction fixed in a body) once the body has turned by ``phi``."""
    c, s = math.cos(phi), math.sin(phi)
    return c * axis[0] - s * axis[1], s * axis[0] + c * axis[1]


def along_and_across(fx: float, fy: float, axis: tuple[float, float]) -> tuple[float, float, float]:
    """A force split into its component along a unit ``axis`` and the rest: (along, x, y)."""
    ux, uy = axis
    along = fx * ux + fy * uy
    return along, fx - along * ux, fy - along * uy


@dataclass(frozen=True)
class HeldSlide:
    """A driven sliding joint (prismatic, or a pin in a slot), held by a pivot (impulse
    ``cells``) whose force at ``at`` splits into the driver's effort Q along the axis and
    the reaction F across it (LINKAGES.md: F excludes any driver effort); ``body`` is
    links[0], ``axis`` the slide's direction in it."""

    name: str
    cells: tuple[Cell, Cell]
    body: pymunk.Body
    axis: tuple[float, float]

    def split(self, dt: float) -> tuple[float, float, float]:
        """(Q, F_x, F_y) of the last step, its impulse / ``dt``."""
        x, y = read(self.cells)
        return along_and_across(x / dt, y / dt, turned(self.axis, self.body.angle))


class MeshReading(Protocol):
    """A gear mesh's tooth force and its parts (:class:`.gear_mesh.ToothContact`)."""

    def reactions(self, dt: float) -> dict[str, float]: ...


class MemberReading(Protocol):
    """An elastic member's sliding end: its joint's whole force, the groove's impulse plus
    the spring's (:class:`.members.MemberEnd`)."""

    def reactions(self, dt: float) -> dict[str, float]: ...


@dataclass(frozen=True)
class Readout:
    """A model's reactions: ``forces`` (impulse cells of F components), ``couples`` (of M
    and Q of gears), ``springs`` (each with whether it is torsional), ``held`` slides,
    ``meshes`` (gear meshes: their tooth force, read from a pin's impulse along its
    direction, and its parts; the impulse itself is among ``forces``), ``members`` (elastic
    members' sliding ends: the joint's force, groove and spring together; the groove's
    impulse is among ``forces``, the spring's ``N_`` among ``springs``), reported as the
    quantities ``names`` (in this order) of a step of ``dt``; ``length`` is what a couple is
    divided by to compare it with a force."""

    names: tuple[str, ...]
    dt: float
    length: float
    forces: tuple[tuple[str, Cell], ...]
    couples: tuple[tuple[str, Cell], ...]
    springs: tuple[tuple[str, pymunk.Constraint, bool], ...]
    held: tuple[HeldSlide, ...]
    meshes: tuple[MeshReading, ...] = ()
    members: tuple[MemberReading, ...] = ()

    @cached_property
    def _cells(self) -> tuple[tuple[Cell, ...], tuple[Cell, ...]]:
        """The force and the couple cells alone, for :meth:`impulses`."""
        return tuple(c for _, c in self.forces), tuple(c for _, c in self.couples)

    @cached_property
    def warm(self) -> tuple[Cell, ...]:
        """Every accumulated impulse Chipmunk carries from one step to the next as its warm
        start (pivots', grooves', gears' and held slides' jAcc; springs keep none)."""
        forces, couples = self._cells
        return (*forces, *couples, *(cell for slide in self.held for cell in slide.cells))

    def accumulated(self) -> list[float]:
        """The warm-start impulses (:attr:`warm`) now, N·s or N·m·s."""
        return read(self.warm)

    def carry(self, impulses: list[float]) -> None:
        """Make ``impulses`` (one per :attr:`warm` cell) the warm start of the next step."""
        write(self.warm, impulses)

    def impulses(self) -> list[float]:
        """What the stop rule compares from step to step: every reaction's impulse, a
        couple's divided by ``length`` (N·s, in no particular order; a spring's sign
        flipped, which no comparison of sizes or changes sees)."""
        forces, couples = self._cells
        out = read(forces)
        if couples:
            length = self.length
            out += [x / length for x in read(couples)]
        if self.springs:
            out += [s.impulse / self.length if torsional else s.impulse
                    for _, s, torsional in self.springs]
        for slide in self.held:
            out += slide.split(1.0)  # the impulse itself
        return out

    def values(self) -> Values:
        """The last step's reactions by name (N, N·m): impulse / dt, a spring's S the
        negative of its signed impulse on body b."""
        named = (*self.forces, *self.couples)
        table = {name: x / self.dt for (name, _), x in zip(named, read(c for _, c in named), strict=True)}
        table |= {name: -s.impulse / self.dt for name, s, _ in self.springs}
        for slide in self.held:
            q, fx, fy = slide.split(self.dt)
            table |= {f"Q_{slide.name}": q, f"F_{slide.name}_x": fx, f"F_{slide.name}_y": fy}
        for mesh in self.meshes:
            table |= mesh.reactions(self.dt)
        for member in self.members:
            table |= member.reactions(self.dt)
        return {name: table[name] for name in self.names}
