"""MuJoCo's C library as the kernels see it: its functions' C pointers, the addresses of
models and data, the constraint arrays' place in MjData's arena, and models copied in place.

MjData's constraint arrays live in its arena, laid out again by each forward pass; the
views the kernels write through are taken after a forward pass at a batch's first pose
and checked to be where the last one left them (:class:`ArenaMoved` otherwise, and the
Python loop runs).
"""

from __future__ import annotations

import ctypes
import sys
from collections.abc import Callable
from functools import cache
from pathlib import Path

import mujoco
import numpy as np

from mechcheck.sim_models.mujoco._fast.plans import MjCalls

#: ``void f(const mjModel *, mjData *)``, the pointers passed as integers of their size.
PASS = ctypes.CFUNCTYPE(None, ctypes.c_ssize_t, ctypes.c_ssize_t)
#: ``mj_setState(const mjModel *, mjData *, const mjtNum *state, int spec)``, and
#: ``mj_getState``'s, the same but for the state's constness.
SET_STATE = ctypes.CFUNCTYPE(None, ctypes.c_ssize_t, ctypes.c_ssize_t, ctypes.c_ssize_t,
                             ctypes.c_int)
#: ``mj_mulM(const mjModel *, const mjData *, mjtNum *res, const mjtNum *vec)``.
MUL = ctypes.CFUNCTYPE(None, ctypes.c_ssize_t, ctypes.c_ssize_t, ctypes.c_ssize_t,
                       ctypes.c_ssize_t)
#: ``mj_forwardSkip(const mjModel *, mjData *, int skipstage, int skipsensor)``.
SKIP = ctypes.CFUNCTYPE(None, ctypes.c_ssize_t, ctypes.c_ssize_t, ctypes.c_int, ctypes.c_int)
#: ``mjModel *mj_copyModel(mjModel *dest, const mjModel *src)``.
COPY_MODEL = ctypes.CFUNCTYPE(ctypes.c_ssize_t, ctypes.c_ssize_t, ctypes.c_ssize_t)


class ArenaMoved(RuntimeError):
    """A forward pass laid MjData's constraint arrays out elsewhere than the first."""


@cache
def library() -> ctypes.CDLL | None:
    """MuJoCo's shared library, the one its Python bindings loaded (next to them)."""
    pattern = {"darwin": "libmujoco*.dylib", "win32": "mujoco.dll"}.get(sys.platform,
                                                                        "libmujoco.so*")
    found = sorted(Path(mujoco.__file__).parent.glob(pattern))
    return ctypes.CDLL(str(found[0])) if found else None


@cache
def functions() -> dict[str, Callable[..., None]]:
    """The MuJoCo functions the kernels call."""
    lib = library()
    assert lib is not None
    out: dict[str, Callable[..., None]] = {
        name: PASS((name, lib))
        for name in ("mj_forward", "mj_kinematics", "mj_comPos", "mj_comVel",
                     "mj_rnePostConstraint", "mj_step", "mj_Euler", "mj_fwdPosition")}
    return out | {"mj_mulM": MUL(("mj_mulM", lib)),
                  "mj_forwardSkip": SKIP(("mj_forwardSkip", lib)),
                  "mj_setState": SET_STATE(("mj_setState", lib)),
                  "mj_getState": SET_STATE(("mj_getState", lib))}


def calls(model: mujoco.MjModel, data: mujoco.MjData) -> MjCalls:
    """``model`` and ``data`` with the functions the kernels call on them."""
    f = functions()
    return MjCalls(model._address, data._address, f["mj_forward"], f["mj_kinematics"],
                   f["mj_comPos"], f["mj_comVel"], f["mj_rnePostConstraint"], f["mj_step"],
                   f["mj_mulM"], f["mj_setState"], f["mj_getState"], f["mj_Euler"],
                   f["mj_fwdPosition"], f["mj_forwardSkip"])


@cache
def copy_model() -> Callable[[int, int], int] | None:
    """MuJoCo's ``mj_copyModel`` (into a model of the same sizes: in place), or None where
    its library is not at a known place. It needs no numba."""
    lib = library()
    return None if lib is None else COPY_MODEL(("mj_copyModel", lib))


def copy_into(copier: Callable[[int, int], int], dest: mujoco.MjModel,
              source: mujoco.MjModel) -> None:
    """``source`` copied into ``dest`` (of the same sizes) by ``copier`` (:func:`copy_model`)."""
    copier(dest._address, source._address)


def constraint_views(data: mujoco.MjData, nefc: int, nv: int) -> tuple[np.ndarray, ...]:
    """Views of the constraint arrays the kernels read and write (efc_J, efc_pos,
    efc_force), where the last forward pass laid them out."""
    return data.efc_J[:nefc * nv], data.efc_pos[:nefc], data.efc_force[:nefc]


def check_arena(data: mujoco.MjData, views: tuple[np.ndarray, ...], nefc: int, nv: int) -> None:
    """Raise :class:`ArenaMoved` unless the constraint arrays are still where ``views`` are."""
    now = constraint_views(data, nefc, nv)
    if any(a.ctypes.data != b.ctypes.data or a.size != b.size for a, b in zip(now, views,
                                                                             strict=True)):
        raise ArenaMoved("MjData's constraint arrays moved between forward passes")
