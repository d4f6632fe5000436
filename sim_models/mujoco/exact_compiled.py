"""``mujoco_solve``'s per-pose loops compiled (:mod:`.exact_kernel`), where numba is installed.

Why: a batched exact sweep makes three MuJoCo passes per pose (kinematics for the load
points, the forward pass for the constraint equations, the post-constraint read-out),
about 9 µs of C on seed E1, and the Python around them took as long again. The kernels
call MuJoCo's own functions through their C function pointers on the same MjData, so
they give the same numbers, bit for bit (``tests/test_mujoco_linkage.py``).

MjData's constraint arrays live in its arena, laid out again by each forward pass; the
views the kernels write through are taken after a forward pass at the sweep's first pose
and checked to be where the last one left them (:class:`ArenaMoved` otherwise, and the
Python loop runs). Without numba, without MuJoCo's shared library at a known place, or
with ``MECHCHECK_PURE_PYTHON=1`` (:mod:`mechcheck.sim_models.compiled`), the Python loops
run.
"""

from __future__ import annotations

import ctypes
import sys
from collections.abc import Callable
from functools import cache
from pathlib import Path
from types import ModuleType

import mujoco
import numpy as np

from mechcheck.sim_models.compiled import kernel

KERNEL = "mechcheck.sim_models.mujoco.exact_kernel"
#: ``void f(const mjModel *, mjData *)``, the pointers passed as integers of their size.
PASS = ctypes.CFUNCTYPE(None, ctypes.c_ssize_t, ctypes.c_ssize_t)
#: ``mj_setState(const mjModel *, mjData *, const mjtNum *state, int spec)``, and
#: ``mj_getState``'s, the same but for the state's constness.
SET_STATE = ctypes.CFUNCTYPE(None, ctypes.c_ssize_t, ctypes.c_ssize_t, ctypes.c_ssize_t,
                             ctypes.c_int)
#: ``mj_mulM(const mjModel *, const mjData *, mjtNum *res, const mjtNum *vec)``.
MUL = ctypes.CFUNCTYPE(None, ctypes.c_ssize_t, ctypes.c_ssize_t, ctypes.c_ssize_t,
                       ctypes.c_ssize_t)


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
                     "mj_rnePostConstraint", "mj_step")}
    return out | {"mj_mulM": MUL(("mj_mulM", lib)),
                  "mj_setState": SET_STATE(("mj_setState", lib)),
                  "mj_getState": SET_STATE(("mj_getState", lib))}


@cache
def copy_model() -> Callable[[int, int], int] | None:
    """MuJoCo's ``mj_copyModel`` (into a model of the same sizes: in place), or None where
    its library is not at a known place. It needs no numba."""
    lib = library()
    return None if lib is None else COPY_MODEL(("mj_copyModel", lib))


def loops() -> ModuleType | None:
    """The compiled loops, or None (the Python ones run)."""
    return kernel(KERNEL) if library() is not None else None


def load_points(loop: ModuleType, model: mujoco.MjModel, data: mujoco.MjData,
                qpos: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:meth:`.linkage_rig.LinkageRig.load_points`, compiled."""
    sites = np.empty((len(qpos), *data.site_xpos.shape))
    centres = np.empty((len(qpos), *data.xipos.shape))
    loop.load_points(functions()["mj_kinematics"], model._address, data._address,
                     np.ascontiguousarray(qpos), data.qpos, data.site_xpos, data.xipos, sites,
                     centres)
    return sites, centres


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
