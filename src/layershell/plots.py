"""PNG figures (matplotlib, Agg backend); :func:`write_figures` writes all figures of a run.

matplotlib is imported inside the functions so that the core package does not need it at
import time. Figures are built on an Agg canvas directly (no pyplot, so the global backend of
an interactive session is left alone and no figure stays registered); every function creates
the parent folder of ``path`` and releases its figure.
"""
from __future__ import annotations

import math
import textwrap
from pathlib import Path

import numpy as np

from .dofs import DofMap
from .element.shape import quad9
from .model import Model
from .units import Units, axis_label

_DPI = 120


def _figure(figsize):
    """A new matplotlib Figure on its own Agg canvas."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize)
    FigureCanvasAgg(fig)
    return fig


def _save(fig, path) -> Path:
    """Write ``fig`` as PNG atomically (temporary file in the same folder, then renamed: a kill
    never leaves a 0-byte or truncated PNG), mode from the umask."""
    from .io.output import atomic_write

    path = Path(path)
    try:
        separate_tick_labels(fig)
        atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=_DPI, format="png"))
    finally:
        fig.clear()  # "close": release artists; the figure is not registered with pyplot
    return path


def plot_xy(path, x: tuple[str, list[float]], y: tuple[str, list[float]], title: str = "") -> Path:
    """One curve of probe y against probe x over the converged steps (axis labels given)."""
    fig = _figure((5.0, 3.8))
    ax = fig.subplots()
    xv, yv = np.asarray(x[1], float), np.asarray(y[1], float)
    m = min(xv.size, yv.size)
    ax.plot(xv[:m], yv[:m], "o-", ms=3, lw=1.2)
    ax.set_xlabel(x[0])
    ax.set_ylabel(y[0])
    ax.set_title("\n".join(textwrap.wrap(title, TITLE_WIDTH)) if title else "")  # a long title wraps, not clipped
    ax.grid(True, alpha=0.4)
    fig.tight_layout()
    return _save(fig, path)


#: characters per line of a figure title (about the width of a 5-inch figure at its font size)
TITLE_WIDTH = 55


def _visible_tick_labels(axis, renderer):
    """The drawn tick labels of ``axis`` inside its view interval, with their window extents."""
    lo, hi = sorted(axis.get_view_interval())
    eps = 1e-9 * max(hi - lo, 1e-300)
    ticks = [t for t in axis.get_major_ticks() if lo - eps <= t.get_loc() <= hi + eps and t.label1.get_visible()
             and t.label1.get_text()]
    return [t.label1.get_window_extent(renderer) for t in ticks]


def tick_labels_overlap(axis, renderer) -> bool:
    """Whether two neighbouring tick labels of ``axis`` touch or overlap (a little gap required)."""
    i = 0 if axis.axis_name == "x" else 1
    spans = sorted((box.get_points()[0, i], box.get_points()[1, i]) for box in _visible_tick_labels(axis, renderer))
    gap = 2.0  # pixels
    return any(a[1] + gap > b[0] for a, b in zip(spans[:-1], spans[1:]))


def separate_tick_labels(fig) -> None:
    """Tick labels of the 2D axes of ``fig`` that do not overlap: plain or ×10ⁿ numbers (an offset
    or power above the axis instead of long labels), and fewer ticks where they still would."""
    from matplotlib.ticker import AutoLocator, MaxNLocator, ScalarFormatter

    axes = [ax for ax in fig.axes if ax.get_visible() and ax.name == "rectilinear"]
    for ax in axes:
        for axis in (ax.xaxis, ax.yaxis):
            if type(axis.get_major_formatter()) is ScalarFormatter and type(axis.get_major_locator()) is AutoLocator:
                fmt = ScalarFormatter(useMathText=True)
                fmt.set_powerlimits((-3, 4))
                axis.set_major_formatter(fmt)
                axis.set_major_locator(MaxNLocator(nbins=6, steps=[1, 2, 2.5, 5, 10]))
    if not axes:
        return
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    for nbins in (5, 4, 3, 2):
        crowded = [axis for ax in axes for axis in (ax.xaxis, ax.yaxis)
                   if isinstance(axis.get_major_locator(), MaxNLocator) and tick_labels_overlap(axis, renderer)]
        if not crowded:
            return
        for axis in crowded:
            axis.set_major_locator(MaxNLocator(nbins=nbins, steps=[1, 2, 2.5, 5, 10]))
        fig.canvas.draw()


def probe_units(spec) -> dict[str, str]:
    """Axis unit of every probe: its own ``unit``, else the physical unit of its quantity derived
    from ``[model] units`` (none where a ``scale`` other than ±1 may have converted it)."""
    units = Units.parse(spec.model.units)
    out = {}
    for p in spec.probes:
        unit = getattr(p, "unit", None)
        if unit is None:
            unit = units.of_probe(p.quantity, p.component) if abs(float(p.scale)) == 1.0 else ""
        out[p.name] = unit
    return out


def _prescribed_magnitudes(model: Model) -> list[float] | None:
    """|value| of every non-zero prescribed displacement that the load factor scales (fixes and
    ties); None where one of them is not a length (a higher director)."""
    mags = []
    for fx in model.fixes:
        if fx.value is None or not fx.scaled or not np.any(np.asarray(fx.value, float)):
            continue
        if any(d != 0 for d in fx.directors):
            return None
        mags += [abs(float(v)) for v in fx.value if v]
    for tie in model.ties:
        value = getattr(tie, "value", None)
        if value is None or not getattr(tie, "scaled", True) or not np.any(np.asarray(value, float)):
            continue
        if not np.all(np.asarray(tie.coeffs, float)[:, 0] == 1.0):
            return None
        mags += [abs(float(v)) for v in np.ravel(value) if v]
    return mags


def load_axis(model: Model) -> tuple[str, float]:
    """Label of the axis of what the load factor λ scales, and the factor on λ: under displacement
    control (scaled prescribed displacements and no scaled loads) the prescribed displacement
    λ·|value| (the largest, where they differ) in the length unit; otherwise λ."""
    mags = _prescribed_magnitudes(model)
    loads = any(getattr(ld, "scaled", True) for ld in (*model.nodal_loads, *model.surface_loads, *model.edge_loads))
    if mags and loads or mags is None and loads:
        return "load factor λ (scales the loads and prescribed displacements)", 1.0
    if mags is None:
        return "load factor λ (scales the prescribed displacements)", 1.0
    if not mags:
        return "load factor λ", 1.0
    vmax = max(mags)
    name = "prescribed displacement" if min(mags) == vmax else "largest prescribed displacement"
    return axis_label(f"{name} λ × {vmax:g}", Units.parse(model.units).length), vmax


#: summary keys of the events the load-displacement figures mark, with their labels and markers
EVENT_MARKS = (("first_cracking_step", "first cracking", "^"), ("first_yield_step", "first yielding", "s"),
               ("first_crushing_step", "first crushing", "v"), ("first_rupture_step", "first rupture", "X"),
               ("first_delamination_step", "first debonding", "D"))


def event_steps(summary: dict) -> dict[str, tuple[int, str]]:
    """label -> (index into the step records, marker) of the events the run saw."""
    steps = [r["step"] for r in summary.get("steps", [])]
    out = {}
    for key, label, marker in EVENT_MARKS:
        step = summary.get(key)
        if step is None and key == "first_delamination_step" and summary.get("first_delamination_load_factor") is not None:
            lam = summary["first_delamination_load_factor"]
            step = next((r["step"] for r in summary.get("steps", []) if r["load_factor"] >= lam), None)
        if step in steps:
            out[label] = (steps.index(step), marker)
    return out


def plot_load_displacement(path, load_factors, probes: dict[str, list[float]], units: str = "",
                           probe_units: dict[str, str | None] | None = None,
                           load: tuple[str, float] = ("load factor λ", 1.0),
                           events: dict[str, tuple[int, str]] | None = None) -> Path:
    """Load-displacement curves: one subplot per probe, probe value on x, ``load = (label, factor)``
    × the load factor on y (:func:`load_axis`: the prescribed displacement under displacement
    control); x axes labelled with ``probe_units[name]``, else ``units``; ``events`` (label ->
    (step index, marker), :func:`event_steps`) marked on every curve."""
    probe_units = probe_units or {}
    lam = load[1] * np.asarray(load_factors, float)
    n = max(len(probes), 1)
    ncols = min(n, 3)
    nrows = math.ceil(n / ncols)
    fig = _figure((4.2 * ncols, 3.4 * nrows))
    flat = fig.subplots(nrows, ncols, squeeze=False).ravel()
    for ax, (name, values) in zip(flat, probes.items()):
        v = np.asarray(values, float)
        m = min(v.size, lam.size)
        ax.plot(v[:m], lam[:m], "o-", ms=3, lw=1.2)
        for label, (i, marker) in (events or {}).items():
            if i < m:
                ax.plot(v[i], lam[i], marker, ms=8, mfc="none", mew=1.5, label=label)
        if events:
            ax.legend(fontsize=7, loc="best")
        ax.set_xlabel(axis_label(name, probe_units.get(name, units)))
        ax.set_ylabel(load[0])
        ax.set_title(name)
        ax.grid(True, alpha=0.4)
    if not probes:
        flat[0].set_title("no probes")
        flat[0].set_ylabel(load[0])
    else:
        for ax in flat[len(probes):]:
            ax.set_visible(False)
    fig.tight_layout()
    return _save(fig, path)


def _sample_surface(model: Model, values: np.ndarray, n: int = 5):
    """Interpolate nodal ``values (n_nodes, k)`` on an n×n grid of every element -> (e, n, n, k)."""
    s = np.linspace(-1.0, 1.0, n)
    XI, ETA = np.meshgrid(s, s, indexing="ij")
    N, _, _ = quad9(XI, ETA)  # (n, n, 9)
    return np.einsum("ijn,enk->eijk", N, values[model.mesh.elements])


def _quads(grid: np.ndarray) -> np.ndarray:
    """(e, n, n, 3) grids -> (e*(n-1)^2, 4, 3) quadrilaterals."""
    q = np.stack([grid[:, :-1, :-1], grid[:, 1:, :-1], grid[:, 1:, 1:], grid[:, :-1, 1:]], axis=-2)
    return q.reshape(-1, 4, 3)


def _outlines(grid: np.ndarray) -> np.ndarray:
    """(e, n, n, 3) grids -> (e*4, n, 3) element boundary polylines."""
    edges = [grid[:, :, 0], grid[:, -1, :], grid[:, ::-1, -1], grid[:, 0, ::-1]]
    return np.stack(edges, axis=1).reshape(-1, grid.shape[1], 3)


def layer_faces(model: Model, dm: DofMap, u_full: np.ndarray, layer: int, elements: np.ndarray, xi: np.ndarray,
                eta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Undeformed position ``X (2, p, 3)`` and displacement ``u (2, p, 3)`` of the bottom (index 0)
    and top face (index 1) of ``layer`` at the points ``(elements, xi, eta) (p,)``: the layer's
    director expansion u = Σ_l u_l (Θ_L³)^l at Θ_L³ = 0 and its thickness H."""
    from .element.geometry import surface_points

    ly = model.layers[layer]
    conn = model.mesh.elements[elements]
    sp = surface_points(model.mesh.nodes[conn], xi[:, None], eta[:, None], per_element=True)
    N = sp.N[:, 0]  # (p, 9)
    offset = np.einsum("pa,pa->p", N, model.offset(layer)[conn])
    H = np.einsum("pa,pa->p", N, np.asarray(ly.thickness, float)[conn])
    U = u_full[dm.element_dofs(model, layer, elements)].reshape(len(elements), 9, ly.directors + 1, 3)
    X, u = [], []
    for thL in (np.zeros_like(H), H):
        powers = thL[:, None] ** np.arange(ly.directors + 1)  # (p, d+1)
        u.append(np.einsum("pa,pl,pali->pi", N, powers, U))
        X.append(sp.X0[:, 0] + (offset + thL)[:, None] * sp.A3[:, 0])
    return np.stack(X), np.stack(u)


def layer_separation(model: Model, dm: DofMap, u_full: np.ndarray) -> tuple[float, int]:
    """The largest distance between the top face of a layer and the bottom face of the layer on
    it, over the nodes where both are present, and that node (-1 without stacked layers)."""
    from .export import director_field

    best, node = 0.0, -1
    for upper, lower in model.below().items():
        both = dm.present[upper] & dm.present[lower]
        H = np.asarray(model.layers[lower].thickness, float)
        top = sum(director_field(dm, u_full, lower, d) * H[:, None] ** d
                  for d in range(model.layers[lower].directors + 1))
        gap = np.where(both, np.linalg.norm(top - director_field(dm, u_full, upper, 0), axis=1), 0.0)
        if gap.size and gap.max() > best:
            best, node = float(gap.max()), int(np.argmax(gap))
    return best, node


def section_plane(model: Model, at) -> tuple[int, float, int, int]:
    """``(axis, value, horizontal, vertical)``: a plane ``x_axis = value`` through the point ``at``
    that cuts the shell across (the global axis along which the normals have the least component,
    of those the shorter extent), drawn in the global axes ``horizontal`` and ``vertical`` (the
    one nearer the normals). ``value`` is kept off node lines and inside the model."""
    mesh = model.mesh
    comp = np.abs(mesh.normals_at_centres()).mean(axis=0)
    extent = np.ptp(mesh.nodes, axis=0)
    candidates = [a for a in range(3) if comp[a] <= comp.min() + 1e-6]
    axis = min(candidates, key=lambda a: extent[a])
    horizontal, vertical = sorted((a for a in range(3) if a != axis), key=lambda a: comp[a])
    lo, hi = mesh.nodes[:, axis].min(), mesh.nodes[:, axis].max()
    margin = 1e-6 * max(extent[axis], 1e-300)
    value = float(np.clip(at[axis] + 0.1 * margin, lo + margin, hi - margin))
    return axis, value, horizontal, vertical


def section_points(model: Model, axis: int, value: float, n: int = 9):
    """Segments of the reference surface's cut with the plane ``x_axis = value``: ``(elements,
    xi, eta)`` of both ends, each ``(s, 2)`` (each element sampled on n×n points, split into
    triangles, the plane's crossings interpolated linearly along their edges)."""
    t = np.linspace(-1.0, 1.0, n)
    XI, ETA = np.meshgrid(t, t, indexing="ij")
    f = _sample_surface(model, model.mesh.nodes, n)[..., axis] - value  # (e, n, n)
    corners = [(slice(None, -1), slice(None, -1)), (slice(1, None), slice(None, -1)),
               (slice(1, None), slice(1, None)), (slice(None, -1), slice(1, None))]
    ne = f.shape[0]
    q_f = np.stack([f[:, a, b] for a, b in corners], -1).reshape(-1, 4)
    q_p = np.stack([np.stack([XI[a, b], ETA[a, b]], -1) for a, b in corners], -2)  # (n-1, n-1, 4, 2)
    q_p = np.broadcast_to(q_p, (ne,) + q_p.shape).reshape(-1, 4, 2)
    tri = np.array([[0, 1, 2], [0, 2, 3]])  # two triangles per cell
    tf = q_f[:, tri].reshape(-1, 3)  # (T, 3)
    tp = q_p[:, tri].reshape(-1, 3, 2)
    te = np.repeat(np.arange(ne), 2 * (n - 1) ** 2)
    cut = (tf.min(1) < 0.0) & (tf.max(1) > 0.0)
    tf, tp, te = tf[cut], tp[cut], te[cut]
    ends = []
    for a, b in ((0, 1), (1, 2), (2, 0)):
        fa, fb = tf[:, a], tf[:, b]
        crosses = fa * fb < 0.0
        w = np.where(crosses, fa / np.where(crosses, fa - fb, 1.0), 0.0)
        ends.append((crosses, tp[:, a] + w[:, None] * (tp[:, b] - tp[:, a])))
    crosses = np.stack([c for c, _ in ends], 1)  # (T, 3): two edges of every cut triangle
    points = np.stack([p for _, p in ends], 1)  # (T, 3, 2)
    first = np.argmax(crosses, axis=1)
    second = 2 - np.argmax(crosses[:, ::-1], axis=1)
    rows = np.arange(len(te))
    xi_eta = np.stack([points[rows, first], points[rows, second]], 1)  # (T, 2, 2)
    return np.stack([te, te], 1), xi_eta[..., 0], xi_eta[..., 1]


def _draw_section(ax, model: Model, dm: DofMap, u_full: np.ndarray, plane, scale: float) -> None:
    """Every layer cut by ``plane`` (:func:`section_plane`): undeformed faces grey, the deformed
    layer filled between its bottom and top face, displacements × ``scale``."""
    from matplotlib.collections import LineCollection, PolyCollection
    from matplotlib.colors import to_rgb

    axis, value, horizontal, vertical = plane
    elements, xi, eta = section_points(model, axis, value)
    cols = [horizontal, vertical]
    colours = ["tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown", "tab:pink",
               "tab:olive", "tab:cyan"]
    for k, ly in enumerate(model.layers):
        stacks_with = [si for si, st in enumerate(model.stacks) if k in st]
        has = np.isin(np.asarray(model.element_stack)[elements[:, 0]], stacks_with)
        if not has.any():
            continue
        e, x, y = elements[has].ravel(), xi[has].ravel(), eta[has].ravel()
        X, u = layer_faces(model, dm, u_full, k, e, x, y)  # (2 faces, 2 s, 3)
        X = X.reshape(2, -1, 2, 3)[..., cols]  # (face, segment, end, 2)
        x_def = X + scale * u.reshape(2, -1, 2, 3)[..., cols]
        quads = np.concatenate([x_def[0], x_def[1][:, ::-1]], axis=1)  # bottom face there, top face back
        c = colours[k % len(colours)]
        light = 0.55 * np.asarray(to_rgb(c)) + 0.45  # opaque: overlapping quads leave no seams
        ax.add_collection(PolyCollection(quads, facecolors=[light], edgecolors=[light], linewidths=0.3))
        ax.add_collection(LineCollection(np.concatenate(X), colors="0.55", linewidths=0.6, linestyles="--",
                                         zorder=3))
        ax.add_collection(LineCollection(np.concatenate(x_def), colors=c, linewidths=1.0))
        ax.plot([], [], color=light, lw=6, label=ly.name)
    ax.plot([], [], color="0.7", lw=0.8, ls="--", label="undeformed")
    ax.autoscale_view()
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    if 0.2 <= (y1 - y0) / max(x1 - x0, 1e-300) <= 5.0:  # not a thin strip: true proportions
        ax.set_aspect("equal", adjustable="datalim")
    ax.legend(fontsize="small", loc="best")


def plot_deformed(path, model: Model, dm: DofMap, u_full: np.ndarray, field: str = "magnitude",
                  scale: float | None = None, info: bool = False):
    """Deformed shape, displacements × ``scale``. Above, a 3D view of the reference surface:
    undeformed grey wireframe, deformed surface coloured by ``field`` ('magnitude' = |u|, or 'x',
    'y', 'z' for a component) of the reference-face displacement. Below, a section through the
    largest separation of two layers (else the largest displacement): every layer's deformed bottom
    and top face, so that a layer that lifts off shows as a gap. ``scale=None``: the largest
    displacement is drawn as 10 % of the model size, or as twice the thickness where that is less
    (never below 1: large displacements are drawn true to scale).

    The colour scale spans the field over the sampled surface (5×5 points per element, nodes
    included). Returns the path, or with ``info`` ``(path, {"field", "scale", "max_u",
    "color_range", "separation", "section"})``."""
    from .export import reference_displacement

    mesh = model.mesh
    u_full = np.asarray(u_full, float)
    u = reference_displacement(model, dm, u_full)
    norms = np.linalg.norm(u, axis=1)
    umax = float(norms.max()) if len(u) else 0.0
    separation, node = layer_separation(model, dm, u_full)
    if node < 0 or separation <= 1e-9 * umax:  # bonded layers: round-off
        separation, node = 0.0, int(np.argmax(norms)) if len(u) else 0
    plane = section_plane(model, mesh.nodes[node])
    if scale is None:
        scale = _default_scale(model, u, max(umax, separation), plane[3], separation)
    comp = {"x": 0, "y": 1, "z": 2, "ux": 0, "uy": 1, "uz": 2}
    if field == "magnitude":
        val, label = norms, "|u|"
    elif field in comp:
        val, label = u[:, comp[field]], f"u_{'xyz'[comp[field]]}"
    else:
        raise ValueError(f"unknown field '{field}' (use 'magnitude', 'x', 'y' or 'z')")

    length = Units.parse(model.units).length
    fig = _figure((8, 10))
    grid = fig.add_gridspec(2, 1, height_ratios=(3, 2))
    ax3 = fig.add_subplot(grid[0], projection="3d")
    clim = _draw_surface(ax3, fig, model, u, val, label, scale, length)
    ax3.set_title(f"reference surface, displacements × {scale:.3g}; max |u| = {umax:.4g}"
                  f"{' ' + length if length else ''}")
    ax = fig.add_subplot(grid[1])
    _draw_section(ax, model, dm, u_full, plane, scale)
    axis, value, horizontal, vertical = plane
    where = "the largest layer separation" if separation > 0.0 else "the largest displacement"
    unit = f" {length}" if length else ""
    ax.set_title(f"section {'xyz'[axis]} = {mesh.nodes[node, axis]:.4g}{unit} through {where}; displacements × {scale:.3g}\n"
                 f"largest separation of two layers: {separation:.3g}{unit}", fontsize=10)
    ax.set_xlabel(axis_label("xyz"[horizontal], length))
    ax.set_ylabel(axis_label("xyz"[vertical], length))
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    path = _save(fig, path)
    if info:
        return path, {"field": label, "scale": float(scale), "max_u": umax, "color_range": clim,
                      "separation": separation, "section": {"axis": "xyz"[axis], "value": value}}
    return path


def _default_scale(model: Model, u: np.ndarray, umax: float, vertical: int, separation: float = 0.0) -> float:
    """Magnification: the largest displacement ``umax`` as 10 % of the model size, or the largest
    one along the section's vertical axis (or the largest separation of two layers) as twice the
    thickness where that is less; never below 1 (large displacements are drawn true to scale)."""
    if umax <= 0.0:
        return 1.0
    scale = 0.1 * model.mesh.size() / umax
    across = max(float(np.abs(u[:, vertical]).max()), separation)
    thickness = float(model.total_thickness().max())
    if across > 0.0 and thickness > 0.0:
        scale = min(scale, 2.0 * thickness / across)
    return max(scale, 1.0)


def _draw_surface(ax, fig, model: Model, u: np.ndarray, val: np.ndarray, label: str, scale: float,
                  length: str) -> tuple[float, float]:
    """The 3D panel of :func:`plot_deformed`; returns the colour range."""
    from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

    X = _sample_surface(model, model.mesh.nodes)
    U = _sample_surface(model, u)
    V = _sample_surface(model, val[:, None])[..., 0]
    x_def = X + scale * U
    quads = _quads(x_def)
    qv = np.stack([V[:, :-1, :-1], V[:, 1:, :-1], V[:, 1:, 1:], V[:, :-1, 1:]], -1).mean(-1).ravel()
    ax.add_collection3d(Line3DCollection(_outlines(X), colors="0.6", linewidths=0.6))
    poly = Poly3DCollection(quads, cmap="viridis", edgecolors="none", linewidths=0.0)
    poly.set_array(qv)
    clim = (0.0, 0.0)
    if V.size:
        lo, hi = float(V.min()), float(V.max())
        clim = (lo, hi)
        poly.set_clim(lo, hi if hi > lo else lo + 1e-30)
    ax.add_collection3d(poly)
    ax.add_collection3d(Line3DCollection(_outlines(x_def), colors="k", linewidths=0.4))
    allp = np.concatenate([X.reshape(-1, 3), x_def.reshape(-1, 3)]) if X.size else np.zeros((1, 3))
    lo, hi = allp.min(0), allp.max(0)
    mid, rng = 0.5 * (lo + hi), hi - lo
    half = 0.5 * max(float(rng.max()), 1e-12) * 1.05
    for setter, c in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), mid):
        setter(c - half, c + half)
    ax.set_box_aspect((1, 1, 1))
    for setter, name in zip((ax.set_xlabel, ax.set_ylabel, ax.set_zlabel), "xyz"):
        setter(axis_label(name, length))
    fig.colorbar(poly, ax=ax, shrink=0.7, label=axis_label(label, length))
    return clim


def height_axis(model: Model, point) -> tuple[float, float, str]:
    """``(origin, factor, label)``: the physical height of the point Θ³ above the reference-surface
    point nearest ``point`` is ``origin + factor Θ³``. Where the normal A3 there is a global axis
    (±x, ±y, ±z), the height is that global coordinate (a model with normal −z has its reference
    face on top: Θ³ runs downwards); elsewhere Θ³ itself, the distance along A3 (stated)."""
    from .element.geometry import surface_points
    from .results import locate

    e, xi, eta, _ = locate(model, point)
    sp = surface_points(model.mesh.nodes[model.mesh.elements[e]][None], np.array([xi]), np.array([eta]))
    X0, A3 = sp.X0[0, 0], sp.A3[0, 0]
    length = Units.parse(model.units).length
    k = int(np.argmax(np.abs(A3)))
    if abs(A3[k]) > 1.0 - 1e-9:
        return float(X0[k]), float(np.sign(A3[k])), axis_label(f"height {'xyz'[k]}", length)
    normal = ", ".join(f"{c:.3g}" for c in A3)
    return 0.0, 1.0, axis_label(f"Θ³, along the normal ({normal})", length)


def plot_through_thickness(path, columns: dict[str, tuple[np.ndarray, np.ndarray]], xlabel: str,
                           mark: tuple[float, float] | None = None, title: str = "",
                           height: tuple[float, float, str] = (0.0, 1.0, "Θ³")) -> Path:
    """Stress (x) versus height (y) along thickness columns: ``columns[name] = (stress, theta3)``,
    plotted at ``origin + factor Θ³`` with ``height = (origin, factor, label)`` (:func:`height_axis`:
    the physical height); ``mark = (stress, Θ³)`` draws one point (e.g. a probe's value) on top."""
    origin, factor, ylabel = height
    fig = _figure((5, 6))
    ax = fig.subplots()
    for name, (s, t) in columns.items():
        ax.plot(np.asarray(s, float), origin + factor * np.asarray(t, float), ".-", lw=1.2, ms=4, label=name)
    if mark is not None:
        ax.plot([mark[0]], [origin + factor * mark[1]], "kx", ms=9, mew=2, label="probe")
    if title:
        ax.set_title(title)
    ax.axvline(0.0, color="0.5", lw=0.6)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(True, alpha=0.4)
    if columns:
        ax.legend(fontsize="small")
    fig.tight_layout()
    return _save(fig, path)


def plot_load_vs_area(path, load_factors, areas: dict[str, list[float]], units: str = "",
                      load: tuple[str, float] = ("load factor λ", 1.0)) -> Path:
    """Load (``load = (label, factor)`` × the load factor, :func:`load_axis`) against the debonded
    area of every interface; ``units``: the area unit."""
    fig = _figure((6.0, 4.2))
    ax = fig.add_subplot(1, 1, 1)
    for name, a in areas.items():
        ax.plot(a, load[1] * np.asarray(load_factors, float), "o-", label=name)
    ax.set_xlabel(axis_label("debonded area", units))
    ax.set_ylabel(load[0])
    ax.grid(True, alpha=0.3)
    ax.legend()
    return _save(fig, path)


# ----------------------------------------------------------------------------- a run's figures


class ZoneHistory:
    """Debonded flags of every interface after the converged steps that zone maps may show.

    Create it with the run's interface controller (or None: then it records nothing) and call
    :meth:`record` once per converged step. Kept: the steps in ``keep`` (``[output] zone_steps``),
    the first step with new debonding and the latest step, so memory (one bool per face Gauss
    point and kept step) and the checkpoint stay bounded however many steps the run has.
    """

    def __init__(self, controller=None, keep=None):
        self.controller = controller
        self.keep = {int(k) for k in (keep or ())}
        self.initial = [r.block.released.copy() for r in controller.runs] if controller is not None else []
        self.steps: list[int] = []
        self.load_factors: list[float] = []
        self.released: list[list[np.ndarray]] = []

    def _first(self) -> int | None:
        return next((s for s, rel in zip(self.steps, self.released)
                     if any(np.any(a & ~b) for a, b in zip(rel, self.initial))), None)

    def record(self, step: int, load_factor: float) -> None:
        if self.controller is None:
            return
        if self.steps and self.steps[-1] not in self.keep and self.steps[-1] != self._first():
            del self.steps[-1], self.load_factors[-1], self.released[-1]  # only the latest is kept
        self.steps.append(int(step))
        self.load_factors.append(float(load_factor))
        self.released.append([r.block.released.copy() for r in self.controller.runs])

    def default_steps(self) -> list[int]:
        """The first step with newly debonded points (beyond the initially debonded zones) and the
        last recorded step."""
        if not self.steps:
            return []
        first = self._first()
        return sorted({s for s in (first, self.steps[-1]) if s is not None})


def plot_zone_maps(path, controller, itf_index: int, maps: list[tuple[str, np.ndarray]], units: str = "") -> Path:
    """Plan view of one interface at several states: face Gauss points bonded (grey) or debonded
    (red), sized by their area; one panel per ``(title, released (e, q))`` in ``maps``; ``units``
    the model's ``[model] units`` (axes in its length unit, the area in length²)."""
    lengths = Units.parse(units)
    from .element.geometry import surface_points
    from .element.quadrature import gauss_2d

    blk = controller.runs[itf_index].block
    pts, _ = gauss_2d(3)
    X = surface_points(controller.mesh_nodes[blk.conn], pts[:, 0], pts[:, 1]).X0
    x, y = X[..., 0].ravel(), X[..., 1].ravel()
    w = blk.w0.ravel()
    s = 400.0 * w / w.max() * min(1.0, 50.0 / max(len(blk.conn), 1)) ** 0.5
    from matplotlib.collections import LineCollection
    from matplotlib.lines import Line2D
    from matplotlib.transforms import offset_copy

    corners = controller.mesh_nodes[blk.conn][:, [0, 4, 1, 5, 2, 6, 3, 7, 0], :2]  # element outlines
    n = max(len(maps), 1)
    fig = _figure((4.6 * n, 4.8))
    for i, (title, released) in enumerate(maps):
        ax = fig.add_subplot(1, n, i + 1)
        ax.add_collection(LineCollection(corners, colors="0.55", linewidths=0.6))
        rel = np.asarray(released, bool).ravel()
        ax.scatter(x[~rel], y[~rel], s=s[~rel], c="0.75")
        ax.scatter(x[rel], y[rel], s=s[rel], c="tab:red")
        ax.set_aspect("equal")
        ax.margins(0.05)
        ax.set_xlabel(axis_label("x", lengths.length))
        ax.set_ylabel(axis_label("y", lengths.length))
        area = float((blk.w0 * np.asarray(released, bool)).sum())
        ax.set_title(f"{blk.itf.name}: {title}\ndebonded area {area:.4g}{' ' + lengths.area if lengths.area else ''}",
                     fontsize=10)
        handles = [Line2D([], [], ls="", marker="o", ms=7, color=c, label=f"{lab} ({k} points)")
                   for c, lab, k in (("0.75", "bonded", int((~rel).sum())), ("tab:red", "debonded", int(rel.sum())))]
        below_label = offset_copy(ax.transAxes, fig=fig, y=-34, units="points")  # under the x label
        ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, 0.0), bbox_transform=below_label,
                  ncol=2, fontsize=8, frameon=False)
    fig.tight_layout()
    return _save(fig, path)


def _safe(name: str) -> str:
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in name)


def _thickness_figures(out: Path, spec, problem, u: np.ndarray, summary: dict, through_thickness) -> dict:
    """thickness_<probe>.png of every stress probe at a point (last converged step): the
    component through all layers against the physical height, the probe's own value marked."""
    from types import SimpleNamespace

    model = spec.model
    lam = summary["steps"][-1]["load_factor"]
    files = {}
    for pd in spec.source.probes:
        if pd.quantity != "stress" or pd.point is None:
            continue
        prof = SimpleNamespace(point=pd.point, component=pd.component, measure=pd.measure, points_per_layer=21,
                               sampling=pd.sampling, frame=pd.frame)
        cols = through_thickness(prof, model, problem.dm, u, lam)
        f = f"thickness_{_safe(pd.name)}.png"
        mark = None
        if isinstance(pd.theta3, (int, float)) and pd.reduce == "none" and pd.scale:
            mark = (float(summary["probes"][pd.name]) / pd.scale, float(pd.theta3))
        plot_through_thickness(out / f, {k: (v, t) for k, (t, v) in cols.items()},
                               axis_label(f"{pd.measure} σ{pd.component} at {tuple(pd.point)} (λ = {lam:.4g})",
                                          Units.parse(model.units).stress), mark=mark,
                               title=f"probe {pd.name}", height=height_axis(model, pd.point))
        vals = np.concatenate([v for _, v in cols.values()])
        files[f] = {"probe": pd.name, "range": (float(vals.min()), float(vals.max()))}
    return files


def write_figures(out, spec, problem, u: np.ndarray, summary: dict, zones: ZoneHistory | None = None,
                  through_thickness=None) -> dict:
    """All PNG figures of a run, written into ``out`` (called once after the last step).

    - ``load_displacement.png`` (every probe but load_factor ones) and
      ``load_displacement_<probe>.png`` (one each): load factor against the probe value per
      converged step, each axis in the probe's ``unit``;
    - ``plot_<name>.png`` for every ``[[plots]]``: probe y against probe x;
    - ``deformed.png``: the deformed reference surface coloured by |u| (last converged step);
    - ``thickness_<probe>.png``: for every stress probe at a ``point``, its component through
      all layers at that point (last converged step), the probe's own Θ³ marked;
    - ``cracks_<layer>.png`` for every concrete layer: its crack pattern in plan, the widest crack
      over the thickness at each in-plane Gauss point (:func:`layershell.crack_plot.plot_cracks`);
    - with delamination: ``debonded_zone_<interface>.png`` (one panel per step of
      ``[output] zone_steps``, default: first debonding and last step) and
      ``load_debonded_area.png``.

    ``through_thickness``: the sampler of the thickness plots (:func:`layershell.runner.through_thickness`;
    None: no thickness plots). Returns ``{file name: info}`` (info: a dict of the plotted data
    ranges, for checks).
    """
    out = Path(out)
    model = spec.model
    steps = summary.get("steps", [])
    files: dict[str, dict] = {}
    if not steps:
        return files
    lam = [s["load_factor"] for s in steps]
    names = [p.name for p in spec.probes if p.quantity != "load_factor"]  # λ against λ: a straight line
    units_of = probe_units(spec)
    load = load_axis(model)
    if names:
        series = {n: [s["probes"][n] for s in steps] for n in names}
        marks = event_steps(summary)
        plot_load_displacement(out / "load_displacement.png", lam, series, "", units_of, load, marks)
        files["load_displacement.png"] = {"probes": names, "events": sorted(marks)}
        for n in names:
            f = f"load_displacement_{_safe(n)}.png"
            plot_load_displacement(out / f, lam, {n: series[n]}, "", units_of, load, marks)
            files[f] = {"probe": n, "range": (float(min(series[n])), float(max(series[n])))}
    for pl in getattr(spec.source, "plots", []):
        xs, ys = ([s["probes"][n] for s in steps] for n in (pl.x, pl.y))
        f = f"plot_{_safe(pl.name)}.png"
        plot_xy(out / f, (axis_label(pl.x, units_of.get(pl.x)), xs),
                (axis_label(pl.y, units_of.get(pl.y)), ys), pl.title or f"{pl.y} against {pl.x}")
        files[f] = {"x": pl.x, "y": pl.y, "range_x": (float(min(xs)), float(max(xs))),
                    "range_y": (float(min(ys)), float(max(ys)))}

    files["deformed.png"] = plot_deformed(out / "deformed.png", model, problem.dm, u, info=True)[1]

    if through_thickness is not None:  # the sampler is handed in (runner.through_thickness): no import circle
        files.update(_thickness_figures(out, spec, problem, u, summary, through_thickness))

    for k, ly in enumerate(model.layers):
        if ly.law is not None and hasattr(ly.law, "crack") and model.point_states.get(k):
            from .crack_plot import plot_cracks

            f = f"cracks_{_safe(ly.name)}.png"
            info = plot_cracks(out / f, model, k, lam[-1])[1]
            files[f] = {"layer": ly.name, "cracked_points": info["cracked_points"], "max_width": info["max_width"]}

    ctl = problem.interfaces
    if ctl is not None and zones is not None and zones.steps:
        wanted = spec.output.zone_steps if spec.output.zone_steps else zones.default_steps()
        chosen = [s for s in wanted if s in zones.steps]
        for i, r in enumerate(ctl.runs):
            maps = [(f"step {s}, λ = {zones.load_factors[zones.steps.index(s)]:.4g}",
                     zones.released[zones.steps.index(s)][i]) for s in chosen]
            if not maps:
                continue
            f = f"debonded_zone_{_safe(r.block.itf.name)}.png"
            plot_zone_maps(out / f, ctl, i, maps, model.units)
            files[f] = {"steps": chosen}
    da = summary.get("debonded_area") or []
    if da:
        plot_load_vs_area(out / "load_debonded_area.png", [a["load_factor"] for a in da],
                          {k: [a[k] for a in da] for k in da[0] if k not in ("step", "load_factor")},
                          Units.parse(model.units).area, load)
        files["load_debonded_area.png"] = {}
    return files
