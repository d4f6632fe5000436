"""A trajectory case run in MuJoCo (backend ``mujoco``, ``mechcheck simulate``): the
linkage released from its state at time 0 and moved by MuJoCo alone, on a ladder of time
steps and integrators, read at the output times from MuJoCo's own state.

The model and the state at time 0 are :mod:`.trajectory_model`'s. Each rung of the ladder
(:func:`ladder`) is a fresh model at one time step ``dt`` and one integrator, stepped by
``mj_step`` (``nstep`` steps at a time, no Python between them, unless Coulomb friction
needs the reactions at every step) and read at the output times:

- every moving link's displacement (t_x, t_y, φ) from the drawn pose: φ from the signed sum
  of the hinges on its path to the ground (MuJoCo's qpos, so it keeps its turns), t from its
  body's origin ``xpos`` less the drawn origin turned by φ;
- the time step divides the output spacing where the outputs lie on a grid
  (:func:`output_grid`), so every output is a step and nothing is interpolated; elsewhere
  (MuJoCo's default 2 ms against a finer spacing, or outputs off any grid) the output is read
  between the two steps around it by a cubic Hermite interpolation of the coordinates and
  their rates (MuJoCo's qvel), whose error O(dt⁴) is below the integrators' own;
- the closure gap (``closure_gap_m``): the largest distance between the two sites of a
  loop-closing joint met at the output times, m.

The ladder: MuJoCo's default settings first (its default integrator and time step, on the
model as mechcheck builds it: its stiffest constraints, a time constant of 2·dt), then each
of Euler, implicitfast and RK4 at the time steps ``dt0``, ``dt0/2``, … (``dt0`` the largest
step ≤ MuJoCo's default on the output grid) down to the finest whose run stays within
:func:`step_budget` steps (:data:`STEP_BUDGET`, fewer for a large linkage or with Coulomb
friction); the last rung, the finest RK4 run, decides the verdict. A run past the budget is refused
(``not_applicable``, saying so and what would help).

Coulomb friction (:mod:`.linkage_friction`) is applied as the driven runs apply it: before
each step, from the reactions MuJoCo reports with the senses of its own joint velocities,
held through the step (so every integrator is first order there, and a joint that sticks
chatters around rest by about μ·N·dt²/m).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from fractions import Fraction

import mujoco
import numpy as np
from scipy.interpolate import CubicHermiteSpline

from mechcheck.analytic.case import Case, Simulation
from mechcheck.analytic.solution import Status
from mechcheck.analytic.trajectory import Trajectory
from mechcheck.analytic.values import CaseError
from mechcheck.sim_models.mujoco.linkage_friction import apply_friction
from mechcheck.sim_models.mujoco.linkage_model import Unbuildable
from mechcheck.sim_models.mujoco.linkage_rig import Array, LinkageRig
from mechcheck.sim_models.mujoco.mjwarnings import raised_during
from mechcheck.sim_models.mujoco.trajectory_model import (
    effort_actuators,
    initial_state,
    load_actuators,
    prescribe,
    refusal,
    trajectory_rig,
)

#: MuJoCo's own defaults (those of an MjOption as MuJoCo makes it).
DEFAULT_TIMESTEP = float(mujoco.MjOption().timestep)
INTEGRATORS = {"Euler": mujoco.mjtIntegrator.mjINT_EULER,
               "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST,
               "RK4": mujoco.mjtIntegrator.mjINT_RK4}
DEFAULT_INTEGRATOR = next(name for name, code in INTEGRATORS.items()
                          if int(code) == int(mujoco.MjOption().integrator))
#: Steps a run may take (the finest rung's): about a second for a small linkage (RK4 four
#: times that). A run past its budget is refused.
STEP_BUDGET = 100_000
#: And at most this many link-steps (steps × moving links): a step's cost grows with the
#: linkage (the N four-bar's 81 links gets 8 600 steps, Andrews' 7 the whole budget).
WORK_BUDGET = 700_000
#: With Coulomb friction, whose reactions are read in Python before every step (~0.4 ms a
#: step on exam Q2, measured): a few seconds a run.
FRICTION_STEP_BUDGET = 10_000
#: Most time steps on the ladder (each half the one before).
MAX_LEVELS = 12
#: An output time is on the step grid when t/dt is this close to an integer.
ON_STEP = 1e-6
#: Outputs lie on a grid when t/t_last is a fraction with at most this denominator.
GRID_DENOMINATOR = 100_000


@dataclass(frozen=True)
class Rung:
    """One run of the ladder: a time step (s) and an integrator."""

    dt: float
    integrator: str
    default: bool = False


def output_grid(outputs: tuple[float, ...]) -> float | None:
    """The largest spacing h with every output time a multiple of it (s), or None."""
    last = max(outputs)
    if last <= 0.0:
        return None
    fractions = [Fraction(t / last).limit_denominator(GRID_DENOMINATOR) for t in outputs]
    if any(abs(float(f) - t / last) > 1e-12 for f, t in zip(fractions, outputs, strict=True)):
        return None
    return last / math.lcm(*(f.denominator for f in fractions))


def step_budget(case: Case) -> int:
    """The steps a run of ``case`` may take (:data:`STEP_BUDGET`, :data:`WORK_BUDGET`,
    :data:`FRICTION_STEP_BUDGET`)."""
    budget = min(STEP_BUDGET, WORK_BUDGET // len(case.linkage.moving_links))
    return min(budget, FRICTION_STEP_BUDGET) if case.has_coulomb_friction else budget


def ladder(simulation: Simulation, budget: int = STEP_BUDGET) -> tuple[Rung, ...]:
    """MuJoCo's default rung, then every integrator at each time step from ``dt0`` halving
    down to the finest within ``budget`` steps (module doc); the finest RK4 run last."""
    grid = output_grid(simulation.outputs)
    dt0 = DEFAULT_TIMESTEP if grid is None else grid / math.ceil(grid / DEFAULT_TIMESTEP - 1e-9)
    levels = 1
    while levels < MAX_LEVELS and simulation.end / (dt0 / 2**levels) <= budget:
        levels += 1
    rungs = [Rung(dt0 / 2**k, name, default=(k == 0 and dt0 == DEFAULT_TIMESTEP
                                               and name == DEFAULT_INTEGRATOR))
             for k in range(levels) for name in INTEGRATORS]
    if dt0 != DEFAULT_TIMESTEP:
        rungs.insert(0, Rung(DEFAULT_TIMESTEP, DEFAULT_INTEGRATOR, default=True))
    return tuple(rungs)


def simulate_case(case: Case, rungs: tuple[Rung, ...] | None = None) -> tuple[Trajectory, ...]:
    """The ``mujoco`` backend's runs of a trajectory case, one per rung (:func:`ladder`)."""
    assert case.simulation is not None
    rungs = rungs or ladder(case.simulation, step_budget(case))
    why = refusal(case)
    if why is not None:
        return (refused(case, rungs[-1], why),)
    return tuple(run_rung(case, rung) for rung in rungs)


def refused(case: Case, rung: Rung, why: str) -> Trajectory:
    assert case.simulation is not None
    times = np.array(case.simulation.outputs)
    return Trajectory("mujoco", times, np.full((times.size, 3 * len(case.linkage.moving_links)),
                                               np.nan),
                      status="not_applicable", message=why, settings=settings_of(rung),
                      default=rung.default)


def settings_of(rung: Rung, rig: LinkageRig | None = None) -> dict[str, object]:
    out: dict[str, object] = {"dt": rung.dt, "integrator": rung.integrator}
    if rig is not None:
        out |= {"iterations": int(rig.model.opt.iterations),
                "tolerance": float(rig.model.opt.tolerance),
                "solref_timeconst": 2.0 * rung.dt}
    return out


def run_rung(case: Case, rung: Rung) -> Trajectory:
    """One rung: the model built, set at its state at time 0 and stepped to the last output,
    read at every output (module doc)."""
    assert case.simulation is not None
    steps = math.ceil(case.simulation.end / rung.dt - ON_STEP)
    budget = step_budget(case)
    if steps > budget:
        return refused(case, rung, (
            f"{steps} steps of {rung.dt:g} s exceed mujoco's step budget of {budget}: "
            "a shorter simulate.end would help"))
    tic = time.perf_counter()
    try:
        (run, warnings) = raised_during(lambda: Run(case, rung).through())
    except (Unbuildable, CaseError) as why:
        return refused(case, rung, str(why))
    wall = time.perf_counter() - tic
    message = " | ".join(warnings)
    status: Status = "ok" if run.finite else "error"
    if not run.finite:
        message = ("MuJoCo's state diverged (a smaller time step would help)"
                   + (f": {message}" if message else ""))
    return Trajectory("mujoco", np.array(case.simulation.outputs), run.coordinates,
                      status=status, message=message, settings=settings_of(rung, run.rig),
                      default=rung.default, wall_time=wall, steps=run.steps,
                      diagnostics=run.diagnostics())


def step_of(t: float, dt: float) -> tuple[int, bool]:
    """The step at or just before time ``t`` and whether ``t`` is on it."""
    n = t / dt
    near = round(n)
    if abs(n - near) <= ON_STEP:
        return near, True
    return math.floor(n), False


class Run:
    """A rung's model stepped through the output times."""

    def __init__(self, case: Case, rung: Rung) -> None:
        assert case.simulation is not None
        self.simulation = case.simulation
        self.dt = rung.dt
        self.rig = rig = trajectory_rig(case, rung.dt)
        m, d = rig.model, rig.data
        m.opt.integrator = INTEGRATORS[rung.integrator]
        # MuJoCo's own choice (sparse from 60 dofs: 0.57 against 0.81 ms a step on the N
        # four-bar's 81 links, measured); nothing here reads the dense efc_J the build asks.
        m.opt.jacobian = mujoco.mjtJacobian.mjJAC_AUTO
        mujoco.mj_resetData(m, d)
        prescribe(rig)
        qpos, qvel = initial_state(case, rig)
        rig.set_state(qpos, qvel)
        d.ctrl[load_actuators(rig)] = 1.0
        self.efforts = effort_actuators(rig)
        self.switches = sorted({t for _, driver in self.efforts if driver.effort is not None
                                for t in driver.effort.times})
        self.friction = case.has_coulomb_friction
        self.steps = 0
        self.coordinates = np.full((len(self.simulation.outputs), 3 * len(rig.moving_links)),
                                   np.nan)
        self.gap = 0.0
        self.iterations = 0
        self.finite = True

    def through(self) -> Run:
        """Step to every output time and read it (between two steps where it is not one);
        once MuJoCo's state blows up (it then resets it), the rows left stay NaN."""
        for k, t in enumerate(self.simulation.outputs):
            n, exact = step_of(t, self.dt)
            before = self.read_at(n)
            if before is None:
                break
            if exact:
                self.coordinates[k] = before[0]
                continue
            after = self.read_at(n + 1)
            if after is None:
                break
            spline = CubicHermiteSpline([n * self.dt, (n + 1) * self.dt],
                                        np.stack([before[0], after[0]]),
                                        np.stack([before[1], after[1]]))
            self.coordinates[k] = spline(t)
        return self

    def read_at(self, n: int) -> tuple[Array, Array] | None:
        """:meth:`read` at step ``n``, or None where the state blew up on the way."""
        self.advance(n)
        return self.read() if self.finite else None

    def advance(self, n: int) -> None:
        """Step to step ``n``, switching each effort's slope at its table's rows."""
        while self.steps < n and self.finite:
            target = min(n, self.next_switch())
            self.set_efforts()
            self.step(target - self.steps)
            self.steps = target
            self.finite = not self.rig.data.warning[mujoco.mjtWarning.mjWARN_BADQACC].number
        self.set_efforts()

    def next_switch(self) -> int:
        """The first step after the current one at or past a row of an effort table."""
        rows = [math.ceil(t / self.dt - ON_STEP) for t in self.switches]
        return min([r for r in rows if r > self.steps], default=self.steps + 10**12)

    def set_efforts(self) -> None:
        """Each effort at its value now (its actuator's activation) and the slope of its
        table's current row (its ctrl): the activation integrates the slope exactly."""
        d, m = self.rig.data, self.rig.model
        t = self.steps * self.dt
        for actuator, driver in self.efforts:
            effort = driver.effort
            assert effort is not None
            d.act[m.actuator_actadr[actuator]] = float(effort.at(t))
            d.ctrl[actuator] = slope(effort.times, effort.values, t)

    def step(self, count: int) -> None:
        m, d = self.rig.model, self.rig.data
        if not self.friction:
            mujoco.mj_step(m, d, nstep=count)
            return
        for _ in range(count):
            mujoco.mj_forward(m, d)
            apply_friction(self.rig, self.rig.reactions(), self.rig.joint_rates(d.qvel))
            d.xfrc_applied[:] = self.rig.extra
            mujoco.mj_step(m, d)

    def read(self) -> tuple[Array, Array]:
        """(coordinates, their rates) of the current state; the closure gap and the solver's
        iterations noted."""
        rig = self.rig
        m, d = rig.model, rig.data
        mujoco.mj_kinematics(m, d)
        mujoco.mj_comPos(m, d)
        coordinates, rates = link_coordinates(rig)
        self.gap = max(self.gap, closure_gap(rig))
        self.iterations = max(self.iterations, int(d.solver_niter[0]))
        return coordinates, rates

    def diagnostics(self) -> dict[str, float]:
        return {"closure_gap_m": self.gap, "solver_iterations": float(self.iterations)}


def slope(times: tuple[float, ...], values: tuple[float, ...], t: float) -> float:
    """The slope of a piecewise-linear table at time ``t`` (0 outside its rows)."""
    k = int(np.searchsorted(times, t, side="right"))
    if k == 0 or k >= len(times):
        return 0.0
    return (values[k] - values[k - 1]) / (times[k] - times[k - 1])


def link_coordinates(rig: LinkageRig) -> tuple[Array, Array]:
    """Every moving link's (t_x, t_y, φ) from the drawn pose and its rates, from MuJoCo's
    state (after its kinematics): φ the signed sum of its hinges (qpos keeps the turns), t
    the body origin less the drawn origin turned by φ."""
    m, d = rig.model, rig.data
    phi, omega = rig.rotation @ d.qpos, rig.rotation @ d.qvel
    coordinates = np.empty(3 * len(rig.moving_links))
    rates = np.empty_like(coordinates)
    jacp = np.zeros((3, m.nv))
    for k, link in enumerate(rig.moving_links):
        b = rig.body[link]
        c, s = math.cos(phi[k]), math.sin(phi[k])
        ox, oy = rig.origins[link]
        turned = np.array([c * ox - s * oy, s * ox + c * oy])
        mujoco.mj_jac(m, d, jacp, None, d.xpos[b], b)
        velocity = (jacp @ d.qvel)[:2]
        coordinates[3 * k:3 * k + 3] = (*(d.xpos[b, :2] - turned), phi[k])
        rates[3 * k:3 * k + 3] = (velocity[0] + omega[k] * turned[1],
                                  velocity[1] - omega[k] * turned[0], omega[k])
    return coordinates, rates


def closure_gap(rig: LinkageRig) -> float:
    """The largest distance between the two sites of a loop-closing joint, m."""
    d = rig.data
    return max((float(np.linalg.norm(d.site_xpos[a] - d.site_xpos[b]))
                for a, b in rig.loop_sites.values()), default=0.0)
