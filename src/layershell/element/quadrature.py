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


def ply_rule(n: int, fractions) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Thickness rule of a ply stack on ζ ∈ [-1, 1]: the n-point Gauss rule in each ply, mapped
    into the ply's interval (the plies' thickness ``fractions``, bottom to top, sum 1) with the
    weights scaled by the fraction. Returns points ``(n·plies,)``, weights (sum 2) and the ply
    of each point. One ply gives :func:`gauss_1d` itself."""
    x, w = gauss_1d(n)
    f = np.asarray(fractions, float)
    edges = np.concatenate([[0.0], np.cumsum(f) / f.sum()]) * 2.0 - 1.0
    edges[-1] = 1.0
    lo, hi = edges[:-1, None], edges[1:, None]
    zeta = (lo + 0.5 * (hi - lo) * (x + 1.0)).ravel()
    wz = (0.5 * (hi - lo) * w).ravel()
    return zeta, wz, np.repeat(np.arange(f.size), n)


def ply_of(fractions, s: np.ndarray) -> np.ndarray:
    """The ply (index) at layer fractions ``s`` = Θ_L³ / H_L ∈ [0, 1]; on a ply boundary the
    lower ply."""
    f = np.asarray(fractions, float)
    inner = np.cumsum(f)[:-1] / f.sum()
    return np.searchsorted(inner, np.asarray(s, float), side="left")


def ply_samples(fractions, n: int) -> np.ndarray:
    """Layer fractions Θ_L³ / H_L of ``n`` evenly spaced samples in each ply, ``(plies, n)``, from
    the ply's bottom to its top; ends on an inner ply boundary moved 1e-9 of the ply into it, so
    that each sample takes its own ply's material (:func:`ply_of`). One ply: linspace(0, 1, n)."""
    f = np.asarray(fractions, float)
    f = f / f.sum()
    lo = np.concatenate([[0.0], np.cumsum(f)[:-1]])
    m = np.tile(np.linspace(0.0, 1.0, n), (f.size, 1))
    m[1:, 0] = 1e-9
    m[:-1, -1] = 1.0 - 1e-9
    return lo[:, None] + f[:, None] * m
