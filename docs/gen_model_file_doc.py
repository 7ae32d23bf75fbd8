"""Generate docs/model-file.md from the pydantic schema (the single source of truth).

    python docs/gen_model_file_doc.py          # rewrites docs/model-file.md

tests/test_docs.py checks that the file is up to date.
"""
from __future__ import annotations

import types
import typing
from pathlib import Path

import annotated_types
from pydantic import BaseModel

from layershell.io import schema

SECTIONS = [
    ("[model]", schema.ModelSettings, "General settings."),
    ("[mesh] type = \"rectangle\"", schema.RectangleMesh, "Flat rectangular plate in the x-y plane."),
    ("[mesh] type = \"cylinder\"", schema.CylinderMesh, "Cylindrical panel or ring sector."),
    ("[mesh] type = \"revolution\"", schema.RevolutionMesh,
     "Shell of revolution about z from a meridian through the points (meridian_r, meridian_z): a polyline "
     "with n_meridian equal elements, or segments (straight or circular arcs) with their own element counts "
     "and element sets. Node sets: first, last (the circles at the first/last meridian point), start, end "
     "(the meridians at angle 0 and angle; open shells), and with segments meridian_point_0, 1, ... . "
     "The first element coordinate line is the hoop direction (material axis 1 of a layer without "
     "'direction')."),
    ("segments = [{...}] (revolution mesh)", schema.MeridianSegment,
     "One piece of the meridian between consecutive meridian points."),
    ("[mesh] type = \"plate_with_circle\"", schema.PlateWithCircleMesh,
     "Flat rectangular plate in the x-y plane with a circular or elliptical front (e.g. of a delamination) "
     "along element edges: nodes on the ellipse, a refined ring outside it, a butterfly grid inside and a "
     "transition to the plate edges. Element sets: inside, ring, outer, outside (ring and outer). Node sets: "
     "front, inside (front included), interior (strictly inside the front), xmin, xmax, ymin, ymax. A layer without 'direction' takes material axis 1 "
     "along global x on this mesh."),
    ("[mesh] type = \"file\"", schema.FileMesh, "A 9-node quadrilateral mesh read with meshio."),
    ("[materials.NAME] type = \"isotropic\"", schema.Isotropic, "Isotropic linear elastic material."),
    ("[materials.NAME] type = \"orthotropic\"", schema.OrthotropicMat,
     "Orthotropic material, nine constants in the material frame (axis 3 = shell normal)."),
    ("[materials.NAME] type = \"concrete\"", schema.ConcreteMat,
     "Cracking and crushing concrete (a layer's material; theory: docs/concrete.md). A strength class gives every "
     "constant from the fib Model Code 2010 mean values; any constant given overrides it."),
    ("[materials.NAME] type = \"steel\"", schema.SteelMat,
     "Reinforcing steel, elastic-plastic with hardening, for `reinforcement` inside a layer."),
    ("[materials.NAME] type = \"textile\"", schema.TextileMat,
     "Textile reinforcement (carbon, AR glass), linear elastic to rupture, for `reinforcement` inside a layer."),
    ("[[layers]]", schema.LayerDef, "Layers, from the reference face outward."),
    ("reinforcement = [{...}] (layer)", schema.ReinforcementDef,
     "A sheet of bars or textile yarns inside a layer, bonded to it: a uniaxial material at a height above the "
     "layer's bottom face, with its area per unit width along a direction."),
    ("[imperfection]", schema.ImperfectionDef,
     "Optional: a geometric imperfection, moving the mesh nodes along the reference face's normal before the "
     "analysis (a buckling mode of `layershell buckle`, or a formula)."),
    ("plies = [{...}] (layer)", schema.PlyDef,
     "One ply of a layer's ply stack, bottom to top: integrated with its own Gauss points, material and angle "
     "under the layer's directors."),
    ("[[stacks]]", schema.StackDef,
     "Optional: which elements carry which layers (default: all layers everywhere). Every element carries exactly "
     "one stack: selections must not overlap, and one stack without `where` and `set` takes the remaining "
     "elements."),
    ("[[supports]] type = \"fix\"", schema.FixDef, "Zero displacement components of chosen directors."),
    ("[[supports]] type = \"symmetry\"", schema.SymmetryDef, "Symmetry plane: u_l · n = 0 for all directors and layers."),
    ("[[supports]] type = \"hinge\"", schema.HingeDef, "Hinged support at a height in the thickness (thesis 3.4.2)."),
    ("[[loads]] type = \"surface\"", schema.SurfaceLoadDef, "Traction per reference area on a face."),
    ("[[loads]] type = \"edge\"", schema.EdgeLoadDef, "Traction through the thickness on boundary edges."),
    ("[[loads]] type = \"volume\"", schema.VolumeLoadDef, "Body force per volume."),
    ("[[loads]] type = \"gravity\"", schema.GravityDef,
     "Self-weight from the materials' density (the loaded layers need a material with density > 0)."),
    ("[[loads]] type = \"nodal\"", schema.NodalLoadDef, "Director forces given directly at nodes."),
    ("[steps]", schema.Steps, "Load stepping and Newton settings."),
    ("[[probes]]", schema.ProbeDef, "Named scalar outputs, one value per converged step."),
    ("[[profiles]]", schema.ProfileDef, "A stress component through the thickness at a point."),
    ("[[lines]]", schema.LineDef,
     "Components of a displacement, stress or traction along a polyline on the reference surface, at the last "
     "converged step: line_<name>.csv (distance along the line s, the point x, y, z, one column per component; "
     "empty where the layer is absent) and line_<name>.png."),
    ("[[plots]]", schema.PlotDef,
     "A figure plot_<name>.png of one probe against another (e.g. load in kN/m² against deflection in mm)."),
    ("[[interfaces]]", schema.InterfaceDef, "Delamination and friction at the interface below a layer."),
    ("initially_debonded = [{...}]", schema.InitialZone, "Initially debonded zones of an interface."),
    ("[delamination]", schema.DelaminationDef, "Delamination solution settings."),
    ("[output]", schema.OutputDef, "Output settings."),
]


def _bounds(meta) -> str:
    """' > 0', ' 0 to 1', ... from annotated_types constraints (Gt, Ge, Lt, Le)."""
    lo = hi = None
    for m in meta:
        for attr, op in (("gt", ">"), ("ge", "≥")):
            if getattr(m, attr, None) is not None:
                lo = (op, getattr(m, attr))
        for attr, op in (("lt", "<"), ("le", "≤")):
            if getattr(m, attr, None) is not None:
                hi = (op, getattr(m, attr))
    num = lambda v: f"{v:g}" if isinstance(v, float) else f"{v:,}".replace(",", " ")  # noqa: E731
    if lo and hi:
        if lo[0] == "≥" and hi[0] == "≤":
            return f" from {num(lo[1])} to {num(hi[1])}"
        return f" {lo[0]} {num(lo[1])} and {hi[0]} {num(hi[1])}"
    if lo:
        return f" {lo[0]} {num(lo[1])}"
    return f" {hi[0]} {num(hi[1])}" if hi else ""


def _lengths(meta) -> tuple[int | None, int | None]:
    lo = next((m.min_length for m in meta if getattr(m, "min_length", None) is not None), None)
    hi = next((m.max_length for m in meta if getattr(m, "max_length", None) is not None), None)
    return lo, hi


def _plural(word: str) -> str:
    return {"text": "texts", "true/false": "true/false values"}.get(word.split(" ")[0], word.split(" ")[0] + "s") \
        + word[len(word.split(" ")[0]):]


def _type(ann, meta=()) -> str:
    """A type annotation in words: 'number > 0', 'list of 3 numbers', "one of 'x', 'y'", ..."""
    meta = list(meta)
    origin, args = typing.get_origin(ann), typing.get_args(ann)
    if origin is typing.Annotated:
        return _type(args[0], meta + [m for a in args[1:] for m in (getattr(a, "metadata", None) or [a])])
    if ann is schema.NumOrFormula or (origin in (typing.Union, types.UnionType)
                                      and set(args) - {type(None)} == {float, str}):
        return "number or formula"
    if origin in (typing.Union, types.UnionType):
        arms = [a for a in args if a is not type(None)]
        parts = [_type(a, meta if len(arms) == 1 else ()) for a in arms]  # Field(ge=...) of an optional number
        return " or ".join(dict.fromkeys(parts))
    if origin is typing.Literal:
        vals = ", ".join(f'"{a}"' for a in args)
        return vals if len(args) == 1 else f"one of {vals}"
    if origin is list:
        item = _type(args[0]) if args else "value"
        lo, hi = _lengths(meta)
        if isinstance(args[0], type) and issubclass(args[0], BaseModel):
            return "list of tables {...}"
        if item.startswith("one of "):
            return f"list of {item.removeprefix('one of ')}"
        if lo is not None and lo == hi:
            return f"list of {lo} {_plural(item)}"
        if lo is not None and hi is not None:
            return f"list of {lo} {'or' if hi == lo + 1 else 'to'} {hi} {_plural(item)}"
        if lo is not None and lo > 1:
            return f"list of at least {lo} {_plural(item)}"
        return f"list of {_plural(item)}"
    if isinstance(ann, type) and issubclass(ann, BaseModel):
        return "table {...}"
    if ann is bool:
        return "true/false"
    if ann is int:  # whole numbers: > 0 is ≥ 1
        meta = [annotated_types.Ge(m.gt + 1) if getattr(m, "gt", None) is not None else m for m in meta]
        return "integer" + _bounds(meta)
    if ann is float:
        return "number" + _bounds(meta)
    if ann is str:
        pattern = next((m.pattern for m in meta if getattr(m, "pattern", None)), None)
        if pattern:
            return "name (letters, digits, _)"
        return "text" + (" (not empty)" if _lengths(meta)[0] else "")
    return str(ann)


#: formulas whose variables are not x, y, z
FORMULA_VARIABLES = {(schema.EdgeLoadDef, "distribution"): "t, x, y, z"}


def _key_type(cls, name: str, fld) -> str:
    """The type column of key ``name`` of table ``cls``."""
    kind = _type(fld.annotation, fld.metadata)
    if kind == "number or formula":
        kind += " in " + FORMULA_VARIABLES.get((cls, name), "x, y, z")
    if name == "where" and kind == "text":
        kind = "condition in x, y, z"
    return kind


def _default(fld) -> str:
    if fld.is_required():
        return "required"
    v = fld.get_default(call_default_factory=True)
    if v is None:
        return "not set"
    return f"`{_toml(v)}`"


def _toml(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return f'"{v}"'
    if isinstance(v, list):
        return "[" + ", ".join(_toml(x) for x in v) + "]"
    if isinstance(v, float):
        return repr(v).replace("e-0", "e-")
    return str(v)


def render() -> str:
    out = ["# Model file reference", "",
           "Generated from `src/layershell/io/schema.py` by `docs/gen_model_file_doc.py`; do not edit by hand.",
           "Every example under `examples/` is a complete model file. Formulas (thickness, load magnitudes, "
           "selections with `where`) use a safe parser: arithmetic, comparisons, `and`/`or`/`not`, "
           "`a if c else b`, and the functions abs, sqrt, exp, log, log10, sin, cos, tan, asin, acos, atan, "
           "atan2, sinh, cosh, tanh, min, max, floor, ceil, hypot, deg, rad, where(c, a, b), near(a, b) "
           "(|a - b| ≤ 10⁻⁶ × model size); a selection (`where`) must be a condition, e.g. `x > 0` or `near(x, 0)`, "
           "not a number.",
           "",
           "Units: layershell has no unit system of its own; give every value in one consistent set (e.g. kN and m, "
           "so stresses in kN/m²). The meanings name the kind of quantity: (length), (force/area), (force), "
           "(degrees). Types: *number* is a decimal or whole number, *integer* a whole number, *condition* a "
           "formula that is true or false at each point; *not set* means the key may be left out.", ""]
    for title, cls, text in SECTIONS:
        out += [f"## `{title}`", "", text, "", "| key | type | default | meaning |", "|---|---|---|---|"]
        for name, fld in cls.model_fields.items():
            if name == "type":
                continue
            desc = (fld.description or "").replace("|", "\\|")
            kind = _key_type(cls, name, fld).replace("|", "\\|")
            out.append(f"| `{name}` | {kind} | {_default(fld)} | {desc} |".replace("\n", " "))
        out.append("")
    return "\n".join(out) + "\n"


def main() -> None:
    Path(__file__).with_name("model-file.md").write_text(render(), encoding="utf-8")


if __name__ == "__main__":
    main()
