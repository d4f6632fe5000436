"""The assumption studies (quick sweeps): their data obey the physics they are about,
the simulators' curves follow the analytic ones, and each conclusion quotes its data."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from mechcheck.studies import STUDIES, run_study
from mechcheck.studies.common import crossing
from mechcheck.tolerance import rule

#: Simulator curves are compared point by point with the analytic curve; each point is
#: one driven or settled run, so the policy's tolerance for that kind of run applies.
DRIVEN = max(rule(sim, "torque", kind).rtol for sim in ("mujoco", "pymunk")
             for kind in ("dynamic", "friction"))
SETTLED = max(rule(sim, "torque", "static").rtol for sim in ("mujoco", "pymunk"))


def curves(data: pd.DataFrame) -> dict[str, pd.DataFrame]:
    """The study's rows per source (analytic first, then each simulator)."""
    return {str(src): g.reset_index(drop=True) for src, g in data.groupby("source", sort=False)}


def test_quasi_static_miss_grows_like_omega_squared() -> None:
    """The static torque's miss grows like ω² at low speed, and both simulators measure it."""
    r = run_study("quasi_static", quick=True)
    c = curves(r.data)
    a = c["analytic (D'Alembert)"]
    slope = np.polyfit(np.log(a["omega"][:3]), np.log(a["relative_miss"][:3]), 1)[0]
    assert slope == pytest.approx(2.0, abs=0.02)
    for sim in ("mujoco", "pymunk"):
        assert np.allclose(c[sim]["T_dynamic"], a["T_dynamic"], rtol=DRIVEN), sim
    one = crossing(a["omega"], a["relative_miss"], 0.01)
    assert one is not None and f"{one:.3g} rad/s" in r.conclusion


def test_massless_error_falls_like_one_over_load() -> None:
    """Ignoring weights errs by weight-torque/load-torque: ∝ 1/load for large loads."""
    r = run_study("massless", quick=True)
    c = curves(r.data)
    a = c["analytic (with weights)"]
    big = a.tail(2)
    ratio = big["relative_error"].iloc[0] / big["relative_error"].iloc[1]
    assert ratio == pytest.approx(big["load_N"].iloc[1] / big["load_N"].iloc[0], rel=0.05)
    for sim in ("mujoco", "pymunk"):
        assert np.allclose(c[sim]["T_weighted"], a["T_weighted"], rtol=SETTLED), sim


def test_friction_circle_radius_ratio_is_sqrt_one_plus_mu_squared() -> None:
    """μ·r / (r·sin(atan μ)) = √(1 + μ²); the torque difference is smaller and simulators agree."""
    r = run_study("friction_angle", quick=True)
    c = curves(r.data)
    a = c["analytic"]
    assert np.allclose(a["radius_difference"], np.sqrt(1 + a["mu"] ** 2) - 1, rtol=1e-12)
    assert (a["torque_difference"] < a["radius_difference"]).all()
    for sim in ("mujoco", "pymunk"):
        assert np.allclose(c[sim]["T_exact"], a["T_exact"], rtol=DRIVEN), sim
        assert np.allclose(c[sim]["T_small_angle"], a["T_small_angle"], rtol=DRIVEN), sim


def test_superposition_is_exact_without_friction_only() -> None:
    """Summing single-load solutions is exact at μ = 0 and errs increasingly with μ."""
    r = run_study("superposition_friction", quick=True)
    c = curves(r.data)
    a = c["analytic"]
    assert a["superposition_error"].iloc[0] <= 1e-9
    assert (np.diff(a["superposition_error"].to_numpy()[1:]) > 0).all()
    for sim in ("mujoco", "pymunk"):
        assert c[sim]["superposition_error"].iloc[0] <= 10 * DRIVEN
        assert np.allclose(c[sim]["T_all"], a["T_all"], rtol=DRIVEN), sim


def test_near_toggle_forces_grow_like_one_over_delta() -> None:
    """|F34| ∝ 1/δ towards the change point; the condition number grows with it."""
    r = run_study("near_toggle", quick=True)
    d = r.data[r.data["F34_N"].notna()]
    slope = np.polyfit(np.log(d["delta_deg"].tail(3)), np.log(d["F34_N"].tail(3)), 1)[0]
    assert slope == pytest.approx(-1.0, abs=0.02)
    assert (np.diff(d["condition_number"].to_numpy()) > 0).all()
    assert "δ^" in r.conclusion and not math.isnan(d["condition_number"].iloc[-1])


def test_every_study_is_registered_with_a_figure() -> None:
    """Every registered study runs quickly and returns a PNG figure and a conclusion."""
    for name in STUDIES:
        if name in ("quasi_static", "massless", "friction_angle", "superposition_friction",
                    "near_toggle"):
            continue  # run above
        r = run_study(name, quick=True)
        assert r.figure.startswith(b"\x89PNG") and r.conclusion
