"""Sparse linear solves of the reduced tangent, with automatic backend choice.

``pardiso``: Intel MKL PARDISO through ``pypardiso`` (installed by default on x86-64), used in its
*real symmetric indefinite* mode (mtype = -2, upper triangle) where the tangent is symmetric - it
is not always positive definite (buckling, limit points) - and in its general mode (mtype = 11)
where it is not (checked on every call, O(nnz)). With the exact friction return mapping the
contact tangents are symmetric too; with the earlier smooth friction law the symmetric mode's
pivot perturbation (1e-8) once changed the Newton path on the penalty-stiffened tangents (126
instead of 24 iterations in a debonding step of the §5.1 plate), which no longer occurs. The
symbolic analysis (fill-reducing ordering) is kept and reused while the sparsity pattern does not
change - every Newton iteration of a bond state has the same pattern - and only the numerical
factorisation is redone.

``superlu``: SciPy's SuperLU (always available), the automatic fallback. COLAMD ordering: on the
multi-layer shell tangents it fills 2-6x less than MMD(AᵀA + A) (measured in
``benchmarks/solvers.py``).

Measured on this project's models (2-core machine, ``benchmarks/solvers.py``): PARDISO factorises
the 5 099-DOF pull-off tangent in 0.02 s against 0.6 s (SuperLU/COLAMD) and 3.5 s (SuperLU/MMD).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

BACKENDS = ("auto", "pardiso", "superlu")


class SingularSystemError(RuntimeError):
    """The reduced tangent is singular (a rigid-body mode is not supported, or a limit point)."""


def _have_pardiso() -> bool:
    try:
        import os

        import pypardiso  # loads MKL (searching the environment for it) or raises

        # point later solver instances straight at the library instead of searching again
        os.environ.setdefault("PYPARDISO_MKL_RT", pypardiso.ps.libmkl._name)
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
    negative_pivots: int | None = None  # inertia: negative eigenvalues of the tangent
    perturbed_pivots: int | None = None


def is_symmetric(K: sp.spmatrix, rtol: float = 1e-12) -> bool:
    """Whether K equals its transpose to ``rtol`` of its largest entry (friction tangents are not
    symmetric)."""
    fast = getattr(K, "symmetry_error", None)  # assembly.ReducedTangent: O(nnz) via its pattern maps
    err = fast() if fast is not None else None
    if err is not None:
        return K.nnz == 0 or err <= rtol * K.max_abs()
    K = sp.csr_matrix(K)
    d = abs(K - K.T)
    return d.nnz == 0 or d.max() <= rtol * abs(K).max()


class PardisoSymmetric:
    """MKL PARDISO for a symmetric (indefinite) matrix, reusing the symbolic analysis."""

    MTYPE = -2

    def __init__(self) -> None:
        import pypardiso

        backend_name("pardiso")
        self._s = pypardiso.PyPardisoSolver(mtype=self.MTYPE)
        self._indptr: np.ndarray | None = None
        self._indices: np.ndarray | None = None
        self.info = FactorInfo("pardiso")

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

    def _call(self, A: sp.csr_matrix, phase: int, b: np.ndarray) -> np.ndarray:
        self._s.set_phase(phase)
        return self._s._call_pardiso(A, b)

    def solve(self, K: sp.spmatrix, r: np.ndarray) -> np.ndarray:
        from pypardiso.pardiso_wrapper import PyPardisoError

        A = self.matrix(K)
        b = np.asfortranarray(r, dtype=float)
        same = (self._indptr is not None and np.array_equal(A.indptr, self._indptr)
                and np.array_equal(A.indices, self._indices))
        self._s._check_A(A)
        try:
            if not same:
                if self._indptr is not None:
                    self._s.free_memory(everything=True)
                self._call(A, 11, b)  # symbolic analysis (ordering)
                self._indptr, self._indices = A.indptr.copy(), A.indices.copy()
            self._call(A, 22, b)  # numerical factorisation
            x = self._call(A, 33, b)  # solve with iterative refinement
        except PyPardisoError as exc:
            self._indptr = None
            raise SingularSystemError(f"PARDISO failed ({exc})") from exc
        ip = self._s.iparm
        self.info = FactorInfo("pardiso", not same, int(ip[22]), int(ip[13]))
        return x

    def release(self) -> None:
        if self._indptr is not None:
            self._s.free_memory(everything=True)
            self._indptr = None


class PardisoGeneral(PardisoSymmetric):
    """MKL PARDISO for a general real matrix (mtype = 11): the tangent with friction is not
    symmetric (the regularised slip law couples normal pressure and tangential traction)."""

    MTYPE = 11

    def matrix(self, K: sp.spmatrix) -> sp.csr_matrix:
        A = sp.csr_matrix(K, copy=True)
        A.sort_indices()
        return A


class LinearSolver:
    """Solves K x = r for the symmetric reduced tangent K with the chosen backend; one instance
    per problem keeps PARDISO's symbolic analysis between calls."""

    def __init__(self, backend: str = "auto", symmetric: bool = True) -> None:
        self.backend = backend_name(backend)
        self.symmetric = symmetric  # use PARDISO's symmetric mode when K is symmetric
        self._pardiso: dict[bool, PardisoSymmetric] = {}
        self.info = FactorInfo(self.backend)

    def solve(self, K: sp.spmatrix, r: np.ndarray) -> np.ndarray:
        if K.shape[0] == 0:
            return np.zeros(0)
        if self.backend == "pardiso":
            sym = self.symmetric and is_symmetric(K)
            if sym not in self._pardiso:
                self._pardiso[sym] = PardisoSymmetric() if sym else PardisoGeneral()
            x = self._pardiso[sym].solve(K, r)
            self.info = self._pardiso[sym].info
        else:
            try:
                lu = spla.splu(sp.csc_matrix(K), permc_spec="COLAMD")
            except RuntimeError as exc:  # "Factor is exactly singular"
                raise SingularSystemError(str(exc)) from exc
            x = lu.solve(r)
            self.info = FactorInfo("superlu", True)
        if not np.all(np.isfinite(x)):
            raise SingularSystemError("the solution of the linear system is not finite")
        # a singular tangent - an unsupported rigid-body motion - leaves a large residual; slender
        # multi-layer shells are ill-conditioned (relative residuals ~1e-5 are normal there)
        rn = np.linalg.norm(r)
        if rn > 0 and np.linalg.norm(K @ x - r) > 1e-2 * rn:
            raise SingularSystemError("the linear system is (nearly) singular: the solution does not satisfy it")
        return x

    def release(self) -> None:
        for p in self._pardiso.values():
            p.release()


_DEFAULT: dict[str, LinearSolver] = {}


def solve(K: sp.spmatrix, r: np.ndarray, backend: str = "auto") -> np.ndarray:
    """Solve K x = r for the symmetric K (a shared solver per backend; for repeated solves of
    one problem prefer a :class:`LinearSolver` of its own)."""
    name = backend_name(backend)
    if name not in _DEFAULT:
        _DEFAULT[name] = LinearSolver(name)
    return _DEFAULT[name].solve(K, r)
