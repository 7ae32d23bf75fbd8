"""Shape functions and quadrature, MODEL.md §5 (2.208)-(2.211), (2.273)-(2.277)."""
import numpy as np
import pytest

from layershell.element.quadrature import gauss_1d, gauss_2d
from layershell.element.shape import NODE_XI, THESIS_TO_VTK, quad9


def test_partition_of_unity_and_kronecker(rng):
    x = rng.uniform(-1, 1, (50, 2))
    N, dN, ddN = quad9(x[:, 0], x[:, 1])
    assert np.allclose(N.sum(-1), 1.0, atol=1e-14)
    assert np.allclose(dN.sum(-2), 0.0, atol=1e-13)
    assert np.allclose(ddN.sum(-3), 0.0, atol=1e-13)
    Nn, _, _ = quad9(NODE_XI[:, 0], NODE_XI[:, 1])
    assert np.allclose(Nn, np.eye(9))


def test_reproduces_biquadratic_fields(rng):
    c = rng.standard_normal(9)
    f = lambda x, y: (c[0] + c[1] * x + c[2] * y + c[3] * x * y + c[4] * x**2 + c[5] * y**2
                      + c[6] * x**2 * y + c[7] * x * y**2 + c[8] * x**2 * y**2)
    fn = f(NODE_XI[:, 0], NODE_XI[:, 1])
    x = rng.uniform(-1, 1, (40, 2))
    N, dN, ddN = quad9(x[:, 0], x[:, 1])
    assert np.allclose(N @ fn, f(x[:, 0], x[:, 1]), atol=1e-12)
    h = 1e-6
    dfx = (f(x[:, 0] + h, x[:, 1]) - f(x[:, 0] - h, x[:, 1])) / (2 * h)
    dfy = (f(x[:, 0], x[:, 1] + h) - f(x[:, 0], x[:, 1] - h)) / (2 * h)
    assert np.allclose(np.einsum("qn,n->q", dN[..., 0], fn), dfx, atol=1e-8)
    assert np.allclose(np.einsum("qn,n->q", dN[..., 1], fn), dfy, atol=1e-8)
    X, Y = x[:, 0], x[:, 1]
    dxy = c[3] + 2 * c[6] * X + 2 * c[7] * Y + 4 * c[8] * X * Y
    dxx = 2 * c[4] + 2 * c[6] * Y + 2 * c[8] * Y**2
    assert np.allclose(np.einsum("qn,n->q", ddN[..., 0, 1], fn), dxy, atol=1e-12)
    assert np.allclose(np.einsum("qn,n->q", ddN[..., 1, 0], fn), dxy, atol=1e-12)
    assert np.allclose(np.einsum("qn,n->q", ddN[..., 0, 0], fn), dxx, atol=1e-12)


def test_thesis_node_numbering():
    thesis = {1: (1, 1), 2: (-1, 1), 3: (-1, -1), 4: (1, -1), 5: (0, 1), 6: (-1, 0), 7: (0, -1), 8: (1, 0), 9: (0, 0)}
    for k, xy in thesis.items():
        assert tuple(NODE_XI[THESIS_TO_VTK[k]]) == xy


def test_gauss_points_of_the_thesis():
    x, w = gauss_1d(3)
    assert np.allclose(x, [-0.7745966692, 0.0, 0.7745966692])
    assert np.allclose(w, [5 / 9, 8 / 9, 5 / 9])
    # thickness positions Θ³/H = (ζ+1)/2 (2.277)
    assert np.allclose((x + 1) / 2, [0.1127016654, 0.5, 0.8872983346])
    pts, wts = gauss_2d(3)
    assert pts.shape == (9, 2) and np.isclose(wts.sum(), 4.0)


@pytest.mark.parametrize("n", [2, 3, 4])
def test_gauss_exactness(n):
    x, w = gauss_1d(n)
    for k in range(2 * n):
        assert np.isclose(np.sum(w * x**k), (1 - (-1) ** (k + 1)) / (k + 1))
