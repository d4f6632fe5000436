"""Reading force *vectors* out of pymunk's own solver state.

Why the accumulated impulse, read through cffi
----------------------------------------------
``Constraint.impulse`` is a magnitude only (|jAcc| for a pivot or groove,
|jAcc| for a gear or motor), so a sign convention check like "F_ij by i on j"
cannot be made from it. Two routes give vectors:

1. **Accumulated impulse (chosen).** Chipmunk keeps, per constraint, the
   impulse it accumulated over the Gauss–Seidel iterations of the last step
   (``jAcc``; a vector for pivots and grooves, a signed scalar for gears and
   motors) and applies it as ``−jAcc`` to body a and ``+jAcc`` to body b. That
   *is* the constraint force pymunk applied, per joint, with its sign, so
   ``jAcc / dt`` is F_ij when body a is link i and body b is link j.
2. **Per-body momentum balance.** Δ(m v), Δ(I ω) and the applied loads over
   a step give each body's *total* constraint force and moment. A link
   carries two or three joints, so splitting that total into joint reactions
   means solving the member-equilibrium equations again with the simulated
   accelerations: the reactions would then come from our own linear algebra,
   not from pymunk, and any error in it would be shared with the analytic
   reference we compare against.

The price of route 1 is that the C structs are private: the offsets, and their check
against public values once per process, are the fence's (:mod:`._fast.layout`). Route 2
is kept as an independent check of signs and body assignment in
``tests/test_pymunk_forces.py``.
"""

from __future__ import annotations

import pymunk

from mechcheck.sim_models.pymunk._fast import impulse_cells, read

Vec = tuple[float, float]


def accumulated_impulse(constraint: pymunk.Constraint) -> Vec | float:
    """jAcc of the last step: a vector (pivot, groove) or a signed scalar (gear, motor).

    It is the impulse the constraint applied to its body b (−jAcc to body a).
    """
    j = read(impulse_cells(constraint))
    return (j[0], j[1]) if len(j) == 2 else j[0]


def torque_on_b(constraint: pymunk.Constraint, dt: float) -> float:
    """Torque (N·m, CCW +) a gear or motor applied to its body b during the last step."""
    j = accumulated_impulse(constraint)
    assert isinstance(j, float)
    return j / dt
