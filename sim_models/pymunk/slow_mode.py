"""The slow mode of pymunk's constraint solver next to a change point: measured from its own
iterates, and extrapolated.

Chipmunk solves a step's constraints by Gauss–Seidel, warm-started from the impulses the
previous step accumulated. At a fixed pose (the constraint solve that primes a held run,
:func:`.linkage.primed_settle_run`) the impulses x_n after consecutive steps are therefore
the iterates of one linear fixed-point map. Next to a change point one mode of that map
decays far more slowly than the others. Measured on seed E1 at θ12 = 180° − δ, per step of
100 iterations: ρ = 0.99975 at δ = 0.135° (condition number 880), 0.999965 at 0.05°
(2 400), 0.999998 at 0.012° (9 900). The plain iteration needs about 1/(1 − ρ) steps per
e-fold: 4 000 to 500 000.

Once the faster modes have died out, the differences Δ_n = x_n − x_{n−1} shrink by ρ each
step along one direction, and the iterates' limit is x_n + Δ_n·ρ/(1 − ρ) (Aitken's Δ²
extrapolation). :class:`SlowMode` measures ρ from consecutive differences. When ρ has held
still for :data:`RATIO_STEPS` steps, it writes the extrapolated impulses back as
Chipmunk's warm start (:meth:`~.readout.Readout.carry`). The solver goes on from there,
and the stop rule judges its own later steps. Nothing comes from the analytic solution: the
x_n are pymunk's accumulated impulses, and the limit is the fixed point of pymunk's solver.
Measured with the settings used next to a change point (1 600 iterations a step,
:func:`~.settings.near_change_point`): one extrapolation after 9 steps left the impulses
1e-12 off the analytic reactions at δ = 0.135°, 4e-11 at 0.05°; at 0.0115° (condition
number 1.03e4) a second one, over a window, left 3e-10.
"""

from __future__ import annotations

import math

import numpy as np

from mechcheck.sim_models.pymunk.readout import Readout
from mechcheck.sim_models.pymunk.settle import WINDOW_SHARE, slow_window

#: Only a mode slower than this per step is extrapolated: a faster one dies out in a few
#: dozen steps anyway, and the stop rule's threshold assumes no slower contraction
#: (:data:`.settle.ASSUMED_CONTRACTION`).
SLOW = 0.9
#: ρ is trusted once the step ratios of this many consecutive steps agree within
#: :data:`RATIO_AGREEMENT` × (1 − ρ): by then the faster modes have died out. A faster mode
#: still present would make the ratios wander, and extrapolating with 1/(1 − ρ) would
#: amplify it instead.
RATIO_STEPS = 4
#: The extrapolation leaves about this fraction of the slow mode (an error ε·(1 − ρ) in ρ
#: leaves ε of it), so each extrapolation gains a factor of about 100.
RATIO_AGREEMENT = 1.0e-2
#: A window's net change at or below this fraction of the impulses is their rounding (the
#: settling's own window test, :data:`~.settle.WINDOW_SHARE` × 10 ×
#: ``settle_force_change``): extrapolating it would only magnify it 1/WINDOW_SHARE-fold.
WINDOW_NOISE = WINDOW_SHARE * 1.0e-9


def step_ratio(difference: np.ndarray, before: np.ndarray) -> float:
    """The factor by which a step's change shrank along the previous one (0 once nothing
    changes)."""
    norm = float(before @ before)
    return float(difference @ before) / norm if norm > 0.0 else 0.0


def steady_ratio(ratios: list[float]) -> float | None:
    """The last ratio if it is slow (:data:`SLOW` < ρ < 1) and the last :data:`RATIO_STEPS`
    agree with it (:data:`RATIO_AGREEMENT`), else None."""
    if len(ratios) < RATIO_STEPS:
        return None
    rho = ratios[-1]
    if not SLOW < rho < 1.0:
        return None
    spread = max(abs(r - rho) for r in ratios[-RATIO_STEPS:])
    return rho if spread <= RATIO_AGREEMENT * (1.0 - rho) else None


class SlowMode:
    """Watches the warm-start impulses of a model solved at a fixed pose, step after step
    (:meth:`observe`), and extrapolates their slow mode when it is steady.

    ``contraction`` is the slowest step ratio trusted so far (0 until one is), and
    ``extrapolations`` how many times the impulses were carried to their limit.

    After the first extrapolation the slow mode's step change soon sinks into the
    rounding of the impulses (3e-13 of them at condition number 1.5e4), and its ratio can
    no longer be measured from one step to the next. Its ρ is known, though, so it is
    extrapolated again over a window: W = :func:`~.settle.slow_window` steps after the
    faster modes have died out (:data:`RATIO_STEPS`), the limit is
    x + (x − x_W)·ρ^W/(1 − ρ^W), if the window's net change is above the rounding
    (``noise``, of the impulses' size).
    """

    def __init__(self, readout: Readout, noise: float = WINDOW_NOISE):
        self.readout = readout
        self.noise = noise
        self.contraction = 0.0
        self.extrapolations = 0
        self._previous: np.ndarray | None = None
        self._difference: np.ndarray | None = None
        self._ratios: list[float] = []
        self._anchor: np.ndarray | None = None
        self._since = 0

    def observe(self) -> None:
        """Read the impulses of the step just taken; carry them to the slow mode's limit if
        its ratio is steady, or once a window has passed since the last time."""
        x = np.array(self.readout.accumulated())
        if self.contraction == math.inf:   # gave up extrapolating (see _over_window)
            return
        if self.contraction:
            self._over_window(x)
            return
        if self._previous is not None:
            difference = x - self._previous
            if self._difference is not None:
                self._ratios.append(step_ratio(difference, self._difference))
                rho = steady_ratio(self._ratios)
                if rho is not None:
                    x = self._extrapolate(x, difference, rho)
                    difference = None
            self._difference = difference
        self._previous = x

    def _over_window(self, x: np.ndarray) -> None:
        self._since += 1
        if self._since == RATIO_STEPS:
            self._anchor = x
        window = slow_window(self.contraction)
        if self._anchor is None or self._since < RATIO_STEPS + window:
            return
        net = x - self._anchor
        if np.abs(net).max() > self.noise * np.abs(x).max():
            shrink = self.contraction ** window
            # Next to a change point the mode may stop shrinking by ρ and each carry makes
            # it larger: once the limit is no longer a number, stop carrying (plain steps
            # from here, which the settle rules judge) rather than overflow.
            with np.errstate(over="ignore", invalid="ignore"):
                limit = x + net * (shrink / (1.0 - shrink))
            if np.isfinite(limit).all():
                self._carry(limit)
            else:
                self.contraction = math.inf
        else:
            self._since, self._anchor = 0, None

    def _extrapolate(self, x: np.ndarray, difference: np.ndarray, rho: float) -> np.ndarray:
        self.contraction = rho
        return self._carry(x + difference * (rho / (1.0 - rho)))

    def _carry(self, limit: np.ndarray) -> np.ndarray:
        self.readout.carry(limit.tolist())
        self.extrapolations += 1
        self._ratios, self._since, self._anchor = [], 0, None
        return limit
