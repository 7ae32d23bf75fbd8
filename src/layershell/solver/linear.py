"""Sparse linear solves of the reduced tangent, with automatic backend choice.

``pardiso``: Intel MKL PARDISO (through ``pypardiso``'s handle on MKL, installed by default on
x86-64), used in its *real symmetric indefinite* mode (mtype = -2, upper triangle) where the
tangent is symmetric - it is not always positive definite (buckling, limit points) - and in its
general mode (mtype = 11) where it is not. Assembled tangents whose contributions are all
symmetric by construction (element tangents, contact with the exact friction return mapping)
say so (``ReducedTangent.known_symmetric``); other matrices are checked on every call (O(nnz)).
The symbolic analysis (fill-reducing ordering) is kept and reused while the sparsity pattern
does not change - every Newton iteration of a bond state has the same pattern - and only the
numerical factorisation is redone. PARDISO is called with explicit parameters (MKL's
``pardisoinit`` defaults, zero-based indices, the ordering picked by measured flops, iterative
refinement only after perturbed pivots; see :class:`PardisoSymmetric`).

``superlu``: SciPy's SuperLU (always available), the automatic fallback. COLAMD ordering: on the
multi-layer shell tangents it fills 2-6x less than MMD(AᵀA + A) (measured in
``benchmarks/solvers.py``).

Measured on this project's models (2-core machine, ``benchmarks/solvers.py``): PARDISO factorises
the 5 099-DOF pull-off tangent in 0.024 s (minimum-degree ordering; 0.034 s with METIS) against
0.6 s (SuperLU/COLAMD) and 3.5 s (SuperLU/MMD).

**Kept factorisations** (``reuse``): where a factorisation costs many solves - PARDISO's
flops against the entries a solve and a product with K read, ``factorisation_cost`` - a
Newton iteration first solves its tangent by GMRES (:func:`gmres`) preconditioned with the
last factorisation, of an earlier iteration's tangent. The tangents of one load step differ
little (the geometric stiffness, cohesive points that soften), so GMRES converges in a few
iterations. A solve may take at most as many iterations as a factorisation costs (and gives
up earlier where its rate of convergence would not get there); where it fails, K is
factorised and that factorisation kept, and a solve that took more than half the cost retires
the factorisation it used. On the cohesive §5.1 plate on 24 × 24 (57 036 DOFs, 1.3 s per LU
factorisation against 0.035 s per GMRES iteration) most solves take 4-15 iterations. Small
models (the DCB's strip: a factorisation costs 3-6 iterations) are always factorised.
"""
from __future__ import annotations

import ctypes
import math
import zlib
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

BACKENDS = ("auto", "pardiso", "superlu")


class SingularSystemError(RuntimeError):
    """The reduced tangent is singular (a rigid-body mode is not supported, or a limit point)."""


# what PardisoSymmetric uses of pypardiso's solver object (its handle on MKL): checked once, so
# that a pypardiso release without them falls back to SciPy instead of failing mid-run
_PYPARDISO_ATTRIBUTES = ("_mkl_pardiso", "_pt_type", "pt", "perm", "iparm", "libmkl")


def _have_pardiso() -> bool:
    try:
        import os

        import pypardiso  # loads MKL (searching the environment for it) or raises

        # point later solver instances straight at the library instead of searching again
        os.environ.setdefault("PYPARDISO_MKL_RT", pypardiso.ps.libmkl._name)
        if not all(hasattr(pypardiso.ps, a) for a in _PYPARDISO_ATTRIBUTES):
            return False
        getattr(pypardiso.ps.libmkl, "pardisoinit")
    except Exception:
        return False
    return True


_PARDISO_OK: bool | None = None


def backend_name(preferred: str = "auto") -> str:
    """The backend ``preferred`` resolves to on this machine."""
    global _PARDISO_OK
    if preferred not in BACKENDS:
        raise ValueError(f"unknown linear solver {preferred!r}; use one of {', '.join(BACKENDS)}")
    if preferred == "superlu":
        return "superlu"
    if _PARDISO_OK is None:
        _PARDISO_OK = _have_pardiso()
    if preferred == "pardiso" and not _PARDISO_OK:
        raise RuntimeError("solver = 'pardiso' was requested but pypardiso/MKL cannot be loaded; "
                           "install it with `pip install pypardiso` or use solver = 'auto'")
    return "pardiso" if _PARDISO_OK else "superlu"


@dataclass
class FactorInfo:
    """What the last factorisation reported (PARDISO only; None where unknown)."""

    backend: str = ""
    analysed: bool = False  # a new symbolic analysis was done (pattern changed)
    negative_pivots: int | None = None  # inertia: negative eigenvalues of the tangent (symmetric mode only)
    perturbed_pivots: int | None = None


# GMRES on a kept factorisation (LinearSolver ``reuse``)
# residual of a GMRES solve, relative to the right-hand side: Newton's own tolerance (the
# corrections are then exact to that share and Newton converges as with a direct solve; on the
# 12 × 12 cohesive plate 1e-10 and 1e-8 took the same 735 Newton iterations, 1e-8 7 % less time;
# 1e-6 took one iteration more)
KRYLOV_RTOL = 1e-8
KRYLOV_MAX = 30  # GMRES iterations per solve at most (no restarts), and at most a factorisation's cost
REUSE_MIN_COST = 16.0  # "auto": keep factorisations that cost at least this many GMRES iterations
# a GMRES solve that took more than this share of a factorisation's cost: the next one factorises
# (the kept factorisation has aged; the solves on it only get dearer)
REUSE_AGED = 0.5
# give a GMRES solve up once the rate of its last KRYLOV_WINDOW iterations, continued, would not
# reach the tolerance within STAGNATION_SLACK × the iterations left (GMRES accelerates; on the 12 × 12
# cohesive plate's 693 solves this gave up 19 of 486 that would have converged and saved 70 % of
# the iterations spent in the ones that did not)
KRYLOV_WINDOW = 4
STAGNATION_SLACK = 3.0
# flops of a factorisation per entry that one GMRES iteration reads (the factor, in both
# triangular solves, and K in its product): the solve is bound by memory, the factorisation by
# arithmetic. Measured on the cohesive plate (6 × 6 to 24 × 24) and the DCB: 11-20
FLOPS_PER_SOLVE_ENTRY = 16.0


def gmres(K, precondition, b: np.ndarray, rtol: float = KRYLOV_RTOL,
          maxiter: int = KRYLOV_MAX) -> tuple[np.ndarray, int, bool]:
    """Solve K x = b by GMRES, right-preconditioned (x = M⁻¹ y), without restarts; returns
    ``(x, iterations, converged)``. Classical Gram-Schmidt with one re-orthogonalisation
    (matrix products over the basis). Right preconditioning minimises the residual of x itself,
    and the test is on the least-squares residual of the Arnoldi relation: SciPy's gmres
    preconditions from the left and tests ‖b - K x‖ computed in floating point, which on the
    penalty-stiffened tangents of layered shells does not fall below 10⁻⁸ ‖b‖ (the round-off of
    K x; a direct solve's residual is as large), so it would not stop."""
    n = b.size
    beta = float(np.linalg.norm(b))
    if beta == 0.0:
        return np.zeros(n), 0, True
    hist = np.empty(maxiter)
    V = np.empty((maxiter + 1, n))
    Z = np.empty((maxiter, n))
    H = np.zeros((maxiter + 1, maxiter))
    V[0] = b / beta
    g = np.zeros(maxiter + 1)
    g[0] = beta
    y = np.zeros(0)
    for j in range(maxiter):
        Z[j] = precondition(V[j])
        w = K @ Z[j]
        h = V[:j + 1] @ w
        w -= V[:j + 1].T @ h
        h2 = V[:j + 1] @ w
        w -= V[:j + 1].T @ h2
        H[:j + 1, j] = h + h2
        H[j + 1, j] = hn = float(np.linalg.norm(w))
        y, *_ = np.linalg.lstsq(H[:j + 2, :j + 1], g[:j + 2], rcond=None)
        res = float(np.linalg.norm(H[:j + 2, :j + 1] @ y - g[:j + 2]))
        if not np.isfinite(res):
            return np.zeros(n), j + 1, False
        if res <= rtol * beta or hn == 0.0:
            return Z[:j + 1].T @ y, j + 1, True
        hist[j] = res
        if j >= KRYLOV_WINDOW + 1 and _stagnates(hist[j - KRYLOV_WINDOW], res, rtol * beta, maxiter - j - 1):
            return Z[:j + 1].T @ y, j + 1, False
        V[j + 1] = w / hn
    return Z[:maxiter].T @ y, maxiter, False


def _stagnates(before: float, now: float, target: float, left: int) -> bool:
    """GMRES's residual went from ``before`` to ``now`` in KRYLOV_WINDOW iterations: would that
    rate, continued, miss ``target`` within STAGNATION_SLACK × ``left`` iterations?"""
    if now >= before:
        return True
    need = KRYLOV_WINDOW * math.log(target / now) / math.log(now / before)
    return need > STAGNATION_SLACK * left


def is_symmetric(K: sp.spmatrix, rtol: float = 1e-12) -> bool:
    """Whether K equals its transpose to ``rtol`` of its largest entry (friction tangents are not
    symmetric)."""
    if getattr(K, "known_symmetric", False):  # assembly.ReducedTangent of symmetric contributions
        return True
    fast = getattr(K, "symmetry_check", None)  # assembly.ReducedTangent: one O(nnz) pass via its pattern maps
    check = fast() if fast is not None else None
    if check is not None:
        err, top = check
        return K.nnz == 0 or err <= rtol * top
    K = sp.csr_matrix(K)
    d = abs(K - K.T)
    return d.nnz == 0 or d.max() <= rtol * abs(K).max()


# fill-reducing orderings of PARDISO (iparm[1]); "auto" analyses the first pattern of a solver
# with both up to AUTO_ORDERING_MAX_DOFS and keeps the one whose factorisation needs fewer flops
ORDERINGS = {"metis": 3, "mmd": 0}
AUTO_ORDERING_MAX_DOFS = 50_000


class PardisoSymmetric:
    """MKL PARDISO for a symmetric (indefinite) matrix, reusing the symbolic analysis.

    PARDISO is called directly (through pypardiso's handle on MKL) with zero-based CSR indices,
    so the int32 index arrays of the reduced pattern are passed without a copy per call, and
    with explicit parameters (``pardisoinit`` defaults, then the ordering). The fill-reducing
    ordering is chosen per solver (``ordering="auto"``): on the layered-shell tangents minimum
    degree fills less than METIS up to about 2·10⁴ DOFs (pull-off 335 against 452 MFLOP per
    factorisation, 22 473-DOF plate 5.3 against 7.0 GFLOP) and more above (88 k DOFs: 64.6
    against 52.6 GFLOP), so the first pattern up to ``AUTO_ORDERING_MAX_DOFS`` is analysed with
    both and the cheaper one (fewer flops, then the smaller factor) kept for every later pattern
    (``benchmarks/solvers.py``); where that is the one analysed last, its analysis is used as it is."""

    MTYPE = -2

    def __init__(self, ordering: str = "auto", decisions: dict | None = None) -> None:
        import pypardiso

        backend_name("pardiso")
        if ordering != "auto" and ordering not in ORDERINGS:
            raise ValueError(f"unknown PARDISO ordering {ordering!r}; use auto, {', '.join(ORDERINGS)}")
        self._s = pypardiso.PyPardisoSolver(mtype=self.MTYPE)
        self._init_parameters()
        self._ordering: int | None = None if ordering == "auto" else ORDERINGS[ordering]
        # "auto" choices by pattern, shared by the solvers of one problem: the choice follows from
        # the pattern alone, so a solver started afresh (every load step) need not compare again
        self._decisions = decisions
        self._indptr: np.ndarray | None = None
        self._indices: np.ndarray | None = None
        self._pattern_ref: tuple = (None, None)  # the index arrays last seen (identity check)
        self._A: sp.csr_matrix | None = None  # the matrix of the factorisation in place
        self.flops = 0.0  # of a numerical factorisation, as the analysis reported it
        self.factor_entries = 0
        self.info = FactorInfo("pardiso")

    def factorisation_cost(self, nnz_K: int) -> float:
        """A factorisation's cost in GMRES iterations on it (one solve and one product with a K
        of ``nnz_K`` entries; :data:`FLOPS_PER_SOLVE_ENTRY`). The symmetric mode stores one
        triangle and reads it twice per solve."""
        read = self.factor_entries * (2 if self.MTYPE == -2 else 1) + nnz_K
        return self.flops / (FLOPS_PER_SOLVE_ENTRY * max(read, 1))

    def apply(self, b: np.ndarray) -> np.ndarray:
        """Solve with the factorisation in place (of the matrix last factorised)."""
        return self._raw(self._A, 33, b)

    def _init_parameters(self) -> None:
        """MKL's defaults for this matrix type (``pardisoinit``, checked by :func:`backend_name`),
        zero-based indices."""
        s = self._s
        ip = s.iparm
        s.libmkl.pardisoinit(s.pt.ctypes.data_as(ctypes.c_void_p), ctypes.byref(ctypes.c_int32(self.MTYPE)),
                             ip.ctypes.data_as(ctypes.c_void_p))
        ip[34] = 1  # zero-based CSR indices
        # iterative refinement only after perturbed pivots (pardisoinit asks for 2 steps after
        # every solve): the extra steps cost 6 ms per pull-off solve and, on the penalty-stiffened
        # contact tangents, lengthened the Newton paths (pull-off 460 against 425 iterations,
        # §5.1 strong 409 against 132, slip 203 against 136; the same results)
        ip[7] = 0

    def matrix(self, K: sp.spmatrix) -> sp.csr_matrix:
        return self.upper(K)

    @staticmethod
    def upper(K: sp.spmatrix) -> sp.csr_matrix:
        """Upper triangle in CSR with every diagonal entry stored (PARDISO requires it)."""
        fast = getattr(K, "upper_triangle", None)  # assembly.ReducedTangent: a gather, no sort
        A = fast() if fast is not None else None
        if A is not None:
            return A
        U = sp.triu(K, format="coo")
        n = K.shape[0]
        d = np.arange(n)
        A = sp.csr_matrix((np.concatenate([U.data, np.zeros(n)]),
                           (np.concatenate([U.row, d]), np.concatenate([U.col, d]))), shape=K.shape)
        A.sort_indices()
        return A

    def _check(self, A: sp.csr_matrix) -> sp.csr_matrix:
        """Sorted CSR, float64, int32 indices, no empty row (PARDISO would fail or crash)."""
        if A.shape[0] != A.shape[1] or not sp.issparse(A) or A.format != "csr":
            raise ValueError("PARDISO needs a square CSR matrix")
        if not A.has_sorted_indices:
            A.sort_indices()
        if A.dtype != np.float64:
            A = A.astype(np.float64)
        if A.nnz >= np.iinfo(np.int32).max:
            raise ValueError(f"the tangent has {A.nnz} stored entries, more than the 32-bit indices of "
                             "PARDISO allow; use a coarser mesh or fewer directors")
        if A.indptr.dtype != np.int32 or A.indices.dtype != np.int32:
            A = sp.csr_matrix((A.data, A.indices.astype(np.int32), A.indptr.astype(np.int32)), shape=A.shape)
        if not np.diff(A.indptr).all():
            raise SingularSystemError("the matrix has an empty row (a DOF without stiffness)")
        return A

    def _call(self, A: sp.csr_matrix, phase: int, b: np.ndarray) -> np.ndarray:
        """One PARDISO phase (11 analysis, 22 factorisation, 33 solve, -1 release) on ``A``
        (checked by :meth:`_check`); the analysis picks the ordering (see the class)."""
        if phase == 11:
            self._analyse(A, b)
            return np.zeros_like(b)
        return self._raw(A, phase, b)

    def _raw(self, A: sp.csr_matrix, phase: int, b: np.ndarray) -> np.ndarray:
        from pypardiso.pardiso_wrapper import PyPardisoError

        s = self._s
        if phase == 11:
            s.iparm[17] = s.iparm[18] = -1  # report the factor's size and flops (overwritten by each report)
        b = np.asfortranarray(b, dtype=float)
        x = np.zeros_like(b)
        err = ctypes.c_int32(0)
        i32 = ctypes.POINTER(ctypes.c_int32)
        f64 = ctypes.POINTER(ctypes.c_double)
        s._mkl_pardiso(s.pt.ctypes.data_as(ctypes.POINTER(s._pt_type[0])),
                       ctypes.byref(ctypes.c_int32(1)), ctypes.byref(ctypes.c_int32(1)),
                       ctypes.byref(ctypes.c_int32(self.MTYPE)), ctypes.byref(ctypes.c_int32(phase)),
                       ctypes.byref(ctypes.c_int32(A.shape[0])), A.data.ctypes.data_as(f64),
                       A.indptr.ctypes.data_as(i32), A.indices.ctypes.data_as(i32), s.perm.ctypes.data_as(i32),
                       ctypes.byref(ctypes.c_int32(1 if b.ndim == 1 else b.shape[1])),
                       s.iparm.ctypes.data_as(i32), ctypes.byref(ctypes.c_int32(0)),
                       b.ctypes.data_as(f64), x.ctypes.data_as(f64), ctypes.byref(err))
        if err.value != 0:
            raise PyPardisoError(err.value)
        return x

    def _analyse(self, A: sp.csr_matrix, b: np.ndarray) -> None:
        ip = self._s.iparm
        if self._ordering is None:  # "auto": the first pattern decides
            key = (_pattern_key(A, self.MTYPE)
                   if self._decisions is not None and A.shape[0] <= AUTO_ORDERING_MAX_DOFS else None)
            if A.shape[0] > AUTO_ORDERING_MAX_DOFS:
                self._ordering = ORDERINGS["metis"]
            elif key is not None and key in self._decisions:
                self._ordering = self._decisions[key]
            else:
                flops = {}
                codes = list(ORDERINGS.values())
                for code in codes:
                    if flops:
                        self._free()
                    ip[1] = code
                    self._raw(A, 11, b)
                    flops[code] = (int(ip[18]), int(ip[17]))  # MFLOP, then factor size on a tie
                self._ordering = min(flops, key=flops.get)
                if key is not None:
                    self._decisions[key] = self._ordering
                if self._ordering == codes[-1]:
                    return  # the analysis in place is the chosen one
                self._free()
        ip[1] = self._ordering
        self._raw(A, 11, b)

    def _free(self) -> None:
        empty = sp.csr_matrix((np.zeros(0), np.zeros(0, np.int32), np.zeros(1, np.int32)), shape=(0, 0))
        self._raw(empty, -1, np.zeros(0))

    def solve(self, K: sp.spmatrix, r: np.ndarray) -> np.ndarray:
        from pypardiso.pardiso_wrapper import PyPardisoError

        A = self._check(self.matrix(K))
        b = np.asfortranarray(r, dtype=float)
        # the pattern of the analysis in place? The assembler hands out the same index arrays for
        # one pattern (checked by identity first: comparing 4 M indices took 3.5 % of the DCB's run)
        same = self._indptr is not None and (
            (A.indptr is self._pattern_ref[0] and A.indices is self._pattern_ref[1])
            or (np.array_equal(A.indptr, self._indptr) and np.array_equal(A.indices, self._indices)))
        try:
            if not same:
                if self._indptr is not None:
                    self._free()
                    self._indptr = None
                self._analyse(A, b)  # symbolic analysis (ordering)
                self._indptr, self._indices = A.indptr.copy(), A.indices.copy()
                ip = self._s.iparm  # what the analysis reported: factorisation MFLOP, entries of the factor
                self.flops, self.factor_entries = 1e6 * max(int(ip[18]), 0), max(int(ip[17]), 0)
            self._pattern_ref = (A.indptr, A.indices)
            self._A = None
            self._raw(A, 22, b)  # numerical factorisation
            self._A = A  # the matrix factorised (phase 33 refines on it after perturbed pivots)
            x = self._raw(A, 33, b)  # solve (iterative refinement after perturbed pivots)
        except PyPardisoError as exc:
            if self._indptr is not None:
                try:
                    self._free()
                except PyPardisoError:  # pragma: no cover - nothing left to release
                    pass
            self._indptr = None
            self._A = None
            raise SingularSystemError(f"PARDISO failed ({exc})") from exc
        ip = self._s.iparm
        # PARDISO's inertia (iparm[22], negative eigenvalues; Bunch-Kaufman pivoting) exists in the
        # symmetric indefinite mode only
        self.info = FactorInfo("pardiso", not same, int(ip[22]) if self.MTYPE == -2 else None, int(ip[13]))
        return x

    def release(self) -> None:
        """Free PARDISO's memory (factors and analysis)."""
        self._free()
        self._indptr = None
        self._A = None


def _pattern_key(A: sp.csr_matrix, mtype: int) -> tuple:
    """Identifies a sparsity pattern (CRC-32 of the index arrays; about 1 ms per million entries)."""
    return (mtype, A.shape[0], A.nnz, zlib.crc32(A.indptr.view(np.uint8)), zlib.crc32(A.indices.view(np.uint8)))


class PardisoGeneral(PardisoSymmetric):
    """MKL PARDISO for a general real matrix (mtype = 11): the tangent with friction is not
    symmetric (the regularised slip law couples normal pressure and tangential traction)."""

    MTYPE = 11

    def _init_parameters(self) -> None:
        """As for the symmetric matrix, and without the scaling and weighted matching that
        ``pardisoinit`` switches on for unsymmetric matrices (iparm[10], iparm[12]): they are
        computed from the values of the matrix in the symbolic analysis, so that the
        factorisations of later matrices would depend on which matrix was analysed - a run
        restarted from a checkpoint would differ from the uninterrupted one. Without them the
        analysis depends on the pattern alone, as in the symmetric mode, and can be kept from
        step to step (pivots are perturbed, then refined, where they are small: iparm[9])."""
        super()._init_parameters()
        self._s.iparm[10] = 0
        self._s.iparm[12] = 0

    def matrix(self, K: sp.spmatrix) -> sp.csr_matrix:
        """K itself where it is a sorted CSR matrix (PARDISO only reads it; the DCB spent 8 ms
        of each iteration copying its 4 M entries), else a sorted CSR copy."""
        if sp.isspmatrix_csr(K) and K.has_sorted_indices:
            return K
        A = sp.csr_matrix(K, copy=True)
        A.sort_indices()
        return A


REUSE = ("auto", "always", "never")


@dataclass
class SolveCounts:
    """What a :class:`LinearSolver` did (summary.json ``linear_solves``)."""

    factorisations: int = 0
    krylov_solves: int = 0  # right-hand sides solved by GMRES on a kept factorisation
    krylov_iterations: int = 0  # in all, failed attempts included
    krylov_failures: int = 0  # attempts that did not converge (then factorised)

    def as_dict(self) -> dict:
        return dict(self.__dict__)


class LinearSolver:
    """Solves K x = r for the reduced tangent K with the chosen backend; one instance per problem
    keeps PARDISO's symbolic analysis between calls and, with ``reuse`` (module docstring), its
    last factorisation as GMRES's preconditioner: "auto" where a factorisation costs at least
    :data:`REUSE_MIN_COST` GMRES iterations, "always" (any size; tests), "never"."""

    def __init__(self, backend: str = "auto", symmetric: bool = True, decisions: dict | None = None,
                 reuse: str = "auto") -> None:
        if reuse not in REUSE:
            raise ValueError(f"unknown reuse {reuse!r}; use one of {', '.join(REUSE)}")
        self.backend = backend_name(backend)
        self.symmetric = symmetric  # use PARDISO's symmetric mode when K is symmetric
        self._pardiso: dict[bool, PardisoSymmetric] = {}
        self._decisions = decisions  # PARDISO's ordering choices by pattern (see PardisoSymmetric)
        self.reuse = reuse
        self._kept: PardisoSymmetric | None = None  # holds the last factorisation
        self._cost = 0.0  # of that factorisation, in GMRES iterations
        self.counts = SolveCounts()
        self.info = FactorInfo(self.backend)

    def _krylov(self, K: sp.spmatrix, r: np.ndarray) -> np.ndarray | None:
        """x by GMRES on the kept factorisation, or None where there is none or GMRES does not
        converge within a factorisation's cost (the caller factorises). A solve that needed more
        than REUSE_AGED of that cost retires the factorisation."""
        p = self._kept
        if p is None or p._A is None or p._A.shape[0] != K.shape[0]:
            return None
        cols = r.reshape(r.shape[0], -1)
        X = np.empty_like(cols, dtype=float)
        most = 0
        for j in range(cols.shape[1]):
            x, its, ok = gmres(K, p.apply, np.ascontiguousarray(cols[:, j], dtype=float),
                               maxiter=int(min(KRYLOV_MAX, self._cost)))
            self.counts.krylov_iterations += its
            if not ok or not np.all(np.isfinite(x)):
                self.counts.krylov_failures += 1
                return None
            X[:, j] = x
            most = max(most, its)
            self.counts.krylov_solves += 1
        if most > REUSE_AGED * self._cost:
            self._kept = None
        return X.reshape(r.shape)

    def _keep(self, p: PardisoSymmetric, K: sp.spmatrix) -> None:
        """After a factorisation: keep it where reuse pays (or is asked for)."""
        cost = p.factorisation_cost(K.nnz)
        if self.reuse == "always" or (self.reuse == "auto" and cost >= REUSE_MIN_COST):
            self._kept, self._cost = p, (float(KRYLOV_MAX) if self.reuse == "always" else cost)
        else:
            self._kept, self._cost = None, 0.0

    def solve(self, K: sp.spmatrix, r: np.ndarray) -> np.ndarray:
        if K.shape[0] == 0:
            return np.zeros(0)
        if self.backend == "pardiso":
            x = self._krylov(K, r)  # None without a kept factorisation (always with reuse "never")
            if x is not None:
                return x  # converged to KRYLOV_RTOL: no singularity check needed
            sym = self.symmetric and is_symmetric(K)
            if sym not in self._pardiso:
                cls = PardisoSymmetric if sym else PardisoGeneral
                self._pardiso[sym] = cls(decisions=self._decisions)
            x = self._pardiso[sym].solve(K, r)
            self.counts.factorisations += 1
            self.info = self._pardiso[sym].info
            self._keep(self._pardiso[sym], K)
        else:
            try:
                lu = spla.splu(sp.csc_matrix(K), permc_spec="COLAMD")
            except RuntimeError as exc:  # "Factor is exactly singular"
                raise SingularSystemError(str(exc)) from exc
            x = lu.solve(r)
            self.counts.factorisations += 1
            self.info = FactorInfo("superlu", True)
        if not np.all(np.isfinite(x)):
            raise SingularSystemError("the solution of the linear system is not finite")
        # a singular tangent - an unsupported rigid-body motion - leaves a large residual; slender
        # multi-layer shells are ill-conditioned (relative residuals ~1e-5 are normal there).
        # PARDISO perturbs the pivots it finds (nearly) zero and reports them: without one the
        # factorisation met no singularity and the check (a product with K, 10 ms per solve of
        # the 200-element DCB) is skipped
        rn = np.linalg.norm(r)
        if self.info.perturbed_pivots == 0:
            return x
        if rn > 0 and np.linalg.norm(K @ x - r) > 1e-2 * rn:
            raise SingularSystemError("the linear system is (nearly) singular: the solution does not satisfy it")
        return x

    def release(self) -> None:
        for p in self._pardiso.values():
            p.release()
        self._kept, self._cost = None, 0.0


_DEFAULT: dict[str, LinearSolver] = {}


def solve(K: sp.spmatrix, r: np.ndarray, backend: str = "auto") -> np.ndarray:
    """Solve K x = r for the symmetric K (a shared solver per backend; for repeated solves of
    one problem prefer a :class:`LinearSolver` of its own)."""
    name = backend_name(backend)
    if name not in _DEFAULT:
        _DEFAULT[name] = LinearSolver(name)
    return _DEFAULT[name].solve(K, r)
