"""``[imperfection]``: the mesh nodes moved along the reference face's normal before the analysis,
by a buckling mode of ``layershell buckle`` (buckling_modes.npz) scaled to an amplitude, or by a
formula of x, y, z."""
from __future__ import annotations

import zipfile
from pathlib import Path

import numpy as np

from .. import mesh as meshmod
from ..formula import FormulaError
from .errors import XYZ, InputError, formula

F = "imperfection"


def _mode_shape(m: meshmod.Mesh, imp, base: Path) -> np.ndarray:
    """The normal displacement of mode ``imp.mode`` at the nodes, scaled to a largest |value| of 1."""
    from ..buckling_output import MODES_FILE, normal_components

    folder = base / imp.folder
    path = folder / MODES_FILE
    if not path.is_file():
        raise InputError(f"'{F}.folder': '{imp.folder}' holds no {MODES_FILE} (looked for {path}); write the modes "
                         f"first with `layershell buckle MODEL --modes {imp.mode} --out {imp.folder}` on the perfect "
                         "model, or correct the folder (relative to the model file)")
    try:
        with np.load(path) as data:
            nodes, disp = data["nodes"], data["displacement"]
    except (OSError, ValueError, KeyError, zipfile.BadZipFile) as exc:
        raise InputError(f"'{F}.folder': {path} cannot be read ({exc}); write it again with "
                         "`layershell buckle`") from None
    if imp.mode > disp.shape[0]:
        raise InputError(f"'{F}.mode': mode {imp.mode} does not exist, {path} holds {disp.shape[0]} mode(s); give a "
                         f"mode from 1 to {disp.shape[0]}, or write more with `layershell buckle MODEL --modes "
                         f"{imp.mode}`")
    if nodes.shape != m.nodes.shape or not np.allclose(nodes, m.nodes, rtol=0.0, atol=1e-9 * m.size()):
        raise InputError(f"'{F}.folder': the modes in {path} belong to another mesh ({nodes.shape[0]} nodes against "
                         f"this model's {m.n_nodes}, or other coordinates); run `layershell buckle` on this model "
                         "without its [imperfection]")
    w = normal_components(m.nodes, m.elements, disp[imp.mode - 1][None])[0]
    top = float(np.abs(w).max())
    if not top > 0.0:
        raise InputError(f"'{F}.mode': mode {imp.mode} moves the reference face not at all along its normal (an "
                         "in-plane mode, or a mode local to a layer above a held reference face, such as a "
                         "sub-laminate over a delamination), so it gives no imperfection of the mesh; choose "
                         "another mode")
    return w / top


def imperfect_nodes(m: meshmod.Mesh, imp, base: Path) -> np.ndarray:
    """The node coordinates of ``m`` moved by the imperfection ``imp`` (schema.ImperfectionDef)."""
    from .build import nodal_normals

    if imp.formula is not None:
        fn = formula(imp.formula, XYZ, f"{F}.formula")
        x, y, z = m.nodes.T
        try:
            with np.errstate(all="ignore"):
                w = np.broadcast_to(np.asarray(fn(x=x, y=y, z=z), float), (m.n_nodes,))
        except (FormulaError, ValueError, TypeError) as exc:
            raise InputError(f"'{F}.formula': '{imp.formula}' cannot be evaluated at the nodes ({exc}); give a "
                             "formula of x, y, z") from None
        if not np.all(np.isfinite(w)):
            bad = int(np.flatnonzero(~np.isfinite(w))[0])
            raise InputError(f"'{F}.formula': '{imp.formula}' is not finite at node {bad} "
                             f"{m.nodes[bad].round(6).tolist()}; give a formula that is finite over the whole mesh")
    else:
        w = _mode_shape(m, imp, base)
    return m.nodes + (imp.amplitude * w)[:, None] * nodal_normals(m)
