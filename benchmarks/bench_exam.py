"""Exam Q1 and Q2 (seed 002): agreement and run time of MuJoCo and pymunk, and the MuJoCo
contact-friction study behind the choice of ``frictionloss`` in :mod:`mechcheck.sim_models.mujoco.exam`.

Run: /work/venv/bin/python benchmarks/bench_exam.py
"""

from __future__ import annotations

import math
import time

import mujoco
import numpy as np

from mechcheck.analytic.exam import exam_q1, exam_q2, q1_equilibrium, q2_drive_force
from mechcheck.sim_models.mujoco import exam as mujoco_exam
from mechcheck.sim_models.pymunk import exam as pymunk_exam

BACKENDS = {"mujoco": mujoco_exam, "pymunk": pymunk_exam}
Q2_TIMES = np.linspace(-0.2, 0.2, 9)


def q1_table() -> str:
    system = exam_q1()
    ref = q1_equilibrium(system).as_dict()
    lines = ["| backend | quantity | simulator | analytic | error |", "|---|---|---|---|---|"]
    for name, module in BACKENDS.items():
        r = module.settle_q1(system)
        assert r.values is not None, r.message
        got = r.values.as_dict()
        for q, v in got.items():
            if q == "phi":
                lines.append(f"| {name} | φ (deg) | {math.degrees(v):.9f} | {math.degrees(ref[q]):.9f} "
                             f"| {abs(v - ref[q]):.1e} rad |")
            elif q == "x":
                lines.append(f"| {name} | x (m) | {v:.12f} | {ref[q]:.12f} | {abs(v - ref[q]):.1e} m |")
            else:
                lines.append(f"| {name} | {q} (N) | {v:.9f} | {ref[q]:.9f} "
                             f"| {abs(v - ref[q]) / abs(ref[q]):.1e} rel |")
        lines.append(f"| {name} | run | {r.steps} steps | dt {r.diagnostics['timestep']:g} s "
                     f"| {r.wall_time_s * 1e3:.1f} ms |")
    return "\n".join(lines)


def q2_table() -> str:
    system, motion = exam_q2()
    lines = ["| backend | readings | max rel. error of F | median | steps | wall time |",
             "|---|---|---|---|---|---|"]
    for name, module in BACKENDS.items():
        r = module.drive_q2(system, motion, Q2_TIMES)
        ref = q2_drive_force(system, motion, r.times)
        err = np.abs(r.force - ref) / np.abs(ref)
        lines.append(f"| {name} | {len(r.times)} | {err.max():.1e} | {np.median(err):.1e} | {r.steps} "
                     f"| {r.wall_time_s * 1e3:.1f} ms |")
    return "\n".join(lines)


def contact_friction_run(cone: str, noslip: int, stiff: bool, dt: float = 1e-4) -> tuple[float, float, float]:
    """Q2 with MuJoCo's contact friction (a box on a plane): (N min, N max, median rel. error of F)."""
    system, motion = exam_q2()
    soft = f'solref="{2 * dt} 1" solimp="0.9999 0.9999 0.001"' if stiff else ""
    xml = f"""<mujoco><option timestep="{dt}" gravity="0 0 -{system.gravity}" cone="{cone}"
      noslip_iterations="{noslip}" integrator="Euler" tolerance="1e-16"/>
      <worldbody><geom type="plane" size="5 5 0.1" friction="{system.mu} 0 0" {soft}/>
      <body name="mass" pos="0 0 0.05"><joint name="x" type="slide" axis="1 0 0"/>
        <joint name="z" type="slide" axis="0 0 1"/>
        <geom type="box" size="0.05 0.05 0.05" mass="{system.mass}" friction="{system.mu} 0 0" {soft}/></body>
      <body name="driver"><joint name="drive" type="slide" axis="1 0 0"/>
        <inertial pos="0 0 0" mass="1e9" diaginertia="1 1 1"/></body></worldbody>
      <tendon><fixed stiffness="{system.k1 + system.k2}" springlength="0"><joint joint="x" coef="1"/></fixed>
      </tendon><equality><joint joint1="x" joint2="drive" polycoef="0 1 0 0 0" solref="{2 * dt} 1"
      solimp="0.9999 0.9999"/></equality></mujoco>"""
    model = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(model)
    while d.time < 2.0:  # let the box come to rest on its contact first
        mujoco.mj_step(model, d)
    t0 = -0.3
    path = motion.position(t0 + dt * np.arange(-1, int(0.5 / dt) + 2))
    d.qpos[0] = d.qpos[2] = path[1]
    d.qvel[0] = d.qvel[2] = (path[1] - path[0]) / dt
    normals, errors = [], []
    wrench = np.zeros(6)
    for n in range(int(0.5 / dt)):
        t = t0 + n * dt
        d.qfrc_applied[2] = 1e9 * (path[n + 2] - 2 * path[n + 1] + path[n]) / dt**2
        mujoco.mj_step(model, d)
        if abs(t) < 0.2:
            normal = 0.0
            for i in range(d.ncon):
                mujoco.mj_contactForce(model, d, i, wrench)
                normal += float((d.contact[i].frame.reshape(3, 3).T @ wrench[:3])[2])
            row = np.flatnonzero(d.efc_type == mujoco.mjtConstraint.mjCNSTR_EQUALITY)[0]
            ref = float(q2_drive_force(system, motion, [t])[0])
            normals.append(normal)
            errors.append(abs(d.efc_force[row] - ref) / abs(ref))
    return min(normals), max(normals), float(np.median(errors))


def contact_table() -> str:
    system, _ = exam_q2()
    lines = [f"MuJoCo contact friction instead of frictionloss (m·g = {system.normal_force:.2f} N):", "",
             "| cone | noslip | contact softness | N min | N max | median rel. error of F |",
             "|---|---|---|---|---|---|"]
    for cone, noslip, stiff in (("pyramidal", 0, False), ("elliptic", 0, False), ("pyramidal", 10, False),
                                ("elliptic", 0, True)):
        lo, hi, err = contact_friction_run(cone, noslip, stiff)
        lines.append(f"| {cone} | {noslip} | {'solref 2·dt' if stiff else 'default'} | {lo:.2f} | {hi:.2f} "
                     f"| {err:.2f} |")
    return "\n".join(lines)


if __name__ == "__main__":
    tic = time.perf_counter()
    print("## Exam Q1 (F = 10 N, m = 3 kg, k = 200 N/m, l = 0.5 m, slider 0.5 kg)\n")
    print(q1_table())
    print("\n## Exam Q2 (m = 2 kg, k1 = 150, k2 = 250 N/m, μ = 0.3, x = 0.01·sin(2πt) m)\n")
    print(q2_table())
    print()
    print(contact_table())
    print(f"\n(total {time.perf_counter() - tic:.1f} s)")
