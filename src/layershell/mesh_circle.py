"""Flat rectangular plate with an elliptical (or circular) front meshed along element edges.

The mesh is made of three parts, all 9-node quadrilaterals:

* inside the ellipse, a structured core (a rectangle at half the semi-axes) and an O-ring of
  elements from the core's boundary to the ellipse (a butterfly grid: no degenerate element);
* a refined ring outside the ellipse, between the ellipse and the ellipse with semi-axes
  ``a + ring_width``, ``b + ring_width``, with ``ring_layers`` element layers;
* a transition from the ring to the plate edges along rays from the centre, ``outer_layers``
  layers graded geometrically so that the first one is as thick as a ring layer on the median
  ray (thinner towards a near edge, thicker towards a far one).

Every corner node of the front lies on the ellipse (x = c_x + a cos t, y = c_y + b sin t), at
equal arc lengths within each quarter of the ellipse, with the mid-side nodes at the arc-length
midpoints, so that the quadratic element edges follow the ellipse. The plate's outer edges are
straight with their mid-side nodes at the midpoints.
"""
from __future__ import annotations

import numpy as np

from .element.shape import NODE_XI
from .mesh import Mesh, MeshError, _orient

#: the core rectangle inside the ellipse spans this fraction of the semi-axes
CORE_FRACTION = 0.5
#: geometric growth of the transition's layer thickness when outer_layers is not given
OUTER_GROWTH = 1.3


def _quads(idx: np.ndarray) -> np.ndarray:
    """(e, 9) quad9 connectivity of a structured node-id grid ``idx[j, i]`` of odd shape
    (2 n_eta + 1, 2 n_xi + 1), ξ along i and η along j."""
    n_eta, n_xi = (idx.shape[0] - 1) // 2, (idx.shape[1] - 1) // 2
    j0, i0 = np.meshgrid(2 * np.arange(n_eta), 2 * np.arange(n_xi), indexing="ij")
    di, dj = (NODE_XI[:, 0] + 1).astype(int), (NODE_XI[:, 1] + 1).astype(int)
    return idx[j0.ravel()[:, None] + dj[None], i0.ravel()[:, None] + di[None]]


def _speed(t: np.ndarray, a: float, b: float) -> np.ndarray:
    return np.hypot(a * np.sin(t), b * np.cos(t))


def _arc(t0: float, t: np.ndarray, a: float, b: float, n_pieces: int = 64) -> np.ndarray:
    """Arc length of the ellipse from parameter ``t0`` to each ``t`` (t ≥ t0): 16-point
    Gauss-Legendre on ``n_pieces`` equal pieces (to round-off for a/b up to about 20)."""
    x, w = np.polynomial.legendre.leggauss(16)
    t = np.asarray(t, float)
    span = (t - t0) / n_pieces
    left = t0 + span[..., None] * np.arange(n_pieces)  # (..., pieces)
    pts = left[..., None] + 0.5 * span[..., None, None] * (x + 1.0)
    return 0.5 * span * np.einsum("...pq,q->...", _speed(pts, a, b), w)


def _equal_arcs(t0: float, t1: float, n: int, a: float, b: float) -> np.ndarray:
    """The n + 1 parameters that divide the ellipse arc from t0 to t1 into equal arc lengths
    (Newton on the arc length, converged to round-off)."""
    length = float(_arc(t0, np.array(t1), a, b))
    target = length * np.arange(n + 1) / n
    t = t0 + (t1 - t0) * np.arange(n + 1) / n
    for _ in range(30):
        step = (_arc(t0, t, a, b) - target) / _speed(t, a, b)
        t = t - step
        if np.abs(step).max() < 1e-15 * (1.0 + abs(t1)):
            break
    t[0], t[-1] = t0, t1
    return t


def front_parameters(a: float, b: float, front_size: float) -> tuple[np.ndarray, int, int]:
    """Ellipse parameters t of the front's 2N nodes (corner and mid-side, counter-clockwise from
    t = -π/4) and the element counts m_1 (each of the quarters about the x axis) and m_2 (about
    the y axis): each quarter is split into the fewest equal arcs no longer than ``front_size``."""
    quarters = -np.pi / 4 + np.pi / 2 * np.arange(5)
    lengths = np.array([float(_arc(quarters[0], np.array(quarters[1]), a, b)),
                        float(_arc(quarters[1], np.array(quarters[2]), a, b))])
    m1, m2 = (int(v) for v in np.maximum(1, np.ceil(lengths / front_size * (1 - 1e-12))))
    t = [_equal_arcs(quarters[k], quarters[k + 1], 2 * (m1 if k % 2 == 0 else m2), a, b)[:-1] for k in range(4)]
    return np.concatenate(t), m1, m2


def _core(m1: int, m2: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Normalised coordinates (u, v) of the core rectangle's nodes (ids 0..), its id grid, and the
    ids of its boundary loop (counter-clockwise from (s, -s), 2N entries)."""
    s = CORE_FRACTION
    u = np.linspace(-s, s, 2 * m2 + 1)
    v = np.linspace(-s, s, 2 * m1 + 1)
    U, V = np.meshgrid(u, v, indexing="xy")
    idx = np.arange(U.size).reshape(U.shape)
    loop = np.concatenate([idx[:-1, -1], idx[-1, :0:-1], idx[:0:-1, 0], idx[0, :-1]])
    return np.stack([U.ravel(), V.ravel()], -1), idx, loop


def _side_points(centre: np.ndarray, box: np.ndarray, t: np.ndarray, a: float, b: float) -> np.ndarray:
    """Points on the rectangle's boundary for each of the 2N front positions: where the ray from
    the centre through the ring's outer ellipse (semi-axes a, b) at parameter t leaves the plate,
    so that the transition's radial lines never cross; every rectangle corner replaces the even
    position nearest to it (in t), and the odd positions are the midpoints of their neighbours."""
    (x0, y0), (x1, y1) = box
    d = np.stack([a * np.cos(t), b * np.sin(t)], -1)
    with np.errstate(divide="ignore", invalid="ignore"):
        sx = np.where(d[:, 0] > 0, (x1 - centre[0]) / d[:, 0], np.where(d[:, 0] < 0, (x0 - centre[0]) / d[:, 0], np.inf))
        sy = np.where(d[:, 1] > 0, (y1 - centre[1]) / d[:, 1], np.where(d[:, 1] < 0, (y0 - centre[1]) / d[:, 1], np.inf))
    out = centre + np.minimum(sx, sy)[:, None] * d
    on_x, on_y = sx <= sy, sy <= sx  # the edge each ray leaves through: its coordinate exactly
    out[on_x, 0] = np.where(d[on_x, 0] > 0, x1, x0)
    out[on_y, 1] = np.where(d[on_y, 1] > 0, y1, y0)
    corners = np.array([[x1, y0], [x1, y1], [x0, y1], [x0, y0]])
    rel = corners - centre
    tc = np.arctan2(rel[:, 1] / b, rel[:, 0] / a)
    even = np.arange(0, t.size, 2)
    gap = np.abs((t[even][None] - tc[:, None] + np.pi) % (2 * np.pi) - np.pi)
    at = even[gap.argmin(1)]
    if np.unique(at).size < 4 or sum((at[(k + 1) % 4] - at[k]) % t.size for k in range(4)) != t.size:
        raise MeshError("the front has too few elements to reach the four plate corners in turn; give a smaller "
                        "front_size")
    out[at] = corners
    out[1::2] = 0.5 * (out[0::2] + np.roll(out[0::2], -1, axis=0))  # straight edges: mid-side nodes at the midpoints
    return out


def _geometric(n: int, first: float) -> np.ndarray:
    """2n+1 fractions in [0, 1] of n layers growing geometrically from thickness ``first``
    (uniform if n·first ≥ 1); mid-side values at the midpoints."""
    if n * first >= 1.0 or n == 1:
        c = np.linspace(0.0, 1.0, n + 1)
    else:
        lo, hi = 1.0, 2.0
        while first * (hi ** n - 1) / (hi - 1) < 1.0:
            hi *= 2.0
        for _ in range(200):
            q = 0.5 * (lo + hi)
            lo, hi = (q, hi) if first * (q ** n - 1) / (q - 1) < 1.0 else (lo, q)
        h = first * q ** np.arange(n)
        c = np.concatenate([[0.0], np.cumsum(h)]) / h.sum()
    out = np.empty(2 * n + 1)
    out[0::2] = c
    out[1::2] = 0.5 * (c[:-1] + c[1:])
    return out


def _check_fits(a: float, b: float, c: np.ndarray, box: np.ndarray, front_size: float, ring_width: float,
                ring_layers: int, outer_layers: int | None) -> None:
    clear = np.array([c[0] - a - box[0, 0], box[1, 0] - c[0] - a, c[1] - b - box[0, 1], box[1, 1] - c[1] - b])
    if min(a, b, front_size, ring_width) <= 0 or ring_layers < 1 or (outer_layers is not None and outer_layers < 1):
        raise MeshError("semi-axes, front_size, ring_width must be positive and ring_layers, outer_layers at least 1")
    if clear.min() <= 0:
        raise MeshError(f"the ellipse leaves the plate (its distance to the edges xmin, xmax, ymin, ymax is "
                        f"{', '.join(f'{v:.6g}' for v in clear)}); move the centre or shrink the semi-axes")
    if clear.min() <= ring_width:
        raise MeshError(f"the ring of width {ring_width:.6g} reaches an edge (the ellipse is {clear.min():.6g} from "
                        f"the nearest edge); give ring_width below {clear.min():.6g}")


def _rows(c, box, a, b, front_size, ring_width, ring_layers, outer_layers):
    """Node positions: the core's (ids 0..), its id grid and boundary loop, and the rows of the
    O-grid from the core's boundary outward (inner O-ring, ring, transition), 2N points each;
    the numbers of inner O-ring and transition layers."""
    t, m1, m2 = front_parameters(a, b, front_size)
    direction = np.stack([np.cos(t), np.sin(t)], -1)
    front = c + np.stack([a * np.cos(t), b * np.sin(t)], -1)
    ring_out = front + ring_width * direction
    core_uv, core_idx, loop = _core(m1, m2)
    core_xy = c + core_uv * np.array([a, b])
    n_inner = max(1, int(round((1 - CORE_FRACTION) * min(a, b) / front_size)))  # square-ish inner elements
    side = _side_points(c, box, t, a + ring_width, b + ring_width)
    reach = np.linalg.norm(side - ring_out, axis=1)  # length of each radial line of the transition
    layer = ring_width / ring_layers
    if outer_layers is None:  # enough layers to grow from a ring layer to the farthest corner
        outer_layers = max(1, int(np.ceil(np.log1p((OUTER_GROWTH - 1) * reach.max() / layer) / np.log(OUTER_GROWTH))))
    r_in = np.linspace(0.0, 1.0, 2 * n_inner + 1)[1:-1]
    r_ring = np.linspace(0.0, 1.0, 2 * ring_layers + 1)[1:]
    r_out = _geometric(outer_layers, layer / np.median(reach))[1:]
    rows = ([(1 - r) * core_xy[loop] + r * front for r in r_in] + [front]  # the front exactly on the ellipse
            + [front + r * ring_width * direction for r in r_ring] + [(1 - r) * ring_out + r * side for r in r_out])
    return core_xy, core_idx, loop, rows, n_inner, outer_layers


def _sets(nodes: np.ndarray, elements: np.ndarray, front: np.ndarray, edge: np.ndarray, counts, box: np.ndarray,
          tol: float) -> tuple[dict, dict]:
    """Node and element sets (see :func:`plate_with_ellipse`); ``front``/``edge``: the node ids on
    the ellipse and on the plate's boundary; ``counts``: elements inside, in the ring, outer."""
    n_in, n_ring, n_out = counts
    node_sets = {"front": front, "inside": np.unique(elements[:n_in]),
                 "interior": np.setdiff1d(elements[:n_in], front)}
    for name, axis, at in (("xmin", 0, box[0, 0]), ("xmax", 0, box[1, 0]), ("ymin", 1, box[0, 1]),
                           ("ymax", 1, box[1, 1])):
        node_sets[name] = np.sort(edge[np.abs(nodes[edge, axis] - at) <= tol])
    element_sets = {"inside": np.arange(n_in), "ring": n_in + np.arange(n_ring),
                    "outer": n_in + n_ring + np.arange(n_out), "outside": n_in + np.arange(n_ring + n_out)}
    return node_sets, element_sets


def plate_with_ellipse(lx: float, ly: float, center, semi_axes, front_size: float, ring_width: float,
                       ring_layers: int, outer_layers: int | None = None, origin=(0.0, 0.0, 0.0),
                       normal: str = "+z") -> Mesh:
    """Rectangle lx × ly (corner ``origin``, in the plane z = origin_z) with an ellipse of centre
    ``center`` (x, y) and ``semi_axes`` (a along x, b along y; a circle when a = b) whose boundary
    is a line of element edges (see the module docstring for the parts).

    Element sets: 'inside' (the ellipse's interior), 'ring', 'outer', 'outside' (ring and outer).
    Node sets: 'front' (on the ellipse), 'inside' (the nodes of the inside elements, front
    included), 'interior' (those strictly inside the front), 'xmin', 'xmax', 'ymin', 'ymax' (the
    plate edges)."""
    a, b = (float(v) for v in semi_axes)
    c = np.asarray(center, float)[:2]
    o = np.asarray(origin, float)
    box = np.array([[o[0], o[1]], [o[0] + lx, o[1] + ly]])
    _check_fits(a, b, c, box, front_size, ring_width, ring_layers, outer_layers)
    core_xy, core_idx, loop, rows, n_inner, outer_layers = _rows(c, box, a, b, front_size, ring_width, ring_layers,
                                                                 outer_layers)
    n2 = loop.size  # 2N positions around
    ids = np.vstack([loop[None], len(core_xy) + np.arange(len(rows) * n2).reshape(len(rows), n2)])
    xy = np.vstack([core_xy] + rows)
    wrap = np.hstack([ids, ids[:, :1]])  # the O-grid closes on itself
    ring_start, out_start = 2 * n_inner, 2 * (n_inner + ring_layers)
    parts = [_quads(core_idx), _quads(wrap[:ring_start + 1]), _quads(wrap[ring_start:out_start + 1]),
             _quads(wrap[out_start:])]
    elements = np.vstack(parts).astype(np.int64)
    nodes = np.column_stack([xy, np.full(len(xy), o[2])])
    counts = (len(parts[0]) + len(parts[1]), len(parts[2]), len(parts[3]))
    node_sets, element_sets = _sets(nodes, elements, ids[ring_start], ids[-1], counts, box, 1e-9 * max(lx, ly))
    mesh = Mesh(nodes, elements, node_sets, element_sets)
    sign = -1.0 if normal.strip().startswith("-") else 1.0
    mesh = _orient(mesh, lambda cc: np.tile([0.0, 0.0, sign], (len(cc), 1)))
    try:
        mesh.check()
    except MeshError:
        with np.errstate(invalid="ignore", divide="ignore"):
            jg, _ = mesh.jacobians()
            ratio = jg.min(1) / np.abs(jg).max(1)
        bad = np.flatnonzero(~(ratio >= Mesh.MIN_JACOBIAN_RATIO))
        where = ", ".join(f"{np.isin(bad, v).sum()} in the {k}" for k, v in element_sets.items()
                          if k != "outside" and np.isin(bad, v).any())
        raise MeshError(f"{bad.size} element(s) would fold or be badly distorted ({where}; the smallest signed "
                        f"Jacobian over the largest is {ratio[bad].min():.3g}, at least {Mesh.MIN_JACOBIAN_RATIO} is "
                        "needed): the ellipse or its ring sits too close to a plate edge or corner, or the front has "
                        "too few elements; move the centre towards the middle, shrink the semi-axes or ring_width, "
                        "or give a smaller front_size") from None
    return mesh
