"""9-node quadrilateral surface meshes and generators.

A mesh describes the **reference surface** (a face of the shell). Element node order is the
VTK ``quad9`` order (see :mod:`layershell.element.shape`); the normal A_3 = A_1 × A_2 must
point from the reference face into the material (MODEL.md §2, orientation rule) — the
generators take care of it through their ``normal`` argument.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .element.geometry import surface_points
from .element.shape import NODE_XI


class MeshError(ValueError):
    """Invalid mesh data."""


@dataclass
class Mesh:
    nodes: np.ndarray  # (n_nodes, 3)
    elements: np.ndarray  # (n_elements, 9) node indices
    node_sets: dict[str, np.ndarray] = field(default_factory=dict)
    element_sets: dict[str, np.ndarray] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    node_fields: dict[str, np.ndarray] = field(default_factory=dict)  # named nodal values, (n_nodes,)

    @property
    def n_nodes(self) -> int:
        return len(self.nodes)

    @property
    def n_elements(self) -> int:
        return len(self.elements)

    def size(self) -> float:
        """Diagonal of the bounding box (for tolerances)."""
        return float(np.linalg.norm(np.ptp(self.nodes, axis=0))) or 1.0

    def normals_at_centres(self) -> np.ndarray:
        sp = surface_points(self.nodes[self.elements], np.zeros(1), np.zeros(1))
        return sp.A3[:, 0]

    def flip(self, mask: np.ndarray) -> None:
        """Reverse the orientation (normal) of the elements in ``mask`` (mirror xi)."""
        perm = np.array([1, 0, 3, 2, 4, 7, 6, 5, 8])
        self.elements[mask] = self.elements[mask][:, perm]

    #: smallest allowed ratio min/max of the signed area Jacobian over an element's 3×3 Gauss points
    MIN_JACOBIAN_RATIO = 0.05

    def jacobians(self) -> tuple[np.ndarray, np.ndarray]:
        """Signed area Jacobians (A1 × A2) · N_c of every element (2.10), with N_c the unit normal
        at the element centre: at the 3×3 Gauss points ``(e, 9)`` and at the 9 nodes ``(e, 9)``.
        Positive everywhere for a valid element; a sign change means the element folds over."""
        from .element.quadrature import gauss_2d
        from .element.shape import quad9

        X = self.nodes[self.elements]  # (e, 9, 3)

        def cross(xi, eta):
            _, dN, _ = quad9(xi, eta)  # (q, 9, 2)
            A = np.einsum("qna,eni->eqai", dN, X)
            return np.cross(A[:, :, 0], A[:, :, 1])  # (e, q, 3)

        nc = cross(np.zeros(1), np.zeros(1))[:, 0]
        nrm = np.linalg.norm(nc, axis=1)
        nc = nc / np.where(nrm > 0, nrm, 1.0)[:, None]
        pts, _ = gauss_2d(3)
        jg = np.einsum("eqi,ei->eq", cross(pts[:, 0], pts[:, 1]), nc)
        jn = np.einsum("eqi,ei->eq", cross(NODE_XI[:, 0], NODE_XI[:, 1]), nc)
        return jg, jn

    def inconsistent_orientation(self) -> np.ndarray:
        """Ids of elements whose node order (normal A3) is reversed relative to their neighbours.

        Two elements sharing an edge must run along it in opposite directions. In every connected
        patch the orientation shared by the larger number of elements is taken as right; the
        others are returned (sorted). Edges shared by more than two elements are ignored."""
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import connected_components

        ne = self.n_elements
        if ne < 2:
            return np.zeros(0, np.int64)
        corners = self.elements[:, :4]
        a = corners.ravel()
        b = np.roll(corners, -1, axis=1).ravel()
        el = np.repeat(np.arange(ne), 4)
        keep = a != b  # collapsed edges (poles) carry no orientation
        a, b, el = a[keep], b[keep], el[keep]
        key = np.stack([np.minimum(a, b), np.maximum(a, b)], 1)
        _, inv, cnt = np.unique(key, axis=0, return_inverse=True, return_counts=True)
        inv = inv.ravel()
        order = np.argsort(inv, kind="stable")
        shared = cnt[inv[order]] == 2
        pair = order[shared].reshape(-1, 2)  # the two edge uses of every edge shared by two elements
        e1, e2 = el[pair[:, 0]], el[pair[:, 1]]
        same = a[pair[:, 0]] == a[pair[:, 1]]  # both run the same way: orientations disagree
        # double cover: vertex 2e = element e as given, 2e + 1 = element e flipped
        s1 = np.concatenate([2 * e1, 2 * e1 + 1])
        s2 = np.concatenate([2 * e2 + same, 2 * e2 + 1 - same])
        g = coo_matrix((np.ones(s1.size), (s1, s2)), shape=(2 * ne, 2 * ne))
        _, lab = connected_components(g, directed=False)
        as_given, flipped = lab[0::2], lab[1::2]
        ok = as_given != flipped  # False on a non-orientable patch (Möbius strip): nothing to say
        votes = np.bincount(as_given[ok], minlength=lab.max() + 1)
        # a patch appears twice in the cover (as given / flipped); the larger class wins
        bad = ok & (votes[as_given] < votes[flipped])
        tie = ok & (votes[as_given] == votes[flipped]) & (as_given > flipped)
        return np.flatnonzero(bad | tie)

    def check(self) -> None:
        """Reject inverted or badly distorted elements, naming them and their Jacobians.

        Rejected are elements (i) whose node order is reversed relative to their neighbours
        (:meth:`inconsistent_orientation`), (ii) whose signed area Jacobian (2.10) at the 3×3 Gauss
        points and the nodes has min/max below :attr:`MIN_JACOBIAN_RATIO` (negative: folded, e.g. a
        misplaced mid-side node; small: a corner angle near 180° or a squeezed element), (iii) whose
        normal turns by more than 60° within the element. Nodes of a collapsed edge (a pole of a
        shell of revolution, zero Jacobian by construction) are left out of (ii).
        """
        e = self.elements
        if e.ndim != 2 or e.shape[1] != 9:
            raise MeshError(f"elements must have 9 nodes each, got shape {e.shape}")
        if e.min() < 0 or e.max() >= self.n_nodes:
            raise MeshError("element connectivity refers to nodes that do not exist")
        flipped = self.inconsistent_orientation()
        if flipped.size:
            b = flipped[:10]
            with np.errstate(invalid="ignore", divide="ignore"):
                jg, _ = self.jacobians()
            detail = "; ".join(f"element {i}: Jacobian {-jg[i].max():.4g} to {-jg[i].min():.4g}" for i in b)
            raise MeshError(
                f"{flipped.size} element(s) are inverted (node order reversed relative to their neighbours, "
                f"so their normal points the other way): ids {b.tolist()}{' ...' if flipped.size > 10 else ''} "
                f"({detail}, signed area Jacobians (2.10) at the Gauss points relative to the neighbours' "
                "orientation); reverse their node order (Gmsh: 'ReverseMesh Surface {...};' or consistently "
                "oriented curve loops) so that all normals point into the material"
            )
        from .element.quadrature import gauss_2d

        with np.errstate(invalid="ignore", divide="ignore"):
            jg, jn = self.jacobians()
            X = self.nodes[e]
            dist = np.linalg.norm(X[:, :, None] - X[:, None, :], axis=-1)  # (e, 9, 9)
            collapsed = (dist < 1e-9 * self.size()).sum(2) > 1  # nodes of a collapsed edge (pole)
            jn = np.where(collapsed, np.inf, jn)
            jmax = np.maximum(jg.max(1), np.where(collapsed, -np.inf, jn).max(1))
            jmin = np.minimum(jg.min(1), jn.min(1))
            ratio = np.where(jmax > 0, jmin / np.where(jmax > 0, jmax, 1.0), -np.inf)
            pts, _ = gauss_2d(3)
            sp = surface_points(self.nodes[e], pts[:, 0], pts[:, 1])
            cosang = np.nan_to_num(np.einsum("eqi,ei->eq", sp.A3, self.normals_at_centres()), nan=-1.0)
        bad = np.flatnonzero((ratio < self.MIN_JACOBIAN_RATIO) | (cosang.min(1) < 0.5))
        if bad.size:
            b = bad[:10]
            detail = "; ".join(f"element {i}: Jacobian min {jmin[i]:.4g}, max {jmax[i]:.4g}, min/max {ratio[i]:.3g}"
                               for i in b)
            raise MeshError(
                f"{bad.size} element(s) are inverted or badly distorted: ids {b.tolist()}"
                f"{' ...' if bad.size > 10 else ''} ({detail}); the signed area Jacobian (2.10) must stay "
                f"positive with min/max ≥ {self.MIN_JACOBIAN_RATIO} over each element (Gauss points and nodes): "
                "fix the node order or the element shape (move misplaced mid-side or centre nodes, avoid corner "
                "angles near 0° or 180°)"
            )


def _structured(nx: int, ny: int, fn, edge_names=("s0", "s1", "t0", "t1")) -> Mesh:
    """Structured (2nx+1) x (2ny+1) grid of quad9 elements; ``fn(s, t)`` maps [0,1]^2 to 3D.
    The four boundary edges become node sets named ``edge_names`` (s = 0, s = 1, t = 0, t = 1)."""
    s = np.linspace(0.0, 1.0, 2 * nx + 1)
    t = np.linspace(0.0, 1.0, 2 * ny + 1)
    S, T = np.meshgrid(s, t, indexing="xy")
    nodes = fn(S.ravel(), T.ravel())
    idx = np.arange(S.size).reshape(T.shape[0], S.shape[1])  # [row j (t), col i (s)]
    elems = []
    for j in range(ny):
        for i in range(nx):
            i0, j0 = 2 * i, 2 * j
            loc = [(i0 + int(x + 1), j0 + int(y + 1)) for x, y in NODE_XI]
            elems.append([idx[jj, ii] for ii, jj in loc])
    sets = {edge_names[0]: idx[:, 0], edge_names[1]: idx[:, -1], edge_names[2]: idx[0, :], edge_names[3]: idx[-1, :]}
    return Mesh(np.asarray(nodes, float), np.asarray(elems, dtype=np.int64), {k: np.array(v) for k, v in sets.items()})


def _orient(mesh: Mesh, normal_fn) -> Mesh:
    """Flip elements whose normal disagrees with ``normal_fn(centre)``."""
    c = mesh.nodes[mesh.elements[:, 8]]
    want = normal_fn(c)
    mesh.flip(np.einsum("ei,ei->e", mesh.normals_at_centres(), want) < 0)
    return mesh


def graded(n: int, ratio: float = 1.0) -> np.ndarray:
    """The 2n+1 node coordinates in [0, 1] of n elements whose sizes grow geometrically from the
    first to the last by ``ratio`` (last/first); mid-side nodes at the element midpoints."""
    q = ratio ** (1.0 / (n - 1)) if n > 1 else 1.0
    h = q ** np.arange(n)
    c = np.concatenate([[0.0], np.cumsum(h)]) / h.sum()
    out = np.empty(2 * n + 1)
    out[0::2] = c
    out[1::2] = 0.5 * (c[:-1] + c[1:])
    return out


def _distinct(values: np.ndarray, tol: float) -> np.ndarray:
    """Sorted ``values`` with those closer than ``tol`` to the previous one dropped."""
    v = np.sort(values)
    return v[np.concatenate([[True], np.diff(v) > tol])] if v.size else v


def _size_knots(length: float, refine: np.ndarray, ratio: float) -> tuple[np.ndarray, np.ndarray]:
    """Knots and values of the piecewise linear element-size field along [0, length]: 1 at the
    refine points, rising linearly with the distance from the nearest one to ``ratio`` at the
    farthest point (uniform without refine points)."""
    if refine.size == 0 or ratio == 1.0:
        return np.array([0.0, length]), np.ones(2)
    knots = _distinct(np.concatenate([[0.0, length], refine, 0.5 * (refine[:-1] + refine[1:])]), 0.0)
    dist = np.abs(knots[:, None] - refine[None, :]).min(1)
    return knots, 1.0 + (ratio - 1.0) * dist / dist.max()


def _density_integral(x: np.ndarray, knots: np.ndarray, h: np.ndarray) -> np.ndarray:
    """∫₀ˣ ds / h(s) for the piecewise linear size field (``knots``, ``h``), exact per piece."""
    dk, dh = np.diff(knots), np.diff(h)
    flat = np.abs(dh) <= 1e-12 * h[:-1]
    slope = np.where(flat, 1.0, dh / np.where(dk > 0, dk, 1.0))
    full = np.where(flat, dk / h[:-1], np.log(h[1:] / h[:-1]) / slope)
    cum = np.concatenate([[0.0], np.cumsum(full)])
    k = np.clip(np.searchsorted(knots, x, side="right") - 1, 0, dk.size - 1)
    part = x - knots[k]
    inner = np.where(flat[k], part / h[k], np.log1p(slope[k] * part / h[k]) / slope[k])
    return cum[k] + inner


def _density_inverse(target: np.ndarray, knots: np.ndarray, h: np.ndarray) -> np.ndarray:
    """The x at which :func:`_density_integral` reaches ``target`` (inverse, exact per piece)."""
    cum = _density_integral(knots, knots, h)
    dk, dh = np.diff(knots), np.diff(h)
    flat = np.abs(dh) <= 1e-12 * h[:-1]
    slope = np.where(flat, 1.0, dh / np.where(dk > 0, dk, 1.0))
    k = np.clip(np.searchsorted(cum, target, side="right") - 1, 0, dk.size - 1)
    rest = target - cum[k]
    inner = np.where(flat[k], rest * h[k], h[k] * np.expm1(slope[k] * rest) / slope[k])
    return knots[k] + inner


def _share_out(n: int, weight: np.ndarray) -> np.ndarray:
    """``n`` elements shared out over pieces in proportion to ``weight``, at least one each
    (largest remainders)."""
    target = n * weight / weight.sum()
    count = np.maximum(1, np.floor(target).astype(np.int64))
    while count.sum() > n:  # the minimum of one took elements from the others
        spare = np.flatnonzero(count > 1)
        count[spare[np.argmin((target - count)[spare])]] -= 1
    while count.sum() < n:
        count[np.argmax(target - count)] += 1
    return count


def _corners_on_lines(length: float, n: int, breaks: np.ndarray, knots: np.ndarray, h: np.ndarray) -> np.ndarray:
    """The n + 1 element corners: every break is a corner, and within each piece between breaks
    the corners divide the integral of 1/h into equal parts."""
    at = _density_integral(breaks, knots, h)
    count = _share_out(n, np.diff(at))
    piece = np.repeat(np.arange(count.size), count)
    step = np.concatenate([np.arange(c) for c in count])
    target = at[piece] + step * (np.diff(at) / count)[piece]
    corners = np.concatenate([_density_inverse(target, knots, h), [length]])
    corners[np.cumsum(np.concatenate([[0], count]))] = breaks  # the lines exactly, not to round-off
    return corners


def node_lines(length: float, n: int, lines=(), refine=(), ratio: float = 1.0, start: float = 0.0) -> np.ndarray:
    """The 2n+1 node coordinates in [start, start + length] of ``n`` elements along one side, with
    element corners exactly at every coordinate of ``lines`` and ``refine`` and at both ends.

    Without ``refine`` the elements are shared out over the pieces between lines in proportion
    to their length and are equal within each piece. With ``refine``, the element size grows
    linearly with the distance from the nearest refine point, so that the longest element over
    the shortest is ``ratio`` (to round-off, or as close as the integer element counts
    allow; MeshError if they miss it by more than 10 %); this grades towards both ends, an
    interior line or any set of lines. Mid-side nodes lie at the element midpoints."""
    length, start = float(length), float(start)
    tol = 1e-9 * length
    as_given = np.concatenate([np.asarray(lines, float).ravel(), np.asarray(refine, float).ravel()])
    given, refine = as_given - start, np.asarray(refine, float).ravel() - start
    outside = given[(given < -tol) | (given > length + tol)]
    if outside.size:
        raise MeshError(f"node line at {outside[0] + start:.9g} lies outside [{start:.9g}, {start + length:.9g}]")
    breaks = _distinct(np.concatenate([[0.0, length], np.clip(given, 0.0, length)]), tol)
    if breaks.size - 1 > n:
        raise MeshError(f"{n} element(s) cannot put corners at {breaks.size} node lines {(breaks + start).tolist()}; "
                        f"give at least {breaks.size - 1} elements")
    ref = _distinct(np.clip(refine, 0.0, length), tol)

    def corners(size_ratio: float) -> np.ndarray:
        return _corners_on_lines(length, n, breaks, *_size_knots(length, ref, size_ratio))

    def achieved(c: np.ndarray) -> float:
        el = np.diff(c)
        return float(el.max() / el.min())

    c = corners(1.0)
    if ref.size and ratio != 1.0 and n > 1:
        lo, hi = 0.0, np.log(ratio)  # bisection on the log of the size field's ratio
        while achieved(corners(np.exp(hi))) < ratio and hi < 60.0:
            lo, hi = hi, 2.0 * hi
        best = None
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            cm = corners(np.exp(mid))
            r = achieved(cm)
            if best is None or abs(np.log(r / ratio)) < abs(np.log(achieved(best) / ratio)):
                best = cm
            if abs(r / ratio - 1.0) < 1e-12:
                break
            lo, hi = (mid, hi) if r < ratio else (lo, mid)
        c = best
        if abs(achieved(c) / ratio - 1.0) > 0.1:
            el = np.diff(c)
            raise MeshError(f"the ratio {ratio:.6g} cannot be reached with {n} element(s) and node lines at "
                            f"{(breaks + start).tolist()} (closest: element lengths {el.min():.6g} to {el.max():.6g}, "
                            f"ratio {achieved(c):.4g}); give more elements or a ratio near {achieved(c):.3g}")
    c = start + c
    c[np.abs(given[:, None] - (c - start)[None]).argmin(1)] = as_given  # the lines as written, not recomputed
    c[0], c[-1] = start, start + length
    out = np.empty(2 * n + 1)
    out[0::2] = c
    out[1::2] = 0.5 * (c[:-1] + c[1:])
    return out


def rectangle(lx: float, ly: float, nx: int, ny: int, origin=(0.0, 0.0, 0.0), normal: str = "+z",
              grading_x: float = 1.0, grading_y: float = 1.0, lines_x=(), lines_y=(), refine_x=(), refine_y=(),
              refine_ratio_x: float = 1.0, refine_ratio_y: float = 1.0) -> Mesh:
    """Flat rectangular plate in the x-y plane; ``normal`` '+z' (reference face at the bottom)
    or '-z' (reference face on top, material below). ``grading_x``/``grading_y``: size of the
    last element over the first along x/y (geometric; < 1 refines towards the far edge).

    ``lines_x``/``lines_y`` (absolute coordinates, origin included): element edges lie exactly
    there; ``refine_x``/``refine_y``: node lines towards which the elements shrink, the longest
    over the shortest being ``refine_ratio_x``/``refine_ratio_y`` (:func:`node_lines`). Either
    these or ``grading_x``/``grading_y`` along one side, not both."""
    o = np.asarray(origin, float)

    def side(length, n, grading, lines, refine, ratio, start, name):
        if len(lines) == 0 and len(refine) == 0:
            return o[start] + length * graded(n, grading)
        if grading != 1.0:
            raise MeshError(f"grading_{name} grades from one edge; with lines_{name} or refine_{name} give the "
                            f"edges to refine towards in refine_{name} instead")
        try:
            return node_lines(length, n, lines, refine, ratio, o[start])
        except MeshError as exc:
            raise MeshError(f"along {name} (lines_{name}, refine_{name}, refine_ratio_{name}, n{name}): {exc}") from None

    gx = side(lx, nx, grading_x, lines_x, refine_x, refine_ratio_x, 0, "x")
    gy = side(ly, ny, grading_y, lines_y, refine_y, refine_ratio_y, 1, "y")

    def fn(s, t):
        i, j = np.rint(s * 2 * nx).astype(int), np.rint(t * 2 * ny).astype(int)
        return np.stack([gx[i], gy[j], o[2] + 0 * s], -1)

    mesh = _structured(nx, ny, fn, ("xmin", "xmax", "ymin", "ymax"))
    sign = -1.0 if normal.strip().startswith("-") else 1.0
    return _orient(mesh, lambda c: np.tile([0.0, 0.0, sign], (len(c), 1)))


def _inner_grid(mesh: Mesh, elements: np.ndarray, n: int) -> np.ndarray:
    """(e, n, n, 3) points of ``elements`` on an n × n grid just inside each element
    (ξ, η ∈ ±(1 − 10⁻⁶)), indexed [element, η, ξ]."""
    from .element.shape import quad9

    t = np.linspace(-1.0 + 1e-6, 1.0 - 1e-6, n)
    xi, eta = np.meshgrid(t, t, indexing="xy")
    shape, _, _ = quad9(xi.ravel(), eta.ravel())  # (n², 9)
    pts = np.einsum("qn,eni->eqi", shape, mesh.nodes[mesh.elements[elements]])
    return pts.reshape(len(elements), n, n, 3)


def elements_cut_by(mesh: Mesh, inside, n: int = 7) -> np.ndarray:
    """Ids of the elements that a region's boundary crosses instead of following their edges:
    ``inside(points (m, 3)) -> (m,) bool`` takes both values on an n × n grid just inside them."""
    cut = []
    for block in np.array_split(np.arange(mesh.n_elements), max(1, mesh.n_elements // 20_000)):  # bounded memory
        flags = np.asarray(inside(_inner_grid(mesh, block, n).reshape(-1, 3)), bool).reshape(block.size, n * n)
        cut.append(block[flags.any(1) & ~flags.all(1)])
    return np.concatenate(cut)


def axis_crossings(mesh: Mesh, inside, elements: np.ndarray, n: int = 7) -> tuple[np.ndarray, np.ndarray]:
    """Where a region's boundary crosses ``elements`` of a flat mesh with axis-parallel edges:
    the distinct x at which ``inside`` changes along lines of constant y through them, and the
    distinct y along lines of constant x (n lines each, located by bisection to better than 10⁻¹²
    of the element size), rounded to 10⁻⁹ of the mesh size in decimal digits."""
    grid = _inner_grid(mesh, np.asarray(elements, np.int64), n)
    rows, cols = grid, grid.transpose(0, 2, 1, 3)  # lines along ξ, then along η
    a = np.concatenate([rows[:, :, :-1].reshape(-1, 3), cols[:, :, :-1].reshape(-1, 3)])
    b = np.concatenate([rows[:, :, 1:].reshape(-1, 3), cols[:, :, 1:].reshape(-1, 3)])
    fa, fb = np.asarray(inside(a), bool), np.asarray(inside(b), bool)
    a, b, fa = a[fa != fb], b[fa != fb], fa[fa != fb]
    for _ in range(45):
        mid = 0.5 * (a + b)
        same = np.asarray(inside(mid), bool) == fa
        a = np.where(same[:, None], mid, a)
        b = np.where(same[:, None], b, mid)
    step = np.abs(b - a)
    at = 0.5 * (a + b)
    along_x = step[:, 0] >= step[:, 1]
    digits = int(9 - np.floor(np.log10(mesh.size())))
    tol = 1e-9 * mesh.size()
    return _distinct(np.round(at[along_x, 0], digits), tol), _distinct(np.round(at[~along_x, 1], digits), tol)


def cylinder(radius: float, angle_start: float, angle_end: float, width: float, n_arc: int, n_width: int,
             normal: str = "inward", axis: str = "z") -> Mesh:
    """Cylindrical panel / ring sector (angles in degrees) of reference-face radius ``radius``.

    ``axis='z'``: the arc lies in the x-y plane (angle from +x towards +y), width along z.
    ``axis='y'``: the arc lies in the x-z plane (angle from +x towards +z), width along y.
    ``normal='inward'`` puts the reference face on the outer face (A_3 towards the axis),
    ``'outward'`` on the inner face.
    """
    a0, a1 = np.deg2rad(angle_start), np.deg2rad(angle_end)

    def fn(s, t):
        ph = a0 + (a1 - a0) * s
        w = width * t
        if axis == "z":
            return np.stack([radius * np.cos(ph), radius * np.sin(ph), w], -1)
        return np.stack([radius * np.cos(ph), w, radius * np.sin(ph)], -1)

    mesh = _structured(n_arc, n_width, fn, ("start", "end", "bottom", "top"))
    sign = -1.0 if normal == "inward" else 1.0

    def want(c):
        r = c.copy()
        r[:, 2 if axis == "z" else 1] = 0.0
        return sign * r / np.linalg.norm(r, axis=1, keepdims=True)

    return _orient(mesh, want)


@dataclass(frozen=True)
class MeridianSegment:
    """One piece of a meridian between two consecutive meridian points: ``elements`` elements
    along it, an optional element-set ``name``, and an optional ``arc_center`` (r_c, z_c) that
    makes it the shorter circular arc about that centre (default: a straight line)."""

    elements: int
    name: str | None = None
    arc_center: tuple[float, float] | None = None


def _meridian_nodes(r: np.ndarray, z: np.ndarray, segments: list[MeridianSegment],
                    thickness: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Node positions (r, z) along a segmented meridian (2 n_k + 1 nodes per segment, shared end
    points) and the thickness interpolated linearly in the segment parameter (arc length)."""
    rs, zs, hs = [], [], []
    for k, seg in enumerate(segments):
        u = np.linspace(0.0, 1.0, 2 * seg.elements + 1)
        if k > 0:
            u = u[1:]
        p0, p1 = np.array([r[k], z[k]]), np.array([r[k + 1], z[k + 1]])
        if seg.arc_center is None:
            pts = p0[None] + u[:, None] * (p1 - p0)[None]
        else:
            c = np.asarray(seg.arc_center, float)
            rho0, rho1 = np.linalg.norm(p0 - c), np.linalg.norm(p1 - c)
            if abs(rho0 - rho1) > 1e-6 * max(rho0, rho1) or rho0 == 0:
                raise MeshError(
                    f"segments[{k}].arc_center {c.tolist()}: the centre must be equally far from both end points "
                    f"({p0.tolist()} at {rho0:.9g}, {p1.tolist()} at {rho1:.9g}); correct the centre or the points")
            a0 = np.arctan2(*(p0 - c)[::-1])
            da = (np.arctan2(*(p1 - c)[::-1]) - a0 + np.pi) % (2 * np.pi) - np.pi
            if abs(abs(da) - np.pi) < 1e-9:
                raise MeshError(f"segments[{k}]: the arc is a half circle, its direction is ambiguous; split it "
                                "with a meridian point in between")
            rho = 0.5 * (rho0 + rho1)
            a = a0 + u * da
            pts = c[None] + rho * np.stack([np.cos(a), np.sin(a)], -1)
        rs.append(pts[:, 0])
        zs.append(pts[:, 1])
        if thickness is not None:
            hs.append(thickness[k] + u * (thickness[k + 1] - thickness[k]))
    return np.concatenate(rs), np.concatenate(zs), (np.concatenate(hs) if thickness is not None else None)


def revolution(meridian_r, meridian_z, n_meridian: int | None, n_circ: int, angle: float = 360.0,
               normal: str = "inward", segments: list[MeridianSegment] | None = None,
               thickness=None) -> Mesh:
    """Shell of revolution about the z axis from a meridian through the points (r_k, z_k).

    Either ``n_meridian`` elements of equal length along the polyline (resampled by arc length),
    or ``segments``: one :class:`MeridianSegment` per pair of consecutive points, each straight or
    a circular arc, with its own number of elements and an element-set name (segments may share a
    name). ``n_circ`` elements around the axis over ``angle`` degrees. ``normal`` 'inward' or
    'outward' relative to the axis (a dome with the reference surface on the inner face:
    'outward'). The first element coordinate line is the hoop direction, so a layer without
    ``direction`` has material axis 1 along the hoop.

    ``thickness``: optional value per meridian point, interpolated linearly along the meridian
    (per segment) and stored as ``node_fields['h_meridian']``.

    Node sets: 'first'/'last' (the circles at the first and last meridian point), 'start'/'end'
    (the meridians at angle 0 and ``angle``; merged when closed) and, with segments,
    'meridian_point_k' (the circle through meridian point k).
    """
    r = np.asarray(meridian_r, float)
    z = np.asarray(meridian_z, float)
    if r.shape != z.shape or r.ndim != 1 or r.size < 2:
        raise MeshError("meridian: r and z need the same length >= 2")
    h = None if thickness is None else np.asarray(thickness, float)
    if h is not None and h.shape != r.shape:
        raise MeshError(f"meridian_thickness: give one value per meridian point ({r.size}), got {h.size}")
    if segments is None:
        if n_meridian is None or n_meridian < 1:
            raise MeshError("give n_meridian (elements along the meridian) or segments")
        sl = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(r), np.diff(z)))])
        at = np.linspace(0.0, sl[-1], 2 * n_meridian + 1)
        mr, mz = np.interp(at, sl, r), np.interp(at, sl, z)
        mh = np.interp(at, sl, h) if h is not None else None
        rows = np.full(n_meridian, -1)
    else:
        if len(segments) != r.size - 1:
            raise MeshError(f"segments: give one segment per pair of consecutive meridian points ({r.size - 1}), "
                            f"got {len(segments)}")
        mr, mz, mh = _meridian_nodes(r, z, list(segments), h)
        n_meridian = sum(sg.elements for sg in segments)
        rows = np.repeat(np.arange(len(segments)), [sg.elements for sg in segments])
    closed = abs(angle - 360.0) < 1e-9
    n_row = 2 * n_meridian

    def fn(s, t):
        j = np.rint(t * n_row).astype(np.int64)
        ph = np.deg2rad(angle) * s
        return np.stack([mr[j] * np.cos(ph), mr[j] * np.sin(ph), mz[j]], -1)

    mesh = _structured(n_circ, n_meridian, fn, ("start", "end", "first", "last"))
    n_s = 2 * n_circ + 1
    grid_row = np.arange(mesh.n_nodes) // n_s  # meridian node index of every grid node
    if mh is not None:
        mesh.node_fields["h_meridian"] = mh[grid_row]
    if segments is not None:
        ends = 2 * np.concatenate([[0], np.cumsum([sg.elements for sg in segments])])
        for k, j in enumerate(ends):
            mesh.node_sets[f"meridian_point_{k}"] = j * n_s + np.arange(n_s)
        el_row = np.arange(mesh.n_elements) // n_circ  # elements are numbered row by row
        for k, sg in enumerate(segments):
            if sg.name:
                sel = np.flatnonzero(rows[el_row] == k)
                prev = mesh.element_sets.get(sg.name, np.zeros(0, np.int64))
                mesh.element_sets[sg.name] = np.union1d(prev, sel)
    if closed:
        mesh = merge_coincident(mesh)
    sign = -1.0 if normal == "inward" else 1.0
    return _orient_revolution(mesh, sign)


def _orient_revolution(mesh: Mesh, sign: float) -> Mesh:
    n = mesh.normals_at_centres()
    c = mesh.nodes[mesh.elements[:, 8]]
    rc = np.hypot(c[:, 0], c[:, 1])
    er = np.stack([c[:, 0], c[:, 1], 0 * rc], -1) / np.maximum(rc, 1e-300)[:, None]
    # radial part decides; for a horizontal (flat) ring use the vertical part
    rad = np.einsum("ei,ei->e", n, er)
    key = np.where(np.abs(rad) > 1e-6, rad, n[:, 2])
    mesh.flip(sign * key < 0)
    return mesh


def merge_coincident(mesh: Mesh, tol: float | None = None) -> Mesh:
    """Merge nodes closer than ``tol`` (default 1e-9 × mesh size)."""
    tol = tol if tol is not None else 1e-9 * mesh.size()
    key = np.round(mesh.nodes / tol).astype(np.int64)
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)
    remap = np.empty_like(order)
    remap[order] = np.arange(order.size)
    nodes = mesh.nodes[first[order]]
    elements = remap[inv.ravel()][mesh.elements]
    sets = {k: np.unique(remap[inv.ravel()][v]) for k, v in mesh.node_sets.items()}
    fields = {k: np.asarray(v)[first[order]] for k, v in mesh.node_fields.items()}
    return Mesh(nodes, elements, sets, dict(mesh.element_sets), list(mesh.notes), fields)
