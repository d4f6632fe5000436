"""Offsets into Chipmunk's private C structs (why they are read: :mod:`..forces`), checked
once per process (:func:`check_layout`) against public, independent values: the base
``cpConstraint`` fields, each joint's public parameters, the body's properties and, after
a step with load, |jAcc| against the public ``impulse`` magnitude. Any mismatch raises
:class:`LayoutError`, never a silently wrong force. A :data:`Cell` is where one double of
a jAcc lives; :func:`read` and :func:`write` are the only Python that indexes one.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence

import numpy as np
import pymunk
from pymunk._chipmunk_cffi import ffi

Vec = tuple[float, float]

_DOUBLE = 8
#: Byte offsets in Chipmunk 7 / Munk2D's private structs (LP64): the base
#: ``cpConstraint`` is 6 pointers, 3 cpFloat, a cpBool padded to 8 and 3
#: pointers = 104 bytes; joint fields follow (chipmunk_structs.h).
BASE_FIELDS = {"maxForce": 48, "errorBias": 56, "maxBias": 64}
CONSTRAINT_SIZE = 104
PIVOT_FIELDS = {"anchorA": 104, "anchorB": 120, "jAcc": 200}
GROOVE_FIELDS = {"grv_a": 120, "grv_b": 136, "anchorB": 152, "jAcc": 256}
GEAR_FIELDS = {"phase": 104, "ratio": 112, "jAcc": 144}
#: A pin joint's impulse is a scalar along its direction n (set by the step's pre-step).
PIN_FIELDS = {"anchorA": 104, "anchorB": 120, "dist": 136, "n": 176, "jAcc": 200}
MOTOR_FIELDS = {"rate": 104, "jAcc": 120}
#: Springs: anchors (or rest angle), rest length, stiffness, damping, the force function,
#: then working fields; jAcc is what ``Constraint.impulse`` returns, signed.
DAMPED_SPRING_FIELDS = {"restLength": 136, "stiffness": 144, "damping": 152, "jAcc": 240}
ROTARY_SPRING_FIELDS = {"restAngle": 104, "stiffness": 112, "damping": 120, "jAcc": 160}
#: ``cpBody``: two function pointers, then mass, 1/mass, moment, 1/moment, centre of
#: gravity, position (of the centre of gravity), velocity, force, angle, angular velocity,
#: torque and the transform (a, b, c, d, tx, ty), doubles, read and written by the compiled
#: loops (:mod:`.kernel`); a re-posed step restores p … transform, 15 doubles.
BODY_FIELDS = {"m": 16, "i": 32, "cog": 48, "p": 64, "v": 80, "f": 96, "a": 112, "w": 120,
               "t": 128, "transform": 136}
#: The doubles a re-posed step sets (:meth:`.bulk.Bodies.repose`): p through the transform.
POSE_FIELDS = (BODY_FIELDS["p"], BODY_FIELDS["transform"] + 6 * _DOUBLE)

#: Relative agreement demanded of the layout check: the fields are copied
#: doubles, so a right offset matches exactly; a wrong one reads an unrelated
#: number. The slack only absorbs the rounding of |jAcc| = hypot(x, y).
LAYOUT_RTOL = 1.0e-12

_checked = False


class LayoutError(RuntimeError):
    """The pymunk build's private struct layout is not the one this module reads."""


def _doubles(constraint: pymunk.Constraint) -> object:
    return ffi.cast("double *", constraint._constraint)


def read_double(constraint: pymunk.Constraint, offset: int) -> float:
    """The cpFloat at byte ``offset`` of the constraint's C struct."""
    return float(_doubles(constraint)[offset // _DOUBLE])  # type: ignore[index]


def read_vect(constraint: pymunk.Constraint, offset: int) -> Vec:
    """The cpVect at byte ``offset`` of the constraint's C struct."""
    return read_double(constraint, offset), read_double(constraint, offset + _DOUBLE)


#: Where one double of a constraint's jAcc lives: (its struct as doubles, index).
Cell = tuple[object, int]


def impulse_cells(constraint: pymunk.Constraint) -> list[Cell]:
    """Where the constraint's jAcc lives: two cells (pivot, groove) or one (gear, pin,
    motor, spring).

    A cell points into the constraint's C struct and stays valid while the constraint
    exists; reading it costs one cffi index, which is what a loop reading every step needs.
    """
    if not _checked:
        check_layout()
    for kind, fields, size in ((pymunk.PivotJoint, PIVOT_FIELDS, 2),
                               (pymunk.GrooveJoint, GROOVE_FIELDS, 2),
                               (pymunk.GearJoint, GEAR_FIELDS, 1),
                               (pymunk.PinJoint, PIN_FIELDS, 1),
                               (pymunk.SimpleMotor, MOTOR_FIELDS, 1),
                               (pymunk.DampedSpring, DAMPED_SPRING_FIELDS, 1),
                               (pymunk.DampedRotarySpring, ROTARY_SPRING_FIELDS, 1)):
        if isinstance(constraint, kind):
            d, k = _doubles(constraint), fields["jAcc"] // _DOUBLE
            return [(d, k + i) for i in range(size)]
    raise TypeError(f"no impulse layout known for {type(constraint).__name__}")


def direction_cells(pin: pymunk.PinJoint) -> list[Cell]:
    """Where a pin joint's unit direction n (anchor a → anchor b) of its last step lives:
    its impulse on body b is jAcc·n."""
    if not _checked:
        check_layout()
    d, k = _doubles(pin), PIN_FIELDS["n"] // _DOUBLE
    return [(d, k), (d, k + 1)]


def read(cells: Iterable[Cell]) -> list[float]:
    """The doubles at ``cells`` now, in their order."""
    return [d[k] for d, k in cells]  # type: ignore[index]


def write(cells: Iterable[Cell], values: Iterable[float]) -> None:
    """Write ``values``, one per cell, into the structs."""
    for (d, k), value in zip(cells, values, strict=True):
        d[k] = value  # type: ignore[index]


def _close(a: float, b: float) -> bool:
    return math.isclose(a, b, rel_tol=LAYOUT_RTOL, abs_tol=1e-300)


def _expect(what: str, read: float, public: float) -> None:
    if not _close(read, public):
        raise LayoutError(
            f"pymunk {pymunk.version} (Chipmunk {pymunk.chipmunk_version}): the private "
            f"struct field {what} reads {read!r} but the public API says {public!r}; the "
            "accumulated-impulse offsets in sim_models/pymunk/_fast/layout.py do not match this "
            "build, so force vectors cannot be read")


def _check_base(c: pymunk.Constraint) -> None:
    c.max_force = 1234.5
    c.error_bias = 0.321
    c.max_bias = 98.75
    for name, public in (("maxForce", c.max_force), ("errorBias", c.error_bias),
                         ("maxBias", c.max_bias)):
        _expect(f"cpConstraint.{name}", read_double(c, BASE_FIELDS[name]), public)
    c.max_force = c.max_bias = math.inf


def _check_fields(c: pymunk.Constraint, fields: dict[str, int],
                  public: dict[str, Callable[[], float | Vec]]) -> None:
    for name, get in public.items():
        value = get()
        if isinstance(value, (int, float)):
            _expect(f"{type(c).__name__}.{name}", read_double(c, fields[name]), float(value))
        else:
            got = read_vect(c, fields[name])
            _expect(f"{type(c).__name__}.{name}.x", got[0], float(value[0]))
            _expect(f"{type(c).__name__}.{name}.y", got[1], float(value[1]))


def address(cell: Cell) -> int:
    """The memory address of a cell's double, for compiled code (:mod:`.compiled`)."""
    d, k = cell
    return int(ffi.cast("uintptr_t", d)) + _DOUBLE * k


def body_address(body: pymunk.Body) -> int:
    """The address of a body's C struct (its fields at :data:`BODY_FIELDS`); checked by
    :func:`check_layout`."""
    if not _checked:
        check_layout()
    return int(ffi.cast("uintptr_t", body._body))


def pose_doubles(bodies: Sequence[pymunk.Body]) -> np.ndarray:
    """Per body, a row of the doubles :data:`POSE_FIELDS` spans (position … transform),
    as they are now."""
    start, end = POSE_FIELDS
    return np.array([np.frombuffer(ffi.buffer(ffi.cast("char *", b._body) + start, end - start))
                     for b in bodies])


def _check_body(body: pymunk.Body) -> None:
    d = ffi.cast("double *", body._body)
    public = {"m": body.mass, "i": body.moment, "cog": body.center_of_gravity.x,
              "v": body.velocity.x, "f": body.force.x, "a": body.angle,
              "w": body.angular_velocity, "t": body.torque}
    for name, value in public.items():
        _expect(f"cpBody.{name}", float(d[BODY_FIELDS[name] // _DOUBLE]), float(value))
    for name, value in (("cog", body.center_of_gravity.y), ("v", body.velocity.y),
                        ("f", body.force.y)):
        _expect(f"cpBody.{name}.y", float(d[BODY_FIELDS[name] // _DOUBLE + 1]), float(value))
    # p is the centre of gravity in the world; the transform, the rotation (cos, sin) as
    # cpTransformNewTranspose lays it out, then the origin.
    p = body.local_to_world(body.center_of_gravity)
    k = BODY_FIELDS["p"] // _DOUBLE
    _expect("cpBody.p.x", float(d[k]), p.x)
    _expect("cpBody.p.y", float(d[k + 1]), p.y)
    (cos, sin), (tx, ty) = body.rotation_vector, body.local_to_world((0.0, 0.0))
    k = BODY_FIELDS["transform"] // _DOUBLE
    for i, value in enumerate((cos, sin, -sin, cos, tx, ty)):
        _expect(f"cpBody.transform[{i}]", float(d[k + i]), value)


def _probe_space() -> tuple[pymunk.Space, list[pymunk.Constraint]]:
    """A loaded pendulum-on-a-slide with one joint of every kind we read, and a linear and
    a torsional spring between its bodies."""
    space = pymunk.Space()
    space.gravity = (0.3, -9.0)
    s = space.static_body
    crank = pymunk.Body(2.0, 0.1)
    crank.position = (0.1, 0.2)
    slider = pymunk.Body(1.5, 0.05)
    slider.position = (0.7, -0.05)
    slider.angular_velocity = 3.0  # so the friction motor saturates
    pivot = pymunk.PivotJoint(s, crank, (0.1, 0.2), (0.0, 0.0))
    gear = pymunk.GearJoint(s, crank, 0.37, 1.0)
    groove = pymunk.GrooveJoint(s, slider, (-1.1, -0.05), (2.3, -0.05), (0.0, 0.0))
    motor = pymunk.SimpleMotor(s, slider, 0.0)
    link = pymunk.PivotJoint(crank, slider, (0.6, -0.25), (0.0, 0.0))
    spring = pymunk.DampedSpring(crank, slider, (0.0, 0.0), (0.1, 0.0), 0.45, 35.0, 0.5)
    rotary = pymunk.DampedRotarySpring(crank, slider, 0.2, 4.5, 0.25)
    pin = pymunk.PinJoint(crank, slider, (0.05, -0.1), (0.2, 0.03))
    pin.distance = 0.61  # not the drawn distance: a pin joint that pulls
    space.add(crank, slider, pivot, gear, groove, motor, link, spring, rotary, pin)
    return space, [pivot, gear, groove, motor, link, spring, rotary, pin]


def _check_pin_direction(pin: pymunk.PinJoint) -> None:
    """n after a step (bodies not moved since): the unit vector between the anchors."""
    a = pin.a.local_to_world(pin.anchor_a)
    b = pin.b.local_to_world(pin.anchor_b)
    size = math.hypot(b.x - a.x, b.y - a.y)
    nx, ny = read_vect(pin, PIN_FIELDS["n"])
    # Chipmunk's n is computed from the centre of gravity, not the transform: equal to rounding.
    if abs(nx - (b.x - a.x) / size) > 1e-9 or abs(ny - (b.y - a.y) / size) > 1e-9:
        raise LayoutError(f"layout probe: PinJoint.n reads ({nx}, {ny}), its anchors give "
                          f"({(b.x - a.x) / size}, {(b.y - a.y) / size})")


def check_layout() -> None:
    """Verify the private offsets against public values; raise :class:`LayoutError` if not.

    Runs once per process (the first force read calls it).
    """
    global _checked
    space, (pivot, gear, groove, motor, link, spring, rotary, pin) = _probe_space()
    for c in (pivot, gear, groove, motor, link, spring, rotary, pin):
        _check_base(c)
    _check_fields(pivot, PIVOT_FIELDS, {"anchorA": lambda: pivot.anchor_a,
                                        "anchorB": lambda: pivot.anchor_b})
    _check_fields(groove, GROOVE_FIELDS, {"grv_a": lambda: groove.groove_a,
                                          "grv_b": lambda: groove.groove_b,
                                          "anchorB": lambda: groove.anchor_b})
    _check_fields(gear, GEAR_FIELDS, {"phase": lambda: gear.phase, "ratio": lambda: gear.ratio})
    _check_fields(pin, PIN_FIELDS, {"anchorA": lambda: pin.anchor_a,
                                    "anchorB": lambda: pin.anchor_b,
                                    "dist": lambda: pin.distance})
    _check_fields(motor, MOTOR_FIELDS, {"rate": lambda: motor.rate})
    _check_fields(spring, DAMPED_SPRING_FIELDS, {"restLength": lambda: spring.rest_length,
                                                 "stiffness": lambda: spring.stiffness,
                                                 "damping": lambda: spring.damping})
    _check_fields(rotary, ROTARY_SPRING_FIELDS, {"restAngle": lambda: rotary.rest_angle,
                                                 "stiffness": lambda: rotary.stiffness,
                                                 "damping": lambda: rotary.damping})
    motor.max_force = 0.7  # a saturated motor: nonzero, known-magnitude jAcc
    # Every body field distinct and nonzero, so a wrong offset cannot read an equal value.
    crank = pivot.b
    crank.velocity, crank.angular_velocity, crank.angle = (0.3, -0.2), 0.7, 0.35
    crank.force, crank.torque = (0.25, -0.5), 0.125
    _check_body(crank)
    space.step(1e-3)
    _check_body(crank)
    for c, offset in ((pivot, PIVOT_FIELDS["jAcc"]), (link, PIVOT_FIELDS["jAcc"]),
                      (groove, GROOVE_FIELDS["jAcc"])):
        jx, jy = read_vect(c, offset)
        if c.impulse <= 0.0:
            raise LayoutError(f"layout probe: {type(c).__name__} carried no impulse")
        _expect(f"{type(c).__name__}.|jAcc|", math.hypot(jx, jy), c.impulse)
    assert isinstance(pin, pymunk.PinJoint)
    _check_pin_direction(pin)
    for c, offset in ((gear, GEAR_FIELDS["jAcc"]), (motor, MOTOR_FIELDS["jAcc"]),
                      (pin, PIN_FIELDS["jAcc"])):
        if c.impulse <= 0.0:
            raise LayoutError(f"layout probe: {type(c).__name__} carried no impulse")
        _expect(f"{type(c).__name__}.|jAcc|", abs(read_double(c, offset)), c.impulse)
    for c, offset in ((spring, DAMPED_SPRING_FIELDS["jAcc"]), (rotary, ROTARY_SPRING_FIELDS["jAcc"])):
        if c.impulse == 0.0:
            raise LayoutError(f"layout probe: {type(c).__name__} carried no impulse")
        _expect(f"{type(c).__name__}.jAcc", read_double(c, offset), c.impulse)
    _checked = True
