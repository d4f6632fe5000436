"""Exam Q1 and Q2 of seed 002 as MuJoCo models: Q1 settles, Q2 is driven.

Both models lie in the x–y plane, gravity is set explicitly to (0, −g, 0)
(MuJoCo's default is along −z), contacts are disabled, and every constraint
uses ``solimp`` 0.9999 with ``solref`` (2·dt, 1), the stiffest MuJoCo allows
(SIMULATORS.md). Every force is read from MuJoCo's own state.

Q1 (:func:`settle_q1`). The slider has slide joints x and y; x carries the
spring as MuJoCo's own joint stiffness (``springref`` 0, so it is unstretched
at x = 0) and y is held at 0 by a joint equality, whose force *is* the
slide's normal force. The bar is a free planar body (slide x, slide y, hinge
z about its end A) pinned to the slider by a ``connect`` equality between a
site at A on each body, first site on the bar, so the connect force is the
pin force by the slider on the bar. F is applied at B through
``xfrc_applied`` at B's current position every step. Joint damping on the
slider's x and the bar's hinge, roughly critical, removes the motion; it
exerts nothing at rest, so it cannot bias the settled forces. The model
starts from a pose the caller chooses (default x = 0, φ = 0, the bar hanging
straight down), never the analytic equilibrium, and is stepped until it has
settled — velocities and force changes below :data:`VELOCITY_TOL` and
:data:`FORCE_CHANGE_RTOL` — or its step budget is spent (``not_settled``).
The pose x, φ is MuJoCo's ``qpos``, the spring force its ``qfrc_spring``.

Q2 (:func:`drive_q2`). The mass has slide joints x and y, y held at 0 by a
joint equality (the normal force). The springs k1 and k2 are two fixed
tendons with stiffness on x, coefficients +1 (k1, stretched when x > 0) and
−1 (k2, compressed), both with spring length 0. The motion is imposed by a
joint equality x = x_d to a heavy driver slide (:data:`DRIVER_MASS`) whose
applied force makes its own semi-implicit Euler steps land exactly on the
prescribed x(t) at every step; the equality's force is the drive force F.

Friction in Q2, and why this way. MuJoCo's contact friction was tried first
(a box on a plane, condim 3, driven the same way; ``benchmarks/bench_exam.py``
repeats it): while sliding its tangential force is exactly μ times the
contact's normal force (pyramidal or elliptic cone, with or without noslip),
but the box chatters on its soft contact even when pushed at constant speed,
and that normal force swings between 0 and 1.2·m·g (default contact
softness) or 0 and 48·m·g (solref 2·dt). The median error of F was 16–19 %
and 100 %, respectively. So friction is MuJoCo's own
dry-friction constraint, the x joint's ``frictionloss``: a box-constrained
force that saturates at ±frictionloss whenever the joint slides and opposes
the motion by itself (measured: saturated one step from a reversal, at
|ẋ| = 4e-4 m/s; after the sign change the drive equality needs a few steps
to absorb the 2·μ·N jump, 3e-4 N then 2e-4 N, so readings sit away from
reversals, where ẋ = 0 makes F indeterminate anyway). Its limit is set before every
step to μ·|N|, N being the normal equality's force MuJoCo computes for that
same state (a first ``mj_forward``); measured, the friction row then carries
exactly −μ·N.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import ArrayLike, NDArray

from mechcheck.analytic.exam import (
    Q1_DAMPING_RATIO as DAMPING_RATIO,
    Q1_FORCE_CHANGE_RTOL as FORCE_CHANGE_RTOL,
    Q1_VELOCITY_TOL as VELOCITY_TOL,
    Motion,
    Q1Result,
    Q1System,
    Q2Result,
    Q2System,
    Status,
    checked_times,
    drive_until_steady,
    q1_dampers,
    q1_result,
    q1_timestep,
    reading_steps,
    unsteady_message,
)
from mechcheck.sim_models.mujoco import mjwarnings  # noqa: F401  (MuJoCo warnings into Python before any model)

BACKEND = "mujoco"

#: solimp at the maximum MuJoCo allows (impedance 0.9999 at any violation):
#: the constraint regulariser is 1e-4 of the constraint's inverse inertia
#: (SIMULATORS.md; MuJoCo's default 0.9 left 30–50 % errors in statics).
STIFF_SOLIMP = (0.9999, 0.9999, 0.001, 0.5, 2.0)

#: Newton's default tolerance (1e-8) stops with a residual acceleration that
#: keeps the bodies creeping; 1e-16 lets the forces settle to rounding
#: (as in :mod:`mechcheck.sim_models.mujoco.model`).
SOLVER_TOLERANCE = 1e-16

#: Q1 step budget: 100 s of simulated time at the longest step; the exam
#: system settles in ~550 steps.
MAX_STEPS = 10_000

#: Mass of the Q2 driver, kg. It carries the mass's reaction F (≲ 100 N) with
#: an acceleration F/DRIVER_MASS ~ 1e-7 m/s², so over a second it leaves the
#: prescribed path by ~1e-7 m (reported as ``driver_deviation``).
DRIVER_MASS = 1e9

#: Q2 time step, s. The force read at step n is m·Δ²x/dt² + (k1 + k2)·x + μ·N,
#: whose central second difference differs from ẍ by dt²/12·x⁗: 2e-7 of F for
#: the exam motion at 1e-3 s (measured 1e-6 with the constraint softness).
Q2_TIMESTEP = 1e-3

#: First lead-in before the first reading, s, and the longest it may grow to.
#: The normal equality starts unloaded and needs ~40 steps to carry m·g to
#: 1e-9 (measured: change 6e-7 after 10 steps, 1e-10 after 40); a reading is
#: accepted only once N no longer changes (:data:`NORMAL_CHANGE_RTOL`),
#: otherwise the lead-in doubles.
LEAD_IN = 0.05
MAX_LEAD_IN = 0.8
#: N is steady when it changes by less than this fraction between two steps.
NORMAL_CHANGE_RTOL = 1e-9


Array = NDArray[np.float64]


def _stiff(dt: float) -> dict[str, list[float]]:
    return {"solref": [2.0 * dt, 1.0], "solimp": list(STIFF_SOLIMP)}


def _base_spec(name: str, dt: float, gravity: float) -> mujoco.MjSpec:
    spec = mujoco.MjSpec()
    spec.modelname = name
    spec.compiler.degree = False
    opt = spec.option
    opt.timestep = dt
    opt.gravity = [0.0, -gravity, 0.0]  # the plane is x–y: weight along −y, set explicitly
    opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    opt.integrator = int(mujoco.mjtIntegrator.mjINT_EULER)  # joint damping is implicit in Euler
    opt.tolerance = SOLVER_TOLERANCE
    return spec


def _slide(body: mujoco.MjsBody, name: str, axis: tuple[float, float, float],
           **kwargs: object) -> None:
    body.add_joint(name=name, type=mujoco.mjtJoint.mjJNT_SLIDE, axis=list(axis), **kwargs)


# ------------------------------------------------------------------------- Q1


@dataclass(frozen=True)
class Q1Settings:
    """Start pose and stopping rule of a Q1 settling run.

    ``start_x`` (m) and ``start_phi`` (rad) are where the run starts, at rest;
    the default hangs the bar straight down at the spring's rest point.
    """

    start_x: float = 0.0
    start_phi: float = 0.0
    damping_ratio: float = DAMPING_RATIO
    velocity_tol: float = VELOCITY_TOL
    force_change_rtol: float = FORCE_CHANGE_RTOL
    max_steps: int = MAX_STEPS


def q1_spec(system: Q1System, settings: Q1Settings = Q1Settings()) -> mujoco.MjSpec:
    """The MuJoCo model of exam Q1 (pure: a new spec every call)."""
    s = system
    dt = q1_timestep(s)
    c_x, c_phi = q1_dampers(s, settings.damping_ratio)
    spec = _base_spec("exam-Q1", dt, s.gravity)
    world = spec.worldbody
    # The slider only translates; its inertia just has to be valid. An explicit
    # ipos: left unset (NaN) the XML writer drops the whole <inertial>.
    i_slider = s.slider_mass * s.length**2 / 12.0
    slider = world.add_body(name="slider", mass=s.slider_mass, ipos=[0.0, 0.0, 0.0],
                            inertia=[i_slider] * 3, explicitinertial=True)
    _slide(slider, "slider_x", (1.0, 0.0, 0.0), stiffness=s.stiffness, springref=0.0, damping=c_x)
    _slide(slider, "slider_y", (0.0, 1.0, 0.0))
    slider.add_site(name="A_on_slider")
    i_bar = s.mass * s.length**2 / 12.0  # uniform bar about its centre
    bar = world.add_body(name="bar", mass=s.mass, ipos=[0.0, -0.5 * s.length, 0.0],
                         inertia=[i_bar] * 3, explicitinertial=True)
    _slide(bar, "bar_x", (1.0, 0.0, 0.0))
    _slide(bar, "bar_y", (0.0, 1.0, 0.0))
    # Body frame at A, bar along −y at φ = 0: the hinge angle is φ itself.
    bar.add_joint(name="phi", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0.0, 0.0, 1.0], damping=c_phi)
    bar.add_site(name="A_on_bar")
    bar.add_site(name="B", pos=[0.0, -s.length, 0.0])
    # First site on the bar: the connect force is the force on the bar.
    spec.add_equality(name="pin", type=mujoco.mjtEq.mjEQ_CONNECT, objtype=mujoco.mjtObj.mjOBJ_SITE,
                      name1="A_on_bar", name2="A_on_slider", **_stiff(dt))
    spec.add_equality(name="slide", type=mujoco.mjtEq.mjEQ_JOINT, name1="slider_y",
                      data=[0.0] * 12, **_stiff(dt))
    return spec


def q1_xml(system: Q1System) -> str:
    """The Q1 model as MJCF, for review."""
    return str(q1_spec(system).to_xml())


@dataclass
class _Q1Rig:
    """The compiled Q1 model with its data and where everything is."""

    system: Q1System
    model: mujoco.MjModel
    data: mujoco.MjData
    bar: int
    site_b: int
    dof: dict[str, int]
    pin: int
    slide: int

    @classmethod
    def build(cls, system: Q1System, settings: Q1Settings) -> _Q1Rig:
        model = q1_spec(system, settings).compile()

        def jid(name: str) -> int:
            return int(model.jnt_dofadr[model.joint(name).id])

        return cls(system, model, mujoco.MjData(model), model.body("bar").id, model.site("B").id,
                   {n: jid(n) for n in ("slider_x", "slider_y", "bar_x", "bar_y", "phi")},
                   model.equality("pin").id, model.equality("slide").id)

    def start(self, x: float, phi: float) -> None:
        """At rest at slider position x, bar angle φ (assembled: the bar's A on the slider)."""
        mujoco.mj_resetData(self.model, self.data)
        q = self.data.qpos
        q[self.dof["slider_x"]] = q[self.dof["bar_x"]] = x
        q[self.dof["phi"]] = phi

    def apply_force(self) -> None:
        """F along +x at B's current position, as a wrench about the bar's centre of mass."""
        m, d = self.model, self.data
        mujoco.mj_kinematics(m, d)
        force = np.array([self.system.force, 0.0, 0.0])
        d.xfrc_applied[self.bar, :3] = force
        d.xfrc_applied[self.bar, 3:] = np.cross(d.site_xpos[self.site_b] - d.xipos[self.bar], force)

    def _rows(self, eq: int) -> NDArray[np.int_]:
        d = self.data
        return np.flatnonzero((d.efc_type == mujoco.mjtConstraint.mjCNSTR_EQUALITY) & (d.efc_id == eq))

    def forces(self) -> Array:
        """(spring force on the slider, pin force on the bar x, y, normal force on the slider), N."""
        d = self.data
        pin = d.efc_force[self._rows(self.pin)]
        normal = d.efc_force[self._rows(self.slide)]
        return np.array([d.qfrc_spring[self.dof["slider_x"]], pin[0], pin[1], normal[0]])

    def point_speed(self) -> float:
        """Largest slide speed or hinge speed × l, m/s."""
        v = np.abs(self.data.qvel)
        slides = max(v[self.dof[n]] for n in ("slider_x", "slider_y", "bar_x", "bar_y"))
        return float(max(slides, v[self.dof["phi"]] * self.system.length))

    def pose(self) -> tuple[float, float]:
        q = self.data.qpos
        return float(q[self.dof["slider_x"]]), float(q[self.dof["phi"]])

    def pin_violation(self) -> float:
        """Distance between the two A sites, m (the soft connect's violation)."""
        d = self.data
        a_bar = d.site_xpos[self.model.site("A_on_bar").id]
        a_slider = d.site_xpos[self.model.site("A_on_slider").id]
        return float(np.linalg.norm(a_bar - a_slider))


def settle_q1(system: Q1System, settings: Q1Settings = Q1Settings()) -> Q1Result:
    """Exam Q1's equilibrium as MuJoCo finds it by settling from ``settings``' start pose.

    Example
    -------
    >>> from mechcheck.analytic.exam import exam_q1
    >>> result = settle_q1(exam_q1())
    >>> result.status, round(math.degrees(result.values.phi), 1)
    ('ok', 34.2)
    """
    tic = time.perf_counter()
    rig = _Q1Rig.build(system, settings)
    m, d = rig.model, rig.data
    rig.start(settings.start_x, settings.start_phi)
    previous: Array | None = None
    change = speed = math.inf
    settled = False
    step = 0
    for step in range(settings.max_steps + 1):  # noqa: B007 - the step count is reported
        rig.apply_force()
        mujoco.mj_forward(m, d)
        current = rig.forces()
        speed = rig.point_speed()
        if previous is not None:
            scale = max(float(np.abs(current).max()), 1e-300)
            change = float(np.abs(current - previous).max()) / scale
            if change <= settings.force_change_rtol and speed <= settings.velocity_tol:
                settled = True
                break
        previous = current
        mujoco.mj_Euler(m, d)
    x, phi = rig.pose()
    diagnostics = {"x": x, "phi": phi, "timestep": m.opt.timestep,
                   "pin_violation": rig.pin_violation(),
                   "slide_violation": abs(float(d.qpos[rig.dof["slider_y"]])),
                   "start_x": settings.start_x, "start_phi": settings.start_phi}
    forces = tuple(float(v) for v in rig.forces())
    return q1_result(BACKEND, settled, x, phi, (forces[0], forces[1], forces[2], forces[3]),
                     steps=step, elapsed=time.perf_counter() - tic, speed=speed, change=change,
                     max_steps=settings.max_steps, diagnostics=diagnostics)


# ------------------------------------------------------------------------- Q2


@dataclass(frozen=True)
class Q2Settings:
    """Time step, lead-in and driver of a Q2 driven run (see the module constants)."""

    timestep: float = Q2_TIMESTEP
    lead_in: float = LEAD_IN
    max_lead_in: float = MAX_LEAD_IN
    driver_mass: float = DRIVER_MASS
    normal_change_rtol: float = NORMAL_CHANGE_RTOL


def q2_spec(system: Q2System, settings: Q2Settings = Q2Settings()) -> mujoco.MjSpec:
    """The MuJoCo model of exam Q2 (pure: a new spec every call)."""
    s = system
    dt = settings.timestep
    spec = _base_spec("exam-Q2", dt, s.gravity)
    world = spec.worldbody
    mass = world.add_body(name="mass", mass=s.mass, ipos=[0.0, 0.0, 0.0], inertia=[s.mass] * 3,
                          explicitinertial=True)
    # The friction constraint as stiff as the equalities; its limit is set every step.
    _slide(mass, "x", (1.0, 0.0, 0.0), solref_friction=[2.0 * dt, 1.0],
           solimp_friction=list(STIFF_SOLIMP))
    _slide(mass, "y", (0.0, 1.0, 0.0))
    driver = world.add_body(name="driver", mass=settings.driver_mass, ipos=[0.0, 0.0, 0.0],
                            inertia=[1.0] * 3, explicitinertial=True)
    _slide(driver, "drive", (1.0, 0.0, 0.0))
    for name, coef, k in (("k1", 1.0, s.k1), ("k2", -1.0, s.k2)):
        tendon = spec.add_tendon(name=name, stiffness=k, springlength=[0.0, 0.0])
        tendon.wrap_joint("x", coef)
    spec.add_equality(name="surface", type=mujoco.mjtEq.mjEQ_JOINT, name1="y", data=[0.0] * 12,
                      **_stiff(dt))
    # x − x_d = 0: Jacobian +1 on x, so the force is the drive force on the mass.
    spec.add_equality(name="drive", type=mujoco.mjtEq.mjEQ_JOINT, name1="x", name2="drive",
                      data=[0.0, 1.0] + [0.0] * 10, **_stiff(dt))
    return spec


def q2_xml(system: Q2System) -> str:
    """The Q2 model as MJCF, for review."""
    return str(q2_spec(system).to_xml())


@dataclass
class _Q2Run:
    """One driven run: readings at the steps asked for, and what is needed to judge them."""

    times: Array
    force: Array
    friction: Array
    normal: Array
    normal_change: Array
    tracking: Array
    driver_deviation: Array
    steps: int


def _drive_once(system: Q2System, motion: Motion, times: Array, settings: Q2Settings,
                lead: float) -> _Q2Run:
    model = q2_spec(system, settings).compile()
    d = mujoco.MjData(model)
    dt = settings.timestep
    x_dof = int(model.jnt_dofadr[model.joint("x").id])
    d_dof = int(model.jnt_dofadr[model.joint("drive").id])
    surface, drive = model.equality("surface").id, model.equality("drive").id
    start, steps = reading_steps(times, dt, lead)
    grid = start + dt * np.arange(-1, steps[-1] + 2)  # t_{-1} … t_{last+1}
    path = motion.position(grid)
    # On the path at t_0 with the velocity that brought it there (its backward difference).
    d.qpos[x_dof] = d.qpos[d_dof] = path[1]
    d.qvel[x_dof] = d.qvel[d_dof] = (path[1] - path[0]) / dt
    equality = mujoco.mjtConstraint.mjCNSTR_EQUALITY
    friction_row = mujoco.mjtConstraint.mjCNSTR_FRICTION_DOF
    n_read = len(steps)
    out = {k: np.full(n_read, np.nan) for k in ("t", "F", "f", "N", "dN", "track", "drv")}
    previous_normal = math.nan
    want = {int(n): [i for i in range(n_read) if steps[i] == n] for n in np.unique(steps)}
    for n in range(int(steps[-1]) + 1):
        # Driver force: its Euler step then lands on x(t_{n+1}) exactly (rigid-body motion).
        d.qfrc_applied[d_dof] = settings.driver_mass * (path[n + 2] - 2.0 * path[n + 1] + path[n]) / dt**2
        mujoco.mj_forward(model, d)
        rows = np.flatnonzero((d.efc_type == equality) & (d.efc_id == surface))
        normal = float(d.efc_force[rows[0]])
        model.dof_frictionloss[x_dof] = system.mu * abs(normal)
        mujoco.mj_step(model, d)  # recomputes this state's forces with the new limit, then steps
        if n in want:
            f_rows = np.flatnonzero((d.efc_type == friction_row) & (d.efc_id == x_dof))
            drive_row = np.flatnonzero((d.efc_type == equality) & (d.efc_id == drive))[0]
            for i in want[n]:
                out["t"][i] = start + n * dt
                out["F"][i] = d.efc_force[drive_row]
                out["f"][i] = d.efc_force[f_rows[0]] if f_rows.size else 0.0
                out["N"][i] = normal
                out["dN"][i] = abs(normal - previous_normal) / abs(normal)
                # Positions at t_n, i.e. before this step's integration.
                out["track"][i] = abs(d.qpos[x_dof] - d.qvel[x_dof] * dt - path[n + 1])
                out["drv"][i] = abs(d.qpos[d_dof] - d.qvel[d_dof] * dt - path[n + 1])
        previous_normal = normal
    return _Q2Run(out["t"], out["F"], out["f"], out["N"], out["dN"], out["track"], out["drv"],
                  int(steps[-1]) + 1)


def drive_q2(system: Q2System, motion: Motion, times: ArrayLike,
             settings: Q2Settings = Q2Settings()) -> Q2Result:
    """The force MuJoCo needs to drive exam Q2's mass along ``motion``, read at ``times``.

    The run starts ``lead_in`` before the first reading on the prescribed
    path; if the normal force is still changing at any reading, the lead-in
    doubles (up to ``max_lead_in``), and if it never steadies the result is
    ``not_settled`` with those readings NaN.
    """
    tic = time.perf_counter()
    t = checked_times(times)
    run, lead, total_steps, steady = drive_until_steady(
        lambda lead: _drive_once(system, motion, t, settings, lead), settings.lead_in,
        settings.max_lead_in, settings.normal_change_rtol)
    force = np.where(steady, run.force, np.nan)
    status: Status = "ok" if bool(np.all(steady)) else "not_settled"
    message = unsteady_message(steady, lead)
    diagnostics = {"timestep": settings.timestep, "lead_in": lead,
                   "max_normal_change": float(np.nanmax(run.normal_change)),
                   "max_tracking_error": float(np.nanmax(run.tracking)),
                   "max_driver_deviation": float(np.nanmax(run.driver_deviation))}
    return Q2Result(BACKEND, run.times, force, run.friction, run.normal, status, total_steps,
                    time.perf_counter() - tic, message=message, diagnostics=diagnostics)
