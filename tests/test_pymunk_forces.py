"""The force-vector reading method: pymunk's accumulated impulses read through cffi."""

from __future__ import annotations

import pymunk
import pytest

from mechcheck.analytic.case import Case
from mechcheck.sim_models.pymunk import forces
from mechcheck.sim_models.pymunk.loads import apply_loads
from mechcheck.sim_models.pymunk.model import build_model
from mechcheck.sim_models.pymunk.readout import reactions
from mechcheck.sim_models.pymunk.settings import SETTLE

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


def test_layout_check_passes_on_this_build() -> None:
    """The private offsets agree with pymunk's public fields and impulse magnitudes."""
    forces.check_layout()


def test_layout_check_fails_loudly_on_a_wrong_offset(monkeypatch: pytest.MonkeyPatch) -> None:
    """A pivot jAcc offset that is off by one field raises LayoutError instead of reading garbage."""
    monkeypatch.setitem(forces.PIVOT_FIELDS, "jAcc", forces.PIVOT_FIELDS["jAcc"] - 16)
    with pytest.raises(forces.LayoutError, match="jAcc"):
        forces.check_layout()


def test_read_magnitudes_equal_public_impulse() -> None:
    """Every pivot's read vector has the length pymunk itself reports as its impulse."""
    model = build_model(e1(), SETTLE)
    apply_loads(model)
    model.space.step(SETTLE.dt)
    for pin in model.pins.values():
        jx, jy = forces.accumulated_impulse(pin)  # type: ignore[misc]
        assert abs(complex(jx, jy)) == pytest.approx(pin.impulse, rel=1e-12)


@pytest.mark.parametrize("make", [e1, lambda: e2().with_(friction=None)], ids=["fourbar", "slider"])
def test_read_forces_balance_each_body_momentum(make: object) -> None:
    """Per body, m·Δv/dt equals the loads plus the read joint forces (F_ij on j, −F_ij on i).

    This is the independent per-body momentum balance: it checks the signs and
    the body a/b assignment of every read vector in a step where the bodies
    still accelerate (the first, unconverged step).
    """
    case = make()  # type: ignore[operator]
    model = build_model(case, SETTLE.with_(damping=1.0))
    apply_loads(model)
    loads = {k: (b.force.x, b.force.y) for k, b in model.bodies.items()}
    model.space.step(SETTLE.dt)
    v = reactions(model)
    on = {2: [v["F12_x"] - v["F23_x"], v["F12_y"] - v["F23_y"]],
          3: [v["F23_x"] - v["F34_x"], v["F23_y"] - v["F34_y"]],
          4: [v["F34_x"] + v["F14_x"], v["F34_y"] + v["F14_y"]]}
    for link, body in model.bodies.items():
        inertial = (body.mass * body.velocity.x / SETTLE.dt, body.mass * body.velocity.y / SETTLE.dt)
        total = (loads[link][0] + on[link][0], loads[link][1] + on[link][1])
        scale = max(abs(x) for x in v.values())
        assert inertial == pytest.approx(total, rel=BALANCE_RTOL, abs=BALANCE_RTOL * scale)


def test_unknown_constraint_kind_is_refused() -> None:
    """Only constraints whose layout was checked can be read."""
    a, b = pymunk.Body(1, 1), pymunk.Body(1, 1)
    with pytest.raises(TypeError):
        forces.accumulated_impulse(pymunk.DampedSpring(a, b, (0, 0), (0, 0), 1, 1, 1))
