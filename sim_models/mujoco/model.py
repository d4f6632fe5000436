"""The settings every MuJoCo model is built with (:class:`Settings`, :data:`STATIC`,
:data:`EXACT`, the mass and armature constants); the builder is :mod:`.linkage_model`, for
any linkage, the four-bar and slider-crank as theirs.

Gravity is switched off in MuJoCo: weights are applied as loads on the real masses only,
which is what lets statics use fictitious masses.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco

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
#: (:meth:`.linkage_rig.LinkageRig.read`). Of the order of the real inertias it neither
#: dominates the drive torque (I_a·α ~ the real inertia torques) nor leaves
#: the drive softer than the rest of the mechanism.
DRIVE_ARMATURE_INERTIA = 1.0

#: solimp at the maximum MuJoCo allows: the impedance d = 0.9999 whatever the
#: violation, so the constraint regulariser R = (1 − d)/d · A is 1e-4 of the
#: constraint's own inverse inertia (MuJoCo's default is d = 0.9 → 0.95).
STIFF_SOLIMP = (0.9999, 0.9999, 0.001, 0.5, 2.0)

#: Newton solver tolerance (see :func:`.linkage_model._options`).
SOLVER_TOLERANCE = 1e-16


@dataclass(frozen=True)
class Settings:
    """How the model is built: time step, constraint softness, masses, clock.

    ``solref_timeconst = None`` means 2·timestep, the stiffest value MuJoCo
    does not clamp. ``masses = "settle"`` gives every link :data:`SETTLE_MASS`;
    ``"real"`` uses the Case's masses (dynamics). ``fictitious_scale``
    multiplies every inertia the Case does not have — the settle mass, a
    massless link's mass and inertia, a point mass's floor inertia — so that a
    driven run can be repeated with twice of it and extrapolated to none
    (:mod:`.linkage_dynamics`). ``inertia_floor`` is the inertia a point mass gets, as a
    fraction of m·L² (:data:`INERTIA_FLOOR_FRACTION`).
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
    inertia_floor: float = INERTIA_FLOOR_FRACTION

    @property
    def solref(self) -> tuple[float, float]:
        tc = 2.0 * self.timestep if self.solref_timeconst is None else self.solref_timeconst
        return (tc, self.solref_dampratio)


STATIC = Settings()
#: The exact solve never simulates, so massless links are made truly massless
#: after compiling (:func:`.linkage.exact_linkage_rig`). M is then singular and
#: MuJoCo's factorisation would warn on every pass; a unit armature on every
#: joint keeps it invertible, and the solve subtracts armature·qacc exactly.
EXACT = Settings(masses="real", fictitious_fraction=1e-6, armature=1.0)


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
