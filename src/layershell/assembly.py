"""Global assembly in the full DOF space with a precomputed scatter map.

The sparsity pattern is built once; each Newton iteration only sums element values into the
CSR data array (``np.bincount`` over a cached index). Reduction to independent DOFs,
K_r = Tᵀ K T, follows (3.69)-(3.72).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .dofs import DofMap
from .element.kernel import LayerBlock, layer_block, layer_response
from .model import Model


@dataclass(frozen=True)
class Block:
    """One layer over the elements of one stack."""

    layer: int
    elements: np.ndarray
    dofs: np.ndarray  # (e, m) full DOFs in kernel order
    ref: LayerBlock


def build_blocks(model: Model, dm: DofMap) -> list[Block]:
    mesh = model.mesh
    blocks = []
    for si, stack in enumerate(model.stacks):
        el = np.flatnonzero(model.element_stack == si)
        if el.size == 0:
            continue
        conn = mesh.elements[el]
        X = mesh.nodes[conn]
        for k in stack:
            ly = model.layers[k]
            ref = layer_block(X, model.offset(k)[conn], ly.thickness[conn], ly.directors, ly.material,
                              ly.angle, ly.direction, max(model.n_thickness, ly.directors))
            blocks.append(Block(k, el, dm.element_dofs(model, k, el), ref))
    return blocks


class Assembler:
    """Internal forces and tangent of the whole model in the full DOF space."""

    def __init__(self, model: Model, dm: DofMap, chunk: int = 256):
        self.model, self.dm, self.chunk = model, dm, chunk
        self.blocks = build_blocks(model, dm)
        self.extra: list = []
        self._pattern()

    def add_blocks(self, extra: list) -> None:
        """Add element-like blocks with ``.dofs (e, m)`` and ``.response(u) -> (f, K)`` (contact)
        to the sparsity pattern and to every evaluation."""
        self.extra = list(extra)
        self._pattern()

    def _pattern(self) -> None:
        n = self.dm.n_full
        rows, cols = [], []
        for b in [*self.blocks, *self.extra]:
            m = b.dofs.shape[1]
            rows.append(np.repeat(b.dofs, m, axis=1).ravel())
            cols.append(np.tile(b.dofs, (1, m)).ravel())
        r = np.concatenate(rows).astype(np.int64)
        c = np.concatenate(cols).astype(np.int64)
        key = r * n + c
        ukey, self.scatter = np.unique(key, return_inverse=True)
        ur, uc = ukey // n, ukey % n
        indptr = np.zeros(n + 1, np.int64)
        np.add.at(indptr, ur + 1, 1)
        self.indptr = np.cumsum(indptr)
        self.indices = uc
        self.nnz = ukey.size

    def evaluate(self, u_full: np.ndarray, tangent: bool = True):
        """Return ``(f_int, K)`` (K None when ``tangent`` is False)."""
        n = self.dm.n_full
        fidx, fval = [], []
        vals = [] if tangent else None
        for b in self.blocks:
            U = u_full[b.dofs].reshape(b.dofs.shape[0], -1, 3)
            for s in range(0, b.dofs.shape[0], self.chunk):
                sl = slice(s, s + self.chunk)
                fe, Ke = layer_response(b.ref, U[sl], self.model.nonlinear, tangent, sl)
                fidx.append(b.dofs[sl].ravel())
                fval.append(fe.ravel())
                if tangent:
                    vals.append(Ke.ravel())
        for b in self.extra:
            fe, Ke = b.response(u_full)
            fidx.append(b.dofs.ravel())
            fval.append(fe.ravel())
            if tangent:
                vals.append(Ke.ravel())
        f = np.bincount(np.concatenate(fidx), weights=np.concatenate(fval), minlength=n)
        if not tangent:
            return f, None
        data = np.bincount(self.scatter, weights=np.concatenate(vals), minlength=self.nnz)
        K = sp.csr_matrix((data, self.indices, self.indptr), shape=(self.dm.n_full,) * 2)
        return f, K
