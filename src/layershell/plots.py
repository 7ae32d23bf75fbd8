"""Quick-look PNG plots (matplotlib, Agg backend).

matplotlib is imported inside the functions so that the core package does not need it at
import time. Figures are built on an Agg canvas directly (no pyplot, so the global backend of
an interactive session is left alone and no figure stays registered); every function creates
the parent folder of ``path`` and releases its figure.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .dofs import DofMap
from .element.shape import quad9
from .model import Model

_DPI = 120


def _figure(figsize):
    """A new matplotlib Figure on its own Agg canvas."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize)
    FigureCanvasAgg(fig)
    return fig


def _save(fig, path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    try:
        fig.savefig(path, dpi=_DPI)
    finally:
        fig.clear()  # "close": release artists; the figure is not registered with pyplot
    return path


def plot_load_displacement(path, load_factors, probes: dict[str, list[float]], units: str = "") -> Path:
    """Load-displacement curves: one subplot per probe, probe value on x, load factor on y."""
    lam = np.asarray(load_factors, float)
    n = max(len(probes), 1)
    ncols = min(n, 3)
    nrows = math.ceil(n / ncols)
    fig = _figure((4.2 * ncols, 3.4 * nrows))
    flat = fig.subplots(nrows, ncols, squeeze=False).ravel()
    for ax, (name, values) in zip(flat, probes.items()):
        v = np.asarray(values, float)
        m = min(v.size, lam.size)
        ax.plot(v[:m], lam[:m], "o-", ms=3, lw=1.2)
        ax.set_xlabel(f"{name} [{units}]" if units else name)
        ax.set_ylabel("load factor")
        ax.set_title(name)
        ax.grid(True, alpha=0.4)
    if not probes:
        flat[0].set_title("no probes")
        flat[0].set_ylabel("load factor")
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


def plot_deformed(path, model: Model, dm: DofMap, u_full: np.ndarray, field: str = "magnitude",
                  scale: float | None = None) -> Path:
    """3D view of the reference surface: undeformed grey wireframe, deformed surface coloured by
    ``field`` ('magnitude' = |u|, or 'x', 'y', 'z' for a component) of the reference-face
    displacement. ``scale=None``: the largest displacement is drawn as 10 % of the model size."""
    from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

    from .export import reference_displacement

    mesh = model.mesh
    u = reference_displacement(model, dm, np.asarray(u_full, float))
    umax = float(np.linalg.norm(u, axis=1).max()) if len(u) else 0.0
    size = mesh.size()
    if scale is None:
        scale = 0.1 * size / umax if umax > 0 else 1.0
    comp = {"x": 0, "y": 1, "z": 2, "ux": 0, "uy": 1, "uz": 2}
    if field == "magnitude":
        val = np.linalg.norm(u, axis=1)
        label = "|u|"
    elif field in comp:
        val = u[:, comp[field]]
        label = f"u_{'xyz'[comp[field]]}"
    else:
        raise ValueError(f"unknown field '{field}' (use 'magnitude', 'x', 'y' or 'z')")

    X = _sample_surface(model, mesh.nodes)
    U = _sample_surface(model, u)
    V = _sample_surface(model, val[:, None])[..., 0]
    x_def = X + scale * U
    quads = _quads(x_def)
    qv = np.stack([V[:, :-1, :-1], V[:, 1:, :-1], V[:, 1:, 1:], V[:, :-1, 1:]], -1).mean(-1).ravel()

    fig = _figure((8, 6))
    ax = fig.add_subplot(projection="3d")
    ax.add_collection3d(Line3DCollection(_outlines(X), colors="0.6", linewidths=0.6))
    poly = Poly3DCollection(quads, cmap="viridis", edgecolors="none", linewidths=0.0)
    poly.set_array(qv)
    if qv.size:
        lo, hi = float(qv.min()), float(qv.max())
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
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_zlabel("z")
    ax.set_title(f"deformed (scale {scale:.3g}), max |u| = {umax:.4g}")
    fig.colorbar(poly, ax=ax, shrink=0.7, label=label)
    return _save(fig, path)


def plot_through_thickness(path, columns: dict[str, tuple[np.ndarray, np.ndarray]], xlabel: str) -> Path:
    """Stress (x) versus Θ³ (y) along thickness columns: ``columns[name] = (stress, theta3)``."""
    fig = _figure((5, 6))
    ax = fig.subplots()
    for name, (s, t) in columns.items():
        ax.plot(np.asarray(s, float), np.asarray(t, float), ".-", lw=1.2, ms=4, label=name)
    ax.axvline(0.0, color="0.5", lw=0.6)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("Θ³")
    ax.grid(True, alpha=0.4)
    if columns:
        ax.legend(fontsize="small")
    fig.tight_layout()
    return _save(fig, path)


def plot_debonded_zone(path, controller, title: str = "") -> Path:
    """Plan view of every interface: face Gauss points (the "integration points of layer L")
    bonded (grey) or debonded (red), sized by their area; one panel per interface."""
    runs = controller.runs
    fig = _figure((5.0 * max(len(runs), 1), 4.6))
    for i, r in enumerate(runs):
        ax = fig.add_subplot(1, max(len(runs), 1), i + 1)
        from .element.geometry import surface_points
        from .element.quadrature import gauss_2d

        pts, _ = gauss_2d(3)
        blk = r.block
        X = surface_points(controller.mesh_nodes[blk.conn], pts[:, 0], pts[:, 1]).X0
        rel = blk.released.ravel()
        w = blk.w0.ravel()
        s = 400.0 * w / w.max()
        ax.scatter(X[..., 0].ravel()[~rel], X[..., 1].ravel()[~rel], s=s[~rel], c="0.75", label="bonded")
        ax.scatter(X[..., 0].ravel()[rel], X[..., 1].ravel()[rel], s=s[rel], c="tab:red", label="debonded")
        ax.set_aspect("equal")
        ax.set_xlabel("x")
        ax.set_ylabel("y")
        ax.set_title(f"{blk.itf.name} {title}".strip())
        ax.legend(loc="upper right", fontsize=8)
    return _save(fig, path)


def plot_load_vs_area(path, load_factors, areas: dict[str, list[float]], units: str = "") -> Path:
    """Load factor against the debonded area of every interface."""
    fig = _figure((6.0, 4.2))
    ax = fig.add_subplot(1, 1, 1)
    for name, a in areas.items():
        ax.plot(a, load_factors, "o-", label=name)
    ax.set_xlabel(f"debonded area{f' [{units}]' if units else ''}")
    ax.set_ylabel("load factor λ")
    ax.grid(True, alpha=0.3)
    ax.legend()
    return _save(fig, path)
