"""Inelastic layers: the stress and tangent of a material law at every integration point of a
layer, and reinforcement sheets (rebar, textile) inside a layer without extra DOFs.

Bulk. The layer kernels with the PK2 stress S and the tangent D = dS/dE of the law at the
Green-Lagrange strain of each point (MITC9: the tied strain mapped to Cartesian axes) in place of
S = C E: f = Σ Bᵀ S dV, K = Σ Bᵀ D B dV + the geometric term of S; compiled
(:mod:`.inelastic_kernel`, the law evaluated vectorised over the element range in between), or
through the kernels' plain NumPy forms (:func:`.kernel.layer_response_reference`,
:func:`.mitc.mitc_response_reference`; ``fast=False``, the independent check). The law sees the
shell normal and two lengths per point for its crack band: the in-plane band
h_in = 13/18 √(element area) (:data:`BAND_FRACTION`) and the thickness-point spacing
h_z = H / (points through the layer).

Sheets. A reinforcement sheet at height ``h`` above the layer's bottom face with the unit
direction a (the tangent-plane projection of a global direction, turned by an angle about the
normal) and the area A_s per unit width (bars: area per bar / spacing) is a uniaxial material
bonded to the layer: its strain is the layer's Green-Lagrange strain along a there,
ε = a·E·a = (∇u a)·a + ½ |∇u a|², at the 3 × 3 in-plane Gauss points, so with F a and g_a·a

    f_ai = Σ_q w_q σ (g_a·a) (F a)_i,   K_aibk = Σ_q w_q [E_t (g_a·a)(F a)_i (g_b·a)(F a)_k + σ (g_a·a)(g_b·a) δ_ik]

and w_q = A_s dA (dA the area element at the sheet's height). The sheet uses the layer's
untied strain also in a MITC9 layer.

State. Every response is a pure function of the displacement and the committed state and
returns the trial state; the solver commits the trial state of a converged solution
(:meth:`layershell.assembly.Assembler.commit`), so that a rejected iterate or increment leaves no
trace.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from .geometry import shell_basis, surface_points
from .kernel import (LayerBlock, basis_gradients, layer_block, layer_response, layer_response_reference,
                     material_frame)
from .quadrature import gauss_2d


#: the share of the element's size that an opened crack takes as its band: the 9-node element's
#: strain is linear along the crack normal, so the Gauss row next to the crack cannot open without
#: the middle one, and a fully opened crack holds the two rows of weight 5/18 + 8/18 (measured:
#: tests/test_concrete_layer.py, the tension bar on three meshes)
BAND_FRACTION = 13.0 / 18.0


@dataclass(frozen=True)
class Sheet:
    """A reinforcement sheet over a block's elements: ``g (e, q, a, 3)`` the basis gradients at its
    points, ``a (e, q, 3)`` its unit direction, ``w (e, q)`` the sheet area per point (A_s dA)."""

    name: str
    law: object
    g: np.ndarray
    a: np.ndarray
    w: np.ndarray


@dataclass(frozen=True)
class InelasticBlock:
    """A layer with a bulk material law (``law``, or None: the elastic ``base``) and sheets.

    ``h_in``, ``h_z`` (e, P): crack-band lengths, ``normal`` (e, P, 3) the shell normal at the
    base block's P points (in its order: ``base.dV``)."""

    base: object
    law: object | None
    h_in: np.ndarray
    h_z: np.ndarray
    normal: np.ndarray
    sheets: tuple[Sheet, ...] = ()

    @property
    def n_dof(self) -> int:
        return self.base.n_dof

    @property
    def n_points(self) -> int:
        return self.base.dV.shape[1]

    @property
    def d(self) -> int:
        return self.base.d

    @property
    def dV(self) -> np.ndarray:
        return self.base.dV

    @property
    def C(self) -> np.ndarray:
        return self.base.C

    @property
    def symmetric(self) -> bool:
        """Whether the tangent is symmetric (the sheets' always is; the bulk law says)."""
        return self.law is None or bool(getattr(self.law, "symmetric", False))


@dataclass
class LayerState:
    """Point states of one inelastic block: ``bulk`` (the law's, over e·P points, element-major)
    and one per sheet (over e·9 points); ``strain`` (e·P, 6) the bulk strain and ``sheet_strain``,
    ``sheet_stress`` (e·9,) per sheet at the state (outputs: crack widths, bar stresses)."""

    bulk: object | None
    sheets: tuple
    strain: np.ndarray | None = None
    sheet_strain: tuple = ()
    sheet_stress: tuple = ()

    def copy(self) -> "LayerState":
        return LayerState(None if self.bulk is None else self.bulk.copy(), tuple(s.copy() for s in self.sheets),
                          None if self.strain is None else self.strain.copy(),
                          tuple(a.copy() for a in self.sheet_strain), tuple(a.copy() for a in self.sheet_stress))

    def to_dict(self, prefix: str) -> dict[str, np.ndarray]:
        out: dict[str, np.ndarray] = {}
        if self.bulk is not None:
            out.update(self.bulk.to_dict(f"{prefix}/bulk/"))
        for k, s in enumerate(self.sheets):
            out.update(s.to_dict(f"{prefix}/sheet{k}/"))
            out[f"{prefix}/sheet{k}.strain"] = self.sheet_strain[k]
            out[f"{prefix}/sheet{k}.stress"] = self.sheet_stress[k]
        if self.strain is not None:
            out[f"{prefix}/strain"] = self.strain
        return out

    def load(self, d: dict, prefix: str) -> "LayerState":
        """The same state with the arrays of ``d`` (written by :meth:`to_dict`); KeyError where one is
        missing or of another size."""

        def state(like, key):
            st = type(like).from_dict(d, key)
            if st.n != like.n:
                raise KeyError(key)
            return st

        def arr(key, like):
            if key not in d or np.shape(d[key]) != np.shape(like):
                raise KeyError(key)
            return np.array(d[key], dtype=float)

        n = len(self.sheets)
        return LayerState(None if self.bulk is None else state(self.bulk, f"{prefix}/bulk/"),
                          tuple(state(s, f"{prefix}/sheet{k}/") for k, s in enumerate(self.sheets)),
                          None if self.strain is None else arr(f"{prefix}/strain", self.strain),
                          tuple(arr(f"{prefix}/sheet{k}.strain", self.sheet_strain[k]) for k in range(n)),
                          tuple(arr(f"{prefix}/sheet{k}.stress", self.sheet_stress[k]) for k in range(n)))


def _put(dst, idx: slice, src) -> None:
    """Write the point state ``src`` into the points ``idx`` of ``dst`` (in place)."""
    for f in dataclasses.fields(dst):
        getattr(dst, f.name)[idx] = getattr(src, f.name)


def initial_state(block: InelasticBlock) -> LayerState:
    """The virgin state of every point of ``block``."""
    e = block.h_in.shape[0]
    bulk = block.law.state(e * block.n_points) if block.law is not None else None
    nq = [e * s.w.shape[1] for s in block.sheets]
    return LayerState(bulk, tuple(s.law.state(n) for s, n in zip(block.sheets, nq)),
                      np.zeros((e * block.n_points, 6)) if bulk is not None else None,
                      tuple(np.zeros(n) for n in nq), tuple(np.zeros(n) for n in nq))


def in_plane_band(X: np.ndarray, sp=None) -> np.ndarray:
    """The in-plane crack band of elements with nodes ``X (e, 9, 3)`` (or their surface points
    ``sp`` at the 3 × 3 Gauss points): :data:`BAND_FRACTION` √(element area)."""
    pts, w2 = gauss_2d(3)
    if sp is None:
        sp = surface_points(X, pts[:, 0], pts[:, 1])
    return BAND_FRACTION * np.sqrt(np.sum(sp.sqrtA * w2, axis=1))


def _point_geometry(base, sp, Hq: np.ndarray):
    """h_in, h_z, normal at the base block's points (LayerBlock q-major, MITC9 z-major)."""
    e, q = Hq.shape
    nz = base.dV.shape[1] // q
    h_in = in_plane_band(None, sp)
    hz = Hq / nz
    if isinstance(base, LayerBlock):  # point = iq · nz + iz
        normal = np.repeat(sp.A3, nz, axis=1)
        h_z = np.repeat(hz, nz, axis=1)
    else:  # point = iz · 9 + iq
        normal = np.tile(sp.A3, (1, nz, 1))
        h_z = np.tile(hz, (1, nz))
    return np.repeat(h_in[:, None], base.dV.shape[1], axis=1), h_z, normal


def sheet_block(X, H_below, H, d: int, height: float, area: float, law, name: str, angle_deg: float = 0.0,
                direction=None) -> Sheet:
    """A sheet at ``height`` above the layer's bottom face (``H_below``, ``H`` nodal (e, 9))."""
    pts, w2 = gauss_2d(3)
    sp = surface_points(X, pts[:, 0], pts[:, 1])
    Hb = sp.interpolate(H_below)
    th = np.full(Hb.shape + (1,), float(height))
    _, Ginv, detG = shell_basis(sp, Hb[..., None] + th)
    g = basis_gradients(sp, Ginv, th, d)[:, :, 0]
    a = material_frame(sp, angle_deg, direction)[..., 0, :]
    w = float(area) * detG[..., 0] * w2[None, :]
    return Sheet(name, law, np.ascontiguousarray(g), np.ascontiguousarray(a), w)


def inelastic_block(X, H_below, H, d: int, material, law, sheets=(), n_thickness: int = 3,
                    element: str = "mitc", angle_deg: float = 0.0, direction=None) -> InelasticBlock:
    """The block of a layer with the bulk ``law`` (or None) and ``sheets``: (name, law, height,
    area, angle, direction) each. ``material`` is the law's initial elastic stand-in (estimates,
    the base block's C)."""
    base = layer_block(X, H_below, H, d, material, angle_deg, direction, n_thickness, element=element,
                       keep_map=law is not None)
    pts, w2 = gauss_2d(3)
    sp = surface_points(X, pts[:, 0], pts[:, 1])
    h_in, h_z, normal = _point_geometry(base, sp, sp.interpolate(H))
    made = tuple(sheet_block(X, H_below, H, d, h, A, lw, nm, ang, dr) for nm, lw, h, A, ang, dr in sheets)
    return InelasticBlock(base, law, h_in, h_z, normal, made)


def sheet_terms(sheet: Sheet, U: np.ndarray, nonlinear: bool, tangent: bool, sl: slice, committed):
    """A sheet's point terms over the elements ``sl`` (compiled strains): ``(ga, Fa, sw, cw)`` with
    g_b·a (e, q, n), F a (e, q, 3), s = σ A_s dA and c = E_t A_s dA (e, q; c None without
    ``tangent``), and the trial (state, strain, stress)."""
    from . import _jit_inelastic as jit

    g, a, w = sheet.g[sl], sheet.a[sl], sheet.w[sl]
    e, q, na = g.shape[:3]
    ga, Fa, eps = np.empty((e, q, na)), np.empty((e, q, 3)), np.empty((e, q))
    jit.sheet_strain(g, a, np.ascontiguousarray(U, dtype=np.float64), bool(nonlinear), ga, Fa, eps)
    sig, Et, trial = sheet.law.response(eps.ravel(), committed, tangent)
    cw = np.ascontiguousarray(Et.reshape(e, q) * w) if tangent else None
    return (ga, Fa, np.ascontiguousarray(sig.reshape(e, q) * w), cw), (trial, eps.ravel(), sig.ravel())


def sheet_response(sheet: Sheet, U: np.ndarray, nonlinear: bool, tangent: bool, sl: slice, committed,
                   fast: bool = True, into=None):
    """Forces ``(e, m)``, tangent ``(e, m, m)`` (None without ``tangent``) and trial state of a sheet.

    With b_q = (g_a·a)(F a)_i (the row dε/dU_ai at point q, m = 3a entries), c = E_t w, s = σ w:
    K = Σ_q c_q b_q b_qᵀ + δ_ik Σ_q s_q (g_a·a)(g_b·a) in compiled point loops (``fast``, added to
    the arrays ``into`` = (f, K) where given, e.g. the bulk's), or literally as einsum (the
    independent check)."""
    if not fast:
        return _sheet_response_reference(sheet, U, nonlinear, tangent, sl, committed)
    from . import _jit_inelastic as jit

    (ga, Fa, sw, cw), trial = sheet_terms(sheet, U, nonlinear, tangent, sl, committed)
    e, q, na = ga.shape
    f, K = into if into is not None else (np.zeros((e, 3 * na)), np.zeros((e, 3 * na, 3 * na)) if tangent else None)
    jit.sheet_add(ga, Fa, sw, cw if tangent else np.zeros((0, 0)), bool(nonlinear), bool(tangent), f,
                  K if tangent else np.zeros((0, 0, 0)))
    return f, K, trial


def _sheet_response_reference(sheet: Sheet, U: np.ndarray, nonlinear: bool, tangent: bool, sl: slice, committed):
    """Plain einsum form of :func:`sheet_response` (the independent check)."""
    g, a, w = sheet.g[sl], sheet.a[sl], sheet.w[sl]
    Ha = np.einsum("eai,eqaJ,eqJ->eqi", U, g, a)  # ∇u a
    eps = np.einsum("eqi,eqi->eq", Ha, a)
    Fa = a + Ha if nonlinear else a
    if nonlinear:
        eps = eps + 0.5 * np.einsum("eqi,eqi->eq", Ha, Ha)
    sig, Et, trial = sheet.law.response(eps.ravel(), committed, tangent)
    e, q = eps.shape
    trial = (trial, eps.ravel(), sig.ravel())
    sig = sig.reshape(e, q)
    ga = np.einsum("eqaJ,eqJ->eqa", g, a)
    Bq = ga[:, :, :, None] * Fa[:, :, None, :]  # (e, q, a, 3) = dε/dU_ai
    m = Bq.shape[2] * 3
    f = np.einsum("eqai,eq->eai", Bq, sig * w).reshape(e, m)
    if not tangent:
        return f, None, trial
    Bm = Bq.reshape(e, q, m)
    K = np.einsum("eqm,eq,eqn->emn", Bm, Et.reshape(e, q) * w, Bm, optimize=True)
    if nonlinear:
        Kg = np.einsum("eqa,eq,eqb->eab", ga, sig * w, ga)
        na = ga.shape[2]
        K = (K.reshape(e, na, 3, na, 3) + Kg[:, :, None, :, None] * np.eye(3)[None, None, :, None, :]).reshape(e, m, m)
    return f, K, trial


def extrapolated_state(block: InelasticBlock, previous: LayerState, current: LayerState,
                       ratio: float = 1.0) -> LayerState | None:
    """The bulk histories extrapolated to the next increment (IMPL-EX; ``ratio`` = its size over
    the last one's), where the law offers it."""
    if block.law is None or not hasattr(block.law, "extrapolate"):
        return None
    return LayerState(block.law.extrapolate(previous.bulk, current.bulk, ratio), ())


def inelastic_response(block: InelasticBlock, U: np.ndarray, nonlinear: bool, tangent: bool, sl: slice,
                       committed: LayerState, implex: LayerState | None = None, fast: bool = True):
    """Forces ``(e, m)``, tangent ``(e, m, m)`` and the trial :class:`LayerState` of the elements
    ``sl`` (a contiguous range) from their nodal vectors ``U (e, a, 3)`` and the committed state
    of the whole block; with ``implex`` (:func:`extrapolated_state`) the bulk law's stress takes
    the damage of the extrapolated histories (IMPL-EX). ``fast``: the bulk through the compiled
    kernel (:mod:`.inelastic_kernel`, the sheets' points as further rows of its products), else
    both through their plain NumPy forms (the independent check)."""
    lo, hi, _ = sl.indices(block.h_in.shape[0])
    sl = slice(lo, hi)
    if block.law is None or not fast:
        return _separate_response(block, U, nonlinear, tangent, sl, committed, implex, fast)
    from .inelastic_kernel import bulk_response

    stress, out = _bulk_stress(block, sl, committed, implex, tangent)
    terms = []
    for k, s in enumerate(block.sheets):
        q = s.w.shape[1]
        terms.append(sheet_terms(s, U, nonlinear, tangent, sl, committed.sheets[k].take(slice(lo * q, hi * q))))
    f, K = bulk_response(block.base, U, nonlinear, tangent, sl, stress, tuple(t[0] for t in terms))
    return f, K, LayerState(out["trial"], tuple(t[1][0] for t in terms), out["strain"],
                            tuple(t[1][1] for t in terms), tuple(t[1][2] for t in terms))


def _bulk_stress(block: InelasticBlock, sl: slice, committed: LayerState, implex, tangent: bool):
    """The bulk law as ``stress(E) -> (S, D)`` over the elements ``sl``
    (:func:`.inelastic_kernel.bulk_response`), and the dict its strain and trial state are left in."""
    lo, hi = sl.start, sl.stop
    P = block.n_points
    c = committed.bulk.take(slice(lo * P, hi * P))
    extra = {} if implex is None else {"implex": implex.bulk.take(slice(lo * P, hi * P))}
    if committed.strain is not None:  # the increment stiffness acts on the change since the commit
        extra["strain_n"] = committed.strain[lo * P:hi * P]
    out = {}

    def stress(E):
        out["strain"] = E.reshape(-1, 6)
        S, D, out["trial"] = block.law.response(out["strain"], c, block.h_in[sl].ravel(), block.h_z[sl].ravel(),
                                                block.normal[sl].reshape(-1, 3), tangent, **extra)
        ne = E.shape[0]
        return S.reshape(ne, P, 6), (None if D is None else D.reshape(ne, P, 6, 6))

    return stress, out


def _separate_response(block: InelasticBlock, U, nonlinear: bool, tangent: bool, sl: slice, committed: LayerState,
                       implex, fast: bool):
    """:func:`inelastic_response` with the sheets added after the bulk: the elastic bulk (no law)
    or the plain NumPy forms of both (``fast=False``)."""
    lo, hi = sl.start, sl.stop
    trial_bulk, out = None, {}
    if block.law is None:
        f, K = layer_response(block.base, U, nonlinear, tangent, sl)
    else:
        stress, out = _bulk_stress(block, sl, committed, implex, tangent)
        f, K = layer_response_reference(block.base, U, nonlinear, tangent, sl, stress)
        trial_bulk = out["trial"]
    trial_sheets, strains, stresses = [], [], []
    for k, s in enumerate(block.sheets):
        q = s.w.shape[1]
        into = (f, K) if fast else None  # the compiled sheets add into the bulk's fresh arrays
        fs, Ks, tr = sheet_response(s, U, nonlinear, tangent, sl, committed.sheets[k].take(slice(lo * q, hi * q)),
                                    fast, into)
        if not fast:
            f = f + fs
            if tangent:
                K = K + Ks
        trial_sheets.append(tr[0])
        strains.append(tr[1])
        stresses.append(tr[2])
    return f, K, LayerState(trial_bulk, tuple(trial_sheets), out.get("strain"), tuple(strains), tuple(stresses))


def put_trial(full: LayerState, block: InelasticBlock, sl: slice, part: LayerState) -> None:
    """Write the trial state ``part`` of the elements ``sl`` into the block-wide ``full``."""
    lo, hi, _ = sl.indices(block.h_in.shape[0])
    if part.bulk is not None:
        P = block.n_points
        _put(full.bulk, slice(lo * P, hi * P), part.bulk)
        full.strain[lo * P:hi * P] = part.strain
    for k, s in enumerate(block.sheets):
        q = s.w.shape[1]
        _put(full.sheets[k], slice(lo * q, hi * q), part.sheets[k])
        full.sheet_strain[k][lo * q:hi * q] = part.sheet_strain[k]
        full.sheet_stress[k][lo * q:hi * q] = part.sheet_stress[k]


def point_stress(model, k: int, elements: np.ndarray, xi: np.ndarray, eta: np.ndarray, s: np.ndarray,
                 E: np.ndarray) -> np.ndarray:
    """The law's PK2 stress ``(p, 6)`` of layer ``k`` at strains ``E (p, 6)`` of points in
    ``elements`` at (ξ, η) and layer fraction ``s`` (0 bottom, 1 top), each with the committed
    state of the element's nearest integration point (``model.point_states``)."""
    from .quadrature import gauss_1d

    out = np.full(E.shape, np.nan)
    gp, _ = gauss_2d(3)
    iq = np.argmin((gp[None, :, 0] - xi[:, None]) ** 2 + (gp[None, :, 1] - eta[:, None]) ** 2, axis=1)
    for blk_elements, blk, st in model.point_states.get(k, ()):
        if blk.law is None:
            continue
        pos = np.searchsorted(blk_elements, elements)
        inside = (pos < blk_elements.size) & (blk_elements[np.minimum(pos, blk_elements.size - 1)] == elements)
        if not inside.any():
            continue
        nz = blk.n_points // 9
        zeta, _ = gauss_1d(nz)
        iz = np.argmin(np.abs((zeta[None, :] + 1) / 2 - s[inside, None]), axis=1)
        j = iz * 9 + iq[inside] if not isinstance(blk.base, LayerBlock) else iq[inside] * nz + iz
        e = pos[inside]
        flat = e * blk.n_points + j
        c = st.bulk.take(flat)
        S, _, _ = blk.law.response(E[inside], c, blk.h_in[e, j], blk.h_z[e, j], blk.normal[e, j], False)
        out[inside] = S
    return out


def layer_point_values(model, k: int, quantity: str, sheet: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Values at the integration points of layer ``k`` in the committed state and the element of
    each point: ``crack_width`` (the law's crack width, 0 where uncracked), ``rebar_stress`` or
    ``rebar_strain`` of the sheet named ``sheet`` (None: every sheet of the layer)."""
    vals, els = [], []
    for blk_elements, blk, st in model.point_states.get(k, ()):
        if quantity == "crack_width":
            if blk.law is None or not hasattr(blk.law, "crack"):
                continue
            w, _ = blk.law.crack(st.strain, st.bulk)
            vals.append(np.asarray(w, float))
            els.append(np.repeat(blk_elements, blk.n_points))
            continue
        for j, s in enumerate(blk.sheets):
            if sheet is not None and s.name != sheet:
                continue
            vals.append(st.sheet_stress[j] if quantity == "rebar_stress" else st.sheet_strain[j])
            els.append(np.repeat(blk_elements, s.w.shape[1]))
    if not vals:
        return np.zeros(0), np.zeros(0, np.int64)
    return np.concatenate(vals), np.concatenate(els)
