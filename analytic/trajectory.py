"""Motion over time: what every backend reports of a linkage that moves freely
(``mechcheck simulate``), and how its numbers read.

A :class:`Trajectory` is a backend's run of a trajectory case (:class:`~.case.Simulation`):
every moving link's displacement from the drawn pose (t_x, t_y, φ, as
:mod:`.linkage_kinematics` holds a pose) at each output time, read from the backend's own
state, with the settings it ran at and what it cost. :func:`trajectory_quantities` reads
them under the names a pose's table uses (``x_<point>``, ``y_<point>``, ``phi_<link>``,
``q_<joint>``), the same way for every backend, so no backend writes its own readout.

The analytic reference (:func:`simulate`) integrates the linkage engine's own equations of
motion in its independent coordinates (:mod:`.linkage_dynamics`).
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from mechcheck.analytic.linkage_forces import pose_quantities
from mechcheck.analytic.linkage_kinematics import LinkagePose
from mechcheck.analytic.rigid import Array

if TYPE_CHECKING:
    from mechcheck.analytic.case import Case
    from mechcheck.analytic.linkage import Linkage
    from mechcheck.analytic.solution import Status


@dataclass(frozen=True)
class EnergyBalance:
    """The energy terms of a trajectory at its output times, J: kinetic, potential (gravity
    and springs), the work done on the linkage by its loads and driver efforts, and what
    dampers and friction dissipated. ``residual`` is the identity they satisfy:
    T + V − W + D − (T + V)(0), zero up to the integrator's tolerance."""

    kinetic: Array
    potential: Array
    work: Array
    dissipated: Array

    @property
    def residual(self) -> Array:
        total = self.kinetic + self.potential - self.work + self.dissipated
        return np.asarray(total - total[0])

    @property
    def scale(self) -> float:
        """The energy the residual is judged against: the largest term met on the way."""
        terms = np.abs(np.stack([self.kinetic, self.potential - self.potential[0], self.work,
                                 self.dissipated]))
        return float(np.max(terms)) if terms.size else 0.0


@dataclass(frozen=True)
class Trajectory:
    """One backend's run of a trajectory case.

    Parameters
    ----------
    backend : the backend's name.
    times : the output times, s (T,).
    coordinates : every moving link's displacement from the drawn pose at each time,
        (T, 3n) in the order of ``linkage.moving_links`` (t_x, t_y in m, φ in rad,
        keeping its turns); NaN rows where the run gave none.
    status, message : ``ok``, or why the run gave no number (and what would help).
    settings : what it ran at (a simulator's ``dt``, ``integrator``, ``iterations``; the
        reference's ``method`` and ``rtol``), for the report's accuracy-against-cost table.
    default : the simulator's default settings (one run of its ladder is).
    wall_time : s, the run alone (building the model included).
    steps : time steps (or right-hand-side evaluations) it took.
    energy : the reference's energy balance at ``times``.
    events : (time, what) where the motion switched (friction sticking or slipping).
    diagnostics : what explains its error, by name (a simulator's largest loop-closure
        gap met, m; its constraint-solver iterations; the reference's energy residual).
    """

    backend: str
    times: Array
    coordinates: Array
    status: Status = "ok"
    message: str = ""
    settings: Mapping[str, object] = field(default_factory=dict)
    default: bool = True
    wall_time: float = float("nan")
    steps: int = 0
    energy: EnergyBalance | None = None
    events: tuple[tuple[float, str], ...] = ()
    diagnostics: Mapping[str, float] = field(default_factory=dict)

    def quantities(self, linkage: Linkage) -> dict[str, Array]:
        return trajectory_quantities(linkage, self.times, self.coordinates)


def trajectory_quantities(linkage: Linkage, times: Array, coordinates: Array) -> dict[str, Array]:
    """``x_``/``y_`` of every point, ``phi_`` of every moving link and ``q_`` of every
    joint at each time, from the links' displacements (T, 3n): what a pose's table
    reports, read the same way for every backend."""
    n = coordinates.shape[0]
    zeros = np.zeros_like(coordinates)
    drivers = np.zeros((n, len(linkage.drivers)))
    pose = LinkagePose(linkage, drivers, coordinates, zeros, zeros, np.full(n, np.nan))
    return pose_quantities(pose)


def simulate(case: Case) -> tuple[Trajectory, ...]:
    """The analytic reference of a trajectory case: one run, at the integrator's tight
    tolerances (:mod:`.linkage_dynamics`); ``not_applicable`` where it does not integrate
    the case (the message says what would be needed), ``no_solution`` from where the motion
    cannot continue (the linkage locks)."""
    from mechcheck.analytic import linkage_dynamics as dynamics

    assert case.simulation is not None, "simulate() takes a trajectory case"
    start = time.perf_counter()
    times = np.array(case.simulation.outputs)
    settings = {"method": dynamics.METHOD, "rtol": dynamics.RTOL,
                "atol": dynamics.RTOL * case.linkage.scale}
    refused = dynamics.refusal(case)
    if refused is not None:
        empty = np.full((times.size, 3 * len(case.linkage.moving_links)), np.nan)
        return (Trajectory("analytic", times, empty, status="not_applicable", message=refused,
                           settings=settings),)
    run = dynamics.integrate(case)
    energy = EnergyBalance(run.kinetic, run.potential, run.work, run.dissipated)
    finite = np.isfinite(energy.residual)
    worst = float(np.abs(energy.residual[finite]).max(initial=0.0))
    scale = energy.scale if np.isfinite(energy.scale) else float("nan")
    return (Trajectory("analytic", run.times, run.coordinates,
                       status="no_solution" if run.message else "ok", message=run.message,
                       settings=settings, wall_time=time.perf_counter() - start,
                       steps=run.evaluations, energy=energy, events=run.events,
                       diagnostics={"energy_residual": worst / scale if scale > 0.0 else worst}),)
