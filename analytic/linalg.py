"""The linear algebra of the linkage engine, behind one door: matrices over many poses held
as their entries, and the solves, condition numbers and ranks the engine asks of them.

A linkage's constraint Jacobian and its member-equilibrium matrix have a few entries per
joint, so they are assembled as entries (row, column, values at N poses), never as dense
(N, rows, columns) arrays unless the system is small:

- **small** (at most :data:`DENSE_COLUMNS` columns): dense and vectorised over the poses,
  which is fastest for a few links at 10⁶ poses;
- **large**: one sparse matrix per pose, factorised by SuperLU; the 2-norm condition number
  from the largest and smallest singular values by Lanczos iteration (ARPACK), the smallest
  through the factorisation; the rank by counting the singular values below the threshold;
  the spectral radius of a⁻¹·b (the Coulomb loop's gain) from the small matrix of b's rows.

So memory grows with the number of entries (linearly with the links), and time with the
factorisations' fill, which for the chains and trees of a linkage stays close to linear.
"""

from __future__ import annotations

import functools
import itertools
import math
import threading
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from mechcheck.analytic import _fast

if TYPE_CHECKING:
    from scipy import sparse

# scipy is imported where a large system needs it: the small, dense path (every built-in
# linkage) does not pay for its import.

Array = NDArray[np.float64]

#: Largest system solved densely (columns): below it the batched dense LAPACK calls over all
#: poses win; above it a sparse factorisation per pose does (benchmarks/bench_chain.py).
DENSE_COLUMNS = 96
#: Relative accuracy of the Lanczos estimates of the extreme singular values.
LANCZOS_TOL = 1e-12
#: Singular values below this fraction of the largest count as zero (rank).
RANK_RTOL = 1e-9


#: Up to this many poses, a matrix's entries are summed into it by one ``np.add.at`` over
#: all of them (one pose pays for a few calls, not one per entry); beyond it, entry by
#: entry, each a contiguous row of poses (``np.add.at`` is 3× slower on long rows).
FEW_POSES = 64


@dataclass
class Batched:
    """A (rows × columns) matrix at each of N poses, held as its entries."""

    rows: int
    cols: int
    poses: int
    _r: list[int] = field(default_factory=list)
    _c: list[int] = field(default_factory=list)
    #: The entries' values in blocks (k, N) of entries added together, or all of them
    #: stacked (entries, N) once derived.
    _v: list[Array] | Array = field(default_factory=list)
    #: A number's row of N values, made once per matrix (entries are never written to).
    _constants: dict[float, Array] = field(default_factory=dict, repr=False)
    #: What is derived from the entries so far (:meth:`_derived`), dropped when one is added.
    _kept: dict[str, Any] = field(default_factory=dict, repr=False)

    @classmethod
    def from_dense(cls, m: Array) -> Batched:
        """The entries of dense matrices (N, rows, cols) that are not zero at every pose."""
        out = cls(m.shape[1], m.shape[2], m.shape[0])
        for r, c in zip(*np.nonzero(np.any(m != 0.0, axis=0)), strict=True):
            out.add(int(r), int(c), m[:, r, c])
        return out

    def add(self, row: int, col: int, values: Array | float) -> None:
        """Add ``values`` (N,) (or one number for every pose) at (row, col)."""
        if isinstance(values, (float, int)):
            self._add_block([row], [col], self._constant(float(values)))
            return
        v = np.asarray(values, dtype=float)
        # Most entries are already a value per pose: broadcasting costs more than the entry.
        self._add_block([row], [col], (v if v.shape == (self.poses,)
                                       else np.broadcast_to(v, (self.poses,)))[None])

    def add_entries(self, rows: list[int], cols: list[int], values: Array) -> None:
        """Add the rows of ``values`` (k, N) at (rows[i], cols[i]): many entries computed
        together, kept as one block."""
        self._add_block(rows, cols, values)

    def _add_block(self, rows: list[int], cols: list[int], values: Array) -> None:
        if not isinstance(self._v, list):
            self._v = [self._v]
        self._kept.clear()
        self._r.extend(rows)
        self._c.extend(cols)
        self._v.append(values)

    def _constant(self, value: float) -> Array:
        """A block (1, N) of ``value`` (read-only: shared by every matrix of a few poses)."""
        if self.poses <= FEW_POSES:
            return _few_constant(value, self.poses)
        row = self._constants.get(value)
        if row is None:
            row = self._constants[value] = _few_constant.__wrapped__(value, self.poses)
        return row

    @property
    def small(self) -> bool:
        return self.cols <= DENSE_COLUMNS

    def _derived(self, what: str, make: Callable[[], Any]) -> Any:
        """``make()``, kept until an entry is added: a solve and its condition number ask for
        the same index, pattern and dense matrix, which one pose pays for in calls."""
        found = self._kept.get(what)
        if found is None:
            found = self._kept[what] = make()
        return found

    def _structure(self) -> _Structure:
        """Where the entries sit (:func:`_structure_of`), found again for the next matrix of
        the same entries' places (the next solve of a case)."""
        found: _Structure = self._derived("structure", lambda: _structure_of(
            self.rows, self.cols, self.poses, self._r, self._c))
        return found

    @property
    def distinct(self) -> bool:
        """No two entries at one place (so scaling the entries or the dense matrix is the
        same arithmetic)."""
        return self._structure().distinct

    @property
    def pattern(self) -> NDArray[np.bool_]:
        """(rows, cols): where the matrix has entries (read-only)."""
        return self._structure().pattern

    def values(self) -> Array:
        """(entries, N)."""
        if not isinstance(self._v, list):
            return self._v
        if not self._v:
            return np.zeros((0, self.poses))
        if self.poses > FEW_POSES:   # a second copy of many poses' entries is not kept
            return np.concatenate(self._v)
        found: Array = self._derived("values", lambda: np.concatenate(self._v))
        return found

    def _entries(self) -> Iterable[Array]:
        """Each entry's values (N,), in the order they were added."""
        return self._v if not isinstance(self._v, list) else itertools.chain.from_iterable(self._v)

    def index(self) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
        """The entries' rows and columns (read-only)."""
        return self._structure().index

    def dense(self) -> Array:
        """(N, rows, cols), duplicates summed (in the order they were added)."""
        if self.poses <= FEW_POSES:   # kept: a solve and its condition number both ask
            return np.array(self._derived("dense", self._dense_few))   # its layout kept
        out = np.zeros((self.rows, self.cols, self.poses))
        for r, c, v in zip(self._r, self._c, self._entries(), strict=True):
            out[r, c] += v   # a row of N contiguous values per entry
        return np.moveaxis(out, 2, 0)

    def _dense_few(self) -> Array:
        """:meth:`dense` of a few poses in one call: each place's entries summed from 0 in
        the order they were added (as ``np.add.at`` sums them, at a fifth of its cost)."""
        if not self._r:
            return np.moveaxis(np.zeros((self.rows, self.cols, self.poses)), 2, 0)
        summed = np.asarray(np.bincount(self._structure().places, weights=self.values().ravel(),
                                        minlength=self.rows * self.cols * self.poses),
                            dtype=np.float64)
        # The poses last in memory, as the many poses' dense() has them: reductions along
        # a row (norms, products) round alike only in the same layout.
        return summed.reshape(self.rows, self.cols, self.poses).transpose(2, 0, 1)

    def at(self, pose: int) -> sparse.csc_matrix:
        """The sparse matrix at one pose, duplicates summed."""
        from scipy import sparse

        r, c = self.index()
        v = self.values()[:, pose] if self._r else np.zeros(0)
        return sparse.csc_matrix((v, (r, c)), shape=(self.rows, self.cols))

    def scaled(self, row_scale: Array, col_scale: Array) -> Batched:
        """diag(row_scale)·A·diag(col_scale); ``row_scale`` (N, rows), ``col_scale`` (cols,)."""
        out = Batched(self.rows, self.cols, self.poses, list(self._r), list(self._c))
        if self._r:
            r, c = self.index()
            # Entry by entry as v · row_scale · col_scale, all entries in three operations.
            out._v = self.values() * row_scale.T[r] * col_scale[c][:, None]
        return out

    def row_norms(self) -> Array:
        """(N, rows): the 2-norm of every row, duplicates summed first."""
        if self.small:
            return np.asarray(np.linalg.norm(self.dense(), axis=2), dtype=np.float64)
        out = np.zeros((self.poses, self.rows))
        for pose in range(self.poses):
            m = self.at(pose).tocsr()
            out[pose] = np.sqrt(np.asarray(m.multiply(m).sum(axis=1)).ravel())
        return out

    def times(self, x: Array) -> Array:
        """(N, rows): the matrix times x (N, cols) at every pose, from the entries."""
        out = np.zeros((self.rows, self.poses))
        if self._r:
            r, c = self.index()
            np.add.at(out, r, self.values() * x.T[c])
        return out.T

    def _blocks(self) -> list[Array]:
        return self._v if isinstance(self._v, list) else [self._v]

    def plus(self, other: Batched) -> Batched:
        out = Batched(self.rows, self.cols, self.poses)
        out._r, out._c = self._r + other._r, self._c + other._c
        out._v = [*self._blocks(), *other._blocks()]
        return out


@functools.lru_cache(maxsize=4 * FEW_POSES)
def _few_constant(value: float, poses: int) -> Array:
    """A read-only block (1, poses) of ``value``."""
    row = np.full((1, poses), value)
    row.flags.writeable = False
    return row


@dataclass(frozen=True)
class _Structure:
    """Where a matrix's entries sit: their rows and columns, the pattern, whether no two
    share a place, and each value's place in the dense (rows, cols, N) array of a few poses
    (for :meth:`Batched._dense_few`'s sum); every array read-only."""

    index: tuple[NDArray[np.intp], NDArray[np.intp]]
    pattern: NDArray[np.bool_]
    distinct: bool
    places: NDArray[np.intp]


#: The structures found so far (:func:`_structure_of`), the most recent last; at most
#: :data:`KEPT_STRUCTURES`: a linkage's matrices keep their entries' places from one solve
#: of a pose to the next, and deriving them costs as much as the matrix's values.
_STRUCTURES: dict[tuple[object, ...], _Structure] = {}
KEPT_STRUCTURES = 256
_STRUCTURES_LOCK = threading.Lock()


def _structure_of(rows: int, cols: int, poses: int, r: list[int], c: list[int]) -> _Structure:
    """The :class:`_Structure` of entries at rows ``r`` and columns ``c``, kept."""
    key = (rows, cols, poses, tuple(r), tuple(c))
    found = _STRUCTURES.get(key)
    if found is not None:
        return found
    ri, ci = np.asarray(r, dtype=np.intp), np.asarray(c, dtype=np.intp)
    pattern = np.zeros((rows, cols), dtype=bool)
    pattern[ri, ci] = True
    places = (((ri * cols + ci) * poses)[:, None] + np.arange(poses)).ravel() \
        if poses <= FEW_POSES else np.zeros(0, dtype=np.intp)
    for a in (ri, ci, pattern, places):
        a.flags.writeable = False
    found = _Structure((ri, ci), pattern, len(set(zip(r, c, strict=True))) == len(r), places)
    with _STRUCTURES_LOCK:  # solves may run in several threads
        _STRUCTURES[key] = found
        while len(_STRUCTURES) > KEPT_STRUCTURES:
            del _STRUCTURES[next(iter(_STRUCTURES))]
    return found


class Dropped(Batched):
    """A matrix whose entries are dropped as they are written: where only the values that
    come with them are wanted (a constraint system's residual without its Jacobian)."""

    def add(self, row: int, col: int, values: Array | float) -> None:
        return None

    def add_entries(self, rows: list[int], cols: list[int], values: Array) -> None:
        return None


def solve(a: Batched | Array, b: Array) -> Array:
    """x with a·x = b at every pose (b: (N, rows)): exact where a is square and regular,
    else the least-squares solution of least norm; NaN where a or b is not finite."""
    if isinstance(a, np.ndarray):
        return _solve_dense(a, b)
    if a.small:
        return _solve_dense(a.dense(), b)
    x = np.full((a.poses, a.cols), np.nan)
    values = a.values()
    finite = np.isfinite(values).all(axis=0) & np.isfinite(b).all(axis=1)
    for pose in np.flatnonzero(finite):
        x[pose] = _solve_sparse(a.at(int(pose)), b[pose])
    return x


def solve_truncated(a: Batched, b: Array, rcond: float) -> Array:
    """Least-squares x of least norm with a·x ≈ b at every pose, ignoring the directions whose
    singular value is below ``rcond`` of the largest (dense: truncated SVD; sparse: LSMR
    damped by ``rcond`` of the largest singular value): a step that does not blow up where a
    is nearly singular."""
    if a.small:
        m = a.dense()
        out = np.full((a.poses, a.cols), np.nan)
        for pose in range(a.poses):
            if np.all(np.isfinite(m[pose])) and np.all(np.isfinite(b[pose])):
                out[pose] = np.linalg.lstsq(m[pose], b[pose], rcond=rcond)[0]
        return out
    from scipy.sparse import linalg as splinalg

    out = np.full((a.poses, a.cols), np.nan)
    for pose in range(a.poses):
        m = a.at(pose)
        top = math.sqrt(_largest_eigenvalue(_gram(m), a.cols))
        out[pose] = splinalg.lsmr(m, b[pose], damp=rcond * top, atol=1e-15, btol=1e-15,
                                  maxiter=20 * max(m.shape))[0]
    return out


def _gram(m: sparse.csc_matrix) -> Callable[[Array], Any]:
    """x ↦ MᵀM·x."""
    return lambda x: m.T @ (m @ x)


def _solve_dense(a: Array, b: Array) -> Array:
    if a.size and a.shape[1] == a.shape[2]:   # numpy's solve without its wrapper, if it gives one
        x = _fast.solve_square(a, b)
        if x is not None:
            return x
    finite = np.isfinite(a).all(axis=(1, 2)) & np.isfinite(b).all(axis=1)
    if not finite.all():  # a pose that is not there (NaN) has no solution; LAPACK would fail
        x = np.full((a.shape[0], a.shape[2]), np.nan)
        if finite.any():
            x[finite] = _solve_dense(a[finite], b[finite])
        return x
    with np.errstate(all="ignore"):
        if a.shape[1] == a.shape[2]:
            try:
                return np.asarray(np.linalg.solve(a, b[..., None])[..., 0], dtype=np.float64)
            except np.linalg.LinAlgError:
                pass
        return np.asarray(np.einsum("nij,nj->ni", np.linalg.pinv(a), b), dtype=np.float64)


def _solve_sparse(m: sparse.csc_matrix, b: Array) -> Array:
    from scipy.sparse import linalg as splinalg

    if m.shape[0] == m.shape[1]:
        try:
            x = splinalg.splu(m).solve(b)
            if np.all(np.isfinite(x)):
                return np.asarray(x, dtype=np.float64)
        except RuntimeError:  # exactly singular: fall through to least squares
            pass
    # Least squares of least norm (LSMR from x = 0), to rounding.
    scale = float(np.abs(b).max(initial=0.0)) or 1.0
    found = splinalg.lsmr(m, b / scale, atol=1e-15, btol=1e-15, maxiter=20 * max(m.shape))
    return np.asarray(found[0] * scale, dtype=np.float64)


def spectral_radius(a: Batched, b: Batched) -> Array:
    """The largest |λ| of a⁻¹·b at every pose (both square, of one size); NaN where a is
    singular or not finite. Dense eigenvalues when small; else those of the smaller matrix
    that has the same non-zero eigenvalues (:func:`_spectral_radius_sparse`)."""
    out = np.full(a.poses, np.nan)
    finite = np.isfinite(a.values()).all(axis=0) & np.isfinite(b.values()).all(axis=0)
    if a.small:
        with np.errstate(all="ignore"):
            try:
                loop = np.linalg.solve(a.dense()[finite], b.dense()[finite])
            except np.linalg.LinAlgError:  # a singular pose has no loop
                return out
            out[finite] = np.abs(np.linalg.eigvals(loop)).max(axis=1, initial=0.0)
        return out
    for pose in np.flatnonzero(finite):
        out[pose] = _spectral_radius_sparse(a.at(int(pose)), b.at(int(pose)))
    return out


def _spectral_radius_sparse(a: sparse.csc_matrix, b: sparse.csc_matrix) -> float:
    """With b's non-zero rows R and columns C, b = E_R·M·E_Cᵀ, and a⁻¹·b has the non-zero
    eigenvalues of M·(a⁻¹·E_R)[C] (AB and BA share them), a matrix of |R| rows solved through
    a's sparse factorisation. Exact, where Arnoldi iteration stalls on the many zero
    eigenvalues a low-rank b gives; its memory is the rows of a times |R|."""
    from scipy.sparse import linalg as splinalg

    b = b.tocoo()
    keep = b.data != 0.0
    rows, cols = np.unique(b.row[keep]), np.unique(b.col[keep])
    if rows.size == 0:   # nothing to loop: every eigenvalue is 0
        return 0.0
    try:
        lu = splinalg.splu(a)
    except RuntimeError:
        return math.nan
    inject = np.zeros((a.shape[0], rows.size))
    inject[rows, np.arange(rows.size)] = 1.0
    small = b.tocsr()[rows][:, cols].toarray() @ lu.solve(inject)[cols]
    if not np.isfinite(small).all():   # a nearly singular a: no loop to speak of
        return math.nan
    return float(np.abs(np.linalg.eigvals(small)).max(initial=0.0))


def condition(a: Batched) -> Array:
    """The 2-norm condition number σ_max/σ_min at every pose (over the columns' space for a
    tall matrix); inf where a is singular or not finite."""
    if a.small or a.rows != a.cols:
        return _condition_dense(a.dense())
    out = np.full(a.poses, np.inf)
    finite = np.isfinite(a.values()).all(axis=0)
    for pose in np.flatnonzero(finite):
        out[pose] = _condition_sparse(a.at(int(pose)))
    return out


def condition_of_dense(m: Array) -> Array:
    """:func:`condition` of dense matrices (N, rows, cols)."""
    return _condition_dense(m)


def _condition_dense(m: Array) -> Array:
    if 0 in m.shape[1:]:
        return np.ones(m.shape[0])
    if m.shape[0] == 1:     # one pose: its matrix alone, in a third of the calls
        return np.array([_condition_one(m[0])])
    out = np.full(m.shape[0], np.inf)
    finite = np.all(np.isfinite(m), axis=(1, 2))
    if finite.any():
        s = np.linalg.svd(m[finite], compute_uv=False)
        with np.errstate(divide="ignore", invalid="ignore"):
            out[finite] = np.where(s[:, -1] > 0.0, s[:, 0] / s[:, -1], np.inf)
    return out


def _condition_one(m: Array) -> float:
    """:func:`_condition_dense` of one matrix: the same SVD, the same quotient."""
    if not np.isfinite(m).all():
        return math.inf
    s = np.linalg.svd(m, compute_uv=False)
    return float(s[0] / s[-1]) if s[-1] > 0.0 else math.inf


def _condition_sparse(m: sparse.csc_matrix) -> float:
    from scipy.sparse import linalg as splinalg

    try:
        lu = splinalg.splu(m)
    except RuntimeError:
        return math.inf
    n = m.shape[0]
    largest = _largest_eigenvalue(_gram(m), n)
    smallest_inverse = _largest_eigenvalue(lambda x: lu.solve(lu.solve(x, trans="T")), n)
    if not (math.isfinite(smallest_inverse) and smallest_inverse > 0.0):
        return math.inf
    return math.sqrt(largest * smallest_inverse)


def _largest_eigenvalue(apply: Callable[[Array], Any], n: int) -> float:
    """The largest eigenvalue of a symmetric positive semi-definite operator of size n."""
    from scipy.sparse import linalg as splinalg

    operator = splinalg.LinearOperator((n, n), matvec=apply, dtype=np.float64)
    with np.errstate(all="ignore"):
        try:
            value = splinalg.eigsh(operator, k=1, which="LA", v0=np.ones(n),
                                   tol=LANCZOS_TOL, return_eigenvectors=False)
        except splinalg.ArpackNoConvergence as failed:
            value = failed.eigenvalues
        except (ValueError, RuntimeError):
            return math.inf
    return float(value[0]) if len(value) and np.isfinite(value[0]) else math.inf


def rank(m: Array | sparse.spmatrix) -> int:
    """The number of singular values of ``m`` (one matrix) above :data:`RANK_RTOL` of the
    largest. Dense SVD when small; else the count of the small ones through a factorisation
    of the augmented system [[I, Mᵀ], [M, −εI]], whose Schur complement is −(MMᵀ + εI)."""
    if isinstance(m, np.ndarray):
        if m.size == 0:
            return 0
        if m.shape[1] <= DENSE_COLUMNS or m.shape[0] <= DENSE_COLUMNS:
            s = np.linalg.svd(m, compute_uv=False)
            return int((s > RANK_RTOL * s[0]).sum()) if s.size and s[0] > 0.0 else 0
    from scipy import sparse
    from scipy.sparse import linalg as splinalg

    if isinstance(m, np.ndarray):
        m = sparse.csc_matrix(m)
    wide = sparse.csc_matrix(m if m.shape[0] <= m.shape[1] else m.T)
    r, c = wide.shape
    if r == 0 or wide.nnz == 0:
        return 0
    top = _largest_eigenvalue(lambda x: wide @ (wide.T @ x), r)
    eps = (1e-3 * RANK_RTOL) ** 2 * top
    augmented = sparse.bmat([[sparse.identity(c), wide.T], [wide, -eps * sparse.identity(r)]],
                            format="csc")
    try:
        lu = splinalg.splu(augmented)
    except RuntimeError:
        return rank(wide.toarray()) if c <= 4 * DENSE_COLUMNS else 0

    def inverse_gram(y: Array) -> Array:
        return np.asarray(-lu.solve(np.concatenate([np.zeros(c), y]))[c:], dtype=np.float64)

    operator = splinalg.LinearOperator((r, r), matvec=inverse_gram, dtype=np.float64)
    threshold = (RANK_RTOL**2) * top
    k = 1
    while True:
        k = min(k, r - 1)
        if k < 1:
            return rank(wide.toarray())
        values = splinalg.eigsh(operator, k=k, which="LA", v0=np.ones(r), tol=LANCZOS_TOL,
                                return_eigenvectors=False)
        small = int(np.sum(1.0 / values - eps <= threshold))
        if small < k or k == r - 1:
            return r - small
        k *= 2
