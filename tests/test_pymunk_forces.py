"""The force-vector reading method: pymunk's accumulated impulses read through cffi."""

from __future__ import annotations

import pymunk
import pytest

from mechcheck.analytic.case import Case
from mechcheck.analytic.linkage_backends import analytic_results
from mechcheck.analytic.presets import as_linkage, redrawn
from mechcheck.analytic.values import GROUND
from mechcheck.sim_models.pymunk import forces
from mechcheck.sim_models.pymunk._fast import layout
from mechcheck.sim_models.pymunk.linkage_model import LinkageModel, apply_loads, build_linkage_model
from mechcheck.sim_models.pymunk.settings import LINKAGE_SETTLE, SolverSettings

from .builtin import builtin

#: Momentum balance over one step is exact arithmetic on the same doubles;
#: the slack covers rounding of products of ~1e3 kg masses and ~1e2 N forces.
BALANCE_RTOL = 1e-9


def e1() -> Case:
    """Seed E1 (SEEDS.md, Söylemez 6.3), loads as stated: T12 = +2.90133 N·m."""
    return builtin("seed-E1-as-stated")


def e2() -> Case:
    """Seed E2 slider-crank with friction, crank clockwise: T12 = −22.897 N·m."""
    return builtin("seed-E2-friction")


def built(case: Case, settings: SolverSettings = LINKAGE_SETTLE) -> LinkageModel:
    """The pymunk model of a four-bar or slider-crank (as its linkage) at its analytic pose."""
    linkage = as_linkage(case)
    return build_linkage_model(linkage, settings, analytic_results(linkage).pose.q[0])


def test_layout_check_passes_on_this_build() -> None:
    """The private offsets agree with pymunk's public fields and impulse magnitudes."""
    layout.check_layout()


def test_layout_check_fails_loudly_on_a_wrong_offset(monkeypatch: pytest.MonkeyPatch) -> None:
    """A pivot jAcc offset that is off by one field raises LayoutError instead of reading garbage."""
    monkeypatch.setitem(layout.PIVOT_FIELDS, "jAcc", layout.PIVOT_FIELDS["jAcc"] - 16)
    with pytest.raises(layout.LayoutError, match="jAcc"):
        layout.check_layout()


def test_read_magnitudes_equal_public_impulse() -> None:
    """Every pivot's read vector has the length pymunk itself reports as its impulse."""
    model = built(e1())
    apply_loads(model)
    model.space.step(LINKAGE_SETTLE.dt)
    for pin in model.pins.values():
        jx, jy = forces.accumulated_impulse(pin)  # type: ignore[misc]
        assert abs(complex(jx, jy)) == pytest.approx(pin.impulse, rel=1e-12)


@pytest.mark.parametrize("make", [e1, lambda: redrawn(e2(), friction=None)], ids=["fourbar", "slider"])
def test_read_forces_balance_each_body_momentum(make: object) -> None:
    """Per body, m·Δv/dt equals the loads plus the read joint forces (F_ij on j, −F_ij on i).

    This is the independent per-body momentum balance: it checks the signs and
    the body a/b assignment of every read vector in a step where the bodies
    still accelerate (the first, unconverged step).
    """
    case = make()  # type: ignore[operator]
    settings = LINKAGE_SETTLE.with_(damping=1.0)
    model = built(case, settings)
    apply_loads(model)
    loads = {k: (b.force.x, b.force.y) for k, b in model.bodies.items()}
    model.space.step(settings.dt)
    v = model.readout.values()
    on = {link: [0.0, 0.0] for link in model.bodies}
    for joint in model.linkage.joints:  # F_j acts on links[1], its opposite on links[0]
        for link, sign in zip(joint.links, (-1.0, 1.0), strict=True):
            if link != GROUND:
                on[link][0] += sign * v[f"F_{joint.name}_x"]
                on[link][1] += sign * v[f"F_{joint.name}_y"]
    scale = max(abs(x) for x in v.values())
    for link, body in model.bodies.items():
        inertial = (body.mass * body.velocity.x / settings.dt, body.mass * body.velocity.y / settings.dt)
        total = (loads[link][0] + on[link][0], loads[link][1] + on[link][1])
        assert inertial == pytest.approx(total, rel=BALANCE_RTOL, abs=BALANCE_RTOL * scale)


def test_unknown_constraint_kind_is_refused() -> None:
    """Only constraints whose layout was checked can be read."""
    a, b = pymunk.Body(1, 1), pymunk.Body(1, 1)
    with pytest.raises(TypeError):
        forces.accumulated_impulse(pymunk.SlideJoint(a, b, (0, 0), (0, 0), 0.5, 1.0))
