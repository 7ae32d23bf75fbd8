"""Global assembly with precomputed scatter maps, in the full and in the reduced DOF space.

The full-space sparsity pattern is built once; each Newton iteration only sums element values
into the CSR data array (``np.bincount`` over a cached index). The reduced tangent
K_r = Tᵀ K T (3.69)-(3.72) is formed without sparse matrix products: once per constraint
operator (bond state) a :class:`ReducedScatter` fixes the pattern of K_r and a sparse map P with
``K_r.data = P @ K.data``, so every iteration costs one ``bincount`` and one sparse
matrix-vector product, and K_r keeps the same pattern (PARDISO reuses its symbolic analysis).
"""
from __future__ import annotations

import weakref
from dataclasses import dataclass, field

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


def build_blocks(model: Model, dm: DofMap, elements: np.ndarray | None = None) -> list[Block]:
    """One block (kernel reference data) per stack and layer, over all elements or only over
    ``elements`` (an MPI rank's range)."""
    mesh = model.mesh
    elements = np.arange(mesh.n_elements) if elements is None else np.asarray(elements, np.int64)
    blocks = []
    for si, stack in enumerate(model.stacks):
        el = elements[model.element_stack[elements] == si]
        if el.size == 0:
            continue
        conn = mesh.elements[el]
        X = mesh.nodes[conn]
        for k in stack:
            ly = model.layers[k]
            if ly.inelastic:
                from .element.inelastic import inelastic_block

                sheets = tuple((r.name, r.law, r.height, r.area, r.angle, r.direction)
                               for r in ly.reinforcement)
                ref = inelastic_block(X, model.offset(k)[conn], ly.thickness[conn], ly.directors, ly.material,
                                      ly.law, sheets, max(model.n_thickness, ly.directors),
                                      getattr(model, "element", "mitc"), ly.angle, ly.direction)
                blocks.append(Block(k, el, dm.element_dofs(model, k, el), ref))
                continue
            ref = layer_block(X, model.offset(k)[conn], ly.thickness[conn], ly.directors, ly.material,
                              ly.angle, ly.direction, max(model.n_thickness, ly.directors),
                              element=getattr(model, "element", "mitc"), plies=ly.ply_table() if ly.plies else None)
            blocks.append(Block(k, el, dm.element_dofs(model, k, el), ref))
    return blocks


def _jit():
    """The compiled assembly loops, or None where Numba is missing (NumPy fallbacks)."""
    try:
        from . import _assembly_jit
    except ImportError:  # pragma: no cover - Numba missing
        return None
    return _assembly_jit


def _assembly_dofs(b) -> np.ndarray:
    """The DOFs an extra block is assembled over: its point form's rows where it has one (a
    contact or cohesive block on the nodal rule, ``ContactBlock._point_form``), else its
    element rows ``dofs``."""
    a = getattr(b, "assembly_dofs", None)
    return b.dofs if a is None else a


def _index_dtype(n: int):
    """int32 where it can hold ``n`` (halves the memory of index arrays), int64 otherwise."""
    return np.int32 if n < np.iinfo(np.int32).max else np.int64


class ReducedScatter:
    """Pattern of K_r = Tᵀ K T and the map ``P (nnz_r × nnz)`` with ``K_r.data = P @ K.data``.

    Entry p = (i, j) of K contributes ``T[i, a] T[j, b] K_p`` to entry (a, b) of K_r
    (3.69)-(3.72). P is built column-wise (CSC: one column per entry of K, the order in which
    the contributions are generated, so without sorting) and stored row-wise (CSR) for the
    product.
    The pattern is structural (no value-dependent cancellation), hence fixed for a bond state.
    Compiled loops (``_assembly_jit``) when Numba is available, vectorised NumPy otherwise
    (``jit=False`` forces the NumPy path).
    """

    def __init__(self, T: sp.csr_matrix, indptr: np.ndarray, indices: np.ndarray, chunk: int = 1 << 22,
                 jit: bool | None = None):
        T = sp.csr_matrix(T)
        T.sum_duplicates()
        T.sort_indices()
        n_full, n_red = T.shape
        self.shape = (n_red, n_red)
        nnz = int(indptr[-1])
        nT = np.diff(T.indptr).astype(np.int64)
        rows = np.repeat(np.arange(n_full, dtype=_index_dtype(n_full)), np.diff(indptr))
        cnt = nT[rows] * nT[indices]
        col_ptr = np.zeros(nnz + 1, np.int64)
        np.cumsum(cnt, out=col_ptr[1:])
        del cnt
        total = int(col_ptr[-1])
        jit_mod = None if jit is False else _jit()
        if jit and jit_mod is None:  # pragma: no cover - Numba missing
            raise ImportError("jit=True needs Numba (layershell._assembly_jit)")
        if jit_mod is not None:
            Tt = T.T.tocsr()
            Tt.sort_indices()
            bp, bi = jit_mod.reduced_pattern(n_red, Tt.indptr, Tt.indices, indptr, indices, T.indptr, T.indices)
            del Tt
            self.nnz = int(bp[-1])
            it = _index_dtype(max(self.nnz, n_red))
            self.indptr, self.indices = bp.astype(it), bi.astype(it)
            q_all = np.empty(total, _index_dtype(max(self.nnz, nnz)))
            w_all = np.empty(total)
            jit_mod.reduced_map(n_red, indptr, indices, T.indptr, T.indices, T.data, self.indptr, self.indices,
                                col_ptr, q_all, w_all)
        else:
            q_all, w_all = self._map_numpy(T, indptr, indices, rows, nT, col_ptr, chunk)
            it = _index_dtype(max(self.nnz, n_red))
        del rows
        # built by columns (entries of K), applied by rows: CSR halves the time of P @ K.data
        self.P = sp.csc_matrix((w_all, q_all, col_ptr.astype(_index_dtype(total))), shape=(self.nnz, nnz)).tocsr()
        del w_all, q_all, col_ptr
        # --- upper triangle (PARDISO's symmetric mode); the mirror of each upper entry on first use
        red_rows = np.repeat(np.arange(n_red, dtype=it), np.diff(self.indptr))
        up = self.indices >= red_rows
        self.upper_pos = np.flatnonzero(up).astype(it)
        self.upper_indices = self.indices[up]
        self.upper_indptr = np.zeros(n_red + 1, it)
        np.cumsum(np.bincount(red_rows[up], minlength=n_red), out=self.upper_indptr[1:])
        up_rows = red_rows[up]
        del red_rows, up
        if int(np.count_nonzero(self.upper_indices == up_rows)) != n_red:
            self.upper_indices = None  # a diagonal entry is missing: PARDISO needs them, general path
        self._mirror: np.ndarray | None | bool = False  # computed on first use (symmetry checks only)

    @property
    def mirror_pos(self) -> np.ndarray | None:
        """For each upper entry (a, b) the position of (b, a) (None where the pattern lacks one);
        built on first use: only the symmetry check needs it, and assembled tangents of
        symmetric contributions skip that check."""
        if self._mirror is False:
            n_red = self.shape[0]
            it = self.indices.dtype
            rows = np.repeat(np.arange(n_red, dtype=it), np.diff(self.indptr))
            up_rows = rows[self.upper_pos]
            del rows
            jit_mod = _jit()
            if self.nnz == 0:
                mirror = np.zeros(0, np.int64)
            elif jit_mod is not None:
                mirror = jit_mod.mirror_positions(self.indptr, self.indices, self.upper_pos, up_rows)
            else:
                keys = np.repeat(np.arange(n_red, dtype=np.int64), np.diff(self.indptr)) * n_red + self.indices
                tk = self.indices[self.upper_pos].astype(np.int64) * n_red + up_rows
                mirror = np.minimum(np.searchsorted(keys, tk), max(self.nnz - 1, 0))
                mirror[keys[mirror] != tk] = -1
                del keys, tk
            self._mirror = mirror.astype(it) if self.nnz == 0 or mirror.min() >= 0 else None
        return self._mirror

    def _map_numpy(self, T, indptr, indices, rows, nT, col_ptr, chunk):
        """Vectorised pattern and map (fallback without Numba): the pattern as the symbolic product
        |T|ᵀ S |T| (positive entries: nothing cancels), positions by binary search."""
        n_full, n_red = T.shape
        nnz = int(indptr[-1])
        S = sp.csr_matrix((np.ones(nnz), indices, indptr), shape=(n_full, n_full))
        Ta = abs(T)
        B = (Ta.T.tocsr() @ S @ Ta).tocsr()
        del S, Ta
        B.sort_indices()
        self.nnz = B.nnz
        it = _index_dtype(max(self.nnz, n_red))
        self.indptr = B.indptr.astype(it)
        self.indices = B.indices.astype(it)
        keys = np.repeat(np.arange(n_red, dtype=np.int64), np.diff(B.indptr)) * n_red + B.indices
        del B
        tp, ti, tv = T.indptr.astype(np.int64), T.indices.astype(np.int64), T.data
        total = int(col_ptr[-1])
        q_all = np.empty(total, _index_dtype(max(self.nnz, nnz)))
        w_all = np.empty(total)
        cnt = np.diff(col_ptr)
        # chunks of K entries with about `chunk` contributions each (bounded temporaries)
        bounds = np.searchsorted(col_ptr, np.arange(0, total + chunk, chunk), side="left")
        bounds = np.unique(np.concatenate([[0], np.clip(bounds, 0, nnz), [nnz]]))
        for p0, p1 in zip(bounds[:-1], bounds[1:]):
            i, j, c = rows[p0:p1].astype(np.int64), indices[p0:p1].astype(np.int64), cnt[p0:p1]
            s0, s1 = col_ptr[p0], col_ptr[p1]
            k = np.arange(s1 - s0) - np.repeat(col_ptr[p0:p1] - s0, c)  # index within (i, j)'s block
            nj = np.repeat(nT[j], c)
            ta = np.repeat(tp[i], c) + k // nj
            tb = np.repeat(tp[j], c) + k % nj
            q_all[s0:s1] = np.searchsorted(keys, ti[ta] * n_red + ti[tb])
            w_all[s0:s1] = tv[ta] * tv[tb]
        return q_all, w_all

    def matrix(self, data_full: np.ndarray, symmetric: bool = False) -> "ReducedTangent":
        """K_r for the values ``data_full`` of the full-space pattern; ``symmetric``: every
        contribution is symmetric by construction (no check needed by the solver)."""
        return self.matrix_from_values(self.P @ data_full, symmetric)

    def diagonal_positions(self) -> np.ndarray | None:
        """The positions of the diagonal entries in the data of this pattern: the first entry of
        each row of the upper-triangle map (sorted indices); None where a row stores no diagonal
        entry (``upper_indices`` None)."""
        if self.upper_indices is None:
            return None
        return self.upper_pos[self.upper_indptr[:-1]]

    def matrix_from_values(self, data_reduced: np.ndarray, symmetric: bool = False) -> "ReducedTangent":
        """K_r with the values ``data_reduced`` of this pattern."""
        K = ReducedTangent((data_reduced, self.indices, self.indptr), shape=self.shape)
        K.indices, K.indptr = self.indices, self.indptr  # share (SciPy may copy them): no copy per iteration
        K.has_sorted_indices = True
        K.scatter = self
        K.known_symmetric = symmetric
        return K

    def memory_bytes(self) -> int:
        arrays = [self.P.data, self.P.indices, self.P.indptr, self.indices, self.indptr, self.upper_pos,
                  self._mirror if isinstance(self._mirror, np.ndarray) else None, self.upper_indices,
                  self.upper_indptr]
        return sum(a.nbytes for a in arrays if a is not None)


class ReducedTangent(sp.csr_matrix):
    """K_r in CSR that knows the index maps of its pattern (:class:`ReducedScatter`), so that the
    symmetry check and the upper triangle for PARDISO (solver/linear.py) are O(nnz) gathers
    instead of sparse transposes and sorts. Matrices derived from it by SciPy operations lose
    the maps and take the general path."""

    scatter: ReducedScatter | None = None
    #: assembled from symmetric contributions only (element tangents, contact blocks declaring
    #: ``symmetric``): the solver skips its O(nnz) symmetry check. Cleared when ``data`` is
    #: changed by hand.
    known_symmetric: bool = False
    #: the check of a K_r that differs from a fixed base only where the extra blocks write
    #: (:class:`_PartialSymmetry`); None: the full pass. Cleared with ``data`` changed by hand.
    partial_symmetry: "_PartialSymmetry | None" = None

    def _maps(self) -> ReducedScatter | None:
        rs = self.scatter
        if rs is not None and self.indices is rs.indices and self.indptr is rs.indptr:
            return rs
        return None

    def symmetry_error(self) -> float | None:
        """max |K_ab - K_ba| (None where the maps do not apply)."""
        rs = self._maps()
        if rs is None or rs.mirror_pos is None:
            return None
        if self.nnz == 0:
            return 0.0
        jit_mod = _jit()
        if jit_mod is not None:
            return float(jit_mod.max_mirror_difference(self.data, rs.upper_pos, rs.mirror_pos))
        return float(np.max(np.abs(self.data[rs.upper_pos] - self.data[rs.mirror_pos])))

    def symmetry_check(self) -> tuple[float, float] | None:
        """(max |K_ab - K_ba|, max |K_ab|) in one pass over the entries (None where the maps do
        not apply): the solver's symmetry test reads every entry once instead of twice."""
        rs = self._maps()
        if rs is None or rs.mirror_pos is None:
            return None
        if self.nnz == 0:
            return 0.0, 0.0
        if self.partial_symmetry is not None:  # a linear model: only the pairs the extra blocks change
            return self.partial_symmetry.check(self.data)
        jit_mod = _jit()
        if jit_mod is None:
            return self.symmetry_error(), self.max_abs()
        err, top = jit_mod.mirror_difference_and_max(self.data, rs.upper_pos, rs.mirror_pos)
        return float(err), float(top)

    def max_abs(self) -> float:
        """Largest |entry| (compiled, no temporary)."""
        if self.nnz == 0:
            return 0.0
        jit_mod = _jit()
        return float(jit_mod.max_abs(self.data) if jit_mod is not None else np.abs(self.data).max())

    def upper_triangle(self) -> sp.csr_matrix | None:
        """The upper triangle with every diagonal entry stored, sorted CSR (None where the maps
        do not apply)."""
        rs = self._maps()
        if rs is None or rs.upper_indices is None:
            return None
        jit_mod = _jit()
        vals = jit_mod.gather(self.data, rs.upper_pos) if jit_mod is not None else self.data[rs.upper_pos]
        A = sp.csr_matrix((vals, rs.upper_indices, rs.upper_indptr), shape=self.shape)
        A.has_sorted_indices = True
        return A


@dataclass
class _PartialSymmetry:
    """The symmetry check of a K_r whose entries differ from a fixed base only at ``rows`` (a
    linear model: the layers' constant tangent plus the extra blocks, :meth:`Assembler.
    evaluate_reduced`): the pairs (entry, mirror) of which neither is such an entry keep the
    base's values, so their largest mirror difference and entry are taken once; an evaluation
    reads only the pairs that touch ``rows`` (the DCB on 200 elements: 0.6 M of 4.2 M
    entries). The result equals the full pass's (tests/test_cohesive_interface.py)."""

    upper: np.ndarray  # the pairs that touch a changing entry: upper positions ...
    mirror: np.ndarray  # ... and their mirrors
    fixed_error: float  # max |K_ab - K_ba| over the other pairs (base values)
    fixed_top: float  # max |K_ab| over the other pairs' entries

    @classmethod
    def of(cls, rs: "ReducedScatter", base: np.ndarray, rows: np.ndarray) -> "_PartialSymmetry | None":
        if rs.mirror_pos is None or base.size == 0:
            return None
        moving = np.zeros(base.size, bool)
        moving[rows] = True
        touch = moving[rs.upper_pos] | moving[rs.mirror_pos]
        up, mi = rs.upper_pos[~touch], rs.mirror_pos[~touch]
        err = float(np.max(np.abs(base[up] - base[mi]), initial=0.0))
        top = float(max(np.max(np.abs(base[up]), initial=0.0), np.max(np.abs(base[mi]), initial=0.0)))
        return cls(np.ascontiguousarray(rs.upper_pos[touch]), np.ascontiguousarray(rs.mirror_pos[touch]), err, top)

    def check(self, data: np.ndarray) -> tuple[float, float]:
        jit_mod = _jit()
        if jit_mod is not None:
            err, top = jit_mod.mirror_difference_and_max(data, self.upper, self.mirror)
        else:
            x, y = data[self.upper], data[self.mirror]
            err = float(np.max(np.abs(x - y), initial=0.0))
            top = float(max(np.max(np.abs(x), initial=0.0), np.max(np.abs(y), initial=0.0)))
        return max(float(err), self.fixed_error), max(float(top), self.fixed_top)


@dataclass
class _LinearBulk:
    """The layer elements' constant tangent of a linear model (``Assembler._linear_bulk``)."""

    data: np.ndarray  # summed CSR data of K_bulk over the full pattern
    n_entries: int  # element entries of the layer blocks (the extra blocks' scatter starts here)
    touched: np.ndarray  # sorted positions of the full pattern the extra blocks write to
    compact: np.ndarray  # the extra blocks' scatter into ``touched``
    #: (ReducedScatter, P @ data, the K_r entries the extra blocks reach, P[those, touched]) of
    #: the last operator
    reduced: tuple | None = None
    #: K_r data arrays and the matrices they were lent to (weak references): an array whose
    #: matrix is gone is filled again instead of allocating the next one (a fresh 4 M-entry
    #: array per iteration cost its page faults: the DCB's copy took 18 ms instead of 5)
    _pool: list = field(default_factory=list)

    def buffer(self, n: int) -> tuple[np.ndarray, object]:
        """An array of ``n`` values no live matrix uses (one of two while Newton holds the last)
        and what it was filled from when it was lent (:meth:`lend`; None for a new one)."""
        for i, (arr, owner, base) in enumerate(self._pool):
            if arr.size == n and owner() is None:
                del self._pool[i]
                return arr, base
        return np.empty(n), None

    def lend(self, arr: np.ndarray, matrix, base: object = None) -> None:
        """``arr`` is now ``matrix``'s data, filled from ``base`` outside the entries the extra
        blocks write (so that the next fill need only restore those)."""
        self._pool = [p for p in self._pool if p[0] is not arr][-1:] + [(arr, weakref.ref(matrix), base)]


class Assembler:
    """Internal forces and tangent of the whole model, in the full or the reduced DOF space."""

    def __init__(self, model: Model, dm: DofMap, chunk: int = 256):
        self.model, self.dm, self.chunk = model, dm, chunk
        self.blocks = build_blocks(model, dm)
        self.extra: list = []
        self._bulk: _LinearBulk | None = None
        # the point states of the inelastic layers (material_state.py)
        from .material_state import MaterialStates

        self.materials = MaterialStates(model, self.blocks)
        self._pattern()

    @property
    def inelastic(self) -> bool:
        """Some layer has a material history (its response depends on the committed state)."""
        return self.materials.active

    @property
    def extrapolated(self) -> dict:
        """The IMPL-EX layers' extrapolated histories (empty: none, or implicit integration)."""
        return self.materials.extrapolated

    def commit(self, u_full: np.ndarray, time: float | None = None) -> None:
        """Take the material state at the converged ``u_full`` as committed (:class:`MaterialStates`)."""
        if self.materials.active:
            self._layers(u_full, np.zeros(self.dm.n_full), None)
            self.materials.commit(time)

    def next_increment(self, time: float | None = None, ratio: float | None = None) -> None:
        self.materials.next_increment(time, ratio)

    def implex_error(self, u_full: np.ndarray) -> float:
        """The IMPL-EX damage error of an increment to ``u_full`` (:meth:`MaterialStates.implex_error`)."""
        if not self.materials.extrapolated:
            return 0.0
        self._layers(u_full, np.zeros(self.dm.n_full), None)
        return self.materials.implex_error()

    def material_dissipation(self, u_full: np.ndarray | None = None) -> float:
        """Energy the layers' materials have dissipated: in the committed state, or where
        ``u_full`` is given in the trial state at ``u_full`` (before it is committed)."""
        if u_full is None or not self.materials.active:
            return self.materials.dissipation()
        self._layers(u_full, np.zeros(self.dm.n_full), None)
        return self.materials.dissipation(trial=True)

    def material_events(self) -> dict[str, bool]:
        return self.materials.events()

    def material_state(self) -> dict[str, np.ndarray]:
        return self.materials.arrays()

    def set_material_state(self, arrays: dict) -> None:
        self.materials.load(arrays)

    def add_blocks(self, extra: list) -> None:
        """Add element-like blocks with ``.dofs (e, m)`` and ``.response(u) -> (f, K)`` (contact)
        to the sparsity pattern and to every evaluation."""
        self.extra = list(extra)
        self._bulk = None  # the pattern changes
        self._pattern()

    def _pattern(self) -> None:
        """Full-space CSR pattern and the scatter index of every element entry into it
        (compiled row-by-row construction without sorting the entries when Numba is available)."""
        n = self.dm.n_full
        dofs_of = [*(b.dofs for b in self.blocks), *(_assembly_dofs(b) for b in self.extra)]
        self.n_entries = int(sum(d.shape[0] * d.shape[1] ** 2 for d in dofs_of))
        jit_mod = _jit()
        if jit_mod is not None and dofs_of:
            dofs = np.concatenate([d.ravel() for d in dofs_of]).astype(np.int64)
            m = np.concatenate([np.full(d.shape[0], d.shape[1], np.int64) for d in dofs_of])
            estart = np.concatenate([[0], np.cumsum(m)])
            vstart = np.concatenate([[0], np.cumsum(m * m)])
            # the CSR pattern has fewer entries than the element matrices together
            self.scatter = np.empty(self.n_entries, _index_dtype(max(self.n_entries, n)))
            indptr, indices = jit_mod.full_pattern(n, dofs, estart, vstart, self.scatter)
            self.nnz = int(indptr[-1])
            it = _index_dtype(max(self.nnz, n))
            self.indptr, self.indices = indptr.astype(it), indices.astype(it)
            if self.scatter.dtype != it:
                self.scatter = self.scatter.astype(it)
        else:
            self._pattern_numpy([*self.blocks, *self.extra])
        self._reduced: tuple[object, ReducedScatter] | None = None

    def _pattern_numpy(self, blocks: list) -> None:
        """The same by sorting all element entries (fallback without Numba)."""
        n = self.dm.n_full
        keys = []
        for b in blocks:
            d = _assembly_dofs(b).astype(np.int64)
            keys.append((d[:, :, None] * n + d[:, None, :]).ravel())
        key = np.concatenate(keys) if keys else np.zeros(0, np.int64)
        del keys
        ukey, scatter = np.unique(key, return_inverse=True)
        del key
        self.nnz = ukey.size
        it = _index_dtype(max(self.nnz, n))
        self.scatter = scatter.astype(it)
        del scatter
        ur = ukey // n
        self.indices = (ukey % n).astype(it)
        del ukey
        self.indptr = np.zeros(n + 1, it)
        np.cumsum(np.bincount(ur, minlength=n), out=self.indptr[1:])

    def reduced_scatter(self, op) -> ReducedScatter:
        """The reduced pattern and map for constraint operator ``op`` (cached per operator)."""
        if self._reduced is None or self._reduced[0] is not op:
            self._reduced = None  # free the previous map first
            self._reduced = (op, ReducedScatter(op.T, self.indptr, self.indices))
        return self._reduced[1]

    def _linear_bulk(self) -> "_LinearBulk | None":
        """The constant part of a geometrically linear model (``nonlinear = false``): the layer
        elements' K in the full pattern, built on first use; None for a nonlinear model, a model
        without interface or contact blocks, or without Numba. A linear element's K_e does not depend on u, so every tangent only adds
        the extra blocks (cohesive interfaces, contact) to it (re-forming the same element
        tangents would take most of an iteration of the DCB, ENF and lap-shear models); the
        internal forces still come from the kernel (:meth:`_layer_forces`)."""
        if self.model.nonlinear or _jit() is None or not self.blocks or not self.extra or self.materials.active:
            return None  # (without extra blocks Newton takes one or two iterations a step: no cache, no memory)
        if self._bulk is None:
            data = np.zeros(self.nnz)
            pos = self._layers(np.zeros(self.dm.n_full), None, data)
            mark = np.zeros(self.nnz, bool)  # the positions the extra blocks write to
            mark[self.scatter[pos:]] = True
            touched = np.flatnonzero(mark).astype(self.scatter.dtype)
            where = np.cumsum(mark, dtype=np.int64) - 1
            compact = where[self.scatter[pos:]].astype(self.scatter.dtype)
            del mark, where
            self._bulk = _LinearBulk(data, pos, touched, compact)
        return self._bulk

    def _layer_forces(self, u_full: np.ndarray) -> np.ndarray:
        """The layer elements' internal forces alone (the kernel without its tangent). Also for
        a linear model: f = K_bulk u as a sparse product loses the accuracy of the strains
        computed first - on a thin cantilever (l/h = 300) its cancellation left residuals of
        5·10⁻¹² where Newton needs 10⁻¹³."""
        f = np.zeros(self.dm.n_full)
        self._layers(u_full, f, None)
        return f

    def _layers(self, u_full: np.ndarray, f: np.ndarray | None, data: np.ndarray | None) -> int:
        """The layer elements at ``u_full``: their forces added to ``f`` and their tangents to
        ``data`` (summed into the CSR data by the compiled scatter, or as the entry array
        without Numba), where given; returns the number of element entries."""
        n = self.dm.n_full
        jit_mod = _jit()
        pos = 0
        for bi, b in enumerate(self.blocks):
            U = u_full[b.dofs].reshape(b.dofs.shape[0], -1, 3)
            for s in range(0, b.dofs.shape[0], self.chunk):
                sl = slice(s, s + self.chunk)
                if bi in self.materials.committed:
                    from .element.inelastic import inelastic_response

                    mat = self.materials
                    fe, Ke, tr = inelastic_response(b.ref, U[sl], self.model.nonlinear, data is not None, sl,
                                                    mat.committed[bi], mat.extrapolated.get(bi))
                    mat.put(bi, sl, tr)
                else:
                    fe, Ke = layer_response(b.ref, U[sl], self.model.nonlinear, data is not None, sl)
                if f is not None:
                    f += np.bincount(b.dofs[sl].ravel(), weights=fe.ravel(), minlength=n)
                if data is None:
                    continue
                flat = np.ascontiguousarray(Ke).reshape(-1)
                if jit_mod is not None:  # sum straight into the CSR data (no entry array, no bincount)
                    jit_mod.scatter_add(data, self.scatter, pos, flat)
                else:
                    data[pos:pos + flat.size] = flat
                pos += flat.size
        return pos

    def _extra_values(self, u_full: np.ndarray, tangent: bool, f: np.ndarray, data, scatter, pos: int) -> None:
        """Add the extra blocks' forces to ``f`` and (when ``tangent``) their tangents to
        ``data`` at ``scatter[pos:]`` (compiled scatter, or the entry array without Numba)."""
        n = self.dm.n_full
        jit_mod = _jit()
        for b in self.extra:
            dofs = _assembly_dofs(b)
            if dofs is not b.dofs:  # point form (nodal rule)
                fe, Ke = b.response(u_full, tangent, points=True)
            elif getattr(b, "compact_tangent", False):
                fe, Ke = b.response(u_full, tangent, compact=True)
            else:
                fe, Ke = b.response(u_full, tangent)
            f += np.bincount(dofs.ravel(), weights=fe.ravel(), minlength=n)
            if not tangent:
                continue
            ne = dofs.shape[0]
            if isinstance(Ke, tuple):  # (values, elements): a subset of the block's elements
                vals, el = Ke
                m2 = vals.shape[1] * vals.shape[2]
                flat = np.ascontiguousarray(vals).reshape(-1)
                if jit_mod is not None:
                    jit_mod.scatter_add_elements(data, scatter, pos, flat, el.astype(np.int64), m2)
                else:
                    data[pos:pos + ne * m2] = 0.0
                    data[pos:pos + ne * m2].reshape(ne, m2)[el] = flat.reshape(-1, m2)
                pos += ne * m2
                continue
            flat = np.ascontiguousarray(Ke).reshape(-1)
            if jit_mod is not None:
                jit_mod.scatter_add(data, scatter, pos, flat)
            else:
                data[pos:pos + flat.size] = flat
            pos += flat.size

    def _values(self, u_full: np.ndarray, tangent: bool, compact: bool = False, forces: bool = True):
        """Full-space internal force and (when ``tangent``) the summed CSR data of K; with
        ``compact`` on a linear model (:meth:`_linear_bulk`) the data of the extra blocks alone at
        the bulk's ``touched`` positions; without ``forces`` (a linear model's tangent) f holds the extra
        blocks' forces only."""
        n = self.dm.n_full
        bulk = self._linear_bulk() if tangent else None
        if bulk is not None:
            f = self._layer_forces(u_full) if forces else np.zeros(n)
            extra = np.zeros(bulk.touched.size)
            self._extra_values(u_full, True, f, extra, bulk.compact, 0)
            if compact:
                return f, extra
            data = bulk.data.copy()
            data[bulk.touched] += extra
            return f, data
        f = np.zeros(n)
        jit_mod = _jit()
        data = None
        if tangent:
            data = np.zeros(self.nnz) if jit_mod is not None else np.empty(self.n_entries)
        pos = self._layers(u_full, f, data)
        self._extra_values(u_full, tangent, f, data, self.scatter, pos)
        if not tangent:
            return f, None
        if jit_mod is None:
            data = np.bincount(self.scatter, weights=data, minlength=self.nnz)
        return f, data

    def evaluate(self, u_full: np.ndarray, tangent: bool = True):
        """Return ``(f_int, K)`` in the full space (K None when ``tangent`` is False)."""
        f, data = self._values(u_full, tangent)
        if data is None:
            return f, None
        return f, self._full_matrix(data)

    def evaluate_both(self, u_full: np.ndarray, op):
        """``(f_int, K, K_r)`` from one assembly: the full-space tangent and the reduced one
        Tᵀ K T of constraint operator ``op`` (the tangent predictor of inelastic layers needs both)."""
        f, data = self._values(u_full, True)
        return f, self._full_matrix(data), self.reduced_scatter(op).matrix(data, symmetric=self.symmetric)

    def _full_matrix(self, data: np.ndarray) -> sp.csr_matrix:
        K = sp.csr_matrix((data, self.indices, self.indptr), shape=(self.dm.n_full,) * 2)
        K.has_sorted_indices = True
        return K

    def evaluate_reduced(self, u_full: np.ndarray, op, forces: bool = True):
        """Return ``(f_int, K_r)``: the full-space internal force and the reduced tangent
        K_r = Tᵀ K T of constraint operator ``op`` (3.69)-(3.72), by the cached reduced scatter.
        ``forces=False`` (the solvers, which have the forces of the iterate already): f_int is
        not needed, and a linear model skips its layer elements' forces (f_int then holds the
        extra blocks' forces only)."""
        rs = self.reduced_scatter(op)
        bulk = self._linear_bulk()
        if bulk is None:
            f, data = self._values(u_full, True)
            return f, rs.matrix(data, symmetric=self.symmetric)
        if bulk.reduced is None or bulk.reduced[0] is not rs:  # P @ K_bulk once per operator
            bulk.reduced = None
            Pt = rs.P[:, bulk.touched].tocsr()
            rows = np.flatnonzero(np.diff(Pt.indptr)).astype(rs.indices.dtype)  # the K_r entries they reach
            base = rs.P @ bulk.data
            bulk.reduced = (rs, base, rows, Pt[rows], _PartialSymmetry.of(rs, base, rows))
        f, extra = self._values(u_full, True, compact=True, forces=forces)
        _, base, rows, Pt, partial = bulk.reduced
        data, filled = bulk.buffer(base.size)
        if filled is not base:  # a new array, or one of another operator; else it holds the base
            np.copyto(data, base)  # everywhere but at rows (nothing writes a lent K_r's data)
        data[rows] = base[rows] + Pt @ extra
        K = rs.matrix_from_values(data, symmetric=self.symmetric)
        K.partial_symmetry = partial
        bulk.lend(data, K, base)
        return f, K

    @property
    def symmetric(self) -> bool:
        """Every contribution to K is symmetric: the element tangents are (Bᵀ C B and the
        geometric term), extra blocks declare it (``symmetric = True``, or ``symmetric_now`` for
        the tangent they gave last)."""
        return (all(getattr(b, "symmetric", False) or getattr(b, "symmetric_now", False) for b in self.extra)
                and all(self.blocks[i].ref.symmetric for i in self.materials.committed))
