"""What engineers read from a concrete layer and its reinforcement, in the committed state.

Per integration point (vectorised over the points of a layer's blocks, ``model.point_states``):

* the crack width w = d⁺ ⟨n·ε·n⟩ × band and the crack normal n (fixed when the point first
  cracked; :meth:`layershell.laws.ConcreteLaw.crack`), and per in-plane Gauss point the widest
  crack over the layer's thickness points (:func:`crack_pattern`, the plan figure);
* the concrete's minimum principal stress (the most compressive), from the law's stress at the
  committed strain and state;
* the state of each reinforcement sheet: 0 elastic, 1 yielded (a plastic strain), 2 ruptured.

:func:`cell_values` reduces them per element for the ParaView surface files.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .element.geometry import surface_points
from .element.kernel import LayerBlock
from .element.quadrature import gauss_2d

ELASTIC, YIELDED, RUPTURED = 0, 1, 2  # the codes of a sheet's state


def _blocks(model, k: int):
    """(elements, block, state) of layer ``k``'s blocks with a bulk law that reports cracks."""
    for blk_elements, blk, st in model.point_states.get(k, ()):
        if blk.law is not None and hasattr(blk.law, "crack"):
            yield blk_elements, blk, st


def _by_plane_point(blk, a: np.ndarray) -> np.ndarray:
    """Values over a block's points (e·P, ...) as (e, 9 in-plane points, nz thickness points, ...)."""
    e, P = blk.h_in.shape
    nz = P // 9
    a = a.reshape((e, P) + a.shape[1:])
    if isinstance(blk.base, LayerBlock):  # point = iq · nz + iz
        return a.reshape((e, 9, nz) + a.shape[2:])
    return np.swapaxes(a.reshape((e, nz, 9) + a.shape[2:]), 1, 2)  # point = iz · 9 + iq


def crack_points(model, k: int):
    """Crack width (p,), crack normal (p, 3) and element (p,) at every bulk point of layer ``k``."""
    w, n, el = [], [], []
    for blk_elements, blk, st in _blocks(model, k):
        wi, ni = blk.law.crack(st.strain, st.bulk)
        w.append(np.asarray(wi, float))
        n.append(np.asarray(ni, float))
        el.append(np.repeat(blk_elements, blk.n_points))
    if not w:
        return np.zeros(0), np.zeros((0, 3)), np.zeros(0, np.int64)
    return np.concatenate(w), np.concatenate(n), np.concatenate(el)


@dataclass(frozen=True)
class CrackPattern:
    """The widest crack over the thickness at each in-plane Gauss point of a layer's elements:
    ``x`` (p, 3) the point on the reference surface, ``width`` (p,), ``normal`` (p, 3) the crack
    normal, ``line`` (p, 3) the crack's trace on the surface (unit n × A3; zero where the crack
    runs parallel to the surface), ``size`` (p,) the element's √area, ``element`` (p,)."""

    x: np.ndarray
    width: np.ndarray
    normal: np.ndarray
    line: np.ndarray
    size: np.ndarray
    element: np.ndarray


def crack_pattern(model, k: int) -> CrackPattern:
    """:class:`CrackPattern` of layer ``k`` in the committed state (empty without a concrete law)."""
    pts, w2 = gauss_2d(3)
    parts = []
    for blk_elements, blk, st in _blocks(model, k):
        wi, ni = blk.law.crack(st.strain, st.bulk)
        w3, n3 = _by_plane_point(blk, np.asarray(wi, float)), _by_plane_point(blk, np.asarray(ni, float))
        iz = np.argmax(w3, axis=2)[..., None]
        width = np.take_along_axis(w3, iz, axis=2)[..., 0]
        normal = np.take_along_axis(n3, iz[..., None], axis=2)[:, :, 0]
        sp = surface_points(model.mesh.nodes[model.mesh.elements[blk_elements]], pts[:, 0], pts[:, 1])
        line = np.cross(normal, sp.A3)
        ln = np.linalg.norm(line, axis=-1, keepdims=True)
        line = np.where(ln > 1e-6, line / np.where(ln > 0, ln, 1.0), 0.0)
        size = np.sqrt(np.sum(sp.sqrtA * w2, axis=1))
        parts.append((sp.X0.reshape(-1, 3), width.ravel(), normal.reshape(-1, 3), line.reshape(-1, 3),
                      np.repeat(size, 9), np.repeat(blk_elements, 9)))
    if not parts:
        z3 = np.zeros((0, 3))
        return CrackPattern(z3, np.zeros(0), z3, z3, np.zeros(0), np.zeros(0, np.int64))
    return CrackPattern(*(np.concatenate(c) for c in zip(*parts)))


def principal_min(model, k: int):
    """The concrete's minimum principal stress (p,) at every bulk point of layer ``k`` (the law's
    stress at the committed strain and state; negative: compression) and the element (p,)."""
    s, el = [], []
    for blk_elements, blk, st in _blocks(model, k):
        S, _, _ = blk.law.response(st.strain, st.bulk, blk.h_in.ravel(), blk.h_z.ravel(), blk.normal.reshape(-1, 3),
                                   False)
        t = np.empty((S.shape[0], 3, 3))
        t[:, [0, 1, 2], [0, 1, 2]] = S[:, :3]
        t[:, 1, 2] = t[:, 2, 1] = S[:, 3]
        t[:, 0, 2] = t[:, 2, 0] = S[:, 4]
        t[:, 0, 1] = t[:, 1, 0] = S[:, 5]
        s.append(np.linalg.eigvalsh(t)[:, 0])
        el.append(np.repeat(blk_elements, blk.n_points))
    if not s:
        return np.zeros(0), np.zeros(0, np.int64)
    return np.concatenate(s), np.concatenate(el)


def sheet_states(model, k: int, sheet: str):
    """The state code (p,) of the reinforcement sheet named ``sheet`` of layer ``k`` at its points
    (:data:`ELASTIC`, :data:`YIELDED`, :data:`RUPTURED`) and the element (p,)."""
    codes, el = [], []
    for blk_elements, blk, st in model.point_states.get(k, ()):
        for j, s in enumerate(blk.sheets):
            if s.name != sheet:
                continue
            ev = s.law.events(st.sheets[j])
            n = st.sheet_stress[j].size
            c = np.where(ev.get("yielding", np.zeros(n, bool)), YIELDED, ELASTIC)
            codes.append(np.where(ev.get("rupture", np.zeros(n, bool)), RUPTURED, c))
            el.append(np.repeat(blk_elements, s.w.shape[1]))
    if not codes:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    return np.concatenate(codes), np.concatenate(el)


def per_element(n_elements: int, values: np.ndarray, elements: np.ndarray, how: str = "max") -> np.ndarray:
    """``values`` at points reduced per element (``max`` or ``min``); NaN where an element has none."""
    sign = 1.0 if how == "max" else -1.0
    cell = np.full(n_elements, -np.inf)
    np.maximum.at(cell, elements, sign * np.asarray(values, float))
    cell = sign * cell
    cell[np.isinf(cell)] = np.nan
    return cell


def widest_normal(n_elements: int, width: np.ndarray, normal: np.ndarray, elements: np.ndarray) -> np.ndarray:
    """The crack normal (n_elements, 3) of each element's widest crack; zero where no point of an
    element has an open crack."""
    order = np.lexsort((width, elements))  # by element, then by width: each element's last is its widest
    last = np.r_[elements[order][1:] != elements[order][:-1], True]
    pick = order[last]
    out = np.zeros((n_elements, 3))
    out[elements[pick]] = np.where((width[pick] > 0)[:, None], normal[pick], 0.0)
    return out
