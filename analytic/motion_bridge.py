"""The rates of a linkage of one coordinate across a nearly singular pose, interpolated
along its branch: what the trajectory reference (:class:`.linkage_dynamics.Tracker`) uses
where its constraint Jacobian is too close to singular to give them to the integrator's
tolerance.

Near a change point (a row of parallelograms lying flat: the joints redundant for an
instant) the positions q(x) are closed only to rounding divided by the Jacobian's smallest
singular value σ, along the directions the constraints hardly hold; the rates S = ∂q/∂x
solved at that pose carry that error divided by σ once more, and the accelerations' bias
q̈₀ = B·ẋ² (with one coordinate, J·B = −J̇·S·S) once more again. Along the branch itself S
and B are smooth functions of x, so where σ falls below :data:`SIGMA` they are taken from
the polynomial through their values at poses of a fixed grid on either side
(:data:`NODES` each, spaced :data:`STEP`) where σ is not that small: deterministic and smooth
in x, as the integrator needs, and within the interpolation's error (a polynomial of degree
2·NODES − 1 over a few tenths of a radian) of the exact values.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.polynomial.chebyshev import chebfit, chebval

from mechcheck.analytic.rigid import Array

#: σ_min of the scaled constraint Jacobian (rows and columns in lengths of the linkage's
#: size) below which the rates are interpolated: on the IFToMM N four-bar (40 windows) σ is
#: 5e-4 upright and 5.4e-4·δ at δ rad from flat, and the rounding in the solved
#: accelerations grows like 1/σ³, past 1e-10 of them below σ ≈ 3e-5.
SIGMA = 5e-5
#: The grid of nodes, in the coordinate's unit (rad; the linkage's size for a slide), and
#: the count of nodes taken on each side of a nearly singular pose.
STEP = 0.02
NODES = 4
#: How far (in grid steps) the nodes are looked for on each side before the rates are
#: solved at the pose itself after all (a linkage nearly singular everywhere).
SEARCH = 50

#: The rates S (3n,) and unit bias B (3n,) at a node, or None where σ is too small there.
NodeRates = Callable[[float], "tuple[Array, Array] | None"]


@dataclass
class Bridge:
    """The interpolated rates of one run's branch: nodes solved once and kept by their grid
    index (``exact`` solves one), polynomials kept by their nodes."""

    exact: NodeRates
    unit: float
    _nodes: dict[int, tuple[Array, Array] | None] = field(default_factory=dict)
    _polynomials: dict[tuple[int, ...], Callable[[float], Array]] = field(default_factory=dict)

    def rates(self, x: float) -> tuple[Array, Array] | None:
        """S and B at coordinate x from the polynomial through the nearest usable nodes on
        either side; None where there are not enough within :data:`SEARCH` steps."""
        below = math.floor(x / (STEP * self.unit))
        left = self._usable(below, -1)
        right = self._usable(below + 1, 1)
        if left is None or right is None:
            return None
        key = tuple(left[::-1] + right)
        if key not in self._polynomials:
            self._polynomials[key] = self._polynomial(key)
        found = self._polynomials[key](x)
        half = found.size // 2
        return found[:half], found[half:]

    def _polynomial(self, key: tuple[int, ...]) -> Callable[[float], Array]:
        """The polynomial through the nodes ``key`` (every column of S and B at once), in
        Chebyshev form over the nodes' span: of degree one below their count, it passes
        through each."""
        xs = np.array(key, dtype=float) * STEP * self.unit
        values = np.array([np.concatenate(node) for i in key
                           if (node := self._node(i)) is not None])
        low, high = xs[0], xs[-1]
        coefficients = chebfit((2.0 * xs - low - high) / (high - low), values, len(key) - 1)
        return lambda x: np.asarray(chebval((2.0 * x - low - high) / (high - low),
                                            coefficients), dtype=np.float64)

    def _usable(self, start: int, way: int) -> list[int] | None:
        """The first :data:`NODES` grid indices from ``start`` toward ``way`` whose nodes
        are usable."""
        found: list[int] = []
        for i in range(start, start + way * SEARCH, way):
            if self._node(i) is not None:
                found.append(i)
                if len(found) == NODES:
                    return found
        return None

    def _node(self, i: int) -> tuple[Array, Array] | None:
        if i not in self._nodes:
            self._nodes[i] = self.exact(i * STEP * self.unit)
        return self._nodes[i]
