"""Fake trajectory backends for the tests of ``mechcheck simulate``: the harness is tested
without the real engines.

The case is a block of mass m between two springs k1, k2 on a slide, released at rest
X0 from where the springs balance: x(t) = X0·cos(ωt), ω = √((k1 + k2)/m) (the undamped
oscillator; any dynamics text, e.g. Meriam & Kraige, Engineering Mechanics: Dynamics,
§8/2). The fake reference returns that closed form with its energy terms
T = ½ m ẋ², V = ½ (k1 + k2) x². Each fake simulator returns the same closed form with a
known error added (an offset of ``error`` × the case's scale from t > 0 on), on a ladder of
three time steps, so that the error the harness measures is known by construction.
"""

from __future__ import annotations

import math

import numpy as np

from mechcheck.analytic.case import Case
from mechcheck.analytic.trajectory import EnergyBalance, Trajectory
from tests.exam_block import exam_block

#: The block: 2 kg between springs of 300 and 200 N/m, released 40 mm from rest.
MASS, K1, K2, X0 = 2.0, 300.0, 200.0, 0.040
OMEGA = math.sqrt((K1 + K2) / MASS)   # 15.811 rad/s


def block_case(name: str = "block-springs", extra: str = "") -> str:
    """The block's case file; ``extra``: TOML inserted before its ``[case.simulate]``."""
    return exam_block(name, drivers=extra, end=0.5, outputs=26, gravity=False,
                      description="A 2 kg block between springs of 300 and 200 N/m, released "
                                  "40 mm from rest")


def closed_form(case: Case, backend: str, offset: float = 0.0, **fields: object) -> Trajectory:
    """The block's closed-form motion as ``backend``'s run, its slide moved by ``offset`` × the
    case's scale from t > 0 on."""
    t = np.asarray(case.simulation.outputs if case.simulation else (), dtype=float)
    x = X0 * np.cos(OMEGA * t)
    coordinates = np.zeros((len(t), 3))
    coordinates[:, 0] = x - X0 + offset * case.scale * (t > 0)
    return Trajectory(backend, t, coordinates, **fields)  # type: ignore[arg-type]


def reference(case: Case) -> tuple[Trajectory, ...]:
    """The fake analytic reference: the closed form with its energy terms."""
    t = np.asarray(case.simulation.outputs if case.simulation else (), dtype=float)
    x, v = X0 * np.cos(OMEGA * t), -X0 * OMEGA * np.sin(OMEGA * t)
    energy = EnergyBalance(0.5 * MASS * v**2, 0.5 * (K1 + K2) * x**2, np.zeros_like(t),
                           np.zeros_like(t))
    return (closed_form(case, "analytic", energy=energy, settings={"method": "closed form"},
                        wall_time=1e-4, steps=1),)


def ladder(case: Case, backend: str, errors: tuple[float, ...],
           **finest: object) -> tuple[Trajectory, ...]:
    """A simulator's ladder: dt 1e-2, 1e-3, 1e-4 …, each with its error, the second the
    default; ``finest`` replaces fields of the last run."""
    runs = []
    for i, error in enumerate(errors):
        dt = 10.0 ** -(i + 2)
        fields: dict[str, object] = {"settings": {"dt": dt, "integrator": "Euler"},
                                     "default": i == 1, "wall_time": 1e-3 * 10**i,
                                     "steps": int(0.5 / dt),
                                     "diagnostics": {"closure_gap_m": 1e-6 * error}}
        if i == len(errors) - 1:
            fields |= finest
        runs.append(closed_form(case, backend, error, **fields))
    return tuple(runs)


def good(case: Case) -> tuple[Trajectory, ...]:
    """Converges: 1e-2, 3e-3, 2e-4 (its finest within 1e-3)."""
    return ladder(case, "fakesim", (1e-2, 3e-3, 2e-4))


def off(case: Case) -> tuple[Trajectory, ...]:
    """Never reaches 1e-3: its finest run is 2e-3 off."""
    return ladder(case, "fakesim_off", (1e-2, 5e-3, 2e-3))


def nan(case: Case) -> tuple[Trajectory, ...]:
    """Its finest run claims ``ok`` with NaN coordinates (it blew up)."""
    runs = ladder(case, "fakesim_nan", (1e-2, 3e-3, 0.0))
    last = runs[-1]
    bad = np.array(last.coordinates)
    bad[5:] = np.nan
    return (*runs[:-1], Trajectory(last.backend, last.times, bad, settings=last.settings))


def none(case: Case) -> tuple[Trajectory, ...]:
    """Gives no number, and says why."""
    t = np.asarray(case.simulation.outputs if case.simulation else (), dtype=float)
    return (Trajectory("fakesim_none", t, np.full((len(t), 3), np.nan), status="not_applicable",
                       message="fakesim_none models no spring between a slide and the ground"),)


#: The fake simulator package (``mechcheck.sim_models.fakesims``): its backends' trajectory
#: runs are the functions above.
PACKAGE = '''
from mechcheck.analytic.contract import Backend

_SOLVE = "mechcheck.analytic.linkage_backends:solve"
BACKENDS = tuple(
    Backend(name, _SOLVE, "settled", "a fake simulator", simulate=f"tests.fake_trajectories:{run}")
    for name, run in (("fakesim", "good"), ("fakesim_off", "off"), ("fakesim_nan", "nan"),
                      ("fakesim_none", "none")))
'''
