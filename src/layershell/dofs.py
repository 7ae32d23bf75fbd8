"""Numbering of the full ("v") DOF space: node, layer, director, direction (MODEL.md (3.40), (3.52))."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .model import Model


@dataclass(frozen=True)
class DofMap:
    """``layer_dofs[k] (n_nodes, d_k+1, 3)``: global full-space DOF of (node, director, direction)
    of layer k, -1 where layer k is absent at the node. Numbered node by node."""

    n_full: int
    layer_dofs: list[np.ndarray]
    present: np.ndarray  # (n_layers, n_nodes) bool

    def translations(self) -> np.ndarray:
        """The full-space DOFs of the face translations u_0 of every layer (director 0)."""
        dofs = np.concatenate([ld[:, 0, :].ravel() for ld in self.layer_dofs])
        return dofs[dofs >= 0]

    def element_dofs(self, model: Model, layer: int, elements: np.ndarray) -> np.ndarray:
        """(e, 9*(d+1)*3) DOFs of ``layer`` for ``elements`` (kernel order)."""
        d = self.layer_dofs[layer][model.mesh.elements[elements]]
        return d.reshape(len(elements), -1)


def number_dofs(model: Model) -> DofMap:
    n_nodes = model.mesh.n_nodes
    nl = len(model.layers)
    present = model.layers_present()
    size = np.array([3 * (ly.directors + 1) for ly in model.layers])
    per_node = (present * size[:, None]).sum(0)
    start = np.concatenate([[0], np.cumsum(per_node)[:-1]])
    within = np.cumsum(present * size[:, None], axis=0) - present * size[:, None]
    layer_dofs = []
    for k, ly in enumerate(model.layers):
        base = start + within[k]
        d = base[:, None] + np.arange(size[k])[None, :]
        d = np.where(present[k][:, None], d, -1)
        layer_dofs.append(d.reshape(n_nodes, ly.directors + 1, 3))
    return DofMap(int(per_node.sum()), layer_dofs, present)
