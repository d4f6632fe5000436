"""Andrews' squeezing mechanism written by hand, for the tests: the IVP test set's equations
and published values (source and derivation in ``benchmarks/reference_andrews.py``, kept
there because the speed benchmark times them too, and benchmarks never import tests).

``ANDREWS.rhs(t, y)`` is the first-order right-hand side for y = (q, q̇) of the seven angles
(β, Θ, γ, Φ, δ, Ω, ε); ``ANDREWS.accelerations(q, q̇)`` gives q̈ and the six multipliers;
``ANDREWS.Q0`` is the consistent initial state, ``ANDREWS.Q_END`` (``QD_END``, ``QDD_END``)
the published state at ``ANDREWS.T_END`` = 0.03 s; ``ANDREWS.energy(q, q̇)`` is conserved.
"""

from __future__ import annotations

from .benchmark_reference import benchmark_module

ANDREWS = benchmark_module("reference_andrews")
