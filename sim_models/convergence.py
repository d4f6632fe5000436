"""How a driven run's reading is judged converged, for either simulator.

A driven run is read at one instant after a lead-in along the prescribed motion.
Its reading is trusted only when it no longer depends on the two numbers the run
chose: the lead-in (:func:`lengthen_lead`: the start-up transient has died) and
the time step (:func:`halve_timestep`: the discretisation error is below the
target). Both compare two of the simulator's own readings; nothing here looks at
the analytic answer. A massless link carries a fictitious inertia k that a
reading removes by running twice, at k and 2k (:func:`massless_limit`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from mechcheck.analytic.solution import FORCE_FLOOR_N, Solution, quantity_kind

#: First lead time, in steps, and the most it may grow to.
LEAD_STEPS = 50
MAX_LEAD_STEPS = 1600
#: Runs with lead N and 2N agree to this fraction of the largest force (or
#: torque/scale): the start-up transient has died. 100× below the 1e-3 target.
LEAD_AGREEMENT_RTOL = 1e-5
#: The lead-in may pass no pose whose condition number is more than this many
#: times the instant's. The condition number of a rocker-driven four-bar grows
#: without bound at a rocker dead point (crank and coupler aligned), that of any
#: drive at a change point; doubling the lead-in through one (exam Q3 with
#: 6400 steps of 2.5e-5 s passes the rocker dead point at θ12 = 36.7°) would
#: make the crank's sense there a matter of chance. A factor 2 keeps the whole
#: lead-in at least half as well conditioned as the instant.
LEAD_CONDITION_GROWTH = 2.0
#: Runs with time steps dt and dt/2 (same number of lead steps) agree to this
#: fraction of the largest force (or torque/scale). The error is O(dt²)
#: (measured on exam Q3 from 2.5e-5 s down by halves: 3.7e-3, 9.5e-4, 2.4e-4,
#: 6.1e-5, 1.6e-5 with massless links at 1e-5 of the real masses; 1.7e-5,
#: 4.3e-6, 1.0e-6 at 1e-2, extrapolated): while the error at least halves per halving, the finer run's
#: error is at most the difference (a third of it at second order), so 1e-4
#: keeps it ≥ 10× below the 1e-3 dynamic target.
TIMESTEP_AGREEMENT_RTOL = 1e-4
#: The time step may be halved this many times (2.5e-5 s → 7.8e-7 s); exam Q3,
#: 6.7° from a rocker dead point, needed four with massless links at 1e-5 of the
#: real masses, and needs one at 1e-2 (:data:`~.model.FICTITIOUS_MASS_FRACTION`).
MAX_TIMESTEP_HALVINGS = 5
#: A reading whose last step, solved again with more solver iterations, moves by more than
#: this fraction of the largest force (or torque/scale) is not yet the constraint solve's
#: answer (pymunk's Gauss–Seidel; the time step's bound, for the same reason).
SOLVER_AGREEMENT_RTOL = TIMESTEP_AGREEMENT_RTOL

def massless_limit(base: dict[str, float], doubled: dict[str, float],
                   units: dict[str, str] | None = None) -> dict[str, float]:
    """Forces and torques extrapolated linearly to zero fictitious inertia, F₀ = 2·F(k) − F(2k);
    the pose as the base run reached it (it is prescribed, not an inertia effect).
    ``units``: a linkage's quantity units (its names do not say their kind)."""
    table = units or {}
    return {q: v if quantity_kind(q, table.get(q)) == "pose" else 2.0 * v - doubled[q]
            for q, v in base.items()}


def inertia_correction(base: dict[str, float], limit: dict[str, float], length: float,
                       units: dict[str, str] | None = None) -> float:
    """The largest change the massless extrapolation ``limit`` made to the base run's
    reading ``base``: the fictitious inertia removed, N (torques divided by ``length``)."""
    table = units or {}
    kinds = {q: quantity_kind(q, table.get(q)) for q in limit}
    return max((abs(base[q] - v) / (length if kinds[q] == "torque" else 1.0)
                for q, v in limit.items() if kinds[q] != "pose"), default=0.0)


def force_vector(values: dict[str, float], length: float,
                 units: dict[str, str] | None = None) -> np.ndarray:
    """The forces of ``values`` and its torques/length, without its pose quantities;
    ``units`` names the unit of each quantity of a linkage (its names do not say it)."""
    table = units or {}
    kinds = {q: quantity_kind(q, table.get(q)) for q in values}
    return np.array([x / length if kinds[q] == "torque" else x
                     for q, x in values.items() if kinds[q] != "pose"])


def force_size(values: dict[str, float], length: float,
               units: dict[str, str] | None = None) -> float:
    """The largest force (or torque/length) of ``values``, at least ``FORCE_FLOOR_N``: what
    :func:`disagreement` is relative to."""
    return max(float(np.abs(force_vector(values, length, units)).max(initial=0.0)),
               FORCE_FLOOR_N)


def disagreement(a: dict[str, float], b: dict[str, float], length: float,
                 units: dict[str, str] | None = None) -> float:
    """Largest difference of forces (and torques/length) relative to the largest of ``b``'s
    (:func:`force_size`); ``units`` names the unit of each quantity of a linkage."""
    va, vb = force_vector(a, length, units), force_vector(b, length, units)
    return float(np.abs(va - vb).max()) / force_size(b, length, units)


@dataclass
class Convergence:
    """Where a driven run's convergence checks ended."""

    values: dict[str, float]
    lead_steps: int
    dt: float
    total_steps: int = 0
    lead_disagreement: float = np.inf
    timestep_disagreement: float = np.inf
    lead_limit: str = ""
    #: How far the reading moves when its last step is solved with more iterations.
    solver_disagreement: float = 0.0
    #: What the simulator measured of the run that gave ``values`` (a continuous sweep's
    #: pose drift, rate error…), by name.
    run: dict[str, float] = field(default_factory=dict)

    @property
    def converged(self) -> bool:
        return (self.lead_disagreement <= LEAD_AGREEMENT_RTOL
                and self.timestep_disagreement <= TIMESTEP_AGREEMENT_RTOL
                and self.solver_disagreement <= SOLVER_AGREEMENT_RTOL)

    @property
    def solver_only_failed(self) -> bool:
        """Whether the iteration rule is the only one that did not hold."""
        return (self.lead_disagreement <= LEAD_AGREEMENT_RTOL
                and self.timestep_disagreement <= TIMESTEP_AGREEMENT_RTOL
                and not self.solver_disagreement <= SOLVER_AGREEMENT_RTOL)

    def verdict(self) -> str:
        """Why the run is not converged (empty when it is)."""
        if not self.lead_disagreement <= LEAD_AGREEMENT_RTOL:
            limit = f"; {self.lead_limit}" if self.lead_limit else ""
            return (f"start-up transient still {self.lead_disagreement:.1e} of the forces (rule: ≤ "
                    f"{LEAD_AGREEMENT_RTOL:.0e}, LEAD_AGREEMENT_RTOL) after {self.lead_steps} "
                    f"lead steps of {self.dt:.3g} s{limit}; governed by the lead-in budget "
                    f"MAX_LEAD_STEPS = {MAX_LEAD_STEPS} (mechcheck.sim_models.convergence)")
        if not self.timestep_disagreement <= TIMESTEP_AGREEMENT_RTOL:
            return (f"time step not converged: runs with dt = {2.0 * self.dt:.3g} s and "
                    f"{self.dt:.3g} s still differ by {self.timestep_disagreement:.1e} of the "
                    f"forces (rule: ≤ {TIMESTEP_AGREEMENT_RTOL:.0e}, TIMESTEP_AGREEMENT_RTOL); "
                    f"governed by MAX_TIMESTEP_HALVINGS = {MAX_TIMESTEP_HALVINGS} "
                    "(mechcheck.sim_models.convergence)")
        if not self.solver_disagreement <= SOLVER_AGREEMENT_RTOL:
            return (f"constraint solve not converged: the last step solved again with more "
                    "iterations "
                    f"moves the reading by {self.solver_disagreement:.1e} of the forces (rule: "
                    f"≤ {SOLVER_AGREEMENT_RTOL:.0e}, SOLVER_AGREEMENT_RTOL, 10× inside the "
                    "1e-3 dynamic tolerance); governed by the simulator's solver iterations "
                    "per step (the 'iterations' diagnostic: the last rung of its ladder)")
        return ""


#: One reading of a driven run with a given number of lead steps and time step.
Reading = Callable[[int, float], dict[str, float]]
#: Why a run with this many lead steps and this time step may not be made ("" if it may).
LeadLimit = Callable[[int, float], str]


def lengthen_lead(read: Reading, limit: LeadLimit, dt: float, scale: float, runs: int,
                  units: dict[str, str] | None = None) -> Convergence:
    """Double the lead steps from :data:`LEAD_STEPS` until two readings agree within
    :data:`LEAD_AGREEMENT_RTOL`, the budget :data:`MAX_LEAD_STEPS` is spent or ``limit``
    forbids a longer lead-in; ``runs`` simulator runs per reading, forces compared
    relative to ``scale`` (torques divided by it)."""
    steps = LEAD_STEPS
    out = Convergence(read(steps, dt), steps, dt, total_steps=runs * steps)
    while not out.lead_disagreement <= LEAD_AGREEMENT_RTOL:
        steps *= 2
        if steps > MAX_LEAD_STEPS:
            out.lead_limit = f"step budget {MAX_LEAD_STEPS} reached"
            break
        out.lead_limit = limit(steps, dt)
        if out.lead_limit:
            break
        values = read(steps, dt)
        residual = disagreement(values, out.values, scale, units)
        out.values, out.lead_steps = values, steps
        out.total_steps += runs * steps
        out.lead_disagreement = residual if np.isfinite(residual) else np.inf
        if not np.isfinite(residual):
            break
    return out


def converge(read: Reading, limit: LeadLimit, dt: float, scale: float, runs: int,
             units: dict[str, str] | None = None) -> Convergence:
    """Both checks in turn: the lead-in lengthened (:func:`lengthen_lead`) and, once two
    readings agree on it, the time step halved (:func:`halve_timestep`)."""
    out = lengthen_lead(read, limit, dt, scale, runs, units)
    if out.lead_disagreement <= LEAD_AGREEMENT_RTOL:
        out = halve_timestep(read, out, scale, runs, units)
    return out


def halve_timestep(read: Reading, out: Convergence, scale: float, runs: int,
                   units: dict[str, str] | None = None) -> Convergence:
    """Halve the time step until two readings agree within :data:`TIMESTEP_AGREEMENT_RTOL`,
    keeping the number of lead steps.

    Every start-up transient of the soft model has time constants ∝ dt (the
    constraints' 2·dt, and the modes their compliance R/k ∝ dt² gives the
    links), so it dies in the same number of steps at any dt (measured on exam
    Q3 with massless links at 1e-5 of the real masses: ~1600 steps at 2.5e-5,
    6.25e-6 and 1.56e-6 s alike).
    """
    for _ in range(MAX_TIMESTEP_HALVINGS):
        dt = 0.5 * out.dt
        values = read(out.lead_steps, dt)
        residual = disagreement(values, out.values, scale, units)
        out.values, out.dt = values, dt
        out.total_steps += runs * out.lead_steps
        out.timestep_disagreement = residual if np.isfinite(residual) else np.inf
        if not residual > TIMESTEP_AGREEMENT_RTOL:  # converged, or NaN: stop either way
            break
    return out


#: The readings of one continuous run through a stretch of poses, with what the simulator
#: measured of each: (lead steps before its first pose, time step, how many of its poses).
StretchReading = Callable[[int, float, int], list[tuple[dict[str, float], dict[str, float]]]]


def stretch_timestep(dt: float, interval: float) -> float:
    """The largest time step up to ``dt`` that puts every pose ``interval`` seconds apart
    on a step: the run is read exactly at each pose."""
    return interval / math.ceil(interval / dt * (1.0 - 1e-12))


def converge_stretch(read: StretchReading, limit: LeadLimit, dt: float, scale: float,
                     runs: int, poses: int, units: dict[str, str] | None = None
                     ) -> list[Convergence] | None:
    """The rules of :func:`converge` on one continuous run through ``poses`` poses: the
    lead-in lengthened at the first pose (:func:`lengthen_lead`: later poses follow a longer
    run, whose start-up transient has died further), then the whole run repeated at half
    the time step (the same lead steps) until each pose's two readings agree within
    :data:`TIMESTEP_AGREEMENT_RTOL`, a repeat running only as far as the last pose not yet
    agreed. None where the lead-in does not converge (its poses are then run one by one).
    Each pose's ``total_steps`` is its share of the stretch's."""
    first = lengthen_lead(lambda steps, step: read(steps, step, 1)[0][0], limit, dt, scale,
                          runs, units)
    if not first.lead_disagreement <= LEAD_AGREEMENT_RTOL:
        return None
    outs = [Convergence(values, first.lead_steps, dt, lead_disagreement=first.lead_disagreement,
                        run=run) for values, run in read(first.lead_steps, dt, poses)]
    total = first.total_steps + runs * round(sum(o.run.get("steps", 0.0) for o in outs[-1:]))
    pending = list(range(poses))
    for _ in range(MAX_TIMESTEP_HALVINGS):
        if not pending:
            break
        dt *= 0.5
        finer = read(first.lead_steps, dt, pending[-1] + 1)
        total += runs * round(finer[-1][1].get("steps", 0.0))
        still = []
        for k in pending:
            residual = disagreement(finer[k][0], outs[k].values, scale, units)
            out = outs[k]
            out.values, out.run, out.dt = finer[k][0], finer[k][1], dt
            out.timestep_disagreement = residual if np.isfinite(residual) else np.inf
            if residual > TIMESTEP_AGREEMENT_RTOL:  # NaN stops a pose, as in :func:`halve_timestep`
                still.append(k)
        pending = still
    for out in outs:
        out.total_steps = total // poses
    return outs


#: A driven run whose pose at the instant is farther than this × the linkage's size from
#: the prescribed one has left its assembly (measured on the built-in linkages: at most
#: 1.8e-5 m in pymunk, the crank shaper; a random six-bar that folded over read 2.75 m).
DRIVEN_DRIFT = 1.0e-3


def left_assembly(drift: float, scale: float) -> str:
    """Why a driven reading ``drift`` (m) from the prescribed pose is withheld, or ``""``."""
    if drift <= DRIVEN_DRIFT * scale:
        return ""
    return (f"the driven run reached the instant {drift:.3g} m from the prescribed pose: it "
            "left the assembly it was started on (readings that agree there are another "
            "linkage's); forces withheld")


def driven_verdict(case: str, backend: str, out: Convergence, diagnostics: dict[str, float | str],
                   units: dict[str, str], scale: float, why_not: Callable[[], str]) -> Solution:
    """A driven reading as a Solution: ``not_settled`` with the pose alone where a check
    failed (``why_not()`` says why) or the run left its assembly (:func:`left_assembly`,
    from the diagnostics' ``pose_drift``), else every value."""
    pose = {q: v for q, v in out.values.items() if quantity_kind(q, units.get(q)) == "pose"}
    why = why_not() if not out.converged else left_assembly(float(diagnostics["pose_drift"]), scale)
    if why:
        return Solution(case, backend, pose, status="not_settled", message=why,
                        diagnostics=diagnostics, units=units)
    return Solution(case, backend, out.values, diagnostics=diagnostics, units=units)
