"""Inelastic layers in the element kernels (element/inelastic.py): a law that is the elastic
material reproduces the elastic kernels (full and MITC9), the tangents of nonlinear laws and of
reinforcement sheets equal finite differences of the forces, and a sheet's axial stiffness adds
E_s A_s to the layer's."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from layershell.element.inelastic import initial_state, inelastic_block, inelastic_response, put_trial
from layershell.element.kernel import layer_block, layer_response_reference
from layershell.element.shape import NODE_XI
from layershell.laws import PointState
from layershell.material import Orthotropic


@dataclass(frozen=True)
class _Hist(PointState):
    emax: np.ndarray


class _CubicBulk:
    """S = C E + β (E·E) E + γ (a·E) E with an irreversible history max |E| (a nonlinear law with a
    state; γ ≠ 0: an unsymmetric tangent)."""

    def __init__(self, mat: Orthotropic, beta: float, gamma: float = 0.0):
        self.C, self.beta, self.gamma = mat.stiffness(), beta, gamma
        self.a = np.array([1.0, -0.5, 0.3, 0.7, -0.2, 0.4])

    def state(self, n):
        return _Hist(np.zeros(n))

    def response(self, eps, committed, h_in, h_z, normal, tangent=True, strain_n=None):
        assert eps.shape[0] == h_in.shape[0] == h_z.shape[0] == normal.shape[0]
        assert strain_n is None or strain_n.shape == eps.shape  # the committed strain, for laws that use it
        e2 = np.einsum("pv,pv->p", eps, eps)
        ae = eps @ self.a
        S = eps @ self.C.T + (self.beta * e2 + self.gamma * ae)[:, None] * eps
        D = None
        if tangent:
            D = (self.C[None] + self.beta * (e2[:, None, None] * np.eye(6) + 2 * eps[:, :, None] * eps[:, None, :])
                 + self.gamma * (ae[:, None, None] * np.eye(6) + eps[:, :, None] * self.a[None, None, :]))
        return S, D, _Hist(np.maximum(committed.emax, np.sqrt(e2)))


class _CubicSheet:
    symmetric = True

    def __init__(self, E, c):
        self.E, self.c = E, c

    def state(self, n):
        return _Hist(np.zeros(n))

    def response(self, eps, committed, tangent=True):
        return (self.E * eps + self.c * eps ** 3, (self.E + 3 * self.c * eps ** 2) if tangent else None,
                _Hist(np.maximum(committed.emax, np.abs(eps))))


def _geometry(n_el=3, seed=0):
    rng = np.random.default_rng(seed)
    xi, eta = NODE_XI.T
    X = np.zeros((n_el, 9, 3))
    for e in range(n_el):
        X[e, :, 0] = 2.0 * e + xi + 0.05 * rng.standard_normal(9)
        X[e, :, 1] = 0.8 * eta + 0.05 * rng.standard_normal(9)
        X[e, :, 2] = 0.1 * xi * eta + 0.02 * rng.standard_normal(9)
    Hb = np.full((n_el, 9), 0.05)
    H = 0.2 + 0.01 * rng.random((n_el, 9))
    return X, Hb, H


MAT = Orthotropic.isotropic(30000.0, 0.2)


@pytest.mark.parametrize("element", ["full", "mitc"])
@pytest.mark.parametrize("d", [1, 2])
def test_elastic_law_reproduces_the_elastic_kernel(element, d):
    X, Hb, H = _geometry()
    blk = inelastic_block(X, Hb, H, d, MAT, _CubicBulk(MAT, 0.0), (), 3, element)
    ref = layer_block(X, Hb, H, d, MAT, n_thickness=3, element=element)
    U = 0.02 * np.random.default_rng(1).standard_normal((3, 9 * (d + 1), 3))
    f, K, _ = inelastic_response(blk, U, True, True, slice(None), initial_state(blk))
    f0, K0 = layer_response_reference(ref, U, True, True)
    assert np.abs(f - f0).max() < 1e-10 * np.abs(f0).max()
    assert np.abs(K - K0).max() < 1e-10 * np.abs(K0).max()


def _fd_check(blk, U, state, h=1e-7):
    f, K, _ = inelastic_response(blk, U, True, True, slice(None), state)
    Kfd = np.zeros_like(K)
    flat = U.reshape(U.shape[0], -1)
    for j in range(flat.shape[1]):
        up, um = flat.copy(), flat.copy()
        up[:, j] += h
        um[:, j] -= h
        fp, _, _ = inelastic_response(blk, up.reshape(U.shape), True, False, slice(None), state)
        fm, _, _ = inelastic_response(blk, um.reshape(U.shape), True, False, slice(None), state)
        Kfd[:, :, j] = (fp - fm) / (2 * h)
    return np.abs(K - Kfd).max() / np.abs(K).max()


@pytest.mark.parametrize("element", ["full", "mitc"])
def test_tangent_of_a_nonlinear_law_with_sheets_equals_finite_differences(element):
    X, Hb, H = _geometry(2)
    sheets = (("bars x", _CubicSheet(200000.0, 5e7), 0.04, 0.003, 0.0, (1.0, 0.0, 0.0)),
              ("bars 30", _CubicSheet(200000.0, -3e7), 0.15, 0.002, 30.0, None))
    blk = inelastic_block(X, Hb, H, 1, MAT, _CubicBulk(MAT, 4e6, 3e5), sheets, 3, element)
    U = 0.01 * np.random.default_rng(2).standard_normal((2, 18, 3))
    K = inelastic_response(blk, U, True, True, slice(None), initial_state(blk))[1]
    assert np.abs(K - K.transpose(0, 2, 1)).max() > 1e-3 * np.abs(K).max()  # the unsymmetric tangent is kept
    assert _fd_check(blk, U, initial_state(blk)) < 1e-6


def _flat(n_el=3):
    """Flat rectangular elements with straight edges (the MITC9 tie correction is round-off)."""
    xi, eta = NODE_XI.T
    X = np.stack([np.stack([1.5 * e + 0.75 * (1 + xi), 0.5 * (1 + eta), 0 * xi], -1) for e in range(n_el)])
    return X, np.full((n_el, 9), 0.05), np.full((n_el, 9), 0.2)


@pytest.mark.parametrize("mesh", ["distorted", "flat"])
@pytest.mark.parametrize("nonlinear", [True, False])
@pytest.mark.parametrize("d", [1, 2])
@pytest.mark.parametrize("element", ["full", "mitc"])
def test_compiled_kernel_equals_the_plain_forms(element, d, nonlinear, mesh):
    """The compiled bulk kernel (element/inelastic_kernel.py) against the layer kernels' plain
    NumPy forms with the same law: forces, the unsymmetric tangent, the trial state and strains of
    an element range, with sheets, from a committed state with history."""
    _compare_with_plain_forms(element, d, nonlinear, mesh, 3)


def test_compiled_mitc_strain_pass_at_cubic_directors():
    """d = 3 (director powers up to (Θ³)³ in the strain pass's derivatives along the frame
    directions, from the natural derivatives of the nodal vectors) on the distorted mesh."""
    _compare_with_plain_forms("mitc", 3, True, "distorted", 4)


def test_compiled_mitc_kernel_sums_its_product_in_pieces():
    """d = 2 with 6 thickness points: the MITC9 product Bᵀ G (6 · 37 + 18 rows of 81 columns) is
    summed over pieces (_jit_inelastic.PRODUCT_ENTRIES), equal to the plain forms."""
    from layershell.element._jit_inelastic import PRODUCT_ENTRIES

    assert (6 * 37 + 18) * 81 > PRODUCT_ENTRIES
    _compare_with_plain_forms("mitc", 2, True, "distorted", 6)


def _compare_with_plain_forms(element, d, nonlinear, mesh, nz):
    n_el = 11
    X, Hb, H = _geometry(n_el, seed=4) if mesh == "distorted" else _flat(n_el)
    sheets = (("bars x", _CubicSheet(200000.0, 5e7), 0.04, 0.003, 0.0, (1.0, 0.0, 0.0)),
              ("bars 30", _CubicSheet(200000.0, -3e7), 0.15, 0.002, 30.0, None))
    blk = inelastic_block(X, Hb, H, d, MAT, _CubicBulk(MAT, 4e6, 3e5), sheets, nz, element)
    if element == "mitc":  # the tie correction: exercised on the distorted mesh, round-off on the flat one
        v = np.abs(blk.base.v).max()
        assert (v > 1e-3) if mesh == "distorted" else (v < 1e-12)
    rng = np.random.default_rng(5)
    U = 0.01 * rng.standard_normal((n_el, 9 * (d + 1), 3))
    c = initial_state(blk)
    put_trial(c, blk, slice(None), inelastic_response(blk, 0.7 * U, nonlinear, False, slice(None), c)[2])
    sl = slice(2, 11)
    for tangent in (True, False):
        f0, K0, t0 = inelastic_response(blk, U[sl], nonlinear, tangent, sl, c, fast=False)
        f1, K1, t1 = inelastic_response(blk, U[sl], nonlinear, tangent, sl, c, fast=True)
        assert np.abs(f1 - f0).max() < 1e-12 * np.abs(f0).max()
        assert np.abs(t1.strain - t0.strain).max() < 1e-12 * np.abs(t0.strain).max()
        assert np.abs(t1.bulk.emax - t0.bulk.emax).max() < 1e-12 * t0.bulk.emax.max()
        assert np.any(t0.bulk.emax > c.bulk.emax[2 * blk.n_points:])  # some points load beyond their history
        if tangent:
            assert np.abs(K1 - K0).max() < 1e-12 * np.abs(K0).max()
        else:
            assert K1 is None and K0 is None


def test_trial_state_is_written_per_element_range_and_committed_state_untouched():
    X, Hb, H = _geometry(3)
    sheets = (("bars", _CubicSheet(200000.0, 0.0), 0.1, 0.003, 0.0, None),)
    blk = inelastic_block(X, Hb, H, 1, MAT, _CubicBulk(MAT, 1e5), sheets, 3, "mitc")
    U = 0.01 * np.random.default_rng(3).standard_normal((3, 18, 3))
    c = initial_state(blk)
    whole = inelastic_response(blk, U, True, False, slice(None), c)[2]
    full = c.copy()
    for lo in range(3):
        put_trial(full, blk, slice(lo, lo + 1), inelastic_response(blk, U[lo:lo + 1], True, False,
                                                                   slice(lo, lo + 1), c)[2])
    assert np.array_equal(full.bulk.emax, whole.bulk.emax) and np.array_equal(full.sheets[0].emax, whole.sheets[0].emax)
    assert not np.any(c.bulk.emax) and np.all(whole.bulk.emax > 0)


def test_sheet_adds_its_axial_stiffness():
    """A flat strip (length 2, width 1) pulled by a uniform axial strain: the axial force is
    (E h + E_s A_s) ε per unit width (plane stress in y free: ν enters the layer's share only)."""
    xi, eta = NODE_XI.T
    X = np.stack([1 + xi, 0.5 + 0.5 * eta, 0 * xi], -1)[None]
    H = np.full((1, 9), 0.2)
    Hb = np.zeros((1, 9))
    Es, As = 200000.0, 0.004
    with_sheet = inelastic_block(X, Hb, H, 1, MAT, None, (("bars", _CubicSheet(Es, 0.0), 0.05, As, 0.0, (1, 0, 0)),),
                                 3, "mitc")
    bare = inelastic_block(X, Hb, H, 1, MAT, None, (), 3, "mitc")
    eps = 1e-4
    U = np.zeros((1, 18, 3))
    U[0, 0::2, 0] = eps * X[0, :, 0]  # director 0 (node-major, then director)
    f1 = inelastic_response(with_sheet, U, False, False, slice(None), initial_state(with_sheet))[0]
    f0 = inelastic_response(bare, U, False, False, slice(None), initial_state(bare))[0]
    right = X[0, :, 0] > 1.99
    df = (f1 - f0).reshape(9, 2, 3)[right, :, 0]
    assert df[:, 0].sum() == pytest.approx(Es * As * eps * 1.0, rel=1e-10)  # the force on director 0
    assert df[:, 1].sum() == pytest.approx(Es * As * eps * 0.05, rel=1e-10)  # its moment Θ_L N on director 1


@pytest.mark.parametrize("element", ["full", "mitc"])
def test_compiled_kernel_splits_elements_over_threads(element, monkeypatch):
    """Elements over 3 threads (40 elements: 3 ranges of sub-blocks) give the one-thread result."""
    X, Hb, H = _geometry(40, seed=6)
    blk = inelastic_block(X, Hb, H, 1, MAT, _CubicBulk(MAT, 4e6, 3e5), (), 3, element)
    U = 0.01 * np.random.default_rng(7).standard_normal((40, 18, 3))
    out = {}
    for n in ("1", "3"):
        monkeypatch.setenv("LAYERSHELL_THREADS", n)
        out[n] = inelastic_response(blk, U, True, True, slice(None), initial_state(blk))
    assert np.array_equal(out["1"][0], out["3"][0]) and np.array_equal(out["1"][1], out["3"][1])
    K0 = inelastic_response(blk, U, True, True, slice(None), initial_state(blk), fast=False)[1]
    assert np.abs(out["3"][1] - K0).max() < 1e-12 * np.abs(K0).max()


def test_blas_limit_reaches_the_blas_of_the_compiled_products():
    """The compiled MITC9 and sheet products call SciPy's BLAS (Numba's np.dot), a library apart
    from NumPy's: held to one thread with NumPy's by ``blas_single_thread`` even where the limit's
    controller is made before SciPy's BLAS is loaded (checked in a fresh process, BLAS threads 2)."""
    import os
    import subprocess
    import sys

    code = ("from layershell.threads import blas_single_thread\n"
            "from threadpoolctl import threadpool_info\n"
            "with blas_single_thread():\n"
            "    import scipy.linalg.cython_blas\n"
            "    libs = [(i['filepath'], i['num_threads']) for i in threadpool_info() if i['user_api'] == 'blas']\n"
            "print(len(libs), max(n for _, n in libs))\n")
    env = {**os.environ, "OMP_NUM_THREADS": "2", "OPENBLAS_NUM_THREADS": "2"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env).stdout.split()
    assert int(out[0]) >= 2 and int(out[1]) == 1
