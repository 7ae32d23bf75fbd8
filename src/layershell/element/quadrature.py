"""Gauss-Legendre rules, MODEL.md §5 (2.273)-(2.277)."""
from __future__ import annotations

from functools import lru_cache

import numpy as np


@lru_cache(maxsize=None)
def gauss_1d(n: int) -> tuple[np.ndarray, np.ndarray]:
    """n-point Gauss-Legendre points and weights on [-1, 1]."""
    x, w = np.polynomial.legendre.leggauss(n)
    x.setflags(write=False)
    w.setflags(write=False)
    return x, w


@lru_cache(maxsize=None)
def gauss_2d(n: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """Tensor-product rule on the square: points ``(n*n, 2)`` ordered eta-major, weights ``(n*n,)``.

    Point ``k = j * n + i`` has ``xi = x[i]``, ``eta = x[j]``.
    """
    x, w = gauss_1d(n)
    xi, eta = np.meshgrid(x, x, indexing="xy")
    pts = np.stack([xi.ravel(), eta.ravel()], axis=-1)
    wts = np.outer(w, w).ravel()
    pts.setflags(write=False)
    wts.setflags(write=False)
    return pts, wts
