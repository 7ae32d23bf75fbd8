"""Element ranges per rank and the local assembly of the *reduced* system (no MPI needed here).

A rank owns a contiguous range of mesh elements (balanced by the kernel's cost per element). For
its range it builds the same layer blocks as :func:`layershell.assembly.build_blocks` and the same
scatter maps as :class:`layershell.assembly.Assembler`:

    element entries --(scatter, bincount)--> local full CSR data --(ReducedScatter.P)--> reduced data

P holds the products T[i, a] T[j, b] of the constraint operator (3.69)-(3.72) for the rows of T
of the rank's DOFs, so the rank's part of K_r = Tᵀ K T is one sparse mat-vec per Newton iteration,
and its pattern (the preallocation of the distributed matrix) is known before the first
evaluation. The sum of the ranks' parts is the serial reduced tangent (tested entry by entry).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from ..assembly import Block, ReducedScatter, _assembly_dofs, build_blocks
from ..constraints import ConstraintOperator
from ..dofs import DofMap
from ..element.kernel import layer_response
from ..model import Model


def element_weights(model: Model) -> np.ndarray:
    """Relative kernel cost per mesh element: Σ over its stack's layers of (element DOFs)² · points
    through the thickness (the tangent einsum dominates, MODEL.md (3.47))."""
    w_stack = np.zeros(len(model.stacks))
    for si, stack in enumerate(model.stacks):
        for k in stack:
            ly = model.layers[k]
            m = 27 * (ly.directors + 1)
            w_stack[si] += m * m * max(model.n_thickness, ly.directors) * len(ly.ply_table())  # points per ply
    return w_stack[model.element_stack]


def element_ranges(weights: np.ndarray, size: int) -> np.ndarray:
    """Boundaries ``b (size + 1,)``: rank r owns elements ``b[r]:b[r+1]`` (contiguous, balanced by
    the cumulative weight; every rank gets at least one element where there are enough)."""
    n = len(weights)
    if size < 1:
        raise ValueError("size must be at least 1")
    c = np.concatenate([[0.0], np.cumsum(weights, dtype=float)])
    targets = c[-1] * np.arange(1, size) / size
    cut = np.searchsorted(c, targets, side="left")
    b = np.concatenate([[0], cut, [n]]).astype(np.int64)
    if n >= size:  # strictly increasing: no empty rank
        for r in range(1, size):
            b[r] = min(max(b[r], b[r - 1] + 1), n - (size - r))
    return b


def interface_rows(block, lo: int, hi: int) -> np.ndarray:
    """The element rows of an interface block (cohesive) that the rank owning mesh elements
    ``lo:hi`` assembles: those on its elements (``block.itf.elements``), so each row goes to
    exactly one rank."""
    el = block.itf.elements
    return np.flatnonzero((el >= lo) & (el < hi))


def local_blocks(model: Model, dm: DofMap, elements: np.ndarray) -> list[Block]:
    """The layer blocks of :func:`layershell.assembly.build_blocks` restricted to ``elements``
    (only this rank's reference data is computed)."""
    return build_blocks(model, dm, elements)


@dataclass
class ReducedPattern:
    """This rank's contribution pattern to the reduced matrix: entry q sits at (rows[q], cols[q])
    (sorted row-major), with values ``G @ data`` from the local full-space CSR data."""

    rows: np.ndarray
    cols: np.ndarray
    G: sp.spmatrix  # (nnz_r, nnz_full_local)


class LocalAssembly:
    """Internal forces and tangent of the elements ``elements`` (this rank's range), returned as
    contributions to the *reduced* system: f_r part on ``red_dofs`` and K_r data on ``pattern``."""

    def __init__(self, model: Model, dm: DofMap, op: ConstraintOperator, elements: np.ndarray,
                 chunk: int = 256, extra: list | None = None):
        self.model, self.dm, self.op, self.chunk = model, dm, op, chunk
        self.elements = np.asarray(elements, np.int64)
        self.blocks = local_blocks(model, dm, self.elements)
        # element-like interface blocks (cohesive): ``(block, rows)`` - the block's
        # element rows this rank inserts (its fixed pattern is part of the preallocation)
        # (rows of the block's assembly form: its face points on the nodal rule, see
        # ``layershell.assembly._assembly_dofs``)
        self.extra = [(b, assembly_rows(b, np.asarray(rows, np.int64))) for b, rows in (extra or [])]
        dofs = ([b.dofs.ravel() for b in self.blocks]
                + [_assembly_dofs(b)[rows].ravel() for b, rows in self.extra])
        # local full DOFs (compact numbering) and the scatter map into the local full CSR pattern
        # (the construction of Assembler._pattern on this rank's elements only)
        self.full_dofs = np.unique(np.concatenate(dofs)) if dofs else np.zeros(0, np.int64)
        nl = self.full_dofs.size
        self._fidx = ([np.searchsorted(self.full_dofs, b.dofs) for b in self.blocks]
                      + [np.searchsorted(self.full_dofs, _assembly_dofs(b)[rows]) for b, rows in self.extra])
        keys = [(d[:, :, None] * nl + d[:, None, :]).ravel() for d in self._fidx]
        key = np.concatenate(keys) if keys else np.zeros(0, np.int64)
        ukey, scatter = np.unique(key, return_inverse=True)
        self.scatter = scatter.ravel()
        self.nnz_full = ukey.size
        indptr = np.zeros(nl + 1, np.int64)
        np.cumsum(np.bincount(ukey // max(nl, 1), minlength=nl), out=indptr[1:])
        # reduced pattern and map K_r.data = P @ K.data of the serial assembler, for the rows of
        # T that belong to this rank's DOFs (3.69)-(3.72)
        Tloc = op.T[self.full_dofs].tocsr()
        rs = ReducedScatter(Tloc, indptr, (ukey % max(nl, 1)).astype(np.int64))
        rows = np.repeat(np.arange(op.n_red, dtype=np.int64), np.diff(rs.indptr))
        self.pattern = ReducedPattern(rows, rs.indices.astype(np.int64), rs.P)
        self._fidx = np.concatenate([f.ravel() for f in self._fidx]) if self._fidx else np.zeros(0, np.int64)
        # force reduction: f_r contributions on the reduced DOFs this rank touches
        self.red_dofs = np.unique(Tloc.indices).astype(np.int64)
        self._Rt = Tloc[:, self.red_dofs].T.tocsr()  # (n_red_local, n_full_local)

    def evaluate(self, u_full: np.ndarray, tangent: bool = True):
        """``(f_r, K_r_data)``: this rank's Tᵀ f_int on ``red_dofs`` and its K_r entries on
        ``pattern`` (None when ``tangent`` is False). Same kernel as the serial assembler."""
        f_loc, data = self.evaluate_local(u_full, tangent)
        return self._Rt @ f_loc, data

    def evaluate_local(self, u_full: np.ndarray, tangent: bool = True):
        """``(f_loc, K_r_data)``: this rank's internal force on the full DOFs ``full_dofs`` and
        its K_r entries on ``pattern`` (None when ``tangent`` is False). The layer blocks by the
        serial kernel; an extra block by its ``response`` (as in ``Assembler._values``), of which
        this rank takes its rows."""
        nl = self.full_dofs.size
        fval, vals = [], []
        for b in self.blocks:
            U = u_full[b.dofs].reshape(b.dofs.shape[0], -1, 3)
            for s in range(0, b.dofs.shape[0], self.chunk):
                sl = slice(s, s + self.chunk)
                fe, Ke = layer_response(b.ref, U[sl], self.model.nonlinear, tangent, sl)
                fval.append(fe.ravel())
                if tangent:
                    vals.append(Ke.ravel())
        for b, rows in self.extra:
            fe, Ke = extra_response(b, u_full, tangent)
            fval.append(fe[rows].ravel())
            if tangent:
                vals.append(Ke[rows].ravel())
        f_loc = np.bincount(self._fidx, weights=np.concatenate(fval) if fval else None, minlength=nl)
        if not tangent:
            return f_loc, None
        data = np.bincount(self.scatter, weights=np.concatenate(vals) if vals else None,
                           minlength=self.nnz_full)
        return f_loc, self.pattern.G @ data

    def reduced_matrix(self, data: np.ndarray) -> sp.csr_matrix:
        """This rank's K_r part as a SciPy matrix (n_red × n_red) - for checks."""
        n = self.op.n_red
        return sp.csr_matrix((data, (self.pattern.rows, self.pattern.cols)), shape=(n, n))


def assembly_rows(block, rows: np.ndarray) -> np.ndarray:
    """The rows of ``block``'s assembly form for its element rows ``rows``: the same rows, or
    the face points of those elements where the block is assembled point by point."""
    dofs = _assembly_dofs(block)
    if dofs is block.dofs:
        return rows
    nq = dofs.shape[0] // block.dofs.shape[0]
    return (rows[:, None] * nq + np.arange(nq)).ravel()


def extra_response(block, u_full: np.ndarray, tangent: bool):
    """``(f, K or None)`` of an element-like block in its assembly form (element rows (e, m),
    (e, m, m), or face points on the nodal rule), with a compact tangent (``(values, rows)``,
    only the rows with stiffness) expanded as in ``Assembler._values``."""
    dofs = _assembly_dofs(block)
    if dofs is not block.dofs:
        fe, Ke = block.response(u_full, tangent, points=True)
    elif getattr(block, "compact_tangent", False):
        fe, Ke = block.response(u_full, tangent, compact=True)
    else:
        fe, Ke = block.response(u_full, tangent)
    if tangent and isinstance(Ke, tuple):
        vals, el = Ke
        full = np.zeros((dofs.shape[0], *vals.shape[1:]))
        full[el] = vals
        Ke = full
    return fe, Ke
