"""The model settings every MuJoCo model is built with (:class:`Settings`, :data:`STATIC`,
:data:`EXACT`, the mass and armature constants), and the four-bar's and slider-crank's own
builder (:func:`build_spec`), which now serves only the turning experiments
(:mod:`.turning`): every backend builds its model with :mod:`.linkage_model`, the four-bar
and slider-crank as their linkage.

The model is planar by construction: every hinge turns about z and the slider
slides along the slide axis u, so nothing can leave the plane. Loop closure at
pin B is a ``connect`` equality between two sites (sites, because a
body-anchored connect would take its second anchor from ``qpos0``, where the
loop is open).

Bodies and frames follow CONVENTIONS.md: every body is built with its link
frame at ``qpos = 0``, so the joint coordinates are

- crank hinge ``A0``: θ12 (global);
- coupler hinge ``A`` (child of the crank): θ13 − θ12;
- rocker hinge ``B0``: θ14 (global); or slider ``slide``: s14 along u;
- optional ``clock`` hinge: φ = θ12 − θ12* (time-like).

Gravity is switched off in MuJoCo: weights are applied as loads on the real
masses only (:mod:`.loads`), which is what lets statics use fictitious masses.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco

from mechcheck.analytic.case import Case, FourBarGeometry, SliderCrankGeometry, preset_geometry
from mechcheck.sim_models.mujoco import mjwarnings  # noqa: F401  (MuJoCo warnings into Python before any model)

#: Fictitious mass of every link while settling statics, kg. Static forces do
#: not depend on masses as long as weights are applied only to the real
#: masses, and a soft constraint's violation at rest scales as 1/m (its
#: regulariser R is proportional to the inverse inertia J M⁻¹ Jᵀ), so a heavy
#: link keeps the settled pose within nanometres of the rigid one.
SETTLE_MASS = 1000.0

#: Mass given to a massless link in a dynamic run, as a fraction of the
#: heaviest real mass (or of 1 kg). MuJoCo refuses massless moving bodies. The
#: inertia forces this adds are removed by extrapolation (:mod:`.linkage_dynamics`), so
#: the fraction is chosen for the simulation, not for its bias: a soft
#: constraint's violation grows as the links it holds get lighter (its
#: regulariser R ∝ inverse inertia), and with 1e-5 exam Q3 needed dt = 1.6e-6 s
#: (9550 steps) and 4 of 24 poses of its sweep (every 15°) never converged; with
#: 1e-2 it converges at 1.25e-5 s (250 steps in each of the two models) and
#: every pose does. Kept small against the real inertia so that what is not
#: linear in it (the soft constraints' errors, friction's |F|) stays
#: negligible: the unloaded massless cases, where the extrapolation removes the
#: whole reading, are left with ≤ 1e-6 of the force floor (measured; 5e-8 with
#: 1e-3, 7e-6 with 0.1).
FICTITIOUS_MASS_FRACTION = 1e-2

#: A real mass whose inertia is below this fraction of m·L² (a point mass) gets
#: this much added: MuJoCo refuses a zero inertia.
INERTIA_FLOOR_FRACTION = 1e-5

#: Armature of the clock hinge, kg·m². So heavy that the mechanism's reaction
#: (order 10 N·m) changes the clock's speed by ~1e-8 rad/s² — a prescribed motion.
CLOCK_ARMATURE = 1e9

#: Armature of the driven hinge in a driven run, as a multiple of (heaviest real
#: mass) × (mechanism scale)², i.e. of the order of the real links' inertias.
#: A massless driven link gets only a fictitious inertia (it was 1e-5 of the
#: real ones, see :data:`FICTITIOUS_MASS_FRACTION`), and MuJoCo's regulariser R
#: of the drive equality is proportional to the inverse inertia it sees
#: (body_invweight0), so the drive held its torque with a violation of ~1e-4
#: rad — magnified 1/|dθ14/dθ12| times in the crank next to a rocker dead
#: point — and the crank sat on a spring of that compliance, a mode with ~5 %
#: damping that rang for ~700 steps (exam Q3). A grounded
#: hinge's armature is a pure couple between ground and the driven link, just
#: like the drive itself: it changes no reaction, and its torque I_a·q̈ is
#: subtracted exactly from the drive torque with MuJoCo's own q̈
#: (:meth:`.rig.Rig.read`). Of the order of the real inertias it neither
#: dominates the drive torque (I_a·α ~ the real inertia torques) nor leaves
#: the drive softer than the rest of the mechanism.
DRIVE_ARMATURE_INERTIA = 1.0

#: solimp at the maximum MuJoCo allows: the impedance d = 0.9999 whatever the
#: violation, so the constraint regulariser R = (1 − d)/d · A is 1e-4 of the
#: constraint's own inverse inertia (MuJoCo's default is d = 0.9 → 0.95).
STIFF_SOLIMP = (0.9999, 0.9999, 0.001, 0.5, 2.0)

#: Newton solver tolerance (see build_spec).
SOLVER_TOLERANCE = 1e-16

#: MuJoCo's defaults, kept to measure how far they are from rigid-body statics.
DEFAULT_SOLREF = (0.02, 1.0)
DEFAULT_SOLIMP = (0.9, 0.95, 0.001, 0.5, 2.0)


@dataclass(frozen=True)
class Settings:
    """How the model is built: time step, constraint softness, masses, clock.

    ``solref_timeconst = None`` means 2·timestep, the stiffest value MuJoCo
    does not clamp. ``masses = "settle"`` gives every link :data:`SETTLE_MASS`;
    ``"real"`` uses the Case's masses (dynamics). ``fictitious_scale``
    multiplies every inertia the Case does not have — the settle mass, a
    massless link's mass and inertia, a point mass's floor inertia — so that a
    driven run can be repeated with twice of it and extrapolated to none
    (:mod:`.linkage_dynamics`).
    """

    timestep: float = 1e-3
    solref_timeconst: float | None = None
    solref_dampratio: float = 1.0
    solimp: tuple[float, float, float, float, float] = STIFF_SOLIMP
    masses: str = "settle"
    fictitious_fraction: float = FICTITIOUS_MASS_FRACTION
    fictitious_scale: float = 1.0
    armature: float = 0.0
    clock: bool = False
    drive_armature: bool = False

    def drive_armature_of(self, case: Case) -> float:
        """The extra armature of the driven hinge, kg·m² (see :data:`DRIVE_ARMATURE_INERTIA`)."""
        if not self.drive_armature:
            return 0.0
        reference = max((m.mass for m in case.masses), default=1.0)
        return DRIVE_ARMATURE_INERTIA * reference * case.geometry.scale**2

    @property
    def solref(self) -> tuple[float, float]:
        tc = 2.0 * self.timestep if self.solref_timeconst is None else self.solref_timeconst
        return (tc, self.solref_dampratio)


STATIC = Settings()
#: The exact solve never simulates, so massless links are made truly massless
#: after compiling (see :func:`zero_fictitious_masses`). M is then singular and
#: MuJoCo's factorisation would warn on every pass; a unit armature on every
#: joint keeps it invertible, and the solve subtracts armature·qacc exactly.
EXACT = Settings(masses="real", fictitious_fraction=1e-6, armature=1.0)
#: MuJoCo's default softness, for the stiffness study only.


def link_length(case: Case, link: int) -> float:
    """A link's length (for fictitious inertias); the slider gets the crank's."""
    g = preset_geometry(case)
    if link == 2:
        return g.a2
    if link == 3:
        return g.a3
    return g.a4 if isinstance(g, FourBarGeometry) else g.a2


def inertial(case: Case, link: int, settings: Settings) -> tuple[float, tuple[float, float], float]:
    """(mass, com in link frame, planar inertia about the com) of a link in the model."""
    length = link_length(case, link)
    real = case.mass_of(link)
    k = settings.fictitious_scale
    if settings.masses == "settle":
        m = k * SETTLE_MASS
        return m, (0.5 * length, 0.0), m * length**2 / 12.0
    reference = max((m.mass for m in case.masses), default=1.0)
    if real is None:
        m = k * settings.fictitious_fraction * reference
        return m, (0.5 * length, 0.0), m * length**2 / 12.0
    # Added, not substituted, so that it extrapolates to the real inertia.
    floor = INERTIA_FLOOR_FRACTION * real.mass * length**2
    if real.inertia >= floor:
        return real.mass, real.com, real.inertia
    return real.mass, real.com, real.inertia + k * floor


def has_fictitious_inertia(case: Case, settings: Settings) -> bool:
    """True when a moving part of the model has inertia the Case does not (see
    :func:`inertial`); a slider's rotational inertia does not count (it cannot turn)."""
    if settings.masses == "settle":
        return True
    if any(case.mass_of(link) is None for link in (2, 3, 4)):
        return True
    turning = [m for m in case.masses if not (m.link == 4 and case.mechanism == "slider_crank")]
    return any(m.inertia < INERTIA_FLOOR_FRACTION * m.mass * link_length(case, m.link)**2
               for m in turning)


def add_link_body(parent: mujoco.MjsBody, case: Case, link: int, settings: Settings,
                  name: str, pos: tuple[float, float], angle: float = 0.0) -> mujoco.MjsBody:
    """A link body whose frame is the link frame at qpos = 0."""
    mass, com, izz = inertial(case, link, settings)
    half = 0.5 * angle
    return parent.add_body(
        name=name, pos=[pos[0], pos[1], 0.0], quat=[math.cos(half), 0.0, 0.0, math.sin(half)],
        mass=mass, ipos=[com[0], com[1], 0.0],
        # Only Izz matters for hinges about z; Ixx = Iyy = Izz satisfies the
        # triangle inequality MuJoCo checks.
        inertia=[izz, izz, izz], explicitinertial=True)


def add_hinge(body: mujoco.MjsBody, name: str, armature: float = 0.0) -> None:
    body.add_joint(name=name, type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0.0, 0.0, 1.0],
                   armature=armature)


def build_spec(case: Case, settings: Settings = STATIC) -> mujoco.MjSpec:
    """The MuJoCo model of ``case`` as an MjSpec (pure: a new spec every call)."""
    spec = mujoco.MjSpec()
    spec.modelname = case.name
    spec.compiler.degree = False
    opt = spec.option
    opt.timestep = settings.timestep
    opt.gravity = [0.0, 0.0, 0.0]  # weights are loads on the real masses (see module doc)
    opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)  # links overlap in the plane
    opt.jacobian = int(mujoco.mjtJacobian.mjJAC_DENSE)  # efc_J read as a dense matrix
    opt.integrator = int(mujoco.mjtIntegrator.mjINT_EULER)
    # Newton's default tolerance (1e-8) stops with a residual acceleration that
    # makes the heavy links creep: the forces then drift by ~1e-8 per step and
    # never settle. The tolerance is relative to the whole problem, which the
    # 1e9 clock armature dominates: 1e-12 still left 7e-5 N·m of step-to-step
    # noise in a clock-driven torque, 1e-16 leaves 2e-9 (measured). Newton
    # still stops after one iteration (the problem is quadratic).
    opt.tolerance = SOLVER_TOLERANCE
    world = spec.worldbody
    g = preset_geometry(case)
    crank = add_link_body(world, case, 2, settings, "link2", (0.0, 0.0))
    add_hinge(crank, "A0", settings.armature)
    coupler = add_link_body(crank, case, 3, settings, "link3", (g.a2, 0.0))
    add_hinge(coupler, "A", settings.armature)
    coupler.add_site(name="B_on_3", pos=[g.a3, 0.0, 0.0])
    if isinstance(g, FourBarGeometry):
        b0 = (g.a1 * math.cos(case.ground_angle), g.a1 * math.sin(case.ground_angle))
        rocker = add_link_body(world, case, 4, settings, "link4", b0)
        add_hinge(rocker, "B0", settings.armature)
        rocker.add_site(name="B_on_4", pos=[g.a4, 0.0, 0.0])
    else:
        add_slider(world, case, g, settings)
    add_load_sites(spec, case)
    if settings.clock:
        clock = world.add_body(name="clock", mass=1.0, inertia=[1.0, 1.0, 1.0],
                               explicitinertial=True)
        add_hinge(clock, "clock", armature=CLOCK_ARMATURE)
    # The first site's body receives the connect force with a + sign: link 4,
    # so the equality force is F34 (by 3 on 4).
    spec.add_equality(name="loop_B", type=mujoco.mjtEq.mjEQ_CONNECT,
                      objtype=mujoco.mjtObj.mjOBJ_SITE, name1="B_on_4", name2="B_on_3",
                      solref=list(settings.solref), solimp=list(settings.solimp))
    drive_joint = "A0" if case.drive_link == 2 else "B0"
    if settings.drive_armature:
        joint = spec.joint(drive_joint)
        joint.armature = joint.armature + settings.drive_armature_of(case)
    spec.add_equality(name="drive", type=mujoco.mjtEq.mjEQ_JOINT, name1=drive_joint,
                      name2="clock" if settings.clock else "",
                      data=[0.0, 1.0, 0.0, 0.0, 0.0] + [0.0] * 7,
                      solref=list(settings.solref), solimp=list(settings.solimp))
    return spec


def add_load_sites(spec: mujoco.MjSpec, case: Case) -> None:
    """A site at every load point and real centre of mass (where weights act).

    The sites make the load points visible in the golden XML, and their
    ``site_xpos`` gives each point's current global position for free.
    """
    for i, load in enumerate(case.loads):
        body = spec.body(f"link{load.link}")
        body.add_site(name=f"load{i}", pos=[load.at[0], load.at[1], 0.0])
    for m in case.masses:
        spec.body(f"link{m.link}").add_site(name=f"weight{m.link}",
                                            pos=[m.com[0], m.com[1], 0.0])


def add_slider(world: mujoco.MjsBody, case: Case, g: SliderCrankGeometry,
               settings: Settings) -> None:
    """The slider: origin on the slide line at s14 = 0, x along u, one slide joint."""
    u = (math.cos(case.ground_angle), math.sin(case.ground_angle))
    origin = (-g.offset * u[1], g.offset * u[0])  # e·n
    slider = add_link_body(world, case, 4, settings, "link4", origin, case.ground_angle)
    slider.add_joint(name="slide", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1.0, 0.0, 0.0],
                     armature=settings.armature)
    slider.add_site(name="B_on_4", pos=[0.0, 0.0, 0.0])


def place_frames_exactly(model: mujoco.MjModel) -> None:
    """Switch off MuJoCo's same-frame shortcut in a compiled model.

    The compiler marks a site (or a centre of mass) within a small distance of its body's
    frame as "same frame" and then puts it exactly there: a load 6e-8 m (or 2e-7 m) from
    a pivot lost its moment (found by the random linkages; the four-bar's loads were moved
    the same way, measured). Off, every site and centre of mass is placed from its own
    offset; the cost is a few multiplications per site.
    """
    model.site_sameframe[:] = 0
    model.body_sameframe[:] = 0
