"""Quasi-static motion: how slowly must a linkage be driven for its motion to follow the
static equilibrium pose within 1 % and 10 %?

The linkage has two degrees of freedom: an arm turned by a driver about a ground pivot, and
a slider on the arm held by a spring along it, under gravity, with viscous friction in its
slot. Quasi-statically the slider sits where spring and weight balance at each arm angle:
the static engine's equilibrium of the free coordinate at that driver value. Driven from
rest at a constant acceleration (no sudden start excites the slider) through a quarter
turn, from horizontal to upright, it lags that pose by the damper's drag (∝ the speed) and
is flung out by the turning (∝ the speed squared). Every run is a trajectory
(``mechcheck simulate``'s machinery): the analytic reference and each installed simulator's
finest run, through the registry.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from mechcheck import backends, solve_poses
from mechcheck.analytic.case import Case, Simulation
from mechcheck.analytic.joint_kinds import PRISMATIC, REVOLUTE
from mechcheck.analytic.linkage import (
    Driver,
    Joint,
    JointFriction,
    LinearSpring,
    Link,
    Linkage,
    LinkMass,
)
from mechcheck.analytic.trajectory import Trajectory
from mechcheck.simulate_run import run_backend, settings_text
from mechcheck.studies.common import StudyResult, groups, levels_reached, loglog_by_source

LEVELS = (0.01, 0.10)

#: The arm (m, kg) and the slider: 0.5 kg drawn 150 mm out, where the spring (200 N/m) is
#: at its free length, so with the arm horizontal the drawn pose is the static equilibrium
#: (the weight is across the slot) and the run starts at rest on the static answer.
ARM_LENGTH = 0.3
ARM_MASS = 0.3
SLIDER_AT = 0.15
SLIDER_MASS = 0.5
STIFFNESS = 200.0
#: N·s/m in the slot: a damping ratio c / (2·√(k·m)) = 0.1, so what the start excites dies
#: out within a few of the slider's periods (2π/√(k/m) = 0.31 s).
DAMPING = 2.0
GRAVITY = 9.81
#: The arm turns from horizontal to upright; the static slider falls by m·g/k = 24.5 mm.
STROKE = math.pi / 2
#: The joint no driver holds: the slider's travel along the arm.
FREE_JOINT = "slot"
#: Arm poses the runs are read at (the same for every speed, so the static answer is
#: solved once).
POSES = 61

TITLE = "Quasi-static motion"
QUESTION = ("How slowly must a linkage be driven for its motion to follow the static "
            "equilibrium pose within 1 % and 10 %?")
#: The method paragraph of the study's report.
METHOD = (
    f"A {ARM_LENGTH * 1000:g} mm arm turned about a ground pivot carries a "
    f"{SLIDER_MASS:g} kg slider on a {STIFFNESS:g} N/m spring along it (drawn at its free "
    f"length, {SLIDER_AT * 1000:g} mm out) with {DAMPING:g} N·s/m of viscous friction in "
    "its slot, under gravity: two degrees of freedom, the arm's prescribed. Static: the "
    "engine's equilibrium of the slider at each arm angle (mechcheck.solve_poses on the "
    "linkage at rest). Motion: the arm driven from rest, horizontal, at a constant "
    "acceleration that brings it upright at ω, a trajectory run by the analytic reference "
    "and each simulator's finest rung (mechcheck simulate's runs), read at "
    f"{POSES} arm angles over the quarter turn. The miss is the worst difference of the "
    "slider's travel from the static one over the stroke, over the static travel "
    "(m·g/k); a simulator's own error is its run's worst difference from the reference "
    "on the same scale.")


def governor_arm(omega: float | None = None) -> Case:
    """The arm and its spring-loaded slider, drawn horizontal; ``omega`` (rad/s) given, a
    trajectory reaching it at the upright pose from rest at constant acceleration, read at
    the arm angles of :func:`arm_angles`; None, the same linkage at rest (a static case)."""
    moving = omega is not None
    alpha = (omega or 0.0) ** 2 / (2.0 * STROKE)
    linkage = Linkage(
        points={"A0": (0.0, 0.0), "E": (ARM_LENGTH, 0.0), "P": (SLIDER_AT, 0.0)},
        links=(Link("ground", ("A0",)), Link("arm", ("A0", "E")), Link("slider", ("P",))),
        joints=(Joint("pivot", REVOLUTE, ("ground", "arm"), "A0"),
                Joint(FREE_JOINT, PRISMATIC, ("arm", "slider"), "P", axis=(1.0, 0.0))),
        drivers=(Driver("pivot", 0.0, acceleration=alpha),),
        masses=(LinkMass("arm", ARM_MASS, (ARM_LENGTH / 2, 0.0), ARM_MASS * ARM_LENGTH**2 / 12),
                LinkMass("slider", SLIDER_MASS, (SLIDER_AT, 0.0), 1e-4)),
        springs=(LinearSpring("spring", (("arm", (0.0, 0.0)), ("slider", (SLIDER_AT, 0.0))),
                              STIFFNESS, SLIDER_AT),),
        gravity=(0.0, -GRAVITY),
        friction=JointFriction(viscous={FREE_JOINT: DAMPING}),
        free_motion=moving)
    if omega is None:
        return Case("governor-arm", linkage)
    times = tuple(float(t) for t in np.sqrt(2.0 * arm_angles() / alpha))
    return Case("governor-arm-driven", linkage, simulation=Simulation(times[-1], times))


def arm_angles() -> np.ndarray:
    """The arm angles (rad) every run is read at, evenly spaced over the stroke."""
    return np.linspace(0.0, STROKE, POSES)


def static_travel() -> np.ndarray:
    """The static answer: the slider's equilibrium travel (m) at each arm angle, from the
    engine's equilibrium search on the linkage at rest."""
    poses = solve_poses(governor_arm(), arm_angles(), condition=False)
    return poses[f"q_{FREE_JOINT}"].to_numpy(dtype=float)


def trajectory_simulators() -> list[str]:
    """The installed backends that run trajectories, the analytic reference first."""
    return [n for n in backends.available() if backends.get(n).simulate is not None]


def finest(name: str, case: Case) -> Trajectory | str:
    """A backend's finest run of ``case`` (the last of its ladder), or why it gave none."""
    runs = run_backend(name, case)
    if isinstance(runs, tuple):
        return runs[-1]
    return runs.message


def travel_of(run: Trajectory, case: Case) -> np.ndarray:
    """The slider's travel along the arm (m) at each output time, from the run's own state."""
    return np.asarray(run.quantities(case.linkage)[f"q_{FREE_JOINT}"], dtype=float)


def rows_at(omega: float, static: np.ndarray, names: list[str]) -> list[dict[str, object]]:
    """One row per source at one speed (the reference first): its worst miss of the static
    pose over the stroke and, for a simulator, its own worst error against the reference,
    both over the static answer's travel."""
    case = governor_arm(omega)
    assert case.simulation is not None
    scale = float(np.max(np.abs(static - static[0])))
    runs = {name: finest(name, case) for name in names}
    reference = runs.get(backends.REFERENCE)
    rows: list[dict[str, object]] = []
    for name, run in runs.items():
        row: dict[str, object] = {"source": name, "omega": omega, "end_time": case.simulation.end}
        if isinstance(run, str) or run.status != "ok":
            rows.append(row | {"miss": math.nan, "own_error": math.nan,
                               "status": run if isinstance(run, str) else run.status})
            continue
        travel = travel_of(run, case)
        own = math.nan
        if name != backends.REFERENCE and isinstance(reference, Trajectory) \
                and reference.status == "ok":
            own = float(np.max(np.abs(travel - travel_of(reference, case)))) / scale
        rows.append(row | {"miss": float(np.max(np.abs(travel - static))) / scale,
                           "own_error": own, "status": "ok",
                           "settings": settings_text(run.settings)})
    return rows


def slope(data: pd.DataFrame) -> float:
    """The exponent p of miss ∝ ω^p through the given points (a log-log fit)."""
    return float(np.polyfit(np.log(data["omega"]), np.log(data["miss"]), 1)[0])


def growth(reference: pd.DataFrame) -> str:
    """How the reference's miss grows with ω: at the slowest and at the fastest three
    speeds, or over the speeds tried where there are fewer than six."""
    if len(reference) < 6:
        return f"the miss grows like ω^{slope(reference):.2f} over the speeds tried"
    return (f"the miss grows like ω^{slope(reference.head(3)):.2f} at the slowest speeds "
            f"and like ω^{slope(reference.tail(3)):.2f} at the fastest")


def floor_note(data: pd.DataFrame) -> str:
    """Each simulator's own error floor and the speeds below which its miss is that error."""
    notes = []
    for src, g in groups(data):
        if src == backends.REFERENCE or g["own_error"].isna().all():
            continue
        floor = float(g["own_error"].max())
        reference = data[data["source"] == backends.REFERENCE].set_index("omega")["miss"]
        hidden = g[g["omega"].map(reference) <= g["own_error"]]["omega"]
        where = (f"below ω = {hidden.max():.3g} rad/s its miss is its own error" if len(hidden)
                 else "the miss stands above it at every speed tried")
        notes.append(f"{src}'s finest runs err by up to {floor:.2g} of the travel ({where})")
    return "; ".join(notes)


def conclusion(data: pd.DataFrame) -> str:
    """The study's one line, from its data: the speeds of the 1 % and 10 % miss, how the
    miss grows, and each simulator's own error floor."""
    reference = data[(data["source"] == backends.REFERENCE) & (data["miss"] > 0)]
    note = floor_note(data)
    return ("The slider misses its static pose (a share of its static travel) "
            + levels_reached(data, "omega", "miss", unit="rad/s", at="ω", levels=LEVELS)
            + f"; {growth(reference)}" + (f"; {note}" if note else "") + ".")


def run(quick: bool = False) -> StudyResult:
    """The arm driven to ω at the upright pose, for ω over two decades; each source's
    worst miss of the static slider travel over the stroke."""
    # Quick: one speed on each side of the 1 % and the 10 % miss.
    omegas = np.array([0.8, 3.5]) if quick else np.geomspace(0.1, 8.0, 12)
    static = static_travel()
    names = trajectory_simulators()
    data = pd.DataFrame([row for w in omegas for row in rows_at(float(w), static, names)])
    figure = loglog_by_source(data, "omega", "miss", levels=LEVELS,
                              xlabel="arm speed at the upright pose ω [rad/s]",
                              ylabel="worst miss of the static pose / static travel",
                              title="Quasi-static motion (spring-loaded slider on a turning arm)")
    return StudyResult("quasi_static_motion", TITLE, QUESTION, data, figure, conclusion(data),
                       METHOD)
