"""Sparse linear solves of the reduced tangent, with automatic backend choice.

PARDISO (``pypardiso``, optional extra ``fast``) when importable, SciPy's SuperLU otherwise.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla


class SingularSystemError(RuntimeError):
    """The reduced tangent is singular (a rigid-body mode is not supported, or a limit point)."""


def _have_pardiso() -> bool:
    try:
        import pypardiso  # noqa: F401
    except Exception:
        return False
    return True


def backend_name(preferred: str = "auto") -> str:
    if preferred == "auto":
        return "pardiso" if _have_pardiso() else "superlu"
    return preferred


def solve(K: sp.spmatrix, r: np.ndarray, backend: str = "auto") -> np.ndarray:
    """Solve K x = r for the symmetric reduced tangent K."""
    name = backend_name(backend)
    if K.shape[0] == 0:
        return np.zeros(0)
    if name == "pardiso":
        import pypardiso

        x = pypardiso.spsolve(sp.csr_matrix(K), r)
    else:
        try:
            lu = spla.splu(sp.csc_matrix(K), permc_spec="MMD_AT_PLUS_A")
        except RuntimeError as exc:  # "Factor is exactly singular"
            raise SingularSystemError(str(exc)) from exc
        x = lu.solve(r)
    if not np.all(np.isfinite(x)):
        raise SingularSystemError("the solution of the linear system is not finite")
    # a singular tangent - an unsupported rigid-body motion - leaves a large residual; slender
    # multi-layer shells are ill-conditioned (relative residuals ~1e-5 are normal there)
    rn = np.linalg.norm(r)
    if rn > 0 and np.linalg.norm(K @ x - r) > 1e-2 * rn:
        raise SingularSystemError("the linear system is (nearly) singular: the solution does not satisfy it")
    return x
