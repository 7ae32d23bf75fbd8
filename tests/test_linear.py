"""Sparse linear solvers: PARDISO (symmetric indefinite, symbolic analysis reused) and SuperLU give
the same solution as a dense solve; singular systems are reported, not returned."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from layershell.solver import linear

BACKENDS = ["superlu"] + (["pardiso"] if linear.backend_name("auto") == "pardiso" else [])


def _laplacian_2d(n: int, shift: float = 0.0) -> sp.csr_matrix:
    T = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(n, n))
    return (sp.kron(T, sp.eye(n)) + sp.kron(sp.eye(n), T) - shift * sp.eye(n * n)).tocsr()


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("shift", [0.0, 1.3])  # SPD, and symmetric indefinite (eigenvalues < 0)
def test_solution_matches_dense(backend, shift):
    K = _laplacian_2d(12, shift)
    r = np.random.default_rng(0).normal(size=K.shape[0])
    x = linear.LinearSolver(backend).solve(K, r)
    assert np.allclose(x, np.linalg.solve(K.toarray(), r), rtol=1e-9, atol=1e-12)


@pytest.mark.skipif("pardiso" not in BACKENDS, reason="pypardiso/MKL not available")
def test_pardiso_reuses_analysis_and_reports_inertia():
    s = linear.LinearSolver("pardiso")
    K = _laplacian_2d(10)
    r = np.ones(K.shape[0])
    s.solve(K, r)
    assert s.info.analysed and s.info.negative_pivots == 0
    K2 = K.copy()
    K2.data = K2.data * 1.7 + 0.0  # same pattern, new values: no new analysis, new factorisation
    K2 = (K2 - 1.3 * 1.7 * sp.eye(K.shape[0])).tocsr()
    K2.sort_indices()
    x = s.solve(K2, r)
    assert not s.info.analysed
    assert np.allclose(K2 @ x, r, rtol=1e-9, atol=1e-10)
    # negative eigenvalues of K2 = number of negative pivots (Sylvester's law of inertia)
    assert s.info.negative_pivots == int((np.linalg.eigvalsh(K2.toarray()) < 0).sum()) > 0
    K3 = _laplacian_2d(11)  # new pattern: analysed again
    s.solve(K3, np.ones(K3.shape[0]))
    assert s.info.analysed


@pytest.mark.parametrize("backend", BACKENDS)
def test_singular_system_is_reported(backend):
    T = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(30, 30)).tolil()
    T[0, 0] = T[-1, -1] = 1.0  # free-free bar: rigid-body mode
    with pytest.raises(linear.SingularSystemError):
        linear.LinearSolver(backend).solve(T.tocsr(), np.linspace(1, 2, 30))


def test_unknown_backend_is_rejected():
    with pytest.raises(ValueError, match="unknown linear solver"):
        linear.backend_name("umfpack")


def _laplacian_3d(n: int) -> sp.csr_matrix:
    T = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(n, n))
    eye = sp.eye(n)
    return (sp.kron(sp.kron(T, eye), eye) + sp.kron(sp.kron(eye, T), eye) + sp.kron(sp.kron(eye, eye), T)).tocsr()


@pytest.mark.skipif("pardiso" not in BACKENDS, reason="pypardiso/MKL not available")
@pytest.mark.parametrize("case", ["shell-like 2D", "3D grid"])
def test_pardiso_parameters_take_effect_and_auto_ordering_takes_the_cheaper(case):
    """PARDISO is called with its parameters applied (iparm[0] = 1): the two orderings give
    different factors, "auto" keeps the one with fewer flops (then the smaller factor) - minimum
    degree for a 3-DOF-per-node 2D pattern, METIS for a 3D grid - and the solution is the same;
    refinement runs only after perturbed pivots, and indices are zero-based."""
    K = (sp.kron(_laplacian_2d(14, 0.5), np.ones((3, 3)) + 3 * np.eye(3)).tocsr() if case == "shell-like 2D"
         else _laplacian_3d(8))
    r = np.random.default_rng(1).normal(size=K.shape[0])
    stats = {}
    for name in ("metis", "mmd"):
        s = linear.PardisoSymmetric(ordering=name)
        x = s.solve(K, r)
        assert np.allclose(K @ x, r, rtol=1e-9, atol=1e-9 * np.abs(r).max())
        stats[name] = (int(s._s.iparm[18]), int(s._s.iparm[17]))  # MFLOP, factor nonzeros
        ip = s._s.iparm
        assert ip[0] == 1 and ip[34] == 1 and ip[7] == 0 and ip[1] == linear.ORDERINGS[name]
        s.release()
    assert stats["metis"] != stats["mmd"]  # the ordering parameter reached PARDISO
    best = min(stats, key=stats.get)
    assert best == ("mmd" if case == "shell-like 2D" else "metis")
    auto = linear.PardisoSymmetric()
    x = auto.solve(K, r)
    assert auto._s.iparm[1] == linear.ORDERINGS[best] and int(auto._s.iparm[17]) == stats[best][1]
    assert np.allclose(K @ x, r, rtol=1e-9, atol=1e-9 * np.abs(r).max())
    x2 = auto.solve(K, 2 * r)  # same pattern: the chosen analysis is reused
    assert not auto.info.analysed and np.allclose(x2, 2 * x)
    with pytest.raises(ValueError, match="ordering"):
        linear.PardisoSymmetric(ordering="amd")


@pytest.mark.parametrize("backend", BACKENDS)
def test_unsymmetric_matrix_takes_the_general_path(backend):
    K = _laplacian_2d(9, 0.7).tolil()
    K[3, 4] += 0.3  # unsymmetric
    K = K.tocsr()
    r = np.random.default_rng(2).normal(size=K.shape[0])
    s = linear.LinearSolver(backend)
    x = s.solve(K, r)
    assert np.allclose(x, np.linalg.solve(K.toarray(), r), rtol=1e-9, atol=1e-12)
    if backend == "pardiso":
        assert list(s._pardiso) == [False]  # general mode (mtype 11) only


@pytest.mark.skipif("pardiso" not in BACKENDS, reason="pypardiso/MKL not available")
def test_ordering_choice_is_shared_by_pattern(monkeypatch):
    """Solvers sharing a decision table (one problem's, started afresh every load step) compare
    the orderings once per pattern: a new solver on a known pattern analyses only once, with the
    same choice; a new pattern is compared again."""
    analyses = []
    raw = linear.PardisoSymmetric._raw

    def counting(self, A, phase, b):
        if phase == 11:
            analyses.append(int(self._s.iparm[1]))
        return raw(self, A, phase, b)

    monkeypatch.setattr(linear.PardisoSymmetric, "_raw", counting)
    decisions: dict = {}
    K = _laplacian_3d(8)
    r = np.ones(K.shape[0])
    x1 = linear.LinearSolver("pardiso", decisions=decisions).solve(K, r)
    assert len(analyses) == 3 and len(decisions) == 1  # METIS, minimum degree, then the choice (METIS)
    analyses.clear()
    x2 = linear.LinearSolver("pardiso", decisions=decisions).solve(K, r)
    assert analyses == [linear.ORDERINGS["metis"]] and np.array_equal(x1, x2)
    analyses.clear()
    linear.LinearSolver("pardiso", decisions=decisions).solve(_laplacian_3d(7), np.ones(343))
    assert len(analyses) >= 2 and len(decisions) == 2
