"""A space's bodies read and written in bulk, for loops that touch them every step.

Per body and per step, the settling loop reads the angle and velocities and writes the
damped velocities, the loads' force and torque. Through pymunk's properties that is a
dozen cffi calls and Vec2d objects per body, several times the cost of the step itself
(Watt six-bar, 100 iterations: 23 µs a step). pymunk's batch iterators
(:mod:`pymunk.batch`) copy the same fields between the C bodies and one array in a single
call; :class:`Bodies` calls them on preallocated arrays, in the C setters' own order
(``cpBodySetVelocity``, ``cpBodySetForce``, ...), so the bodies end up exactly as the
property setters would leave them.

:mod:`pymunk.batch` is marked experimental, and this module drives its C iterator with
pymunk's private handles (``Space._space``, ``Buffer._float_arr``) to skip a per-call
allocation. :class:`Bodies` therefore checks, when built, that the iterator visits the
bodies in the order given, and after every read that it wrote where it was told.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence

import numpy as np
import pymunk
import pymunk.batch as batch
from pymunk._chipmunk_cffi import ffi, lib

Fields = batch.BodyFields
#: Read every step: per body x, y of the origin, angle, vx, vy, ω (columns in the
#: iterator's field order).
STATE = Fields.POSITION | Fields.ANGLE | Fields.VELOCITY | Fields.ANGULAR_VELOCITY
STATE_COLUMNS = 6
#: Written every step of a settling run: per body vx, vy, ω, fx, fy, torque.
PUSH = Fields.VELOCITY | Fields.ANGULAR_VELOCITY | Fields.FORCE | Fields.TORQUE
#: Written to place the bodies, after the angle (a body turns about its centre of
#: gravity, so setting the angle second would move its origin): per body x, y of the
#: origin, vx, vy, ω, fx, fy, torque.
POSE = (Fields.POSITION | Fields.VELOCITY | Fields.ANGULAR_VELOCITY | Fields.FORCE
        | Fields.TORQUE)


class BatchLayoutError(RuntimeError):
    """pymunk's batch iterator does not visit or fill the bodies as this module expects."""


class _Channel:
    """One direction of transfer (get or set) of ``fields`` between the bodies and a
    preallocated (n, k) array."""

    def __init__(self, space: pymunk.Space, fields: Fields, rows: int, columns: int,
                 setter: bool):
        # Headroom: the C array grows (reallocates) only when it is full; this one never is.
        self.memory = np.zeros(2 * rows * columns + 8)
        self.array = self.memory[:rows * columns].reshape(rows, columns)
        self.view = self.memory.data  # a memoryview, for struct packing
        self.buffer = batch.Buffer()
        self.buffer.set_float_buf(self.memory)
        self.floats = self.buffer._float_arr
        self.data = ffi.new("pmBatchedData *")
        self.data.fields = fields.value
        self.data.floatArray = self.floats
        self.data.intArray = self.buffer._int_arr
        name = "pmSpaceBodySetIteratorFuncBatched" if setter else "pmSpaceBodyGetIteratorFuncBatched"
        self.visit = ffi.addressof(lib, name)
        self.space = space._space
        self.start = ffi.cast("double *", self.floats.arr)
        self.size = rows * columns

    def run(self) -> None:
        self.floats.num = 0
        lib.cpSpaceEachBody(self.space, self.visit, self.data)


class Bodies:
    """The bodies of ``space``: :attr:`state` (n, 6) of ``bodies`` in their order after
    :meth:`read`; velocities and loads set by :meth:`advance`; a pose set by :meth:`stage`
    and :meth:`repose`.

    The iterator also visits the space's static body, after the dynamic ones: its rows
    follow, and every write gives it back the values it has (at rest, unloaded).
    """

    def __init__(self, space: pymunk.Space, bodies: Sequence[pymunk.Body]):
        if any(body.mass <= 0.0 or body.moment <= 0.0 for body in bodies):
            raise ValueError("every body of a model needs a positive mass and moment")
        n = len(bodies)
        ids = batch.Buffer()
        batch.get_space_bodies(space, Fields.BODY_ID, ids)
        visited = list(memoryview(ids.int_buf()).cast("P"))
        if visited[:n] != [b.id for b in bodies] or set(visited[n:]) - {space.static_body.id}:
            raise BatchLayoutError("pymunk's body iterator does not visit the model's bodies "
                                   "in their order, then at most the static body")
        rows = len(visited)
        self._space = space._space
        self._get = _Channel(space, STATE, rows, STATE_COLUMNS, setter=False)
        self._set = _Channel(space, PUSH, rows, 6, setter=True)
        self._angle = _Channel(space, Fields.ANGLE, rows, 1, setter=True)
        self._pose = _Channel(space, POSE, rows, 8, setter=True)
        static = space.static_body
        self._angle.array[n:] = static.angle
        self._pose.array[n:, :2] = tuple(static.position)
        self.state = self._get.array[:n]
        # The model's bodies' rows (the static body's stay as set above).
        self._state_format = struct.Struct(f"{self.state.size}d")
        self._push_format = struct.Struct(f"{6 * n}d")
        self._angle_format = struct.Struct(f"{n}d")
        self._pose_format = struct.Struct(f"{8 * n}d")
        self.read()

    def read(self) -> np.ndarray:
        """The bodies' origin, angle, velocity and angular velocity now, (n, 6)."""
        self._get.run()
        self.verify()
        return self.state

    def verify(self) -> None:
        """Raise unless the last read filled exactly the preallocated array (a read that
        outgrew it would have moved the data elsewhere)."""
        if self._get.floats.num != self._get.size or self._get.floats.arr != self._get.start:
            raise BatchLayoutError("pymunk's body iterator wrote outside the preallocated array")

    def read_flat(self) -> tuple[float, ...]:
        """:meth:`read` as one tuple, body after body, for a loop that reads every step: it
        does not :meth:`verify` (call that once the loop ends), and a loop over a few bodies
        in Python is cheaper than numpy's per-call overhead on arrays this small."""
        self._get.run()
        return self._state_format.unpack_from(self._get.view)

    def advance(self, push: list[float], dt: float) -> tuple[float, ...]:
        """Set every body's velocities, force and torque (vx, vy, ω, fx, fy, torque, body
        after body), step the space by ``dt`` and :meth:`read_flat`.

        The step is Chipmunk's ``cpSpaceStep`` itself. pymunk's ``Space.step`` wraps it in
        Python bookkeeping (bodies added since the last step checked for a positive mass,
        deferred additions and removals, post-step callbacks: about 0.5 µs a step) that a
        model never needs while it runs: it adds and removes nothing and registers no
        callbacks, and its bodies' masses are checked once, when it is built."""
        self._push_format.pack_into(self._set.view, 0, *push)
        self._set.run()
        lib.cpSpaceStep(self._space, dt)
        return self.read_flat()

    def stage(self, q: Sequence[float], forces: Sequence[float], torques: Sequence[float]) -> None:
        """Ready :meth:`repose` to put every body at its coordinates q (x, y of the origin
        and angle, body after body), at rest, under ``forces`` (fx, fy body after body) and
        ``torques``."""
        pose = [0.0] * (8 * len(torques))
        pose[0::8], pose[1::8] = q[0::3], q[1::3]
        pose[5::8], pose[6::8], pose[7::8] = forces[0::2], forces[1::2], torques
        self._angle_format.pack_into(self._angle.view, 0, *q[2::3])
        self._pose_format.pack_into(self._pose.view, 0, *pose)

    def repose(self) -> None:
        """Set every body's angle, then its origin, velocities, force and torque, as the last
        :meth:`stage` said."""
        self._angle.run()
        self._pose.run()
