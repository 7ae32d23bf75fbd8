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


def _label(name: str, unit: str | None, units: str) -> str:
    u = unit if unit is not None else units
    return f"{name} [{u}]" if u else name


def plot_load_displacement(path, load_factors, probes: dict[str, list[float]], units: str = "",
                           probe_units: dict[str, str | None] | None = None) -> Path:
    """Load-displacement curves: one subplot per probe, probe value on x, load factor on y;
    axes labelled with the probe's own unit where given (else the unit system)."""
    probe_units = probe_units or {}
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
        ax.set_xlabel(_label(name, probe_units.get(name), units))
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
                  scale: float | None = None, info: bool = False):
    """3D view of the reference surface: undeformed grey wireframe, deformed surface coloured by
    ``field`` ('magnitude' = |u|, or 'x', 'y', 'z' for a component) of the reference-face
    displacement. ``scale=None``: the largest displacement is drawn as 10 % of the model size.

    The colour scale spans the field over the sampled surface (5×5 points per element, nodes
    included). Returns the path, or with ``info`` ``(path, {"field", "scale", "max_u",
    "color_range"})``."""
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
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_zlabel("z")
    ax.set_title(f"deformed (scale {scale:.3g}), max |u| = {umax:.4g}")
    fig.colorbar(poly, ax=ax, shrink=0.7, label=label)
    path = _save(fig, path)
    if info:
        return path, {"field": label, "scale": float(scale), "max_u": umax, "color_range": clim}
    return path


def plot_through_thickness(path, columns: dict[str, tuple[np.ndarray, np.ndarray]], xlabel: str,
                           mark: tuple[float, float] | None = None, title: str = "") -> Path:
    """Stress (x) versus Θ³ (y) along thickness columns: ``columns[name] = (stress, theta3)``;
    ``mark = (stress, Θ³)`` draws one point (e.g. a probe's value) on top."""
    fig = _figure((5, 6))
    ax = fig.subplots()
    for name, (s, t) in columns.items():
        ax.plot(np.asarray(s, float), np.asarray(t, float), ".-", lw=1.2, ms=4, label=name)
    if mark is not None:
        ax.plot([mark[0]], [mark[1]], "kx", ms=9, mew=2, label="probe")
    if title:
        ax.set_title(title)
    ax.axvline(0.0, color="0.5", lw=0.6)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("Θ³")
    ax.grid(True, alpha=0.4)
    if columns:
        ax.legend(fontsize="small")
    fig.tight_layout()
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


def plot_zone_maps(path, controller, itf_index: int, maps: list[tuple[str, np.ndarray]]) -> Path:
    """Plan view of one interface at several states: face Gauss points bonded (grey) or debonded
    (red), sized by their area; one panel per ``(title, released (e, q))`` in ``maps``."""
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
        ax.set_xlabel("x")
        ax.set_ylabel("y")
        area = float((blk.w0 * np.asarray(released, bool)).sum())
        ax.set_title(f"{blk.itf.name}: {title}\ndebonded area {area:.4g}", fontsize=10)
        handles = [Line2D([], [], ls="", marker="o", ms=7, color=c, label=f"{lab} ({k} points)")
                   for c, lab, k in (("0.75", "bonded", int((~rel).sum())), ("tab:red", "debonded", int(rel.sum())))]
        ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, fontsize=8,
                  frameon=False)
    fig.tight_layout()
    return _save(fig, path)


def _safe(name: str) -> str:
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in name)


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
    units_of = {p.name: getattr(p, "unit", None) for p in spec.probes}
    if names:
        series = {n: [s["probes"][n] for s in steps] for n in names}
        plot_load_displacement(out / "load_displacement.png", lam, series, model.units, units_of)
        files["load_displacement.png"] = {"probes": names}
        for n in names:
            f = f"load_displacement_{_safe(n)}.png"
            plot_load_displacement(out / f, lam, {n: series[n]}, model.units, units_of)
            files[f] = {"probe": n, "range": (float(min(series[n])), float(max(series[n])))}
    for pl in getattr(spec.source, "plots", []):
        xs, ys = ([s["probes"][n] for s in steps] for n in (pl.x, pl.y))
        f = f"plot_{_safe(pl.name)}.png"
        plot_xy(out / f, (_label(pl.x, units_of.get(pl.x), model.units), xs),
                (_label(pl.y, units_of.get(pl.y), model.units), ys), pl.title or f"{pl.y} against {pl.x}")
        files[f] = {"x": pl.x, "y": pl.y, "range_x": (float(min(xs)), float(max(xs))),
                    "range_y": (float(min(ys)), float(max(ys)))}

    files["deformed.png"] = plot_deformed(out / "deformed.png", model, problem.dm, u, info=True)[1]

    for pd in spec.source.probes:
        if pd.quantity != "stress" or pd.point is None:
            continue
        from types import SimpleNamespace

        if through_thickness is None:  # the sampler is handed in (runner.through_thickness): no import circle
            continue
        prof = SimpleNamespace(point=pd.point, component=pd.component, measure=pd.measure, points_per_layer=21,
                               sampling=pd.sampling, frame=pd.frame)
        cols = through_thickness(prof, model, problem.dm, u, lam[-1])
        f = f"thickness_{_safe(pd.name)}.png"
        mark = None
        if isinstance(pd.theta3, (int, float)) and pd.reduce == "none" and pd.scale:
            mark = (float(summary["probes"][pd.name]) / pd.scale, float(pd.theta3))
        plot_through_thickness(out / f, {k: (v, t) for k, (t, v) in cols.items()},
                               f"{pd.measure} σ{pd.component} at {tuple(pd.point)} (λ = {lam[-1]:.4g})", mark=mark,
                               title=f"probe {pd.name}")
        vals = np.concatenate([v for _, v in cols.values()])
        files[f] = {"probe": pd.name, "range": (float(vals.min()), float(vals.max()))}

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
            plot_zone_maps(out / f, ctl, i, maps)
            files[f] = {"steps": chosen}
    da = summary.get("debonded_area") or []
    if da:
        plot_load_vs_area(out / "load_debonded_area.png", [a["load_factor"] for a in da],
                          {k: [a[k] for a in da] for k in da[0] if k not in ("step", "load_factor")})
        files["load_debonded_area.png"] = {}
    return files
