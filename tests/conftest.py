import numpy as np
import pytest

from layershell.element.shape import NODE_XI


@pytest.fixture
def rng():
    return np.random.default_rng(1234)


def curved_element(rng, R=3.0, distort=0.1):
    """One distorted 9-node element on a cylinder of radius R (nodes moved inside the element)."""
    xi = NODE_XI + distort * rng.standard_normal((9, 2)) * (np.abs(NODE_XI) < 1)
    phi = 0.3 * xi[:, 0]
    y = 0.5 * xi[:, 1] + 0.1 * xi[:, 0]
    return np.stack([R * np.sin(phi), y, R * np.cos(phi)], -1)[None]


def flat_distorted_element(rng, distort=0.15):
    xi = NODE_XI + distort * rng.standard_normal((9, 2)) * (np.abs(NODE_XI) < 1)
    X = np.stack([2.0 * xi[:, 0] + 0.3 * xi[:, 1], 1.5 * xi[:, 1], 0 * xi[:, 0]], -1)
    return X[None]
