"""9-node biquadratic Lagrange quadrilateral, MODEL.md §5 / thesis (2.208)-(2.211).

Node order (the VTK / meshio ``quad9`` order, used everywhere in layershell)::

    3 --- 6 --- 2          (xi, eta):  0 (-1,-1)  1 (1,-1)  2 (1,1)  3 (-1,1)
    |           |                      4 (0,-1)   5 (1,0)   6 (0,1)  7 (-1,0)
    7     8     5                      8 (0,0)
    |           |
    0 --- 4 --- 1

The thesis numbers the same nodes 1 (1,1), 2 (-1,1), 3 (-1,-1), 4 (1,-1), 5 (0,1), 6 (-1,0),
7 (0,-1), 8 (1,0), 9 (0,0); :data:`THESIS_TO_VTK` maps thesis node k (1-based) to ours.
"""
from __future__ import annotations

import numpy as np

NODE_XI = np.array(
    [[-1, -1], [1, -1], [1, 1], [-1, 1], [0, -1], [1, 0], [0, 1], [-1, 0], [0, 0]], dtype=float
)
#: thesis node number (1..9) -> index in the VTK order
THESIS_TO_VTK = {1: 2, 2: 3, 3: 0, 4: 1, 5: 6, 6: 7, 7: 4, 8: 5, 9: 8}

#: local edges as node triples (start, mid, end), counter-clockwise
EDGES = np.array([[0, 4, 1], [1, 5, 2], [2, 6, 3], [3, 7, 0]])


def _lagrange1d(x: np.ndarray):
    """1D quadratic Lagrange functions at nodes -1, 0, 1 and their 1st/2nd derivatives."""
    x = np.asarray(x, dtype=float)
    n = np.stack([0.5 * x * (x - 1.0), 1.0 - x * x, 0.5 * x * (x + 1.0)], axis=-1)
    dn = np.stack([x - 0.5, -2.0 * x, x + 0.5], axis=-1)
    ddn = np.broadcast_to(np.array([1.0, -2.0, 1.0]), dn.shape).copy()
    return n, dn, ddn


# index of each node's 1D function (0: -1, 1: 0, 2: +1) in xi and eta
_IX = (NODE_XI[:, 0] + 1).astype(int)
_IY = (NODE_XI[:, 1] + 1).astype(int)


def quad9(xi: np.ndarray, eta: np.ndarray):
    """Shape functions of the 9-node element at points (xi, eta).

    Returns ``N (..., 9)``, ``dN (..., 9, 2)`` (d/dxi, d/deta) and ``ddN (..., 9, 2, 2)``.
    """
    nx, dnx, ddnx = _lagrange1d(xi)
    ny, dny, ddny = _lagrange1d(eta)
    n = nx[..., _IX] * ny[..., _IY]
    dn = np.stack([dnx[..., _IX] * ny[..., _IY], nx[..., _IX] * dny[..., _IY]], axis=-1)
    d11 = ddnx[..., _IX] * ny[..., _IY]
    d12 = dnx[..., _IX] * dny[..., _IY]
    d22 = nx[..., _IX] * ddny[..., _IY]
    ddn = np.stack([np.stack([d11, d12], -1), np.stack([d12, d22], -1)], -2)
    return n, dn, ddn


def line3(s: np.ndarray):
    """Quadratic 1D functions along an element edge (nodes start, mid, end at s = -1, 0, 1)."""
    n, dn, _ = _lagrange1d(s)
    return n[..., [0, 1, 2]], dn[..., [0, 1, 2]]
