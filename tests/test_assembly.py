"""Issue 6: the reduced-space scatter K_r.data = P @ K.data equals Tᵀ K T (3.69)-(3.72)."""
import numpy as np
import scipy.sparse as sp

from layershell.assembly import ReducedScatter
from layershell.delamination import InterfaceLaw
from layershell.material import Orthotropic
from layershell.mesh import rectangle
from layershell.model import Fix, Hinge, Layer, Model, SurfaceLoad, Symmetry
from layershell.solver import linear
from layershell.solver.problem import Problem


def _three_layers() -> Model:
    """Three layers (d = 2, 3, 1), symmetry plane x = 0, hinge at x = 3, an interface law on the
    upper interface (contact blocks) and that interface debonded for x < 1.6."""
    mesh = rectangle(3.0, 1.0, 3, 2)
    x = mesh.nodes
    n = mesh.n_nodes
    layers = [Layer("a", Orthotropic.isotropic(1e4, 0.25), 2, np.full(n, 0.2)),
              Layer("b", Orthotropic(3.4e4, 3.6e4, 3.4e4, 1.5e4, 1.45e4, 1.45e4, 0.17, 0.17, 0.17), 3,
                    0.1 + 0.02 * x[:, 0]),
              Layer("c", Orthotropic.isotropic(2e4, 0.3), 1, np.full(n, 0.05))]
    sym = np.flatnonzero(np.isclose(x[:, 0], 0))
    hinge = np.flatnonzero(np.isclose(x[:, 0], 3))
    corner = np.flatnonzero(np.isclose(x[:, 0], 0) & np.isclose(x[:, 1], 0))
    m = Model(mesh, layers, [(0, 1, 2)], np.zeros(mesh.n_elements, int),
              fixes=[Fix(corner, 0, (0,), (1,))],
              symmetries=[Symmetry(sym, np.array([1.0, 0.0, 0.0]))],
              hinges=[Hinge(hinge, np.tile([0.0, 0.0, 1.0], (len(hinge), 1)), None, fixed=False)],
              surface_loads=[SurfaceLoad(np.arange(mesh.n_elements), "top", np.array([0, 0, -1.0]),
                                         lambda x, y, z: 1.0 + 0 * x)])
    m.interface_laws = {2: InterfaceLaw(1.0, 1.0, mu0=0.5)}
    m.initially_debonded = {2: np.flatnonzero(x[:, 0] < 1.6)}
    return m


def _compare(pb, u):
    f, K = pb.assembler.evaluate(u)
    f2, Kr = pb.assembler.evaluate_reduced(u, pb.op)
    T = pb.op.T
    ref = (T.T @ K @ T).toarray()
    assert Kr.shape == ref.shape and Kr.has_sorted_indices
    assert np.array_equal(f, f2)
    assert np.abs(Kr.toarray() - ref).max() <= 1e-12 * np.abs(ref).max()
    # the pattern is structural: it contains every nonzero of Tᵀ K T and is symmetric
    pat = sp.csr_matrix((np.ones(Kr.nnz), Kr.indices, Kr.indptr), shape=Kr.shape)
    assert (abs(pat - pat.T)).nnz == 0
    # the pattern maps give the same symmetry measure and upper triangle as the general path
    plain = sp.csr_matrix(Kr.toarray() * (pat.toarray() > 0))
    assert np.isclose(Kr.symmetry_error(), abs(plain - plain.T).max(), rtol=1e-12, atol=0)
    assert linear.is_symmetric(Kr) == linear.is_symmetric(sp.csr_matrix(Kr.toarray()))
    U = Kr.upper_triangle()
    U0 = linear.PardisoSymmetric.upper(plain)
    assert U.has_sorted_indices and np.all(np.diff(U.indptr) > 0)
    assert np.array_equal(U.toarray(), np.triu(Kr.toarray()))
    assert (U - U0).nnz == 0 or abs(U - U0).max() == 0
    return Kr


def test_reduced_scatter_equals_tT_K_T_with_symmetry_hinge_and_partial_debonding(rng):
    pb = Problem.build(_three_layers())
    assert pb.assembler.extra, "the interface law adds contact blocks"
    assert not pb.bonded[2].all() and pb.bonded[2].any() and pb.bonded[1].all()
    u = pb.op.expand(1e-2 * rng.standard_normal(pb.op.n_red))
    Kr0 = _compare(pb, u)
    rs = pb.assembler.reduced_scatter(pb.op)
    assert pb.assembler.reduced_scatter(pb.op) is rs  # cached for the bond state
    # another bond state (more debonded): a new operator, a new map, still exact
    pb.bonded[2] = pb.bonded[2] & (pb.model.mesh.nodes[:, 1] > 0.4)
    pb.rebuild_constraints()
    Kr1 = _compare(pb, u)
    assert pb.assembler.reduced_scatter(pb.op) is not rs
    assert Kr1.shape[0] > Kr0.shape[0]  # debonding frees DOFs


def test_reduced_scatter_general_operator(rng):
    """A random operator with chained rows (up to 4 entries), empty rows (fixed DOFs) and
    arbitrary weights against the sparse triple product."""
    n, nr = 60, 45
    A = sp.random(n, n, density=0.15, random_state=1, format="csr")
    A = (A + A.T + sp.eye(n)).tocsr()
    A.sort_indices()
    rows = np.repeat(np.arange(n), rng.integers(0, 5, n))
    T = sp.csr_matrix((rng.standard_normal(rows.size), (rows, rng.integers(0, nr, rows.size))), shape=(n, nr))
    T.sum_duplicates()
    data = rng.standard_normal(A.nnz)
    K = sp.csr_matrix((data, A.indices, A.indptr), shape=A.shape)
    ref = (T.T @ K @ T).toarray()
    maps = [ReducedScatter(T, A.indptr, A.indices, jit=jit, chunk=37) for jit in (True, False)]  # compiled, NumPy
    for rs in maps:
        assert np.allclose(rs.matrix(data).toarray(), ref, rtol=0, atol=1e-13)
        assert rs.mirror_pos is not None
    a, b = maps
    assert np.array_equal(a.indptr, b.indptr) and np.array_equal(a.indices, b.indices)
    assert (a.P != b.P).nnz == 0


def test_pattern_maps_detect_unsymmetric_values_and_fall_back(rng):
    """A perturbed (unsymmetric, as with friction) K_r is reported unsymmetric; a matrix derived by
    SciPy operations no longer uses the maps and takes the general path with the same result."""
    pb = Problem.build(_three_layers())
    _, Kr = pb.assembler.evaluate_reduced(pb.op.expand(1e-2 * rng.standard_normal(pb.op.n_red)), pb.op)
    assert linear.is_symmetric(Kr) and Kr.symmetry_error() <= 1e-13 * np.abs(Kr.data).max()
    K2 = Kr * 2.0
    assert getattr(K2, "symmetry_error", lambda: None)() is None  # maps do not apply: general path
    assert np.array_equal(linear.PardisoSymmetric.upper(K2).toarray(), np.triu(K2.toarray()))
    assert linear.is_symmetric(K2)
    rows = np.repeat(np.arange(Kr.shape[0]), np.diff(Kr.indptr))
    off = np.flatnonzero(Kr.indices != rows)[0]
    assert Kr.known_symmetric  # assembled from symmetric contributions: the solver skips the check
    Kr.data[off] += 1e-6 * np.abs(Kr.data).max()
    Kr.known_symmetric = False  # values changed by hand
    assert Kr.symmetry_error() >= 0.9e-6 * np.abs(Kr.data).max()
    assert not linear.is_symmetric(Kr)


def test_full_pattern_and_scatter_match_sorting_and_dense_assembly(rng):
    """The compiled full-space pattern/scatter equals the sorting construction, and K equals a
    dense element-by-element sum (with the contact blocks of the interface law)."""
    from layershell.element.kernel import layer_response

    pb = Problem.build(_three_layers())
    A = pb.assembler
    ref = (A.indptr.copy(), A.indices.copy(), A.scatter.copy())
    u = pb.op.expand(1e-2 * rng.standard_normal(pb.op.n_red))
    f, K = A.evaluate(u)
    A._pattern_numpy([*A.blocks, *A.extra])
    for x, y in zip(ref, (A.indptr, A.indices, A.scatter)):
        assert np.array_equal(x, y)
    n = pb.dm.n_full
    Kd, fd = np.zeros((n, n)), np.zeros(n)
    for b in A.blocks:
        fe, Ke = layer_response(b.ref, u[b.dofs].reshape(b.dofs.shape[0], -1, 3), pb.model.nonlinear, True)
        np.add.at(Kd, (b.dofs[:, :, None], b.dofs[:, None, :]), Ke)
        np.add.at(fd, b.dofs, fe)
    for b in A.extra:
        fe, Ke = b.response(u)
        np.add.at(Kd, (b.dofs[:, :, None], b.dofs[:, None, :]), Ke)
        np.add.at(fd, b.dofs, fe)
    assert np.abs(K.toarray() - Kd).max() <= 1e-12 * np.abs(Kd).max()
    assert np.abs(f - fd).max() <= 1e-12 * np.abs(fd).max()


def test_compiled_scatter_equals_numpy_fallback(rng, monkeypatch):
    """The compiled scatter-add into the CSR data (and the compiled symmetry check) give the same
    forces, tangent and symmetry error as the NumPy path (entry array + bincount)."""
    import layershell.assembly as assembly

    pb = Problem.build(_three_layers())
    u = pb.op.T @ (1e-3 * rng.standard_normal(pb.op.n_red))
    f1, K1 = pb.assembler.evaluate_reduced(u, pb.op)
    e1 = K1.symmetry_error()
    monkeypatch.setattr(assembly, "_jit", lambda: None)
    f2, K2 = pb.assembler.evaluate_reduced(u, pb.op)
    assert np.allclose(f1, f2, rtol=0, atol=1e-12 * np.abs(f2).max())
    assert np.allclose(K1.data, K2.data, rtol=0, atol=1e-12 * np.abs(K2.data).max())
    assert abs(e1 - K2.symmetry_error()) <= 1e-12 * np.abs(K2.data).max()


def test_symmetry_is_checked_unless_every_block_declares_it(rng, monkeypatch):
    """Contact blocks declare symmetric tangents, so the assembled K_r skips the solver's check;
    a block that does not declare it brings the O(nnz) check back (with the same answer here)."""
    from layershell.contact import ContactBlock

    pb = Problem.build(_three_layers())
    assert pb.assembler.extra
    u = pb.op.expand(1e-2 * rng.standard_normal(pb.op.n_red))
    _, Kr = pb.assembler.evaluate_reduced(u, pb.op)
    assert Kr.known_symmetric and Kr.symmetry_error() <= 1e-13 * np.abs(Kr.data).max()
    monkeypatch.setattr(ContactBlock, "symmetric", False)
    _, K2 = pb.assembler.evaluate_reduced(u, pb.op)
    assert not K2.known_symmetric and linear.is_symmetric(K2)


def _dcb_problem(nx: int = 6, nonlinear: bool = False, rule: str | None = None):
    """examples/dcb_cohesive.toml on ``nx`` elements (cohesive interface, nodal rule by default)."""
    from helpers import EXAMPLES

    from layershell.io.build import build, parse

    text = (EXAMPLES / "dcb_cohesive.toml").read_text().replace("nx = 150", f"nx = {nx}")
    if nonlinear:
        text = text.replace("nonlinear = false", "nonlinear = true")
    if rule is not None:
        text = text.replace('law = "cohesive"', f'law = "cohesive"\nrule = "{rule}"')
    return Problem.build(build(parse(text, str(EXAMPLES / "dcb_cohesive.toml")), EXAMPLES).model)


def _opening(pb, rng, scale: float, shear: float = 0.0):
    """Random DOFs plus an opening of the upper arm of ``scale`` times the onset separation of
    the cohesive law (some points elastic, some softening, the initial crack fully damaged) and a
    sliding of ``shear`` times it."""
    blk = pb.assembler.extra[0]
    d0 = blk.law.sigma_max / blk.K
    u = pb.op.expand(1e-3 * d0 * rng.standard_normal(pb.op.n_red))
    up = pb.dm.layer_dofs[blk.contact.itf.upper][:, 0, :]  # u_0 of the upper layer (node, 3)
    x = pb.model.mesh.nodes[:, 0]
    u[up[:, 2]] += scale * d0 * (1.0 - x / x.max())  # opening largest at the loaded end
    u[up[:, 0]] += shear * d0 * (1.0 - x / x.max())
    return u


def test_linear_bulk_and_point_form_equal_the_element_assembly(rng, monkeypatch):
    """Issue 13 speed: a geometrically linear model keeps its layer elements' K from the first
    evaluation (``Assembler._linear_bulk``: f = K_bulk u + the cohesive block), and the cohesive
    block on the nodal rule is assembled point by point (``ContactBlock._point_form``: one
    (3 s)² block per face point instead of the element's m² entries). Independent check: the
    same model assembled element by element with both off gives the same internal force, full
    tangent and reduced tangent, on a state with elastic, softening and fully damaged points and
    a mixed mode."""
    from layershell.assembly import Assembler

    pb = _dcb_problem()
    A = pb.assembler
    blk = A.extra[0]
    assert blk.assembly_dofs is not None and blk.assembly_dofs.shape == (blk.dofs.shape[0] * 9, 3 * 5)
    ref = _dcb_problem()
    monkeypatch.setattr(Assembler, "_linear_bulk", lambda self: None)
    ref.assembler.extra[0].contact.assembly_dofs = None
    ref.assembler._pattern()
    assert ref.assembler.nnz > A.nnz  # the element form stores every point's coupling to every node
    for scale, shear in ((0.5, 0.0), (3.0, 0.0), (3.0, 2.0), (-2.0, 1.0)):
        u = _opening(pb, rng, scale, shear)
        f, K = ref.assembler.evaluate(u)
        monkeypatch.undo()
        f1, K1 = A.evaluate(u)
        f2, Kr = A.evaluate_reduced(u, pb.op)
        monkeypatch.setattr(Assembler, "_linear_bulk", lambda self: None)
        tol = 1e-12 * abs(K).max()
        assert np.abs(f1 - f).max() <= 1e-12 * np.abs(f).max() and np.array_equal(f1, f2)
        assert abs(K1 - K).max() <= tol
        assert abs(Kr - (pb.op.T.T @ K @ pb.op.T)).max() <= tol
    assert A._bulk is not None and A._bulk.reduced is not None


def test_point_form_of_the_contact_block_equals_its_element_form(rng):
    """The point form (nodal rule) of a ContactBlock with released points in contact and
    friction: each point's (3 s)² block scattered to its element's DOFs gives the element form's
    force and tangent (``response(points=True)`` against ``response()``); on the Gauss rule
    there is no point form (every point sees every node)."""
    from layershell.contact import ContactBlock
    from layershell.interfaces import interfaces

    pb = Problem.build(_three_layers())
    itf = interfaces(pb.model)[-1]
    assert ContactBlock.build(pb.model, pb.dm, itf, 1e3).assembly_dofs is None
    cb = ContactBlock.build(pb.model, pb.dm, itf, 1e3, rule="lobatto")
    ne, nq, nk = cb.c.shape
    cb.released = rng.random((ne, nq)) < 0.7
    cb.alpha_T, cb.cap = 5e2, rng.uniform(0.0, 2e-3, (ne, nq))
    cb.g_p = 1e-6 * rng.standard_normal((ne, nq, 3))
    u = 1e-5 * rng.standard_normal(pb.dm.n_full)
    f, K = cb.response(u)
    fp, (Kp, rows) = cb.response(u, points=True)
    n = pb.dm.n_full
    assert np.allclose(np.bincount(cb.assembly_dofs.ravel(), fp.ravel(), n), np.bincount(cb.dofs.ravel(), f.ravel(), n),
                       rtol=0, atol=1e-12 * np.abs(f).max())
    dense = np.zeros((n, n))
    np.add.at(dense, (cb.dofs[:, :, None], cb.dofs[:, None, :]), K)
    points = np.zeros((n, n))
    d = cb.assembly_dofs[rows]
    np.add.at(points, (d[:, :, None], d[:, None, :]), Kp)
    assert rows.size == cb.released.sum() and np.abs(points - dense).max() <= 1e-12 * np.abs(dense).max()


def test_cohesive_tangent_is_known_symmetric_in_pure_mode_i_only(rng):
    """A cohesive tangent whose point matrices are exactly symmetric (pure opening along the
    normal: K g ⊗ ∂d/∂δ with g ∥ ∂d/∂δ ∥ n) skips the solver's O(nnz) symmetry check
    (``CohesiveBlock.symmetric_now``); a mixed mode with growing damage is not symmetric, and
    the check stays. Independent check: the assembled K against its transpose."""
    pb = _dcb_problem()
    A = pb.assembler
    u = pb.op.expand(np.zeros(pb.op.n_red))
    blk = A.extra[0]
    up = pb.dm.layer_dofs[blk.contact.itf.upper][:, 0, :]
    x = pb.model.mesh.nodes[:, 0]
    u[up[:, 2]] = 3.0 * blk.law.sigma_max / blk.K * (1.0 - x / x.max())  # opening only
    _, K = A.evaluate(u)
    assert A.symmetric and abs(K - K.T).max() <= 1e-14 * abs(K).max()
    _, Kr = A.evaluate_reduced(u, pb.op)
    assert Kr.known_symmetric
    _, K = A.evaluate(_opening(pb, rng, 3.0, 2.0))
    assert not A.symmetric and abs(K - K.T).max() > 1e-6 * abs(K).max()


def test_nonlinear_model_has_no_linear_bulk():
    """The cache of the layer elements' tangent is for geometrically linear models with
    interface or contact blocks only (a model without them takes one or two Newton iterations
    a step: the cache would only cost memory)."""
    assert _dcb_problem(nonlinear=True).assembler._linear_bulk() is None
    assert _dcb_problem().assembler._linear_bulk() is not None
    m = _three_layers()
    m.nonlinear = False
    plain = Problem.build(m)
    plain.assembler.add_blocks([])
    assert plain.assembler._linear_bulk() is None


def test_reduced_tangents_of_a_linear_model_never_share_their_values(rng):
    """The K_r values of a linear model are filled into arrays that no live matrix uses
    (``_LinearBulk.buffer``): a tangent kept while the next ones are formed keeps its own
    values, and the array of a tangent that is gone is filled again (no new allocation)."""
    import gc

    pb = _dcb_problem()
    A = pb.assembler
    u1, u2, u3 = (_opening(pb, rng, s, 0.5) for s in (0.5, 3.0, 6.0))
    _, K1 = A.evaluate_reduced(u1, pb.op)
    want = K1.data.copy()
    _, K2 = A.evaluate_reduced(u2, pb.op)
    _, K3 = A.evaluate_reduced(u3, pb.op)
    assert np.array_equal(K1.data, want) and not np.shares_memory(K1.data, K2.data)
    assert not np.shares_memory(K2.data, K3.data) and not np.shares_memory(K1.data, K3.data)
    reused = K2.data
    del K2
    gc.collect()
    _, K4 = A.evaluate_reduced(u2, pb.op)
    assert np.shares_memory(K4.data, reused) and np.array_equal(K1.data, want)


def test_one_pass_symmetry_check_equals_the_two_passes(rng):
    """``ReducedTangent.symmetry_check`` (one pass: largest mirror difference and largest
    entry) gives the values of ``symmetry_error`` and ``max_abs``."""
    pb = _dcb_problem()
    _, K = pb.assembler.evaluate_reduced(_opening(pb, rng, 3.0, 2.0), pb.op)
    err, top = K.symmetry_check()
    assert err == K.symmetry_error() > 0 and top == K.max_abs() == abs(K).max()
