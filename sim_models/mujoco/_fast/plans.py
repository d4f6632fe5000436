"""What each compiled kernel is handed: MuJoCo's C functions and one plan of named arrays
(NamedTuples, which numba takes as they are), instead of a long row of positional arguments.

``d_*`` fields are views of the MjData's own arrays: the kernels write into them and read
out of them around each MuJoCo call.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

Array = np.ndarray


class MjCalls(NamedTuple):
    """One model and data (their C addresses) and the MuJoCo functions the kernels call on
    them (through their C pointers, :func:`.pointers.functions`)."""

    m: int
    d: int
    forward: Any
    kinematics: Any
    com_pos: Any
    com_vel: Any
    rne: Any  # mj_rnePostConstraint
    step: Any
    mul_m: Any
    set_state: Any
    get_state: Any
    euler: Any
    fwd_position: Any
    forward_skip: Any


class PointsPlan(NamedTuple):
    """:func:`.exact_kernel.load_points`: the poses, the data's views, the outputs."""

    qpos: Array
    d_qpos: Array
    d_sites: Array
    d_centres: Array
    sites: Array
    centres: Array


class EquationsPlan(NamedTuple):
    """:func:`.exact_kernel.equations`: the poses (qpos, qvel, qacc, the drivers' eq_data
    columns, the loads), the data's views, the outputs, and which parts apply."""

    qpos: Array
    qvel: Array
    qacc: Array
    columns: Array
    loads: Array
    d_qpos: Array
    d_qvel: Array
    held: Array  # eq_data's first column
    d_xfrc: Array
    d_jac: Array
    d_pos: Array
    d_smooth: Array
    jac: Array
    efc_pos: Array
    smooth: Array
    inertial: Array
    rolling: bool  # the poses move: qvel is set at each
    moving: bool  # the poses accelerate: M·qacc is computed at each


class PostPlan(NamedTuple):
    """:func:`.exact_kernel.post`: the poses with their forces imposed, the data's views,
    the arrays copied out (``targets`` row i ← ``sources``), and which parts apply."""

    qpos: Array
    qvel: Array
    qacc: Array
    loads: Array
    forces: Array
    d_qpos: Array
    d_qvel: Array
    d_qacc: Array
    d_xfrc: Array
    d_force: Array
    targets: tuple[Array, ...]
    sources: tuple[Array, ...]
    rolling: bool
    tendons: bool  # the whole forward pass (tendons' lengths and pull), else kinematics
    steady: bool  # qacc stays zero


class Capture(NamedTuple):
    """What a read copies out of MjData into row k of a Snapshot's arrays
    (:func:`.exact_kernel.capture`): the equality forces (the data's constraint views) with
    the carried ones added, and each captured array (``outs`` row k ← ``sources``)."""

    carried: Array
    d_force: Array
    d_pos: Array
    out_force: Array
    out_pos: Array
    outs: tuple[Array, ...]
    sources: tuple[Array, ...]


class ReadsPlan(NamedTuple):
    """:func:`.exact_kernel.reads`: the states (set by ``spec``) with their drivers'
    targets, loads and drive forces, the data's views, the arrays copied out."""

    states: Array
    spec: int
    eq_data: Array
    driver_eqs: Array
    targets: Array
    xfrc: Array
    d_xfrc: Array
    d_qfrc: Array
    drive_dofs: Array
    drives: Array
    capture: Capture


class PassData(NamedTuple):
    """The MjData and MjModel arrays :func:`.step_kernel.passes` resets or reads."""

    full: int  # the FULLPHYSICS state spec
    controls_spec: int
    eq_data: Array
    driver_eqs: Array
    eq_active: Array
    eq_active0: Array
    warnings: Array
    warmstart: Array
    sensordata: Array
    qvel: Array


class PassPlan(NamedTuple):
    """:func:`.step_kernel.passes`: each pose's pass (drivers' targets, start state, held
    controls, budget), how the rollouts are cut, what the stop rules read, the outputs."""

    targets: Array
    starts: Array
    controls: Array
    first_chunk: int
    chunk: int
    readings_left: Array
    earliest: Array
    columns: Array
    column_scale: Array
    weight: Array
    rounding: float
    ended_at: Array
    rules: Array
    ended_state: Array


class DrivePlan(NamedTuple):
    """:func:`.drive_kernel.drive`: a driven run's steps before each reading, its loads
    (:class:`..linkage_dynamics.PointLoads`: fixed body wrenches, forces at sites with their
    bodies, couples), the data's views, the arrays copied out at each reading."""

    steps: Array
    skip_position: int  # mjSTAGE_POS: the forward pass after the position stage
    base: Array
    sites: Array
    bodies: Array
    fx: Array
    fy: Array
    torques: Array
    d_xfrc: Array
    d_sites: Array
    d_centres: Array
    capture: Capture
