"""Generate docs/model-file.md from the pydantic schema (the single source of truth).

    python docs/gen_model_file_doc.py          # rewrites docs/model-file.md

tests/test_docs.py checks that the file is up to date.
"""
from __future__ import annotations

import typing
from pathlib import Path

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
    ("[mesh] type = \"file\"", schema.FileMesh, "A 9-node quadrilateral mesh read with meshio."),
    ("[materials.NAME] type = \"isotropic\"", schema.Isotropic, "Isotropic linear elastic material."),
    ("[materials.NAME] type = \"orthotropic\"", schema.OrthotropicMat,
     "Orthotropic material, nine constants in the material frame (axis 3 = shell normal)."),
    ("[[layers]]", schema.LayerDef, "Layers, from the reference face outward."),
    ("[[stacks]]", schema.StackDef, "Optional: which elements carry which layers (default: all layers everywhere)."),
    ("[[supports]] type = \"fix\"", schema.FixDef, "Zero displacement components of chosen directors."),
    ("[[supports]] type = \"symmetry\"", schema.SymmetryDef, "Symmetry plane: u_l · n = 0 for all directors and layers."),
    ("[[supports]] type = \"hinge\"", schema.HingeDef, "Hinged support at a height in the thickness (thesis 3.4.2)."),
    ("[[loads]] type = \"surface\"", schema.SurfaceLoadDef, "Traction per reference area on a face."),
    ("[[loads]] type = \"edge\"", schema.EdgeLoadDef, "Traction through the thickness on boundary edges."),
    ("[[loads]] type = \"volume\"", schema.VolumeLoadDef, "Body force per volume."),
    ("[[loads]] type = \"gravity\"", schema.GravityDef, "Self-weight from the materials' density."),
    ("[[loads]] type = \"nodal\"", schema.NodalLoadDef, "Director forces given directly at nodes."),
    ("[steps]", schema.Steps, "Load stepping and Newton settings."),
    ("[[probes]]", schema.ProbeDef, "Named scalar outputs, one value per converged step."),
    ("[[profiles]]", schema.ProfileDef, "A stress component through the thickness at a point."),
    ("[[plots]]", schema.PlotDef,
     "A figure plot_<name>.png of one probe against another (e.g. load in kN/m² against deflection in mm)."),
    ("[[interfaces]]", schema.InterfaceDef, "Delamination and friction at the interface below a layer."),
    ("initially_debonded = [{...}]", schema.InitialZone, "Initially debonded zones of an interface."),
    ("[delamination]", schema.DelaminationDef, "Delamination solution settings."),
    ("[output]", schema.OutputDef, "Output settings."),
]


def _type(ann) -> str:
    s = str(ann)
    for a, b in (("typing.", ""), ("<class '", ""), ("'>", ""), ("NoneType", "none"),
                 ("Annotated[", ""), ("Literal", "one of ")):
        s = s.replace(a, b)
    return s.replace("|", " or ")


def render() -> str:
    out = ["# Model file reference", "",
           "Generated from `src/layershell/io/schema.py` by `docs/gen_model_file_doc.py`; do not edit by hand.",
           "Every example under `examples/` is a complete model file. Formulas (thickness, load magnitudes, "
           "selections with `where`) use a safe parser: arithmetic, comparisons, `and`/`or`/`not`, "
           "`a if c else b`, and the functions abs, sqrt, exp, log, log10, sin, cos, tan, asin, acos, atan, "
           "atan2, sinh, cosh, tanh, min, max, floor, ceil, hypot, deg, rad, where(c, a, b), near(a, b) "
           "(|a - b| ≤ 10⁻⁶ × model size).", ""]
    for title, cls, text in SECTIONS:
        out += [f"## `{title}`", "", text, "", "| key | type | default | meaning |", "|---|---|---|---|"]
        for name, fld in cls.model_fields.items():
            if name == "type":
                continue
            default = "required" if fld.is_required() else repr(fld.get_default(call_default_factory=True))
            desc = (fld.description or "").replace("|", "\\|")
            out.append(f"| `{name}` | {_type(fld.annotation)} | {default} | {desc} |".replace("\n", " "))
        out.append("")
    return "\n".join(out) + "\n"


def main() -> None:
    Path(__file__).with_name("model-file.md").write_text(render(), encoding="utf-8")


if __name__ == "__main__":
    main()
