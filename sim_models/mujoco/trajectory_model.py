"""The MuJoCo model of a linkage that moves freely (a trajectory case), and its state at
time 0.

The model is the one every MuJoCo backend builds (:mod:`.linkage_model`, :mod:`.linkage_build`)
with the case's real masses, edited before it is compiled (:func:`free_motion_spec`) so that
everything that acts on the linkage is MuJoCo's own and is evaluated at every stage of every
integrator (Euler, implicitfast and RK4 alike, without a Python call between steps):

- gravity is MuJoCo's (the static builds apply weights as loads, to allow fictitious
  masses): m·g at each body's centre of mass is the sum of its masses' weights; a massless
  link's fictitious mass is compensated (``gravcomp`` = 1), so it weighs nothing;
- a load (a force fixed in direction at a point, and a couple) is a ``site`` actuator at the
  load's site with its ``refsite`` on the world body, whose gear (F_x, F_y, 0, 0, 0, M) is
  then fixed in the world: the moment about the body follows the point as it moves;
- a driver with an effort loses its joint equality and gets an actuator on its joint whose
  force is its activation, integrated from ``ctrl`` (``dyntype`` integrator): the effort at
  time 0 is the initial activation and ``ctrl`` the slope of the table's current row, so a
  constant or piecewise-linear effort is exact at every integrator stage;
- a driver without an effort keeps its prescribed motion q = value + v·t + a·t²/2 through
  the clock of the driven runs (:func:`.linkage_model.build_spec`);
- a damper on a loop-closing joint (no MuJoCo joint there) is a fixed tendon over the
  hinges whose signed sum is the joint's relative rotation, with the damper's coefficient;
- springs, dampers on tree joints and viscous friction are the model's as built; Coulomb
  friction needs the reactions at every step (:mod:`.linkage_friction`, applied by
  :mod:`.trajectory`).

The state at time 0 (:func:`initial_state`) is the analytic engine's pose and velocity solve
with the independent coordinates as drivers: the drivers at their values and rates, the
joints of ``simulation.rates`` at their drawn place and rates, and joints at rest in their
drawn place for any freedom left (the analytic side seeds the start, nothing more).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import mujoco
import numpy as np

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage import Driver, Linkage
from mechcheck.analytic.linkage_dynamics import independent_joints
from mechcheck.analytic.linkage_kinematics import solve_pose
from mechcheck.analytic.values import GROUND
from mechcheck.sim_models.inertia import real_inertial
from mechcheck.sim_models.mujoco.joint_kinds import builder_of
from mechcheck.sim_models.mujoco.linkage_members import split_members
from mechcheck.sim_models.mujoco.linkage_model import (
    Unbuildable,
    body_name,
    joint_damping,
    spanning_tree,
)
from mechcheck.sim_models.mujoco.linkage_rig import Array, LinkageRig
from mechcheck.sim_models.mujoco.model import Settings

#: A massless link's fictitious mass, as a fraction of the heaviest real mass: it changes
#: the motion by about this fraction of the linkage's inertia (MuJoCo refuses massless
#: moving bodies). The driven runs extrapolate theirs away; a trajectory keeps it small.
TRAJECTORY_FICTITIOUS_FRACTION = 1e-4
#: A point mass's inertia, as a fraction of m·L² (MuJoCo refuses none): the static and
#: driven models' 1e-5 changed a pendulum's period by 5e-6 and its angle after one swing by
#: 2.6e-5 rad, measured; this changes it by ~1e-9.
TRAJECTORY_INERTIA_FLOOR = 1e-9
#: The world site every load actuator's gear is expressed in.
WORLD_SITE = "world_frame"


def trajectory_settings(case: Case, dt: float) -> Settings:
    """Real masses, MuJoCo's stiffest constraints at ``dt`` (a time constant of 2·dt), and
    the clock where a driver prescribes a motion."""
    prescribed = any(d.effort is None for d in case.linkage.drivers)
    return Settings(timestep=dt, masses="real", clock=prescribed,
                    fictitious_fraction=TRAJECTORY_FICTITIOUS_FRACTION,
                    inertia_floor=TRAJECTORY_INERTIA_FLOOR)


def refusal(case: Case) -> str | None:
    """Why this linkage has no free-motion MuJoCo model here, or None."""
    linkage = case.linkage
    try:
        tree = spanning_tree(linkage)
    except Unbuildable as why:
        return str(why)
    if tree.meshes:
        return ("a gear mesh re-aims its tendon between steps, which a free-motion run does "
                "not do: mujoco simulates linkages without gear meshes")
    if split_members(linkage):
        return ("elastic members (axial_stiffness) are springs of 1e8 N/m and more: mujoco "
                "simulates rigid linkages only")
    return None


def free_motion_spec(case: Case) -> Callable[[mujoco.MjSpec], None]:
    """The edits that make the built spec a free-motion model (the module doc)."""
    linkage = case.linkage

    def customize(spec: mujoco.MjSpec) -> None:
        spec.option.gravity = [linkage.gravity[0], linkage.gravity[1], 0.0]
        for link in linkage.moving_links:
            if real_inertial(linkage, link) is None:
                spec.body(body_name(link)).gravcomp = 1.0
        spec.worldbody.add_site(name=WORLD_SITE)
        for i, load in enumerate(linkage.loads):
            if load.link != GROUND:
                spec.add_actuator(name=f"load{i}", trntype=mujoco.mjtTrn.mjTRN_SITE,
                                  target=f"load{i}", refsite=WORLD_SITE,
                                  gear=[load.force[0], load.force[1], 0.0, 0.0, 0.0, load.torque])
        for driver in linkage.drivers:
            if driver.effort is not None:
                spec.equality(f"drive_{driver.joint}").active = False
                spec.add_actuator(name=effort_name(driver), trntype=mujoco.mjtTrn.mjTRN_JOINT,
                                  target=driver.joint, dyntype=mujoco.mjtDyn.mjDYN_INTEGRATOR,
                                  actdim=1)
        _closure_dampers(spec, linkage)

    return customize


def effort_name(driver: Driver) -> str:
    return f"effort_{driver.joint}"


def _closure_dampers(spec: mujoco.MjSpec, linkage: Linkage) -> None:
    """Each damper on a loop-closing joint as a fixed tendon over the hinges whose signed
    sum is its relative rotation φ_links[1] − φ_links[0] (a linear function of qpos)."""
    tree = spanning_tree(linkage)
    for joint in tree.closures:
        c = joint_damping(linkage, joint)
        if c <= 0.0:
            continue
        tendon = spec.add_tendon(name=f"damper_{joint.name}", damping=[c, 0.0, 0.0])
        coefficients: dict[str, float] = {}
        for link, sign in ((joint.links[1], 1.0), (joint.links[0], -1.0)):
            for name, turn in _hinges_to_ground(linkage, link):
                coefficients[name] = coefficients.get(name, 0.0) + sign * turn
        for name, coefficient in coefficients.items():
            if coefficient:
                tendon.wrap_joint(name, coefficient)


def _hinges_to_ground(linkage: Linkage, link: str) -> list[tuple[str, float]]:
    """(MuJoCo joint, its sign) of every hinge on ``link``'s path to the ground: the link's
    rotation is their signed sum (as :meth:`.linkage_build.RigModel._rotations`)."""
    tree = spanning_tree(linkage)
    out: list[tuple[str, float]] = []
    while link != GROUND:
        t = tree.parent_joint(link)
        out += [(mj.name, mj.turn) for mj in builder_of(t.joint).joints(t.joint, t.sign) if mj.turn]
        link = t.parent
    return out


def trajectory_rig(case: Case, dt: float) -> LinkageRig:
    """The compiled free-motion model of ``case`` at time step ``dt``."""
    rig = LinkageRig(case, trajectory_settings(case, dt), free_motion_spec(case))
    rig.set_timestep(dt)
    return rig


# -- the state at time 0 -----------------------------------------------------------------

def independent_linkage(case: Case) -> Linkage:
    """The linkage with its independent coordinates as drivers at time 0, chosen as the
    analytic reference chooses them (:func:`~mechcheck.analytic.linkage_dynamics.independent_joints`):
    its drivers at their values and rates, the joints of ``simulation.rates`` at their drawn
    place with their rates, then joints at rest in their drawn place."""
    linkage = case.linkage
    assert case.simulation is not None
    rates = case.simulation.rates
    for j in rates:
        if not linkage.joint(j).kind.drivable:
            raise Unbuildable(f"simulate.rates.{j}: the start's velocities are solved with "
                              "each given rate as a driver's, and a "
                              f"{linkage.joint(j).kind.name} joint takes no driver: give the "
                              "rate of a revolute or prismatic joint instead")
    own = {d.joint: d for d in linkage.drivers}
    return replace(linkage, drivers=tuple(
        Driver(j, own[j].value, own[j].velocity) if j in own else Driver(j, 0.0, rates.get(j, 0.0))
        for j in independent_joints(linkage, tuple(rates))))


def initial_state(case: Case, rig: LinkageRig) -> tuple[Array, Array]:
    """qpos and qvel at time 0 (the module doc), the clock at 0 turning at 1 rad/s."""
    pose = solve_pose(independent_linkage(case))
    if not np.all(np.isfinite(pose.qdot)):
        raise Unbuildable("the linkage does not assemble with its drivers at their values")
    qpos, qvel, _ = rig.joint_states(pose)
    if rig.clock is not None:
        qpos[0, rig.clock], qvel[0, rig.clock] = 0.0, 1.0
    return qpos[0], qvel[0]


def prescribe(rig: LinkageRig) -> None:
    """Each driver without an effort on its motion q = value + v·t + a·t²/2 of the clock's
    angle t (as the driven runs)."""
    for driver in rig.linkage.drivers:
        if driver.effort is None:
            rig.model.eq_data[rig.drive_eq[driver.joint], :3] = (
                driver.value, driver.velocity, 0.5 * driver.acceleration)


def effort_actuators(rig: LinkageRig) -> list[tuple[int, Driver]]:
    """(actuator id, driver) of every driver with an effort."""
    return [(int(mujoco.mj_name2id(rig.model, mujoco.mjtObj.mjOBJ_ACTUATOR, effort_name(d))), d)
            for d in rig.linkage.drivers if d.effort is not None]


def load_actuators(rig: LinkageRig) -> list[int]:
    """The load actuators (each pushes with its gear at ctrl = 1)."""
    return [a for a in range(rig.model.nu)
            if rig.model.actuator_dyntype[a] == mujoco.mjtDyn.mjDYN_NONE]
