"""Warnings that `layershell check` gives before a run: input that is valid but, as written, is not
likely to do what the model means.

* :func:`unheld_layer_warnings`: a support on one layer holds the layers that are bonded to it;
  a layer that is connected to it only through a cohesive interface keeps its own displacements
  there and is held only by the interface's tractions (through a stress-criterion interface, only
  until it debonds). Only supports that move their layer along the surface (a non-zero prescribed
  displacement with a tangential part) are named: they shear the interface where they push or
  pull; a clamp or bearing on one layer is the set-up of most specimens and plates.
* :func:`process_zone_warnings`: the cohesive process zone (:mod:`layershell.process_zone`)
  against the node spacing of the mesh (at least 3 node spacings, Turon et al. 2007).
"""
from __future__ import annotations

import numpy as np

from .cohesive import CohesiveLaw
from .model import Model


def _bonded_groups(model: Model) -> np.ndarray:
    """(n_layers,) group of each layer: layers joined by bonded interfaces (no interface law) share
    a group; a cohesive or delaminating interface separates groups."""
    group = np.arange(len(model.layers))
    for up, lo in model.below().items():
        if up not in model.interface_laws:
            group[group == group[up]] = group[lo]
    return group


def _normals(model: Model) -> np.ndarray:
    """(n_nodes, 3) unit normals of the reference surface at the nodes."""
    from .io.build import nodal_normals

    return nodal_normals(model.mesh)


def _moves_tangentially(support, normals: np.ndarray) -> bool:
    """Whether a support prescribes a non-zero displacement in a direction with a part in the
    tangent plane (a fixture that pushes or pulls its layer along the surface shears an interface
    above it; a bearing along the normal, or a support held at zero, is the test set-up of most
    specimens and plates and is not named)."""
    value = getattr(support, "value", None)
    if value is None:
        return False
    n = normals[np.asarray(support.nodes)]
    if hasattr(support, "components"):
        moving = [c for c, v in zip(support.components, value) if v != 0.0]
        if not moving:
            return False
        along = np.abs(n @ np.eye(3)[moving].T)  # (m, c)
    else:
        if not np.any(np.asarray(value) != 0.0):
            return False
        along = np.abs(np.einsum("mi,mi->m", n, np.asarray(support.direction)))[:, None]
    return bool(np.any(along < 0.99))


def _support_names(spec, nodes: np.ndarray) -> str:
    """The supports[i] of the model file whose node selection is ``nodes``."""
    from .io.build import _node_selection

    names = []
    for i, sd in enumerate(spec.source.supports or []):
        try:
            sel = _node_selection(spec.model.mesh, sd, f"supports[{i}]", required=False)
        except Exception:  # a selection build() accepted; nothing to name otherwise
            continue
        if sel.size == nodes.size and np.array_equal(np.sort(sel), np.sort(nodes)):
            names.append(f"supports[{i}]")
    return " / ".join(names) or "a support"


def _interface_names(spec, model: Model, upper_layers) -> str:
    """'interfaces[i]' ('lower/upper', law) for the interfaces below ``upper_layers``."""
    index = {ly.name: k for k, ly in enumerate(model.layers)}
    below = model.below()
    out = []
    for i, idf in enumerate(spec.source.interfaces or []):
        k = index.get(idf.layer)
        if k in upper_layers:
            law = "cohesive" if isinstance(model.interface_laws.get(k), CohesiveLaw) else "stress criterion"
            out.append(f"interfaces[{i}] ('{model.layers[below[k]].name}/{model.layers[k].name}', {law})")
    return ", ".join(out)


def unheld_layer_warnings(spec) -> list[str]:
    """A warning per supported layer and layer that its supports do not hold: at the supports'
    nodes the layer exists, is connected to the supported layer only through cohesive or
    delaminating interfaces (MODEL.md §9-§10: a cohesive interface leaves both layers their own
    displacements; a stress-criterion one holds them only while bonded), and no support acts on it
    or on a layer bonded to it there."""
    model = spec.model
    if not model.interface_laws:
        return []
    group = _bonded_groups(model)
    present = model.layers_present()
    held = np.zeros_like(present)
    supports = [*model.fixes, *model.ties]
    for c in supports:
        held[np.ix_(group == group[c.layer], np.asarray(c.nodes))] = True
    found: dict[tuple[int, int], list] = {}  # (supported layer, group not held) -> [(nodes, free)]
    normals = _normals(model)
    for c in supports:
        if not _moves_tangentially(c, normals):
            continue
        nodes = np.asarray(c.nodes)
        for g in np.unique(group[group != group[c.layer]]):
            free = present[group == g][:, nodes].any(axis=0) & ~held[np.flatnonzero(group == g)[0], nodes]
            if free.any():
                found.setdefault((c.layer, int(g)), []).append((nodes, free))
    return [_unheld_message(spec, k, np.flatnonzero(group == g), group, present, parts)
            for (k, g), parts in found.items()]


def _unheld_message(spec, k: int, layers: np.ndarray, group: np.ndarray, present: np.ndarray, parts) -> str:
    model = spec.model
    nodes = np.unique(np.concatenate([n for n, _ in parts]))
    free = np.unique(np.concatenate([n[f] for n, f in parts]))
    names = [model.layers[j].name for j in layers if present[j, nodes].any()]
    cut = [up for up, lo in model.below().items()
           if up in model.interface_laws and group[up] != group[lo] and group[layers[0]] in (group[up], group[lo])]
    sups = []
    for n, _ in parts:
        name = _support_names(spec, n)
        if name not in sups:
            sups.append(name)
    sup = ", ".join(sups)
    where = ", ".join(f"{v:.4g}" for v in model.mesh.nodes[free[0]])
    own = model.layers[k].name
    return (f"{sup} on layer '{own}' do(es) not hold layer(s) {names}: at {free.size} of the {nodes.size} "
            f"support node(s) (e.g. ({where})) they are connected to '{own}' only through "
            f"{_interface_names(spec, model, cut)}, so only that interface holds them there (a cohesive interface "
            "by its tractions, a stress-criterion one until it debonds), and a support at a loaded edge shears or "
            f"opens it. To hold the whole stack, set layer = \"all\" in {sup} or add supports on {names} at the same "
            f"nodes; a fixture that bears on '{own}' alone (one arm of a test specimen) is as meant")


def process_zone_warnings(spec) -> list[str]:
    """Per cohesive interface and mode: a warning where the estimated process zone
    (:func:`~layershell.solver.interface_state.interface_zone_estimate`) spans fewer than 3 node
    spacings of the mesh along the debonding front (Turon et al. 2007); the run checks the same
    again with the mode of the points where damage starts."""
    from .interfaces import interfaces
    from .solver.interface_state import default_cohesive_stiffness, interface_zone_estimate, zone_description

    model = spec.model
    index = {ly.name: k for k, ly in enumerate(model.layers)}
    field = {index.get(idf.layer): f"interfaces[{i}]" for i, idf in enumerate(spec.source.interfaces or [])}
    out = []
    for itf in interfaces(model):
        law = model.interface_laws.get(itf.upper)
        if not isinstance(law, CohesiveLaw) or itf.elements.size == 0:
            continue
        K = law.K0 if law.K0 is not None else default_cohesive_stiffness(model, itf, law)
        est, h, _ = interface_zone_estimate(model, itf, law, K)
        short = [m for m in ("I", "II") if est[m]["length"] < 3.0 * h]
        if not short:
            continue
        what = {"I": "opens (mode I)", "II": "slides (mode II)"}
        per_mode = "; ".join(
            f"where it {what[m]} the zone spans {est[m]['length'] / h:.2f} node spacings, fewer than 3: refine "
            f"there to a node spacing of at most {est[m]['length'] / 3:.3g} (elements of "
            f"{2 * est[m]['length'] / 3:.3g})" for m in short)
        out.append(
            f"{field.get(itf.upper, 'interface')} ('{model.layers[itf.lower].name}/{model.layers[itf.upper].name}'): "
            f"the cohesive process zone is estimated at {zone_description(est)} (layershell.process_zone); the "
            f"mesh has a node spacing of {h:.4g} along the debonding front, and {per_mode}. With fewer than 3 "
            "node spacings in the zone the peak load and the debonding load are mesh dependent (Turon et al. 2007)")
    return out


def pre_run_warnings(spec) -> list[str]:
    """All warnings of this module (`layershell check`). They advise and never stop a check: a
    model they cannot assess (an error of their own) gets no warning from them."""
    import os

    out = []
    for check in (unheld_layer_warnings, process_zone_warnings):
        try:
            with np.errstate(all="ignore"):
                out += check(spec)
        except Exception:
            if os.environ.get("LAYERSHELL_TRACEBACK"):
                raise
    return out
