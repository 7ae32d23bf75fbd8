"""Compiled tangent of the concrete law (:meth:`layershell.laws.ConcreteLaw.response`; Numba,
``cache=True``): one pass per point instead of a dozen batched NumPy operations, each of which
writes an (n, 6) or (n, 6, 6) temporary.

:func:`split_tangent` forms, per point, with the eigenvalues w, eigenvectors V and projections
P_k = v_k ⊗ v_k (Voigt) of the effective stress σ̄ = C0 ε,

    M = d[(1 − d⁺) σ̄⁺ + (1 − d⁻) σ̄⁻]/dσ̄ at frozen damage (:func:`split_coefficients`, the
        isotropic derivative Bᵀ diag(a, θ) B of :func:`layershell.laws.spectral.isotropic_derivative`),
    M −= σ̄⁺ ⊗ g⁺ + σ̄⁻ ⊗ g⁻ (the damage's own variation; ``rank2``), g± = (Σ_k γ±_k P_k) ∘ WEIGHT + e±,

and returns M C0 (dσ/dε), C0 = λ 1 ⊗ 1 + 2μ 𝕀 the isotropic elasticity.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ._spectral_jit import voigt_basis



@njit(cache=True, nogil=True, inline="always")
def split_coefficients(wi, wj, kt, kc):  # pragma: no cover
    """θ_ij = ((1 − d_i) ⟨w_i⟩± − (1 − d_j) ⟨w_j⟩±)/(w_i − w_j) of one pair, in the form of
    ``ConcreteLaw._split_derivative``: kt φ + kc (1 − φ), φ the share of the pair's positive parts."""
    oni, onj = wi > 0, wj > 0
    if oni and onj:
        phi = 1.0
    elif not oni and not onj:
        phi = 0.0
    else:
        dw = wi - wj
        dp = max(wi, 0.0) - max(wj, 0.0)
        phi = dp / (dw if dw != 0 else 1.0)
    return kt * phi + kc * (1.0 - phi)


@njit(cache=True, nogil=True)
def split_tangent(V, w, P, d_t, d_c, rank2, g_t, g_c, e_t, sbar, lam, mu, out):  # pragma: no cover
    """out (n, 6, 6) = dσ/dε (module docstring). ``g_t``, ``g_c`` (n, 3): the coefficients γ± of
    the rows g± on the projections; ``e_t`` (n, 6): an extra row added to g⁺ (the crack band's
    variation at onset; zeros elsewhere); ``sbar`` (n, 6) σ̄. Without ``rank2`` only M C0 at frozen
    damage (``g_t``, ``g_c``, ``e_t`` unused). ``lam``, ``mu``: the Lamé constants of C0."""
    B = np.empty((6, 6))
    Bc = np.empty((6, 6))
    c = np.empty(6)
    M = np.empty((6, 6))
    gt = np.empty(6)
    gc = np.empty(6)
    sp = np.empty(6)
    pairs = ((0, 1), (0, 2), (1, 2))
    for n in range(V.shape[0]):
        kt, kc = 1.0 - d_t[n], 1.0 - d_c[n]
        for k in range(3):
            c[k] = kt if w[n, k] > 0 else kc
        for p in range(3):
            i, j = pairs[p]
            c[3 + p] = split_coefficients(w[n, i], w[n, j], kt, kc)
        voigt_basis(V, n, B)
        for b in range(6):
            for a in range(6):
                Bc[b, a] = B[b, a] * c[b]
        for a in range(6):  # Bᵀ diag(c) B is symmetric: its upper triangle, mirrored
            for d in range(a, 6):
                s = 0.0
                for b in range(6):
                    s += Bc[b, a] * B[b, d]
                M[a, d] = s
                M[d, a] = s
        for a in range(6):
            for d in range(3, 6):
                M[a, d] *= 2.0
        if rank2:
            for a in range(6):
                wgt = 1.0 if a < 3 else 2.0
                st = 0.0
                sc = 0.0
                spa = 0.0
                for k in range(3):
                    st += g_t[n, k] * P[n, k, a]
                    sc += g_c[n, k] * P[n, k, a]
                    spa += max(w[n, k], 0.0) * P[n, k, a]
                gt[a] = st * wgt + e_t[n, a]
                gc[a] = sc * wgt
                sp[a] = spa
            for a in range(6):
                sn = sbar[n, a] - sp[a]
                for d in range(6):
                    M[a, d] -= sp[a] * gt[d] + sn * gc[d]
        for a in range(6):  # M C0 with the isotropic C0 = λ 1 ⊗ 1 + μ diag(2, 2, 2, 1, 1, 1)
            tr = lam * (M[a, 0] + M[a, 1] + M[a, 2])
            for d in range(3):
                out[n, a, d] = tr + 2.0 * mu * M[a, d]
            for d in range(3, 6):
                out[n, a, d] = mu * M[a, d]


@njit(cache=True, nogil=True)
def damage_compression1(r, h, E, f_c, eps_c1, G_c):  # pragma: no cover
    """d⁻(r; h) and ∂d⁻/∂r of one point: ``ConcreteLaw.damage_compression`` (Sargin secant to the
    peak E ε_c1, exponential beyond)."""
    rp, k = E * eps_c1, E * eps_c1 / f_c
    eta = min(max(r / rp, 0.0), 1.0)
    den = 1.0 + (k - 2.0) * eta
    if not r > rp:
        return 1.0 - (k - eta) / (k * den), (k - 1.0) ** 2 / (k * den * den) / rp
    inv_es = (h if h > 0 else 1.0) * f_c / G_c
    sig = f_c * np.exp(-(r / E - eps_c1) * inv_es)
    keep = sig / r
    return 1.0 - keep, sig / r ** 2 + keep * inv_es / E


@njit(cache=True, nogil=True)
def histories(w, r_c0, r_t0, h_c, E, f_c, eps_c1, G_c, alpha, kappa,
              r_c, d_c, ddc, r_t, load_t, dtau_t):  # pragma: no cover
    """Per point from the effective principal stresses ``w`` (n, 3) ascending and the committed
    histories ``r_c0``, ``r_t0``: the compression's τ⁻ = (α Ī1⁻ + √(3 J̄2⁻))/(1 − α), history r_c,
    damage d_c and dd⁻/dw (``ddc``); the tension's τ⁺ = ⟨w_3⟩/(1 − κ q⁻/f_c) with q⁻ = (1 − d⁻) τ⁻,
    its history r_t, whether it loads (``load_t``) and dτ⁺/dw (``dtau_t``)
    (``ConcreteLaw._compression`` and the tension part of ``ConcreteLaw._update``)."""
    dev = np.empty(3)
    dtau = np.empty(3)
    for n in range(w.shape[0]):
        m0, m1, m2 = min(w[n, 0], 0.0), min(w[n, 1], 0.0), min(w[n, 2], 0.0)
        i1 = m0 + m1 + m2
        dev[0], dev[1], dev[2] = m0 - i1 / 3.0, m1 - i1 / 3.0, m2 - i1 / 3.0
        s3j2 = np.sqrt(1.5 * (dev[0] * dev[0] + dev[1] * dev[1] + dev[2] * dev[2]))
        tau = (alpha * i1 + s3j2) / (1 - alpha)
        for k in range(3):
            dk = (alpha + (1.5 * dev[k] / s3j2 if s3j2 > 0 else 0.0)) / (1 - alpha)
            dtau[k] = dk if w[n, k] < 0 else 0.0
        load = tau > r_c0[n]
        r = tau if load else r_c0[n]
        d, dd = damage_compression1(r, h_c[n], E, f_c, eps_c1, G_c)
        r_c[n], d_c[n] = r, d
        tp = max(tau, 0.0)
        q = (1.0 - d) * tp
        rho = 1.0 - kappa * q / f_c
        pos = w[n, 2] > 0
        tau_t = (w[n, 2] if pos else 0.0) / rho
        ft = tau_t * kappa / (f_c * rho)
        for k in range(3):
            ddc[n, k] = (dd if load else 0.0) * dtau[k]
            dq = ((1.0 - d) if tau > 0 else 0.0) * dtau[k] - tp * ddc[n, k]
            dtau_t[n, k] = ft * dq
        if pos:
            dtau_t[n, 2] += 1.0 / rho
        load_t[n] = tau_t > r_t0[n]
        r_t[n] = tau_t if load_t[n] else r_t0[n]
