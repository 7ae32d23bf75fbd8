"""Plan figure of a concrete layer's crack pattern (``cracks_<layer>.png`` of a run).

At each in-plane Gauss point (3 × 3 per element) the widest crack over the layer's thickness
points is drawn as a short segment along the crack's trace on the surface (n × A3: across the
principal tension direction), coloured by its width, over the element outlines, in plan (x, y).
Cracks parallel to the surface (n along the shell normal) have no trace and are drawn as dots.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .material_output import crack_pattern
from .units import Units, axis_label

#: a segment's length over its element's √area: 3 points per element side, so 0.28 leaves gaps
#: of about a sixth of the points' spacing between neighbouring segments along a crack
SEGMENT = 0.28


def crack_segments(pattern, cracked: np.ndarray) -> np.ndarray:
    """(p, 2, 2) plan segments of the cracked points: centred on the point, along the crack's
    trace projected on the x-y plane (normalised), of length :data:`SEGMENT` × element size."""
    t = pattern.line[cracked, :2]
    tn = np.linalg.norm(t, axis=1, keepdims=True)
    t = np.where(tn > 1e-9, t / np.where(tn > 0, tn, 1.0), 0.0)
    half = (0.5 * SEGMENT * pattern.size[cracked])[:, None] * t
    c = pattern.x[cracked, :2]
    return np.stack([c - half, c + half], axis=1)


def plot_cracks(path, model, k: int, load_factor: float | None = None) -> tuple[Path, dict]:
    """Plan view of layer ``k``'s cracks in the committed state (module docstring); returns the
    path and ``{"cracked_points", "max_width", "segments"}`` (the drawn segments, for checks)."""
    from matplotlib.collections import LineCollection
    from matplotlib import colormaps
    from matplotlib.colors import ListedColormap, Normalize
    from mpl_toolkits.axes_grid1 import make_axes_locatable

    from .plots import _figure, _save

    lengths = Units.parse(model.units)
    pat = crack_pattern(model, k)
    cracked = pat.width > 0
    segs = crack_segments(pat, cracked)
    flat = np.linalg.norm(pat.line[cracked, :2], axis=1) < 1e-9  # a crack parallel to the surface (in plan)
    wmax = float(pat.width.max()) if cracked.any() else 0.0
    el = model.layer_elements(k)
    outline = model.mesh.nodes[model.mesh.elements[el]][:, [0, 4, 1, 5, 2, 6, 3, 7, 0], :2]
    span = np.ptp(outline.reshape(-1, 2), axis=0)
    width_in = 7.5  # the plan's width on the page (inches); its height follows the model's aspect
    height_in = float(np.clip(width_in * span[1] / max(span[0], 1e-300), 1.2, 6.0))
    fig = _figure((width_in + 2.0, height_in + 1.7))
    ax = fig.add_subplot(1, 1, 1)
    ax.add_collection(LineCollection(outline, colors="0.6", linewidths=0.6))
    cmap = ListedColormap(colormaps["plasma_r"](np.linspace(0.12, 1.0, 256)))  # no near-white end
    norm = Normalize(0.0, wmax if wmax > 0 else 1.0)
    wc = pat.width[cracked]
    lc = LineCollection(segs[~flat], cmap=cmap, norm=norm, linewidths=1.0 + 2.0 * norm(wc[~flat]))
    lc.set_array(wc[~flat])
    ax.add_collection(lc)
    if flat.any():
        ax.scatter(pat.x[cracked][flat, 0], pat.x[cracked][flat, 1], c=wc[flat], cmap=cmap, norm=norm, s=12,
                   marker="o", label="crack parallel to the surface")
        ax.legend(loc="upper right", fontsize=8)
    cax = make_axes_locatable(ax).append_axes("right", size=0.15, pad=0.12)
    cb = fig.colorbar(lc, cax=cax)
    cb.set_label(axis_label("crack width", lengths.length))
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.margins(0.04)
    ax.set_xlabel(axis_label("x", lengths.length))
    ax.set_ylabel(axis_label("y", lengths.length))
    at = f", λ = {load_factor:.4g}" if load_factor is not None else ""
    unit = f" {lengths.length}" if lengths.length else ""
    ax.set_title(f"layer '{model.layers[k].name}': cracks{at}, widest over the thickness at each in-plane point\n"
                 f"{int(cracked.sum())} of {cracked.size} points cracked, largest width {wmax:.3g}{unit}",
                 fontsize=10)
    fig.tight_layout()
    return _save(fig, path), {"cracked_points": int(cracked.sum()), "max_width": wmax, "segments": segs}
