"""Solver settings and stopping thresholds of the pymunk backends, in one place.

Every number a pymunk run depends on lives here, with the reason it has
that value, so that the solver-setting study (:mod:`mechcheck.studies.rigid_joints`)
can vary them and a reader can see what "settled" means.
"""

from __future__ import annotations

from dataclasses import dataclass, replace


@dataclass(frozen=True)
class SolverSettings:
    """Integration, solver and stopping settings of one pymunk run.

    Parameters
    ----------
    dt : time step, s. Constant for the whole run: ``impulse / dt`` is only a
        force if the step that produced the impulse had this length, and
        Chipmunk rescales its warm-start impulses by the step ratio. At rest
        the integration error vanishes, so statics can use a long step
        (0.1 s with 1 t links); driven runs use their own (see
        :data:`mechcheck.sim_models.pymunk.linkage_dynamics.DRIVEN`).
    iterations : Gauss–Seidel iterations per step (``Space.iterations``).
        Warm starting carries the accumulated impulses from step to step, so
        the solver keeps converging over steps; more iterations per step
        shorten the settling, they do not change what it settles to.
    error_bias : fraction of a joint error left uncorrected after one second
        (``Constraint.error_bias``); per step 1 − error_bias^dt is corrected.
        Chipmunk's default 0.9⁶⁰ corrects only 1 % per 0.1 s step; 1e-6
        corrects 75 % per step, which removes the start-up drift in a few
        steps (studied in :mod:`mechcheck.studies.rigid_joints`).
    damping : fraction of velocity kept after one second (``Space.damping``).
        It removes the kinetic energy of the settling transient and has no
        effect on a body at rest, so it cannot bias a settled force. Strong
        damping (0.01, i.e. 37 % kept per 0.1 s step) is needed next to a
        change point, where the mechanism is soft and a weakly damped run
        with strong error correction keeps oscillating (seen at 5° from the
        E1 change point with damping 0.5).
    fictitious_mass : kg, the mass given to every link in a *static* run.
        Pymunk cannot integrate a massless dynamic body. At rest the
        inertia terms vanish, so any positive mass gives the same static
        reactions, provided gravity is applied only to the real masses (it
        is applied as explicit forces m·g at the real centres of mass, never
        through ``Space.gravity``). Equal heavy masses keep the iterative
        solver well conditioned (no mass ratios) and the transient drift,
        which scales as F·dt²/m, tiny.
    fictitious_scale : factor on all fictitious inertia of a driven run (the
        massless links' and what near-point links get, see
        :func:`mechcheck.sim_models.pymunk.linkage_model.driven_inertial`); the twin run
        that removes it by extrapolation has 2.
    quasi_static : a quasi-static run of a static case: the real masses' inertia is
        fictitious too (× ``fictitious_scale``), since statics has none; their weights
        stay explicit forces of the real masses.
    settle_speed : 1/s, settled when every body's largest point speed
        (|v| + |ω|·L), divided by the mechanism's length scale L, is below
        this. Relative, so that a case in metres and one of centimetre links
        are judged alike. The joint-error correction removes a remaining
        drift d at a rate of about d/τ (τ a few steps), so this bounds the
        pose error still to be corrected to about settle_speed·τ·L.
    settle_force_change : settled when no reported force (or torque / L)
        changes by more than this fraction of the largest one between steps.
        Warm-started Gauss–Seidel converges geometrically, so the error still
        left is about this change divided by (1 − contraction per step); with
        the contraction seen here (≤ 0.9) that is ≤ 10× the threshold.
    settle_patience : consecutive steps both criteria must hold, so a
        momentary crossing during an oscillation is not taken as rest.
    max_steps : the budget; past it the run reports ``not_settled``.
    """

    dt: float = 0.1
    iterations: int = 100
    error_bias: float = 1.0e-6
    damping: float = 0.01
    fictitious_mass: float = 1000.0
    fictitious_scale: float = 1.0
    quasi_static: bool = False
    settle_speed: float = 1.0e-9
    settle_force_change: float = 1.0e-10
    settle_patience: int = 3
    max_steps: int = 20000

    def with_(self, **changes: float) -> SolverSettings:
        """A copy with some settings changed."""
        return replace(self, **changes)  # type: ignore[arg-type]


#: Settings of the ``pymunk`` (settle) backend.
SETTLE = SolverSettings()

#: Settings of the ``pymunk_solve`` backend: the bodies are put back on the
#: analytic pose before every step, so only the impulse convergence matters.
#: The stopping rule is the same force-change criterion, tighter because
#: nothing moves.
SOLVE = SolverSettings(settle_force_change=1.0e-14, settle_speed=float("inf"),
                       settle_patience=2, max_steps=2000)

#: Settings of the linkage backends (:mod:`mechcheck.sim_models.pymunk.linkage`): the
#: four-bar's, with a larger step budget. Pymunk's Gauss–Seidel solver converges more
#: slowly the worse the constraint problem is conditioned, and a general linkage can be
#: drawn anywhere below the near-singular line (condition 1e4): a random four-bar at
#: condition 1.2e3 needed 22 261 re-posed steps to converge and 15 140 steps to settle,
#: exam Q1's free coordinates 12 086 steps to settle. The budget only bounds a run;
#: the stop rules end it.
LINKAGE_SETTLE = SETTLE.with_(max_steps=50_000)
LINKAGE_SOLVE = SOLVE.with_(max_steps=50_000)

#: A held pose whose constraint solve's slowest mode shrinks by more than this per step
#: (measured by :class:`~mechcheck.sim_models.pymunk.slow_mode.SlowMode` within
#: :data:`PROBE_STEPS`) is next to a change point, and is settled with
#: :func:`near_change_point`'s settings. Seed E1 at θ12 = 180° − δ, 100 iterations a step:
#: 0.9987 at δ = 0.3° (condition number 395), 0.99975 at 0.135° (880).
SOFT_CONTRACTION = 0.99
#: Re-posed steps in which the slow mode is looked for before settling (they warm the
#: impulses, and count among the run's steps).
PROBE_STEPS = 16
#: Next to a change point, Gauss–Seidel iterations a step × this: the slow mode then
#: shrinks 16× faster per step, the faster modes die out within a step, and its ratio
#: is measured, and extrapolated, after a few steps (:mod:`.slow_mode`).
SOFT_ITERATIONS = 16
#: Next to a change point, the fictitious mass × this. There the large reactions turn
#: with the links: a step that moves a link by s changes their pull on it by ∝ F·s/L,
#: against the constraint solve's restoring, which converges by only 1 − ρ a step; with
#: the bodies light, the settling run is unstable and leaves the held pose within tens of
#: steps even from converged impulses. A heavier body moves F·dt²/m less a step. Measured
#: on seed E1 after a converged constraint solve, 1 600 iterations a step (stable: still
#: at rest after 3 000 steps): 1 000 kg stable at δ = 0.1° (1 − ρ = 2.2e-3), unstable
#: from 0.05° (5.5e-4) inward; 1e4 kg stable down to 0.008° (1.4e-5, condition number
#: 1.5e4), unstable at 0.005° (5.5e-6), where a pose then ends ``not_settled``; 1e5 kg
#: stable down to 0.005° too, but its position rounding is 10× larger (m·ε·L/dt²) and a
#: settling run's own slow mode took 15 000 steps at condition number 1.3e4 (1 100 at
#: 1e4 kg). At rest the mass does not enter the reactions (:class:`SolverSettings`).
SOFT_MASS = 10.0


def near_change_point(settings: SolverSettings) -> SolverSettings:
    """``settings`` for a held pose next to a change point (:data:`SOFT_CONTRACTION`): the
    step budget keeps its size in Gauss–Seidel iterations."""
    return settings.with_(iterations=settings.iterations * SOFT_ITERATIONS,
                          fictitious_mass=settings.fictitious_mass * SOFT_MASS,
                          max_steps=settings.max_steps // SOFT_ITERATIONS)
