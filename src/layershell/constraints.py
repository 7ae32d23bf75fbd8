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


def _director_values(fx) -> np.ndarray:
    """Prescribed values of a fix per (director, component), shape (1, n_dir, n_comp): with director
    0 among the held ones the value moves it (the layer's reference face) and the other held
    directors stay zero, a translation of the section; without director 0 each held director takes
    the value (in its own units)."""
    dirs = list(fx.directors)
    val = np.asarray(fx.value, float)
    out = np.zeros((1, len(dirs), val.size))
    if 0 in dirs:
        out[0, dirs.index(0)] = val
    else:
        out[0] = val
    return out


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
            rows.prescribe(sel, _director_values(fx), fx.scaled)
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
    """Resolve the dependency triples into T (chains such as multi-layer bonds are substituted).

    A support on a DOF that a relation already defines (the reference face of a bonded upper
    layer, a DOF on an oblique symmetry plane or a hinge) keeps that relation: the support becomes
    a row "u_d = value" written in the independent DOFs (:func:`impose_rows`), so the bond holds
    and the support acts on the DOFs the relation refers to."""
    r = rows.cat(rows.rows, np.int64)
    c = rows.cat(rows.cols, np.int64)
    v = rows.cat(rows.vals, float)
    src = rows.cat(rows.srcs, np.int64)
    fixed = np.unique(rows.cat(rows.fixed, np.int64))
    _check_single_source(rows, r, src)
    is_dep = np.zeros(n_full, bool)
    is_dep[r] = True
    plain = fixed[~is_dep[fixed]]  # fixed DOFs no relation defines: removed from the unknowns
    held = fixed[is_dep[fixed]]  # fixed DOFs a relation defines: imposed as rows below
    is_out = is_dep.copy()
    is_out[plain] = True
    indep = np.flatnonzero(~is_out)
    n_red = indep.size
    S = sp.csr_matrix((np.ones(n_red), (indep, np.arange(n_red))), shape=(n_full, n_red))
    D = sp.csr_matrix((v, (r, c)), shape=(n_full, n_full))
    T = _resolve_chain(S, D)
    v_s, v_c = _prescribed_values(n_full, rows)
    on_plain = np.zeros(n_full, bool)
    on_plain[plain] = True
    g_s, g_c = (_resolve_vector(np.where(on_plain, vv, 0.0), D) for vv in (v_s, v_c))
    pres = np.unique(np.concatenate([d[val != 0] for d, val, _ in rows.values])) if rows.values else None
    op = ConstraintOperator(T, indep, fixed, g_s, g_c, pres if pres is not None and pres.size else None)
    if held.size:
        C = sp.csr_matrix((np.ones(held.size), (np.arange(held.size), held)), shape=(held.size, n_full))
        op = impose_rows(op, C, v_s[held], v_c[held])
    return _without_zero_vectors(op)


def _check_single_source(rows: _Rows, r: np.ndarray, src: np.ndarray) -> None:
    """Every dependent DOF must be defined by exactly one relation (one source)."""
    pairs = np.unique(np.stack([r, src], 1), axis=0) if r.size else np.zeros((0, 2), np.int64)
    rr, cnt = np.unique(pairs[:, 0], return_counts=True)
    if np.any(cnt > 1):
        bad = rr[cnt > 1][0]
        names = sorted({rows.names[s] for s in pairs[pairs[:, 0] == bad, 1]})
        raise ConstraintError(
            f"{int((cnt > 1).sum())} DOF(s) are constrained twice (first: full DOF {bad}, by "
            f"{' and '.join(names)}); remove one of the overlapping supports, or use a fix instead"
        )


def _resolve_chain(S: sp.csr_matrix, D: sp.csr_matrix) -> sp.csr_matrix:
    """T = S + D T by substitution (a dependent DOF may refer to dependent DOFs: bond chains)."""
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
    return T


def _resolve_vector(gp: np.ndarray, D: sp.csr_matrix) -> np.ndarray:
    """g = g_p + D g: prescribed values carried to the DOFs that depend on them (the substitution
    of :func:`_resolve_chain` on one column)."""
    return _resolve_chain(sp.csr_matrix(gp[:, None]), D).toarray().ravel()


def _prescribed_values(n_full: int, rows: _Rows) -> tuple[np.ndarray, np.ndarray]:
    """Per full DOF the prescribed value (× λ, constant); zero at homogeneous supports."""
    out = {True: np.zeros(n_full), False: np.zeros(n_full)}
    seen = np.full(n_full, np.nan)
    for d, v, scaled in rows.values:
        clash = ~np.isnan(seen[d]) & ~np.isclose(seen[d], v)
        if clash.any():
            raise ConstraintError(f"a DOF (full DOF {d[clash][0]}) has two different prescribed displacements; "
                                  "give each support component one value (remove the overlap)")
        seen[d] = v
        out[scaled][d] = v
    return out[True], out[False]


def _without_zero_vectors(op: ConstraintOperator) -> ConstraintOperator:
    """None for prescribed vectors that are zero (the operator of a model without displacement
    control), and the prescribed DOFs set whenever one of them is not."""
    g_s = op.g_scaled if op.g_scaled is not None and np.any(op.g_scaled) else None
    g_c = op.g_const if op.g_const is not None and np.any(op.g_const) else None
    pres = op.prescribed
    if g_s is None and g_c is None:
        pres = None
    elif pres is None:
        pres = np.flatnonzero(np.abs(g_s if g_s is not None else 0.0) + np.abs(g_c if g_c is not None else 0.0))
    return ConstraintOperator(op.T, op.independent, op.fixed, g_s, g_c, pres)


def impose_rows(op: ConstraintOperator, C: sp.csr_matrix, v_s: np.ndarray, v_c: np.ndarray,
                ) -> ConstraintOperator:
    """Impose the rows C u = λ v_s + v_c on ``op``'s map u = T u_r + λ g_s + g_c.

    In the independent DOFs a row reads C_r u_r = r with C_r = C T and r = λ (v_s − C g_s) +
    v_c − C g_c (so a bond, hinge or earlier support is respected). Each row eliminates one
    independent DOF, its pivot p: u_p = (r − Σ_{j≠p} C_r,j u_j) / C_r,p. A batch of rows is
    eliminated at once where no row touches another row's pivot; the others wait for the next
    pass, on the updated map. A row left without coefficients is already satisfied (a redundant
    support) or contradicts another support (:class:`ConstraintError`)."""
    T, indep = op.T, op.independent
    n_full = T.shape[0]
    g_s = np.zeros(n_full) if op.g_scaled is None else op.g_scaled.copy()
    g_c = np.zeros(n_full) if op.g_const is None else op.g_const.copy()
    tol = 1e-9 * max(np.abs(v_s).max(initial=0.0), np.abs(v_c).max(initial=0.0), np.abs(g_s).max(),
                     np.abs(g_c).max(), 1e-300)
    scale_c = np.asarray(abs(C).max(axis=1).todense()).ravel()
    todo = np.arange(C.shape[0])
    while todo.size:
        Cs = C[todo]
        Cr = (Cs @ T).tocsr()
        Cr.eliminate_zeros()
        r_s, r_c = v_s[todo] - Cs @ g_s, v_c[todo] - Cs @ g_c
        live = np.asarray(abs(Cr).max(axis=1).todense()).ravel() > 1e-12 * scale_c[todo]
        if np.any(~live & ((np.abs(r_s) > tol) | (np.abs(r_c) > tol))):
            raise ConstraintError(
                "two supports prescribe different displacements at the same point (or a support contradicts a "
                "bond, hinge or symmetry plane there); give the point one value, or remove one of the supports")
        todo, Cr, r_s, r_c = todo[live], Cr[np.flatnonzero(live)], r_s[live], r_c[live]
        if not todo.size:
            break
        now, piv = _independent_pivots(Cr)
        pv = np.asarray(Cr[now, piv]).ravel()
        S = sp.diags(1.0 / pv) @ Cr[now]  # rows: u_p + Σ_j S_j u_j = r / C_r,p
        n_red = T.shape[1]
        h_s, h_c = np.zeros(n_red), np.zeros(n_red)
        h_s[piv], h_c[piv] = r_s[now] / pv, r_c[now] / pv
        g_s, g_c = g_s + T @ h_s, g_c + T @ h_c
        P = sp.csr_matrix((np.ones(piv.size), (piv, np.arange(piv.size))), shape=(n_red, piv.size))
        E = sp.identity(n_red, format="csr") - P @ S
        keep = np.ones(n_red, bool)
        keep[piv] = False
        T = (T @ E).tocsr()[:, np.flatnonzero(keep)]
        T.eliminate_zeros()
        T.sort_indices()
        indep = indep[keep]
        rest = np.ones(todo.size, bool)
        rest[now] = False
        todo = todo[rest]
    pres = op.prescribed
    extra = np.unique(C[np.flatnonzero((v_s != 0) | (v_c != 0))].indices)
    if extra.size:
        pres = extra if pres is None else np.union1d(pres, extra)
    return _without_zero_vectors(ConstraintOperator(T.tocsr(), indep, op.fixed, g_s, g_c, pres))


def _independent_pivots(Cr: sp.csr_matrix) -> tuple[np.ndarray, np.ndarray]:
    """Rows of ``Cr`` that can be eliminated together and their pivot columns: each row's
    largest coefficient among the columns no other row touches (at least 1/10 of the row's
    largest, for a well-conditioned division); at least the first row with its largest."""
    A = abs(Cr).tocsr()
    rowmax = np.asarray(A.max(axis=1).todense()).ravel()
    count = np.bincount(A.indices, minlength=A.shape[1])
    row_of = np.repeat(np.arange(A.shape[0]), np.diff(A.indptr))
    ok = (count[A.indices] == 1) & (A.data >= 0.1 * rowmax[row_of])
    M = sp.csr_matrix((np.where(ok, A.data, 0.0), A.indices, A.indptr), shape=A.shape)
    best = np.asarray(M.max(axis=1).todense()).ravel()
    now = np.flatnonzero(best > 0)
    if now.size:
        return now, np.asarray(M[now].argmax(axis=1)).ravel()
    return np.array([0]), np.asarray(A[0].argmax(axis=1)).ravel()


def apply_ties(op: ConstraintOperator, model: Model, dm: DofMap) -> ConstraintOperator:
    """Supports on a face, at a height, in a direction or through all layers
    (:class:`~layershell.model.Tie`): per node Σ_l c_l u_l · e = λ v (× λ when the tie is
    scaled; v = 0 without a value), imposed on ``op`` by :func:`impose_rows` (so a bond or hinge
    is respected)."""
    for tie in model.ties:
        present = dm.present[tie.layer][tie.nodes]
        nodes, coeffs, dirs = tie.nodes[present], tie.coeffs[present], tie.direction[present]
        if nodes.size == 0:
            continue
        D = dm.layer_dofs[tie.layer][nodes]  # (m, d+1, 3)
        m = nodes.size
        rows = np.repeat(np.arange(m), D.shape[1] * 3)
        vals = (coeffs[:, :, None] * dirs[:, None, :]).ravel()
        C = sp.csr_matrix((vals, (rows, D.ravel())), shape=(m, op.T.shape[0]))
        C.eliminate_zeros()
        value = np.zeros(m) if tie.value is None else np.asarray(tie.value, float)[present]
        zero = np.zeros(m)
        op = impose_rows(op, C, value if tie.scaled else zero, zero if tie.scaled else value)
    return op


def constraint_operator(model: Model, dm: DofMap, bonded=None) -> ConstraintOperator:
    op = build_operator(dm.n_full, collect(model, dm, bonded))
    return apply_ties(op, model, dm) if getattr(model, "ties", None) else op
