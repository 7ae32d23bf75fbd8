"""[[lines]]: a displacement, stress or traction component sampled along a polyline on the
reference surface, written as line_<name>.csv (distance along the line, the point, one column per
component) and line_<name>.png (the components against the distance) at the last converged step.

The samples are evaluated like probes (:class:`layershell.io.probes.Probe`): all points of a line
at once; where the line's layer is absent ([[stacks]]) the values are left empty."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .probes import FIELD_COMPONENTS, _check_heights, component_values, locate_points


@dataclass
class Line:
    name: str
    quantity: str  # displacement | stress | traction
    components: list[str]
    measure: str
    sampling: str
    frame: str
    layer: int | None  # the layer named in the model file
    layer_name: str | None
    local_theta: bool  # traction: Θ_L³ = 0 of ``layer`` (its bottom face)
    s: np.ndarray  # (p,) distance along the line of each sample
    X: np.ndarray  # (p, 3) the samples on the reference surface
    present: np.ndarray  # (p,) the field exists there (the layer is present)
    elements: np.ndarray  # (q,) the present samples: element, ξ, η, Θ³, layer
    xi: np.ndarray
    eta: np.ndarray
    theta: np.ndarray
    layers: np.ndarray
    scale: float = 1.0
    unit: str | None = None

    def values(self, model, dm, u, load_factor: float = 1.0) -> np.ndarray:
        """(p, components) values at the samples; NaN where the field does not exist."""
        out = np.full((self.s.size, len(self.components)), np.nan)
        if self.elements.size:
            if self.quantity == "displacement":
                from ..results import evaluate_points

                ps = evaluate_points(model, dm, u, self.elements, self.xi, self.eta, self.theta, self.layers,
                                     self.local_theta)
            else:
                from ..recovery import stress_points

                ps = stress_points(model, dm, u, self.elements, self.xi, self.eta, self.theta, self.layers,
                                   self.local_theta, self.sampling, load_factor)
            for j, c in enumerate(self.components):
                out[self.present, j] = self.scale * component_values(ps, self.quantity, c, self.measure, self.frame)
        return out


def build_lines(mf, model, layer_index) -> list[Line]:
    """The [[lines]] of the model file, checked: fields named in the errors."""
    from .errors import InputError

    out = []
    names = [ld.name for ld in mf.lines]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise InputError(f"'lines': the names {dup} appear more than once (each names its files line_<name>.csv); "
                         "rename the lines")
    for i, ld in enumerate(mf.lines):
        f = f"lines[{i}]"
        allowed = FIELD_COMPONENTS[ld.quantity]
        bad = [c for c in ld.components if c not in allowed]
        if bad:
            raise InputError(f"'{f}.components': {bad} are not {ld.quantity} components; use some of {list(allowed)}")
        k = None
        if ld.layer is not None:
            if ld.layer not in layer_index:
                raise InputError(f"'{f}.layer': unknown layer '{ld.layer}'; defined: {list(layer_index)}")
            k = layer_index[ld.layer]
        elif ld.quantity == "traction":
            raise InputError(f"'{f}.layer': a traction line needs the layer whose bottom face is meant")
        el, xi, eta, s, X, present = _samples(model, ld, f, k)
        if not present.any():
            raise InputError(f"'{f}.layer': layer '{ld.layer}' is absent along the whole line (the [[stacks]] leave "
                             f"it out there); move '{f}.points' to where the layer lies, or name another layer")
        el, xi, eta = el[present], xi[present], eta[present]
        local = ld.quantity == "traction"
        if local:
            th = np.zeros(el.size)
        else:
            th = np.full(el.size, float(ld.theta3))
            _check_heights(model, f, el, xi, eta, np.array([float(ld.theta3)]), k)
        layers = np.full(el.size, k) if k is not None else _layers_at(model, el, xi, eta, th)
        out.append(Line(ld.name, ld.quantity, list(ld.components), ld.measure, ld.sampling, ld.frame, k, ld.layer,
                        local, s, X, present, el, xi, eta, th, layers, ld.scale, ld.unit))
    return out


def _samples(model, ld, f: str, layer: int | None):
    """(element, ξ, η, distance along the line, point, layer present) of the samples: ``ld.samples``
    points evenly spaced on each straight segment (a shared vertex once), each moved to the nearest
    point of the reference surface (the distance is summed over the moved points); on the end of
    ``layer`` an element that holds it (:func:`locate_points`)."""
    from ..element.geometry import surface_points
    from .errors import InputError

    V = np.asarray(ld.points, float)
    if not np.isfinite(V).all():
        raise InputError(f"'{f}.points': {ld.points} holds a value that is not a finite number; give the vertices "
                         "as numbers")
    size = model.mesh.size()
    dist = locate_points(model, V)[3]
    off = np.flatnonzero(dist > 1e-3 * size)
    if off.size:
        j = int(off[0])
        raise InputError(f"'{f}.points[{j}]': {ld.points[j]} is {dist[j]:.4g} away from the reference surface; give "
                         "the vertices of the line on the reference surface (Θ³ = 0) and the height in theta3")
    t = np.linspace(0.0, 1.0, ld.samples)
    seg = np.concatenate([np.full(t.size - (j > 0), j) for j in range(len(V) - 1)])
    tt = np.concatenate([t[(j > 0):] for j in range(len(V) - 1)])
    P = V[seg] + tt[:, None] * (V[seg + 1] - V[seg])
    el, xi, eta, d, present = locate_points(model, P, layer)
    length = np.linalg.norm(V[seg + 1] - V[seg], axis=1)
    away = np.flatnonzero(d > 1e-3 * size + 0.05 * length)
    if away.size:
        j = int(seg[away[0]])
        raise InputError(f"'{f}.points': the segment from {ld.points[j]} to {ld.points[j + 1]} leaves the shell (a "
                         f"sample lies {d[away[0]]:.4g} from the reference surface); add vertices so that each "
                         "segment runs on the shell")
    sp = surface_points(model.mesh.nodes[model.mesh.elements[el]], xi[:, None], eta[:, None], per_element=True)
    X = sp.X0[:, 0]
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(X, axis=0), axis=1))])
    return el, xi, eta, s, X, present


def _layers_at(model, el, xi, eta, th) -> np.ndarray:
    """The layer of each point's element that contains Θ³ (the lower one on a boundary between
    layers), as :func:`layershell.results.layer_at`, for all points at once."""
    from ..element.shape import quad9

    N = quad9(np.asarray(xi, float), np.asarray(eta, float))[0]
    conn = model.mesh.elements[el]
    out = np.full(el.size, -1)
    stk = model.element_stack[el]
    for si in np.unique(stk):
        in_stack = stk == si
        for k in model.stacks[si]:
            lo = np.einsum("pa,pa->p", N, model.offset(k)[conn])
            hi = np.einsum("pa,pa->p", N, (model.offset(k) + model.layers[k].thickness)[conn])
            tol = 1e-9 * max(float(np.abs(hi).max(initial=0.0)), 1.0)
            out[in_stack & (out < 0) & (th >= lo - tol) & (th <= hi + tol)] = k
        out[in_stack & (out < 0)] = model.stacks[si][-1]
    return out


def write_lines(spec, problem, u, rec, load_factor: float) -> dict[str, str]:
    """line_<name>.csv and (with output plots) line_<name>.png of every [[lines]] entry."""
    from ..units import Units

    units = Units.parse(spec.model.units)
    files = {}
    for ln in spec.lines:
        vals = ln.values(spec.model, problem.dm, u, load_factor)
        cols = [f"{ln.quantity}_{c}" for c in ln.components]
        rows = [[float(s), *map(float, x), *("" if np.isnan(v) else float(v) for v in row)]
                for s, x, row in zip(ln.s, ln.X, vals)]
        rec.write_csv(f"line_{ln.name}.csv", ["s", "x", "y", "z"] + cols, rows)
        files[ln.name] = f"line_{ln.name}.csv"
        if spec.output.plots:
            unit = ln.unit if ln.unit is not None else (units.of_probe(ln.quantity) if abs(ln.scale) == 1.0 else "")
            plot_line(rec.path(f"line_{ln.name}.png"), ln, vals, units.length, unit, load_factor)
    return files


def plot_line(path, ln: Line, vals: np.ndarray, length_unit: str, unit: str, load_factor: float):
    """The components of a line against the distance along it (gaps where the layer is absent)."""
    from ..plots import _figure, _save
    from ..units import axis_label

    fig = _figure((6.0, 3.8))
    ax = fig.subplots()
    for j, c in enumerate(ln.components):
        label = f"u_{c}" if ln.quantity == "displacement" else f"σ{c}" if c.isdigit() else c
        ax.plot(ln.s, vals[:, j], ".-", ms=3, lw=1.2, label=label)
    ax.set_xlabel(axis_label("distance along the line s", length_unit))
    ax.set_ylabel(axis_label(ln.quantity if len(ln.components) > 1 else f"{ln.quantity} {ln.components[0]}", unit))
    where = f", layer '{ln.layer_name}'" if ln.layer_name else ""
    if not ln.local_theta:
        where += f", Θ³ = {float(ln.theta[0]):.4g}"
    ax.set_title(f"{ln.name}{where}, λ = {load_factor:.4g}")
    if len(ln.components) > 1:
        ax.legend(fontsize=8)
    ax.grid(True, alpha=0.4)
    fig.tight_layout()
    return _save(fig, path)
