"""Fast layer kernel (factored syrk form, compiled point loops, threads) against the plain NumPy
form of (2.267)-(2.268), ``layer_response_reference`` — MODEL.md §5, issue 6."""
import dataclasses

import numpy as np
import pytest
from conftest import curved_element

from layershell.element import kernel
from layershell.element.kernel import (layer_block, layer_response, layer_response_reference,
                                       stiffness_factor)
from layershell.material import Orthotropic

ORTHO = Orthotropic(100.0, 50.0, 30.0, 20.0, 15.0, 10.0, 0.25, 0.3, 0.1)


def _block(rng, d, n_el=21):
    """n_el distorted curved elements (different per element), variable thickness, rotated material."""
    X = np.concatenate([curved_element(rng, R=2.0 + k, distort=0.12) for k in range(n_el)])
    H = 0.3 + 0.03 * rng.standard_normal((n_el, 9))
    return layer_block(X, np.full((n_el, 9), 0.05), H, d, ORTHO, angle_deg=35.0, n_thickness=max(3, d))


def _rel(a, b):
    return np.abs(a - b).max() / np.abs(b).max()


@pytest.mark.parametrize("d", [0, 1, 2, 3, 4])
@pytest.mark.parametrize("nonlinear", [True, False])
def test_fast_kernel_equals_reference(rng, d, nonlinear):
    """Large displacements, several elements (crossing sub-block and thread boundaries)."""
    blk = _block(rng, d)
    U = 0.08 * rng.standard_normal((21, 9 * (d + 1), 3))
    f0, K0 = layer_response_reference(blk, U, nonlinear)
    f1, K1 = layer_response(blk, U, nonlinear)
    assert _rel(f1, f0) < 1e-13 and _rel(K1, K0) < 1e-13
    f2, K2 = layer_response(blk, U, nonlinear, tangent=False)
    assert K2 is None and np.array_equal(f2, f1)
    # the tangent is exactly symmetric in its material part, to round-off with the geometric one
    assert _rel(K1, np.swapaxes(K1, 1, 2)) < 1e-14
    # the comparison can fail: a 1e-6 change of one displacement is seen by both outputs
    U[3, 5, 1] += 1e-6
    f3, K3 = layer_response(blk, U, nonlinear)
    assert _rel(f3, f0) > 1e-12 and (_rel(K3, K0) > 1e-12 or not nonlinear)


def test_element_range_and_threads_do_not_change_results(rng, monkeypatch):
    """``sl`` selects elements; 1 or 3 threads give bit-identical results (per-element work)."""
    blk = _block(rng, 2, n_el=40)
    U = 0.05 * rng.standard_normal((40, 27, 3))
    monkeypatch.setenv("LAYERSHELL_THREADS", "1")
    f1, K1 = layer_response(blk, U)
    monkeypatch.setenv("LAYERSHELL_THREADS", "3")
    f3, K3 = layer_response(blk, U)
    assert np.array_equal(f1, f3) and np.array_equal(K1, K3)
    fs, Ks = layer_response(blk, U[11:29], sl=slice(11, 29))
    assert _rel(fs, f1[11:29]) < 1e-15 and _rel(Ks, K1[11:29]) < 1e-15


def test_stiffness_factor(rng):
    """C dV = L Lᵀ with L lower triangular; no factor when C dV is not positive definite."""
    blk = _block(rng, 1, n_el=3)
    L = blk.L
    assert np.allclose(L @ np.swapaxes(L, -1, -2), blk.C * blk.dV[..., None, None], rtol=1e-14,
                       atol=1e-14 * np.abs(blk.C).max())
    assert np.all(np.triu(L, 1) == 0)
    assert stiffness_factor(blk.C, -blk.dV) is None
    C_bad = blk.C.copy()
    C_bad[1, 4, 2, 2] = -1.0  # indefinite at one point
    assert stiffness_factor(C_bad, blk.dV) is None


@pytest.mark.parametrize("nonlinear", [True, False])
def test_general_product_without_factor(rng, nonlinear):
    """Blocks without a Cholesky factor (C dV not positive definite) use K = Bᵀ (B C dV)."""
    blk = _block(rng, 3, n_el=10)
    U = 0.05 * rng.standard_normal((10, 36, 3))
    nofac = dataclasses.replace(blk, L=None)
    f0, K0 = layer_response_reference(nofac, U, nonlinear)
    f1, K1 = layer_response(nofac, U, nonlinear)
    assert _rel(f1, f0) < 1e-13 and _rel(K1, K0) < 1e-13
    # an indefinite C (not admissible physically, but the algebra must still hold)
    C = blk.C.copy()
    C[..., 0, 0] *= -1.0
    bad = dataclasses.replace(blk, C=C, L=stiffness_factor(C, blk.dV))
    assert bad.L is None
    f0, K0 = layer_response_reference(bad, U, nonlinear)
    f1, K1 = layer_response(bad, U, nonlinear)
    assert _rel(f1, f0) < 1e-13 and _rel(K1, K0) < 1e-13


def test_blas_thread_setting_is_restored(rng):
    threadpoolctl = pytest.importorskip("threadpoolctl")
    before = [i["num_threads"] for i in threadpoolctl.threadpool_info() if i["user_api"] == "blas"]
    blk = _block(rng, 0, n_el=20)
    layer_response(blk, 0.01 * rng.standard_normal((20, 9, 3)))
    after = [i["num_threads"] for i in threadpoolctl.threadpool_info() if i["user_api"] == "blas"]
    assert before == after


def test_thread_count_from_environment(monkeypatch):
    monkeypatch.setenv("LAYERSHELL_THREADS", "3")
    assert kernel.kernel_threads() == 3
    monkeypatch.delenv("LAYERSHELL_THREADS")
    monkeypatch.setenv("NUMBA_NUM_THREADS", "1")
    assert kernel.kernel_threads() == 1
