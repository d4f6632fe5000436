"""The engine's fence for one pose's speed (``analytic/_fast``) and the shortcuts a case
solved on its own takes: each gives the numbers of the public route it stands for, to the
bit, or says it cannot."""

from __future__ import annotations

import numpy as np
import pytest

from mechcheck.analytic import _fast
from mechcheck.analytic.linkage_kinematics import constraint_system
from mechcheck.analytic.rigid import Layout

from .builtin import builtin_cases

#: Every built-in case's linkage (a four-bar or slider-crank file as the linkage it reads as).
LINKAGES = {name: case.linkage for name, case in builtin_cases().items()}


@pytest.mark.parametrize("size", [1, 3, 9, 21])
def test_lapack_without_the_wrappers_gives_numpys_numbers(size: int) -> None:
    """numpy's gufuncs called directly solve and invert as numpy.linalg.solve and inv do,
    to the bit (the same LAPACK routines on the same arrays), one pose or several."""
    rng = np.random.default_rng(size)
    for poses in (1, 4):
        a = rng.standard_normal((poses, size, size))
        b = rng.standard_normal((poses, size))
        x = _fast.solve_square(a, b)
        inverse = _fast.inverse(a)
        assert x is not None and inverse is not None
        assert np.array_equal(x, np.linalg.solve(a, b[..., None])[..., 0])
        assert np.array_equal(inverse, np.linalg.inv(a))


def test_a_singular_or_unfinished_matrix_is_left_to_numpy() -> None:
    """Where numpy.linalg raises (a singular matrix) or would meet a NaN, the fence gives
    None and the caller takes numpy's own route."""
    singular = np.array([[[1.0, 2.0], [2.0, 4.0]]])
    assert _fast.solve_square(singular, np.ones((1, 2))) is None
    assert _fast.inverse(singular) is None
    unfinished = np.array([[[1.0, np.nan], [0.0, 1.0]]])
    assert _fast.solve_square(unfinished, np.ones((1, 2))) is None
    assert _fast.inverse(unfinished) is None


@pytest.mark.parametrize("name", sorted(LINKAGES))
def test_the_drawn_residual_is_the_drawings_closure(name: str) -> None:
    """The joints' residual a linkage keeps from its rank at the drawing is the one its
    constraint system gives there with the drivers' rows, and every driver's row is zero at
    the drawing (a driver's value is its joint's coordinate from the drawn pose): so a solve
    tests the drawing's closure on it without evaluating the rows again."""
    linkage = LINKAGES[name]
    q = np.zeros((1, Layout(linkage).size))
    phi, _ = constraint_system(linkage, q, np.zeros((1, len(linkage.drivers))), jacobian=False)
    joints = linkage.constraint_rows
    assert np.array_equal(phi[:, :joints], linkage.drawn_residual)
    assert np.all(phi[:, joints:] == 0.0)
    assert not linkage.drawn_residual.flags.writeable
