"""Material axes that a mesh file's node numbering sets: a note for `check` and `run`.

A layer without `direction` takes its material axis 1 from the first coordinate line A_1 of each
element (:func:`layershell.element.kernel.material_frame`). The generated meshes document that
line (rectangle: +x with normal '+z', -x with '-z'; cylinder: the arc; revolution: the hoop), but in
a mesh file it follows the node numbering, element by element: a mesh numbered clockwise reports
σ_yy as "σ11". Where that line is not +x the note says where it runs and how to fix the axes.
"""
from __future__ import annotations

import numpy as np

from ..element.geometry import surface_points
from ..model import Model

_ALIGNED = np.cos(np.deg2rad(2.0))  # A_1 within 2° of a direction counts as along it


def _in_plane_isotropic(mat) -> bool:
    """Whether the stiffness does not change under a rotation about the normal."""
    close = lambda a, b: np.isclose(a, b, rtol=1e-9, atol=0.0)  # noqa: E731
    nu32 = mat.nu23 * mat.E3 / mat.E2
    return bool(close(mat.E1, mat.E2) and close(mat.G23, mat.G31) and close(mat.nu31, nu32)
                and close(mat.G12, mat.E1 / (2 * (1 + mat.nu12))))


def first_line_directions(model: Model) -> np.ndarray:
    """Where each element's first coordinate line A_1 runs at its centre, as one of '+x', '-x',
    '+y', '-y' (within 2° of the tangent-plane projection of that global axis) or 'other'."""
    sp = surface_points(model.mesh.nodes[model.mesh.elements], np.zeros(1), np.zeros(1))
    t1 = sp.A[:, 0, :, 0]
    t1 = t1 / np.linalg.norm(t1, axis=1, keepdims=True)
    n = sp.A3[:, 0]
    out = np.full(len(t1), "other", dtype=object)
    for axis, name in ((0, "x"), (1, "y")):
        e = np.zeros(3)
        e[axis] = 1.0
        p = e - (n @ e)[:, None] * n
        size = np.linalg.norm(p, axis=1)
        c = np.einsum("ei,ei->e", t1, p / np.maximum(size, 1e-300)[:, None])
        ok = size > 0.1
        out[ok & (c > _ALIGNED)] = "+" + name
        out[ok & (c < -_ALIGNED)] = "-" + name
    return out


def material_axis_notes(model: Model, mesh_type: str) -> list[str]:
    """Notes for the layers without `direction` of a mesh file whose axis 1 is not +x everywhere."""
    if mesh_type != "file":
        return []
    where = first_line_directions(model)
    notes = []
    for k, ly in enumerate(model.layers):
        if ly.direction is not None:
            continue
        carries = np.array([k in model.stacks[s] for s in model.element_stack])
        kinds, counts = np.unique(where[carries].astype(str), return_counts=True)
        if kinds.tolist() == ["+x"]:
            continue
        runs = ", ".join(f"{'global ' + kd if kd != 'other' else 'other directions'} in {c}"
                         for kd, c in sorted(zip(kinds, counts), key=lambda t: -t[1]))
        if _in_plane_isotropic(ly.material):
            what = ("the stress components it reports in the material frame (11, 22, 12, 13, 23 of probes, "
                    "profiles and ParaView files; frame = 'material', the default) refer to these axes: '11' is "
                    "σ_yy where axis 1 runs along y, and '12', '13' change sign where it runs along -x or -y")
            other = " (or frame = 'global' on the outputs)"
        else:
            what = "its orthotropic material (E1 along axis 1) and the stress components it reports follow these axes"
            other = ""
        notes.append(f"layer '{ly.name}' has no 'direction': its material axis 1 follows the first coordinate line "
                     f"of each element, which the node numbering of the mesh file sets; it runs along {runs} of "
                     f"{int(carries.sum())} elements, and {what}. Give direction = [1, 0, 0] in the [[layers]] "
                     f"table of that layer to put axis 1 along the projection of global x whatever the numbering{other}")
    return notes
