"""Linear constraints as one sparse operator: u_full = T u_red (MODEL.md §7-§8).

The bond matrix V (3.63)-(3.67), its delaminated generalisation (4.5)-(4.13), the boundary-
condition matrix R of the hinge (3.73)-(3.90), supports and symmetry planes are all linear
relations "dependent DOF = Σ c · other DOFs" or "DOF = 0". They are collected as triples and
resolved into the rectangular map T (independent → all DOFs), so that K_r = Tᵀ K T,
f_r = Tᵀ f (3.69)-(3.72).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .dofs import DofMap
from .model import Model


class ConstraintError(ValueError):
    """Inconsistent or over-determined constraints."""


@dataclass(frozen=True)
class ConstraintOperator:
    """u_full = T u_red + λ g_scaled + g_const: ``g_*`` are the prescribed displacements
    (supports with a ``value``) carried to the DOFs that depend on them; None without any."""

    T: sp.csr_matrix  # (n_full, n_red)
    independent: np.ndarray  # full DOF index of each reduced DOF
    fixed: np.ndarray  # full DOFs fixed to zero or to a prescribed value
    g_scaled: np.ndarray | None = None  # (n_full,) prescribed displacement per unit load factor
    g_const: np.ndarray | None = None  # (n_full,) prescribed displacement independent of λ
    prescribed: np.ndarray | None = None  # full DOFs with a non-zero prescribed value

    @property
    def n_red(self) -> int:
        return self.T.shape[1]

    def expand(self, u_red: np.ndarray) -> np.ndarray:
        return self.T @ u_red

    def reduce(self, v_full: np.ndarray) -> np.ndarray:
        return self.T.T @ v_full


class _Rows:
    """Collector of dependency triples and fixed DOFs."""

    def __init__(self):
        self.rows: list[np.ndarray] = []
        self.cols: list[np.ndarray] = []
        self.vals: list[np.ndarray] = []
        self.fixed: list[np.ndarray] = []
        self.values: list[tuple[np.ndarray, np.ndarray, bool]] = []  # prescribed (dofs, values, scaled)
        self.srcs: list[np.ndarray] = []
        self.names: list[str] = []

    def source(self, name: str) -> int:
        """Register a constraint source (one relation per dependent DOF per source)."""
        self.names.append(name)
        return len(self.names) - 1

    def dep(self, row, col, val, src: int):
        row, col, val = np.broadcast_arrays(np.asarray(row), np.asarray(col), np.asarray(val, float))
        keep = (row >= 0) & (col >= 0)
        self.rows.append(row[keep].ravel())
        self.cols.append(col[keep].ravel())
        self.vals.append(val[keep].ravel())
        self.srcs.append(np.full(int(keep.sum()), src))

    def fix(self, dofs):
        d = np.asarray(dofs).ravel()
        self.fixed.append(d[d >= 0])

    def prescribe(self, dofs, values, scaled: bool):
        """Fix ``dofs`` to ``values`` (× λ when ``scaled``), an inhomogeneous support."""
        d, v = np.broadcast_arrays(np.asarray(dofs), np.asarray(values, float))
        keep = d >= 0
        self.fix(d[keep])
        self.values.append((d[keep].ravel(), v[keep].ravel(), scaled))

    def cat(self, lst, dtype):
        return np.concatenate(lst).astype(dtype) if lst else np.zeros(0, dtype)


def _vector_constraint(rows: _Rows, src: int, target: np.ndarray, n: np.ndarray, rhs_cols=None, rhs_vals=None):
    """n · u_target = Σ rhs_vals · u[rhs_cols] per node: the component with the largest |n_j|
    becomes dependent. ``target (m, 3)`` DOFs, ``n (m, 3)`` unit vectors."""
    j = np.argmax(np.abs(n), axis=1)
    m = np.arange(len(n))
    nj = n[m, j]
    aligned = np.isclose(np.abs(nj), 1.0, atol=1e-12)
    dep = target[m, j]
    for k in range(3):
        other = k != j
        rows.dep(dep[other & ~aligned], target[m, k][other & ~aligned], -(n[m, k] / nj)[other & ~aligned], src)
    if rhs_cols is None:
        rows.fix(dep[aligned])
    else:
        for c, v in zip(rhs_cols, rhs_vals):
            rows.dep(dep, c, v / nj, src)


def collect(model: Model, dm: DofMap, bonded: dict[int, np.ndarray] | None = None) -> _Rows:
    """All constraint triples of the model for the given bond state (default: fully bonded)."""
    rows = _Rows()
    below = model.below()
    bonded = bonded if bonded is not None else {}
    bond_dep = np.zeros(dm.n_full, bool)
    src_bond = rows.source("bond")
    # --- bond (3.56)-(3.64), generalised (4.6): u_0L = u_0K + Σ_l H_K^l u_lK
    for up, lo in below.items():
        ok = dm.present[up] & dm.present[lo]
        if up in bonded:
            ok &= bonded[up]
        nodes = np.where(ok)[0]
        D_up = dm.layer_dofs[up][nodes]  # (m, d+1, 3)
        D_lo = dm.layer_dofs[lo][nodes]
        H = model.layers[lo].thickness[nodes]
        for l in range(model.layers[lo].directors + 1):
            rows.dep(D_up[:, 0, :], D_lo[:, l, :], (H**l)[:, None], src_bond)
        bond_dep[D_up[:, 0, :].ravel()] = True
    # --- supports
    for fx in model.fixes:
        D = dm.layer_dofs[fx.layer][fx.nodes]
        sel = D[:, list(fx.directors)][:, :, list(fx.components)]
        if getattr(fx, "value", None) is None:
            rows.fix(sel)
        else:  # prescribed displacement (displacement control), value per component
            rows.prescribe(sel, np.asarray(fx.value, float)[None, None, :], fx.scaled)
    # --- symmetry planes: u_l · n = 0 for every free director vector
    for i, sy in enumerate(model.symmetries):
        src = rows.source(f"symmetry plane {i + 1}")
        nvec = np.broadcast_to(np.asarray(sy.normal, float), (len(sy.nodes), 3))
        for k, ly in enumerate(model.layers):
            sel = dm.present[k][sy.nodes]
            D = dm.layer_dofs[k][sy.nodes[sel]]
            for l in range(ly.directors + 1):
                tgt = D[:, l, :]
                free = ~bond_dep[tgt[:, 0]]
                _vector_constraint(rows, src, tgt[free], nvec[sel][free])
    # --- hinges (3.77)-(3.90)
    if model.hinges:
        tot = model.total_thickness()
        first = {st[0] for st in model.stacks}
    for i, hg in enumerate(model.hinges):
        src = rows.source(f"hinge {i + 1}")
        nodes = hg.nodes
        tm = hg.height if hg.height is not None else 0.5 * tot[nodes]
        n = np.asarray(hg.direction, float).reshape(-1, 3)
        n = np.broadcast_to(n, (len(nodes), 3))
        base = [k for k in first if dm.present[k][nodes].all()]
        if not base:
            raise ConstraintError("hinge: the selected nodes do not share a reference layer")
        k1 = base[0]
        U01 = dm.layer_dofs[k1][nodes][:, 0, :]
        for k, ly in enumerate(model.layers):
            sel = dm.present[k][nodes]
            if not sel.any():
                continue
            D = dm.layer_dofs[k][nodes[sel]]
            nn, t = n[sel], tm[sel]
            u01 = U01[sel]
            rhs_cols = [u01[:, j] for j in range(3)]
            for l in range(1, ly.directors + 1):
                if l == 1:  # n·u_1L = -n·u_01 / Θ_m  (3.80)-(3.81)
                    _vector_constraint(rows, src, D[:, 1, :], nn, rhs_cols, [-nn[:, j] / t for j in range(3)])
                else:  # section stays plane
                    _vector_constraint(rows, src, D[:, l, :], nn)
            if k != k1:  # released u_0L keeps the plane section (3.79); bonded ones follow from the bond
                off = model.offset(k)[nodes[sel]]
                free = ~bond_dep[D[:, 0, 0]]
                if free.any():
                    fac = 1.0 - off[free] / t[free]
                    _vector_constraint(rows, src, D[free, 0, :], nn[free], [c[free] for c in rhs_cols],
                                       [fac * nn[free, j] for j in range(3)])
        if hg.fixed:  # u_01 ∈ span(n)
            j = np.argmax(np.abs(n), axis=1)
            m = np.arange(len(nodes))
            for k in range(3):
                o = k != j
                rows.dep(U01[m, k][o], U01[m, j][o], (n[m, k] / n[m, j])[o], src)
    return rows


def build_operator(n_full: int, rows: _Rows) -> ConstraintOperator:
    """Resolve the dependency triples into T (chains such as multi-layer bonds are substituted)."""
    r = rows.cat(rows.rows, np.int64)
    c = rows.cat(rows.cols, np.int64)
    v = rows.cat(rows.vals, float)
    fixed = np.unique(rows.cat(rows.fixed, np.int64))
    is_fixed = np.zeros(n_full, bool)
    is_fixed[fixed] = True
    keep = ~is_fixed[r]  # a fixed DOF is zero whatever else is said of it
    src = rows.cat(rows.srcs, np.int64)[keep]
    r, c, v = r[keep], c[keep], v[keep]
    dep_rows = np.unique(r)
    # every dependent DOF must be defined by exactly one relation (one source)
    pairs = np.unique(np.stack([r, src], 1), axis=0) if r.size else np.zeros((0, 2), np.int64)
    rr, cnt = np.unique(pairs[:, 0], return_counts=True)
    if np.any(cnt > 1):
        bad = rr[cnt > 1][0]
        names = sorted({rows.names[s] for s in pairs[pairs[:, 0] == bad, 1]})
        raise ConstraintError(
            f"{int((cnt > 1).sum())} DOF(s) are constrained twice (first: full DOF {bad}, by "
            f"{' and '.join(names)}); remove one of the overlapping supports, or use a fix instead"
        )
    is_dep = np.zeros(n_full, bool)
    is_dep[dep_rows] = True
    indep = np.flatnonzero(~is_dep & ~is_fixed)
    n_red = indep.size
    S = sp.csr_matrix((np.ones(n_red), (indep, np.arange(n_red))), shape=(n_full, n_red))
    D = sp.csr_matrix((v, (r, c)), shape=(n_full, n_full))
    T = S
    for _ in range(64):
        Tn = (S + D @ T).tocsr()
        Tn.eliminate_zeros()
        if (Tn - T).count_nonzero() == 0 or abs(Tn - T).max() <= 1e-14 * max(1.0, abs(Tn).max()):
            T = Tn
            break
        T = Tn
    else:
        raise ConstraintError("constraints refer to each other in a cycle; check supports, hinges and bonds")
    T.sort_indices()
    g_s, g_c, pres = _prescribed(n_full, rows, D)
    return ConstraintOperator(T, indep, fixed, g_s, g_c, pres)


def _prescribed(n_full: int, rows: _Rows, D: sp.csr_matrix):
    """Prescribed displacement vectors (scaled, constant) with the dependent DOFs that refer to
    prescribed ones (g = g_p + D g, resolved like T), and the prescribed DOFs; Nones without."""
    if not rows.values:
        return None, None, None
    out = []
    seen = np.full(n_full, np.nan)
    for want in (True, False):
        g = np.zeros(n_full)
        for d, v, scaled in rows.values:
            if scaled != want:
                continue
            clash = ~np.isnan(seen[d]) & ~np.isclose(seen[d], v)
            if clash.any():
                raise ConstraintError(f"a DOF (full DOF {d[clash][0]}) has two different prescribed displacements; "
                                      "give each support component one value (remove the overlap)")
            seen[d] = v
            g[d] = v
        gp = g.copy()
        for _ in range(64):
            gn = gp + D @ g
            if np.allclose(gn, g, rtol=0.0, atol=1e-14 * max(1.0, np.abs(gn).max())):
                g = gn
                break
            g = gn
        out.append(g if np.any(g) else None)
    pres = np.unique(np.concatenate([d[v != 0] for d, v, _ in rows.values]))
    return out[0], out[1], pres


def apply_ties(op: ConstraintOperator, model: Model, dm: DofMap) -> ConstraintOperator:
    """Supports on a face, at a height or on a director of any layer (:class:`~layershell.model.Tie`):
    each row c·u = 0 is written in the reduced DOFs of ``op`` (c_r = c T, so a bond or hinge is
    respected) and the reduced DOF with the largest |c_r| is eliminated, u_p = -Σ c_r,j/c_r,p u_j.
    Rows of one tie and component belong to distinct nodes and so to distinct reduced DOFs
    (all relations are node-local), which lets a whole batch be eliminated at once; a row that
    is already satisfied (c_r = 0, e.g. on a fixed DOF) is skipped."""
    T, indep = op.T, op.independent
    for tie in model.ties:
        present = dm.present[tie.layer][tie.nodes]
        nodes, coeffs, dirs = tie.nodes[present], tie.coeffs[present], tie.direction[present]
        if nodes.size == 0:
            continue
        D = dm.layer_dofs[tie.layer][nodes]  # (m, d+1, 3)
        m = nodes.size
        rows = np.repeat(np.arange(m), D.shape[1] * 3)
        vals = (coeffs[:, :, None] * dirs[:, None, :]).ravel()
        C = sp.csr_matrix((vals, (rows, D.ravel())), shape=(m, T.shape[0]))
        Cr = (C @ T).tocsr()
        Cr.eliminate_zeros()
        scale = np.abs(vals).reshape(m, -1).max(1)
        A = abs(Cr)
        piv = np.asarray(A.argmax(axis=1)).ravel()
        pv = np.asarray(Cr[np.arange(m), piv]).ravel()
        ok = np.abs(pv) > 1e-12 * scale
        if not ok.any():
            continue
        Cr, piv, pv = Cr[np.flatnonzero(ok)], piv[ok], pv[ok]
        if np.unique(piv).size != piv.size:
            raise ConstraintError("two supports of one table act on the same degree of freedom; select each node "
                                  "once")
        S = sp.diags(1.0 / pv) @ Cr  # rows: u_p + Σ_j S_j u_j = 0
        n_red = T.shape[1]
        P = sp.csr_matrix((np.ones(piv.size), (piv, np.arange(piv.size))), shape=(n_red, piv.size))
        E = sp.identity(n_red, format="csr") - P @ S
        keep = np.ones(n_red, bool)
        keep[piv] = False
        T = (T @ E).tocsr()[:, np.flatnonzero(keep)]
        T.eliminate_zeros()
        T.sort_indices()
        indep = indep[keep]
    return ConstraintOperator(T.tocsr(), indep, op.fixed)


def constraint_operator(model: Model, dm: DofMap, bonded=None) -> ConstraintOperator:
    op = build_operator(dm.n_full, collect(model, dm, bonded))
    return apply_ties(op, model, dm) if getattr(model, "ties", None) else op
