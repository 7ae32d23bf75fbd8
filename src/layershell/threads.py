"""Thread settings of a run.

NumPy's vector operations (norms and dot products of the residual, O(n) updates) call OpenBLAS,
which splits them over its threads above a few thousand entries. For vectors of 10⁴-10⁵ entries
that gains nothing and costs the threads' wake-up: measured here on a 29 000-entry vector,
``np.linalg.norm`` took 15 µs on one thread and 1.9 ms with OpenBLAS's default threads on a busy
2-core machine, and the cohesive DCB spends a quarter of its CPU time there. A run therefore
holds OpenBLAS to one thread. The parallel parts keep their own threads: the element kernel (its
pool, ``LAYERSHELL_THREADS``) and MKL PARDISO (MKL's threads, not OpenBLAS's).
"""
from __future__ import annotations

import contextlib
import threading

_LOCK = threading.Lock()
_CONTROLLER = None


def controller():
    """The process's threadpoolctl controller (created once: it inspects the loaded libraries)."""
    global _CONTROLLER
    with _LOCK:
        if _CONTROLLER is None:
            # SciPy's OpenBLAS (Numba's np.dot in the compiled kernels) loaded first: the limits reach it
            import scipy.linalg.cython_blas  # noqa: F401
            from threadpoolctl import ThreadpoolController

            _CONTROLLER = ThreadpoolController()
    return _CONTROLLER


def blas_single_thread():
    """Context limiting every BLAS (OpenBLAS and MKL) to one thread, restoring the setting on
    exit: the element kernel's per-element products are small, BLAS threads inside them only
    add synchronisation (and on an oversubscribed machine cost an order of magnitude)."""
    return controller().limit(limits=1, user_api="blas")


def openblas_single_thread():
    """Context holding OpenBLAS (NumPy's and SciPy's BLAS) to one thread; restores the previous
    setting on exit. A no-op context where threadpoolctl or OpenBLAS is missing."""
    try:
        selected = controller().select(internal_api="openblas")
    except Exception:  # pragma: no cover - threadpoolctl unusable here
        return contextlib.nullcontext()
    if not selected.lib_controllers:
        return contextlib.nullcontext()
    return selected.limit(limits=1)
