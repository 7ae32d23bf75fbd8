"""Interlaminar results: the surface traction of layer L on layer L-1, thesis (3.29)-(3.33).

At an interface the traction is evaluated with the **upper** layer's own strain, material and
frame at its bottom face (Θ_L³ = 0): σ_K = σ_S · m̄_3 = σ_m^{k3} m̄_k, whose components σ13, σ23
are the interlaminar shear stresses and σ33 the normal stress (tension positive).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .dofs import DofMap
from .element.quadrature import gauss_2d
from .element.shape import NODE_XI
from .model import Model
from .results import PointState, evaluate_points


@dataclass(frozen=True)
class Interface:
    upper: int  # layer index above the interface
    lower: int  # layer index below
    name: str  # "<lower>/<upper>"
    elements: np.ndarray  # elements whose stack contains both layers


def interfaces(model: Model) -> list[Interface]:
    out = []
    for up, lo in sorted(model.below().items()):
        stacks = [si for si, st in enumerate(model.stacks) if up in st]
        el = np.flatnonzero(np.isin(model.element_stack, stacks))
        out.append(Interface(up, lo, f"{model.layers[lo].name}/{model.layers[up].name}", el))
    return out


def face_points(kind: str = "gauss") -> tuple[np.ndarray, np.ndarray]:
    """In-plane positions of the interface points: the 3×3 Gauss points (the "integration points
    of layer L" (3.48), used for delamination) or the 9 nodes (output)."""
    if kind == "gauss":
        pts, _ = gauss_2d(3)
        return pts[:, 0], pts[:, 1]
    return NODE_XI[:, 0], NODE_XI[:, 1]


def interface_state(model: Model, dm: DofMap, u: np.ndarray, itf: Interface, kind: str = "gauss",
                    sampling: str = "raw", load_factor: float = 1.0) -> PointState:
    """PointState of the upper layer at Θ_L³ = 0 for every element of the interface × 9 points
    (point index = element-major); ``sampling = "recovered"``: transverse stresses from
    :mod:`layershell.recovery` (the applied face loads scaled by ``load_factor``)."""
    xi, eta = face_points(kind)
    ne = itf.elements.size
    args = (model, dm, u, np.repeat(itf.elements, 9), np.tile(xi, ne), np.tile(eta, ne), np.zeros(9 * ne),
            np.full(9 * ne, itf.upper))
    if sampling != "raw":
        from .recovery import stress_points

        return stress_points(*args, local_theta=True, sampling=sampling, load_factor=load_factor)
    return evaluate_points(*args, local_theta=True)


def traction_summary(model: Model, dm: DofMap, u: np.ndarray) -> dict[str, dict[str, float]]:
    """Extremes of the interlaminar tractions at the interface Gauss points, per interface."""
    out = {}
    for itf in interfaces(model):
        if itf.elements.size == 0:
            continue
        t = interface_state(model, dm, u, itf).traction()
        shear = np.hypot(t[:, 0], t[:, 1])
        out[itf.name] = {"max_sigma33": float(t[:, 2].max()), "min_sigma33": float(t[:, 2].min()),
                         "max_shear": float(shear.max())}
    return out
