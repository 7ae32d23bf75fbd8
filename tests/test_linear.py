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


def _convection_2d(n: int, c: float) -> sp.csr_matrix:
    """An unsymmetric (convection-diffusion) matrix: the Laplacian plus c × a one-sided difference."""
    D = sp.diags([-1.0, 1.0], [-1, 0], shape=(n, n))
    return (_laplacian_2d(n) + c * sp.kron(sp.eye(n), D)).tocsr()


def _check_solution(K, X, R):
    """Each column of X solves K x = r to GMRES's tolerance (KRYLOV_RTOL), against a dense solve."""
    exact = np.linalg.solve(K.toarray(), R)
    X2, E2, R2 = X.reshape(len(X), -1), exact.reshape(len(X), -1), R.reshape(len(X), -1)
    for j in range(X2.shape[1]):
        assert np.linalg.norm(K @ X2[:, j] - R2[:, j]) <= 1.01 * linear.KRYLOV_RTOL * np.linalg.norm(R2[:, j])
        assert np.linalg.norm(X2[:, j] - E2[:, j]) <= 1e-5 * np.linalg.norm(E2[:, j])


def test_gmres_solves_with_a_stale_preconditioner_to_its_tolerance():
    """Right-preconditioned GMRES with the LU of another matrix: its answer satisfies K x = b to
    the requested residual (checked independently with a dense solve), it stops as soon as it
    can, and it says when it did not converge within its iterations."""
    import scipy.sparse.linalg as spla

    K = _convection_2d(15, 0.8)
    stale = spla.splu(sp.csc_matrix(_convection_2d(15, 0.5) + 0.05 * sp.eye(K.shape[0])))
    b = np.random.default_rng(1).normal(size=K.shape[0])
    x, its, ok = linear.gmres(K, stale.solve, b, rtol=1e-12, maxiter=60)
    exact = np.linalg.solve(K.toarray(), b)
    assert ok and 1 < its < 60
    assert np.linalg.norm(K @ x - b) <= 1e-10 * np.linalg.norm(b)
    assert np.allclose(x, exact, rtol=1e-9, atol=1e-10 * np.abs(exact).max())
    _, its2, ok2 = linear.gmres(K, stale.solve, b, rtol=1e-12, maxiter=2)
    assert not ok2 and its2 == 2
    x0, its0, ok0 = linear.gmres(K, stale.solve, np.zeros_like(b))
    assert ok0 and its0 == 0 and not x0.any()
    # without a preconditioner GMRES converges slowly (the stale LU is what makes it fast): it
    # gives up early, as soon as its rate of convergence would not reach the tolerance in time
    xp, its_plain, ok_plain = linear.gmres(K, lambda v: v, b, rtol=1e-12, maxiter=60)
    assert not ok_plain and its_plain < 20
    assert np.linalg.norm(K @ xp - b) > 1e-3 * np.linalg.norm(b)  # far from converged indeed


@pytest.mark.skipif("pardiso" not in BACKENDS, reason="pypardiso/MKL not available")
def test_kept_factorisation_solves_nearby_tangents_and_factorises_far_ones():
    """reuse = 'always': the first matrix is factorised, the next ones - close to it, unsymmetric,
    two right-hand sides as in the arc length - are solved by GMRES on that factorisation; a
    matrix far from it (GMRES does not converge within its budget) is factorised, and the new
    factorisation is kept. Every answer against a dense solve."""
    s = linear.LinearSolver("pardiso", reuse="always")
    K0 = _convection_2d(14, 0.3)
    n = K0.shape[0]
    rng = np.random.default_rng(2)
    r = rng.normal(size=n)
    s.solve(K0, r)
    assert s.counts.factorisations == 1
    for k in range(1, 4):  # small changes: no new factorisation
        K = (K0 + sp.diags(0.02 * k * rng.uniform(size=n))).tocsr()
        R = np.column_stack([r, rng.normal(size=n)])
        X = s.solve(K, R)
        _check_solution(K, X, R)
    assert s.counts.factorisations == 1 and s.counts.krylov_solves == 6 and s.counts.krylov_failures == 0
    far = (-_convection_2d(14, 3.0) + 7.5 * sp.eye(n)).tocsr()  # indefinite, another convection
    x = s.solve(far, r)
    _check_solution(far, x, r)
    assert s.counts.krylov_failures == 1 and s.counts.factorisations == 2
    f, its = s.counts.factorisations, s.counts.krylov_iterations
    x = s.solve(far, r)  # solved on the new factorisation at once
    assert s.counts.krylov_iterations - its <= 2 and s.counts.factorisations == f


@pytest.mark.skipif("pardiso" not in BACKENDS, reason="pypardiso/MKL not available")
def test_singular_tangent_is_reported_with_a_kept_factorisation():
    """GMRES cannot solve a singular system whose right-hand side is not in its range: the solver
    factorises it and reports the singularity, as without reuse."""
    s = linear.LinearSolver("pardiso", reuse="always")
    T = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(30, 30)).tolil()
    s.solve(T.tocsr(), np.ones(30))
    T[0, 0] = T[-1, -1] = 1.0  # free-free bar
    with pytest.raises(linear.SingularSystemError):
        s.solve(T.tocsr(), np.linspace(1, 2, 30))
    assert s.counts.krylov_failures == 1


@pytest.mark.skipif("pardiso" not in BACKENDS, reason="pypardiso/MKL not available")
def test_auto_reuse_keeps_only_factorisations_that_cost_many_solves():
    """reuse = 'auto' keeps a factorisation where it costs at least REUSE_MIN_COST GMRES
    iterations by PARDISO's own report (flops against the entries a solve reads). A 2D Laplacian
    of 400 unknowns is cheap to factorise (every solve factorises); a 3D one of 27 000 fills in
    (its separators are planes) and is kept. The cost estimate grows with the fill."""
    small = linear.LinearSolver("pardiso", reuse="auto")
    K = _laplacian_2d(20)
    for shift in (0.0, 0.01, 0.02):
        small.solve((K + shift * sp.eye(K.shape[0])).tocsr(), np.ones(K.shape[0]))
    assert small.counts.factorisations == 3 and small.counts.krylov_solves == 0
    T = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(30, 30))
    I = sp.eye(30)
    K3 = (sp.kron(sp.kron(T, I), I) + sp.kron(sp.kron(I, T), I) + sp.kron(sp.kron(I, I), T)).tocsr()
    big = linear.LinearSolver("pardiso", reuse="auto")
    big.solve(K3, np.ones(K3.shape[0]))
    p = big._kept
    assert p is not None and p.factorisation_cost(K3.nnz) >= linear.REUSE_MIN_COST
    assert small._pardiso[True].factorisation_cost(K.nnz) < linear.REUSE_MIN_COST
    x = big.solve((K3 + 0.01 * sp.eye(K3.shape[0])).tocsr(), np.ones(K3.shape[0]))
    assert big.counts.factorisations == 1 and big.counts.krylov_solves == 1
    assert np.linalg.norm((K3 + 0.01 * sp.eye(K3.shape[0])) @ x - 1.0) <= 1e-9 * np.sqrt(K3.shape[0])


def test_unknown_reuse_is_rejected():
    with pytest.raises(ValueError, match="unknown reuse"):
        linear.LinearSolver("superlu", reuse="sometimes")


@pytest.mark.skipif("pardiso" not in BACKENDS, reason="pypardiso/MKL not available")
def test_kept_factorisations_leave_a_softening_cohesive_path_unchanged():
    """The DCB (100 elements) opened by prescribed displacements past the onset of damage into its
    softening, every tangent solved on kept factorisations where GMRES converges (reuse =
    'always') and every tangent factorised ('never'): the same load steps, Newton iterations,
    loads (to 10⁻⁷) and dissipated energy (to 10⁻⁶), so the Newton tolerance and not the linear
    solver decides the answer. Most solves are GMRES solves, and summary.json counts them."""
    from helpers import run_example
    from test_dcb import DISPLACEMENT_CONTROL

    runs = {}
    for reuse in ("always", "never"):
        runs[reuse] = run_example("dcb_cohesive", {
            **DISPLACEMENT_CONTROL, "nx = 150": "nx = 100",
            "factors = [0.01, 0.02, 0.05,": f'reuse_factorization = "{reuse}"\nfactors = [0.3, 0.4, 0.44, 0.47] #'})
    a, b = runs["always"].summary, runs["never"].summary
    assert runs["always"].converged and runs["never"].converged
    assert [s["iterations"] for s in a["steps"]] == [s["iterations"] for s in b["steps"]]
    Pa = np.array([s["probes"]["P"] for s in a["steps"]])
    Pb = np.array([s["probes"]["P"] for s in b["steps"]])
    assert np.allclose(Pa, Pb, rtol=1e-7, atol=0)
    assert b["energy"]["dissipated_fracture"] > 0  # the interface softens in these steps
    assert a["energy"]["dissipated_fracture"] == pytest.approx(b["energy"]["dissipated_fracture"], rel=1e-6)
    counts = a["linear_solves"]
    assert counts["krylov_solves"] > counts["factorisations"] > 0
    assert "linear_solves" not in b
