"""The exam systems of seed 002 (Sakarya University, 22.04.2014), Q1 and Q2, analytically.

Q1, virtual work. A slider A runs on a horizontal line (coordinate x) and is
held by a spring k, unstretched at x = 0. A uniform bar of mass m and length l
is pinned at A and hangs at φ from the downward vertical; a horizontal force F
acts at its free end B, so B = A + l·(sin φ, −cos φ). The virtual work

    δA = −k·x·δx − m·g·(l/2)·sin φ·δφ + F·(δx + l·cos φ·δφ) = 0

for independent δx, δφ gives F = k·x and tan φ = 2F/(m·g). The exam prints
φ = arctan(0.68) ≈ 34.2° for F = 10 N, m = 3 kg (g = 9.81 m/s²); k and l are
not given (they do not enter φ).

Q2, Lagrange–d'Alembert. A mass m between two springs k1 and k2 (both
unstretched at x = 0) slides on a surface with Coulomb friction μ, pushed by
F. For a prescribed motion x(t),

    F = m·ẍ + (k1 + k2)·x + μ·m·g·sign(ẋ),

which is the exam's F = m·ẍ + (k1 + k2)·x + μ·m·g for ẋ > 0. At ẋ = 0 the
friction force is anywhere in [−μ·m·g, μ·m·g]: F is indeterminate there and
:func:`q2_drive_force` refuses such instants.

Sign conventions (SI units, angles in radians): x and forces positive along
+x (right) and +y (up); φ positive when B swings towards +x.

Example
-------
>>> import math
>>> eq = q1_equilibrium(exam_q1())
>>> round(math.degrees(eq.phi), 1)
34.2
>>> round(math.tan(eq.phi), 2)
0.68
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Literal, Protocol, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]

#: The exam's printed answer to Q1, degrees (seed 002, "φ ≅ 34,2°").
EXAM_Q1_PHI_DEG = 34.2
#: The exam's printed tan φ = 2F/(m·g) (seed 002, "φ = arctan(0,68)").
EXAM_Q1_TAN_PHI = 0.68


def _require_positive(owner: str, **values: float) -> None:
    for name, value in values.items():
        if not (math.isfinite(value) and value > 0.0):
            raise ValueError(f"{owner}: {name} must be a positive finite number, got {value!r}")


def _require_nonnegative(owner: str, **values: float) -> None:
    for name, value in values.items():
        if not (math.isfinite(value) and value >= 0.0):
            raise ValueError(f"{owner}: {name} must be a non-negative finite number, got {value!r}")


# --------------------------------------------------------------------------- Q1


@dataclass(frozen=True)
class Q1System:
    """Exam Q1: spring-held slider A with a bar pinned at A, loaded by F at its end B.

    Parameters
    ----------
    force : F, N, horizontal at B (+x). Any sign; F = 0 gives x = φ = 0.
    mass : m, kg, of the uniform bar.
    length : l, m, of the bar (A to B).
    stiffness : k, N/m, of the slider's spring (unstretched at x = 0).
    slider_mass : kg. Not in the exam (it does not enter x or φ), but a
        simulator cannot move a massless body, so the slider has one and its
        weight is carried by the slide: N = (m + slider_mass)·g.
    gravity : g, m/s², acting along −y.
    """

    force: float = 10.0
    mass: float = 3.0
    length: float = 0.5
    stiffness: float = 200.0
    slider_mass: float = 0.5
    gravity: float = 9.81

    def __post_init__(self) -> None:
        if not math.isfinite(self.force):
            raise ValueError(f"Q1System: force must be finite, got {self.force!r}")
        _require_positive("Q1System", mass=self.mass, length=self.length, stiffness=self.stiffness,
                          slider_mass=self.slider_mass, gravity=self.gravity)

    @property
    def pivot_inertia(self) -> float:
        """The bar's moment of inertia about the pin A, m·l²/3, kg·m²."""
        return self.mass * self.length**2 / 3.0

    @property
    def translating_mass(self) -> float:
        """Slider and bar together, kg: the mass the spring k moves."""
        return self.mass + self.slider_mass

    @property
    def swing_stiffness(self) -> float:
        """The largest |∂Q_φ/∂φ| over all φ, l·√(F² + (m·g/2)²), N·m/rad.

        Q_φ = F·l·cos φ − m·g·(l/2)·sin φ is a sinusoid in φ of that
        amplitude, so this bounds the bar's restoring stiffness at any pose
        (simulators size their damping and time step with it).
        """
        return self.length * math.hypot(self.force, 0.5 * self.mass * self.gravity)

    def frequency_bound(self) -> float:
        """max(√(k/(m + m_slider)), √(swing_stiffness/I_A)), rad/s: the uncoupled natural frequencies."""
        return max(math.sqrt(self.stiffness / self.translating_mass),
                   math.sqrt(self.swing_stiffness / self.pivot_inertia))


@dataclass(frozen=True)
class Q1Equilibrium:
    """Exam Q1 at equilibrium: pose and every force (SI, radians).

    Attributes
    ----------
    x : slider position, m.
    phi : bar angle from the downward vertical, rad (B towards +x positive).
    spring_force : x-component of the spring's force on the slider, N (−k·x).
    pin_x, pin_y : force by the slider on the bar at the pin A, N.
    normal : y-component of the slide's (normal) force on the slider, N.
    """

    x: float
    phi: float
    spring_force: float
    pin_x: float
    pin_y: float
    normal: float

    def as_dict(self) -> dict[str, float]:
        """The quantities by name, for tables and comparisons."""
        return {"x": self.x, "phi": self.phi, "spring_force": self.spring_force,
                "pin_x": self.pin_x, "pin_y": self.pin_y, "normal": self.normal}


def bar_end(system: Q1System, x: float, phi: float) -> tuple[float, float]:
    """Position of the bar's free end B, m (A at (x, 0))."""
    return x + system.length * math.sin(phi), -system.length * math.cos(phi)


def q1_generalized_forces(system: Q1System, x: float, phi: float) -> tuple[float, float]:
    """The virtual-work coefficients (Q_x, Q_φ) = ∂(δA)/∂(δx, δφ) at a pose, N and N·m.

    Both vanish at, and only at, equilibrium (the exam's two equations):
    Q_x = F − k·x, Q_φ = F·l·cos φ − m·g·(l/2)·sin φ.
    """
    s = system
    q_x = s.force - s.stiffness * x
    q_phi = s.force * s.length * math.cos(phi) - s.mass * s.gravity * 0.5 * s.length * math.sin(phi)
    return q_x, q_phi


def q1_equilibrium(system: Q1System) -> Q1Equilibrium:
    """The equilibrium of exam Q1: x = F/k, tan φ = 2F/(m·g), and the forces that hold it.

    The bar is in equilibrium under its weight, F and the pin force R by the
    slider: R = (−F, m·g). The slider under the spring, the bar's −R, its
    weight and the slide's normal force: −k·x + F = 0 and
    N = (m + m_slider)·g.
    """
    s = system
    weight = s.mass * s.gravity
    x = s.force / s.stiffness
    # atan2 keeps the hanging branch (|φ| < 90°) the exam means, whatever the sign of F.
    phi = math.atan2(2.0 * s.force, weight)
    return Q1Equilibrium(x=x, phi=phi, spring_force=-s.stiffness * x, pin_x=-s.force, pin_y=weight,
                         normal=(s.mass + s.slider_mass) * s.gravity)


def exam_q1(stiffness: float = 200.0, length: float = 0.5) -> Q1System:
    """Exam Q1 with its printed data, F = 10 N, m = 3 kg, g = 9.81 m/s².

    The exam leaves k and l open; these defaults are our choice.
    """
    return Q1System(force=10.0, mass=3.0, length=length, stiffness=stiffness, gravity=9.81)


# --------------------------------------------------------------------------- Q2


class Motion(Protocol):
    """A prescribed motion x(t) of the Q2 mass (vectorised over t, SI)."""

    def position(self, t: ArrayLike) -> Array: ...

    def velocity(self, t: ArrayLike) -> Array: ...

    def acceleration(self, t: ArrayLike) -> Array: ...


@dataclass(frozen=True)
class Q2System:
    """Exam Q2: a mass between two springs, with Coulomb friction on a horizontal surface.

    Parameters
    ----------
    mass : m, kg.
    k1, k2 : N/m, the springs on either side, both unstretched at x = 0.
    mu : Coulomb friction coefficient between mass and surface (≥ 0).
    gravity : g, m/s², along −y; the normal force is m·g.
    """

    mass: float = 2.0
    k1: float = 150.0
    k2: float = 250.0
    mu: float = 0.3
    gravity: float = 9.81

    def __post_init__(self) -> None:
        _require_positive("Q2System", mass=self.mass, k1=self.k1, k2=self.k2, gravity=self.gravity)
        _require_nonnegative("Q2System", mu=self.mu)

    @property
    def normal_force(self) -> float:
        """The surface's normal force on the mass, N."""
        return self.mass * self.gravity


@dataclass(frozen=True)
class SineMotion:
    """The prescribed motion x(t) = offset + amplitude·sin(omega·t).

    ẋ > 0 for |omega·t| < π/2 (modulo 2π) when amplitude > 0.
    """

    amplitude: float = 0.01
    omega: float = 2.0 * math.pi
    offset: float = 0.0

    def __post_init__(self) -> None:
        _require_positive("SineMotion", amplitude=self.amplitude, omega=self.omega)
        if not math.isfinite(self.offset):
            raise ValueError(f"SineMotion: offset must be finite, got {self.offset!r}")

    def position(self, t: ArrayLike) -> Array:
        """x(t), m."""
        return self.offset + self.amplitude * np.sin(self.omega * np.asarray(t, dtype=float))

    def velocity(self, t: ArrayLike) -> Array:
        """ẋ(t), m/s."""
        return self.amplitude * self.omega * np.cos(self.omega * np.asarray(t, dtype=float))

    def acceleration(self, t: ArrayLike) -> Array:
        """ẍ(t), m/s²."""
        return -self.amplitude * self.omega**2 * np.sin(self.omega * np.asarray(t, dtype=float))

    def forward_interval(self) -> tuple[float, float]:
        """The open interval of t around 0 on which ẋ > 0, s."""
        half = 0.5 * math.pi / self.omega
        return -half, half


def q2_force(system: Q2System, x: ArrayLike, velocity: ArrayLike, acceleration: ArrayLike) -> Array:
    """F = m·ẍ + (k1 + k2)·x + μ·m·g·sign(ẋ), N (elementwise).

    Raises ValueError at ẋ = 0, where Coulomb friction, and so F, is not unique.
    """
    v = np.asarray(velocity, dtype=float)
    if np.any(v == 0.0):
        raise ValueError("q2_force: at ẋ = 0 the friction force, and so F, is indeterminate")
    s = system
    return (s.mass * np.asarray(acceleration, dtype=float) + (s.k1 + s.k2) * np.asarray(x, dtype=float)
            + s.mu * s.normal_force * np.sign(v))


def q2_drive_force(system: Q2System, motion: Motion, times: ArrayLike) -> Array:
    """The force F(t) that makes the mass follow ``motion`` at ``times``, N."""
    t = np.asarray(times, dtype=float)
    return q2_force(system, motion.position(t), motion.velocity(t), motion.acceleration(t))


def exam_q2() -> tuple[Q2System, SineMotion]:
    """Exam Q2 with our numbers (the exam gives none) and a motion with ẋ > 0 around t = 0.

    F = 5.886 N + 3.210 N·sin(2π t) stays positive, so a relative error of F
    means the same thing at every instant.
    """
    return Q2System(), SineMotion()


# ------------------------------------------------------------- simulator results

#: ``ok``, or ``not_settled``: the simulator did not reach a state the readings
#: are valid in (Q1: no equilibrium within its step budget; Q2: the start-up
#: transient had not died at a reading). Its numbers are then withheld.
Status = Literal["ok", "not_settled"]


@dataclass(frozen=True)
class Q1Result:
    """A simulator's answer to exam Q1, read from its own settled state.

    ``values`` is None unless ``status == "ok"``: an unsettled state is no
    equilibrium, so its forces mean nothing. ``diagnostics`` always carry the
    last pose (``x``, ``phi``) and how the run ended.
    """

    backend: str
    values: Q1Equilibrium | None
    status: Status
    steps: int
    wall_time_s: float
    residual_velocity: float
    force_change: float
    message: str = ""
    diagnostics: Mapping[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class Q2Result:
    """A simulator's drive force along a prescribed Q2 motion, read from its own state.

    ``times`` are the simulator's own reading instants (the step grid point
    nearest each requested time), s. ``force`` is the driving force on the
    mass, ``friction`` the friction force on it and ``normal`` the surface's
    normal force, N, per reading; readings taken before the start-up
    transient had died are NaN and make ``status`` ``not_settled``.
    """

    backend: str
    times: Array
    force: Array
    friction: Array
    normal: Array
    status: Status
    steps: int
    wall_time_s: float
    message: str = ""
    diagnostics: Mapping[str, float] = field(default_factory=dict)


def q1_result(backend: str, settled: bool, x: float, phi: float,
              forces: tuple[float, float, float, float], *, steps: int, elapsed: float,
              speed: float, change: float, max_steps: int,
              diagnostics: dict[str, float]) -> Q1Result:
    """A simulator's Q1 answer: its equilibrium and (spring, pin x, pin y, normal) forces,
    or ``not_settled`` with none when the run did not settle within ``max_steps``."""
    if not settled:
        return Q1Result(backend, None, "not_settled", steps, elapsed, speed, change,
                        message=f"no equilibrium within {max_steps} steps "
                                f"(point speed {speed:.2e} m/s, force change {change:.2e})",
                        diagnostics=diagnostics)
    spring, pin_x, pin_y, normal = forces
    values = Q1Equilibrium(x=x, phi=phi, spring_force=spring, pin_x=pin_x, pin_y=pin_y,
                           normal=normal)
    return Q1Result(backend, values, "ok", steps, elapsed, speed, change, diagnostics=diagnostics)


# -- settling Q1 in a simulator: shared by the MuJoCo and pymunk models -----------------
#: Q1 has settled when no velocity exceeds this point speed, m/s (slide speeds, and
#: the hinge's angular speed times l). With critical damping (decay rate ≥ 5/s here)
#: the pose error left is about this speed over the rate: ~1e-10 m and ~1e-10 rad, far
#: inside the 1e-4 rad target.
Q1_VELOCITY_TOL = 1e-9
#: ... and no reported force changes between two steps by more than this fraction of
#: the largest. Forces converge geometrically by a few per cent per step, so the
#: force error left is ≲ 30× this: ~3e-9, far inside 1e-3.
Q1_FORCE_CHANGE_RTOL = 1e-10
#: Q1 time step: this many steps per period of the fastest uncoupled mode
#: (:meth:`Q1System.frequency_bound`), at most :data:`Q1_MAX_TIMESTEP`. At rest the
#: step does not enter the forces (no inertia terms), so it only has to keep the
#: damped transient stable and well resolved.
Q1_STEPS_PER_PERIOD = 60.0
Q1_MAX_TIMESTEP = 1e-2
#: Damping ratio of the settling dampers (1 = critical for the uncoupled modes).
Q1_DAMPING_RATIO = 1.0


def q1_timestep(system: Q1System) -> float:
    """The Q1 settling time step, s (see :data:`Q1_STEPS_PER_PERIOD`)."""
    return min(Q1_MAX_TIMESTEP,
               2.0 * math.pi / (Q1_STEPS_PER_PERIOD * system.frequency_bound()))


def q1_dampers(system: Q1System, ratio: float = Q1_DAMPING_RATIO) -> tuple[float, float]:
    """(slider damping N·s/m, bar hinge damping N·m·s/rad), ``ratio`` × critical.

    Critical for each uncoupled mode: the spring with the whole translating mass,
    and the bar about A with its largest restoring stiffness. Dampers change the
    path to equilibrium, never the equilibrium.
    """
    c_x = 2.0 * ratio * math.sqrt(system.stiffness * system.translating_mass)
    c_phi = 2.0 * ratio * math.sqrt(system.swing_stiffness * system.pivot_inertia)
    return c_x, c_phi


# -- driving Q2 in a simulator: shared by the MuJoCo and pymunk models ------------------
def checked_times(times: ArrayLike) -> Array:
    """Reading times as a non-empty, finite, ascending 1-D array."""
    t = np.asarray(times, dtype=float)
    if t.ndim != 1 or t.size == 0 or not np.all(np.isfinite(t)) or np.any(np.diff(t) < 0.0):
        raise ValueError("times must be a non-empty, finite, ascending 1-D array")
    return t


def reading_steps(times: Array, dt: float, lead: float) -> tuple[float, NDArray[np.int_]]:
    """(start time, step index of each reading): the grid starts ``lead`` before the first time."""
    start = float(times[0]) - lead
    return start, np.rint((times - start) / dt).astype(int)


class DrivenRun(Protocol):
    """What a driven Q2 run must report for its lead-in to be judged."""

    normal_change: Array
    steps: int


RunT = TypeVar("RunT", bound=DrivenRun)


def drive_until_steady(run_once: Callable[[float], RunT], lead: float, max_lead: float,
                       rtol: float) -> tuple[RunT, float, int, NDArray[np.bool_]]:
    """Run with a lead-in that doubles until the normal force is steady at every reading.

    A reading is steady when its normal force changed by at most ``rtol`` over
    its step (friction of that step was computed from the same N). Returns the
    last run, its lead-in, the steps of all runs and which readings are steady.
    """
    total = 0
    while True:
        run = run_once(lead)
        total += run.steps
        steady = run.normal_change <= rtol
        if bool(np.all(steady)) or not lead < 2.0 * lead <= max_lead:
            return run, lead, total, steady
        lead *= 2.0


def unsteady_message(steady: NDArray[np.bool_], lead: float) -> str:
    """The ``not_settled`` message of a driven run, or "" when every reading is steady."""
    if bool(np.all(steady)):
        return ""
    return (f"the normal force was still changing at {int(np.sum(~steady))} readings "
            f"after a {lead:.3g} s lead-in")
