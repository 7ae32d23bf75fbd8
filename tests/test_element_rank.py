"""Zero-energy modes of a free layer element against the thickness rule (issue 14, kernel cost).

The fully integrated element samples the 6 strain components at 3 × 3 × n_z points. Whether it
has spurious zero-energy modes depends only on n_z and d: on a flat element of constant thickness
its displacement space is Q2(ξ, η) ⊗ P_d(Θ) per direction, and a mode is spurious iff its linear
strain vanishes at every sampling point. :func:`sampled_strain_nullity` counts these modes from
monomials alone (no layershell code), the rank argument the kernel's tangent is checked against.
Measured: the full element needs n_z ≥ d (d = 4 with 3 points has 12 spurious modes), the MITC9
element n_z ≥ d + 1 (6 spurious modes with n_z = d), which is what assembly.build_blocks uses.
"""
import numpy as np
import pytest
from conftest import curved_element, flat_distorted_element

from layershell.element.kernel import layer_block, layer_response
from layershell.material import Orthotropic

ORTHO = Orthotropic(100.0, 50.0, 30.0, 20.0, 15.0, 10.0, 0.25, 0.3, 0.1)
TOL = 1e-10  # relative to the largest Jacobi-scaled eigenvalue; the smallest non-zero one is > 1e-8


def sampled_strain_nullity(d: int, nz: int) -> int:
    """Null-space dimension of the linear strains of Q2(x, y) ⊗ P_d(z) (3 components) sampled at
    the 3 × 3 × nz Gauss points of the cube [-1, 1]³: the zero-energy modes of a flat, fully
    integrated element of constant thickness (C positive definite, weights positive)."""
    g2, _ = np.polynomial.legendre.leggauss(3)
    gz, _ = np.polynomial.legendre.leggauss(nz)
    mono = [(i, j, l) for i in range(3) for j in range(3) for l in range(d + 1)]

    def dpow(x, k, deriv):  # d^deriv/dx^deriv of x**k
        if deriv == 0:
            return x**k
        return k * x ** (k - 1) if k > 0 else 0.0 * x

    rows = []
    for x in g2:
        for y in g2:
            for z in gz:
                # grad[a][J] = ∂_J of monomial a at (x, y, z)
                grad = np.array([[dpow(x, i, 1) * y**j * z**l, x**i * dpow(y, j, 1) * z**l,
                                  x**i * y**j * dpow(z, l, 1)] for i, j, l in mono])
                na = len(mono)
                for I, J in ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1)):
                    r = np.zeros((na, 3))  # ε_IJ = ½(∂_J u_I + ∂_I u_J), DOF (monomial a, direction k)
                    r[:, I] += 0.5 * grad[:, J]
                    r[:, J] += 0.5 * grad[:, I]
                    rows.append(r.ravel())
    B = np.array(rows)
    s = np.linalg.svd(B, compute_uv=False)
    return B.shape[1] - int(np.sum(s > 1e-10 * s[0]))


def zero_modes(X, d: int, nz: int, element: str, H0: float = 0.2) -> int:
    """Number of zero eigenvalues of the free one-layer element's (Jacobi-scaled) linear tangent,
    the element evaluated with exactly ``nz`` thickness points."""
    from layershell.element.mitc import mitc_block

    H = np.full((1, 9), H0)
    if element == "mitc":
        blk = mitc_block(X, -H / 2, H, d, ORTHO, 20.0, None, nz)
    else:
        blk = layer_block(X, -H / 2, H, d, ORTHO, 20.0, n_thickness=nz, element="full")
    _, K = layer_response(blk, np.zeros((1, 9 * (d + 1), 3)), nonlinear=False)
    s = 1 / np.sqrt(np.diag(K[0]))
    ev = np.linalg.eigvalsh(K[0] * s[:, None] * s[None])
    return int(np.sum(np.abs(ev) < TOL * ev.max()))


def test_rank_argument_counts_rigid_modes_and_a_known_spurious_family():
    """The independent count itself: 6 rigid-body modes where the rule is exact, and for d = 4,
    n_z = 2 at least the 27 modes u = a(x, y) (z² − 1/3)² e_k (value and z-derivative vanish at
    both thickness points), so it is not blind to spurious modes."""
    assert sampled_strain_nullity(2, 3) == 6
    assert sampled_strain_nullity(4, 2) >= 6 + 27


@pytest.mark.parametrize("d, nz", [(1, 2), (2, 2), (2, 3), (3, 2), (3, 3), (4, 3), (4, 4)])
@pytest.mark.parametrize("distort", [0.0, 0.15])
def test_full_element_zero_modes_equal_the_rank_argument(rng, d, nz, distort):
    """Flat (regular and distorted) full element: its zero modes are exactly the sampled-strain
    null space — 6 rigid modes for n_z ≥ d, spurious modes below (d = 3 / n_z = 2: 18,
    d = 4 / n_z = 3: 12)."""
    expected = sampled_strain_nullity(d, nz)
    assert zero_modes(flat_distorted_element(rng, distort), d, nz, "full") == expected
    assert (expected == 6) == (nz >= d)


@pytest.mark.parametrize("d", [1, 2, 3, 4])
def test_production_thickness_rules_have_no_spurious_modes(rng, d):
    """The rules assembly.build_blocks uses with the default thickness_points = 3: the full element
    max(3, d) points, MITC9 max(3, d + 1): 6 zero modes flat, 3 exact ones (the translations)
    curved; MITC9 with only d points (d ≥ 2) has 6 more on the flat element."""
    flat, curved = flat_distorted_element(rng, 0.15), curved_element(rng, distort=0.15)
    assert zero_modes(flat, d, max(3, d), "full") == 6
    assert zero_modes(curved, d, max(3, d), "full") == 3
    assert zero_modes(flat, d, max(3, d + 1), "mitc") == 6
    assert zero_modes(curved, d, max(3, d + 1), "mitc") == 3
    if d >= 2:
        assert zero_modes(flat, d, d, "mitc") == 12
