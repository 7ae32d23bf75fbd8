"""The TOML model-file schema, validated with pydantic (every error names its field).

See ``docs/model-file.md`` for the reference; each example under ``examples/`` is a
complete model file. Formulas (thickness, load magnitudes, selections) are parsed by the safe
parser :mod:`layershell.formula`, never ``eval``.
"""
from __future__ import annotations

import math
from typing import Annotated, Literal, Union, get_args

from pydantic import (BaseModel, ConfigDict, Field, FiniteFloat, PositiveFloat, PositiveInt, field_validator,
                      model_validator)

Vec3 = Annotated[list[float], Field(min_length=3, max_length=3)]
NumOrFormula = Union[float, str]

#: descriptions shared by many tables
_NODES = "the nodes where this condition holds (near(x, 0) compares within 10⁻⁶ × the model size)"
_ELEMS = "the elements whose centre satisfies this condition; default: all elements"
_SET_N = "named node set (mesh edges such as xmin, ymax, or a mesh file's physical group)"
_SET_E = "named element set (a mesh file's surface group or a revolution segment's set)"
_POINT = "[x, y, z]: the node nearest to this point"
_SCALED = "multiplied by the load factor λ (false: a constant load, present from the first step)"


def _leaf_types(tp) -> set:
    args = get_args(tp)
    return {tp} if not args else set().union(*(_leaf_types(a) for a in args))


class Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)

    @model_validator(mode="before")
    @classmethod
    def _no_boolean_numbers(cls, data):
        """TOML true/false only where a yes/no is meant: pydantic would read true as the number 1.

        The boolean is handed on as the text 'true'/'false', so that the error names the field.
        """
        if isinstance(data, dict):
            for k, v in data.items():
                if isinstance(v, bool) and k in cls.model_fields:
                    leaves = _leaf_types(cls.model_fields[k].annotation)
                    if bool not in leaves and leaves & {int, float}:
                        data = {**data, k: str(v).lower()}
        return data

    @model_validator(mode="after")
    def _finite_numbers(self):
        """Points, vectors, lists of numbers and the hinge height must be finite: NaN or infinity
        would otherwise pass silently into the geometry."""
        for name in type(self).model_fields:
            v = getattr(self, name)
            values = v if isinstance(v, list) else [v] if name == "height" else []
            for i, x in enumerate(values):
                if isinstance(x, float) and not math.isfinite(x):
                    at = f"{name}[{i}]" if isinstance(v, list) else name
                    raise ValueError(f"{at} must be a finite number (got {x}); give finite values in '{name}'")
        return self


# ------------------------------------------------------------------ general settings
class ModelSettings(Strict):
    title: str = Field("", description="title shown in the report and the figures")
    units: str = Field("", description=(
        "'force, length' (e.g. 'kN, m', 'N, mm'; force N, mN, daN, kN, MN, GN, lbf or kip; length m, dm, cm, "
        "mm, µm, um, km, in or ft): names the units of the report and the figure axes (stresses force/length², "
        "resultants force/length, areas length²); nothing is converted"))
    nonlinear: bool = Field(True, description="geometrically nonlinear (Green-Lagrange) or linear")
    thickness_points: PositiveInt = Field(
        3, le=10, description="Gauss points through each layer, or through each ply of a layer "
        "with 'plies' (at least d are used: d = 4 needs 4)")
    element: Literal["mitc", "full"] = Field(
        "mitc", description="shell element: 'mitc' = assumed-strain MITC9 (membrane and transverse shear "
                            "strains tied, no locking in thin shells; at least d + 1 thickness points), "
                            "'full' = the fully integrated 9-node element (locks in thin shells; for comparison)")

    @field_validator("units")
    @classmethod
    def _units(cls, v):
        from ..units import check_units

        return check_units(v)


# ------------------------------------------------------------------ meshes
class MeshBase(Strict):
    surface: Literal["reference", "middle"] = Field(
        "reference", description="what the mesh describes: 'reference' the reference face (Θ³ = 0) itself, 'middle' "
                                 "the mid-surface of the stack (e.g. a CAD/Gmsh shell), moved here by half the total "
                                 "nodal thickness against the normal A3 (the averaged element normal at each node) "
                                 "so that the stack lies half on each side (thickness formulas are evaluated on the mesh "
                                 "as given); selections and points of supports, loads and probes then refer to the "
                                 "moved (reference) face")


class RectangleMesh(MeshBase):
    type: Literal["rectangle"]
    lx: PositiveFloat = Field(description="length along x (length)")
    ly: PositiveFloat = Field(description="length along y (length)")
    nx: PositiveInt = Field(description="elements along x")
    ny: PositiveInt = Field(description="elements along y")
    origin: Vec3 = Field([0.0, 0.0, 0.0], description="[x, y, z] of the corner with the smallest x and y (length)")
    normal: Literal["+z", "-z"] = Field("+z", description="'+z': reference face at the bottom; '-z': on top")
    grading_x: PositiveFloat = Field(
        1.0, ge=1e-4, le=1e4, description="size of the last element along x over the first (geometric grading; > 1 refines "
                                 "towards the origin edge, < 1 towards x = origin + lx; 1: uniform)")
    grading_y: PositiveFloat = Field(1.0, ge=1e-4, le=1e4, description="the same along y")
    lines_x: list[float] = Field([], description=(
        "x of node lines (length, origin included): element edges lie exactly there, e.g. at plate ends, load "
        "lines and the boundaries of [[stacks]] regions; the nx elements are shared out over the pieces between "
        "lines in proportion to their length"))
    lines_y: list[float] = Field([], description="the same along y (ny elements)")
    refine_x: list[float] = Field([], description=(
        "x of node lines (edges included) towards which the elements shrink, e.g. both ends [x0, x0 + lx] or an "
        "interior line; each is a node line; the element length grows linearly with the distance from the "
        "nearest one; with refine_ratio_x, not with grading_x"))
    refine_y: list[float] = Field([], description="the same along y")
    refine_ratio_x: float = Field(1.0, ge=1.0, le=1e4, description=(
        "with refine_x: the longest element along x over the shortest (exactly where the element counts "
        "allow, an error when they miss it by more than 10 %)"))
    refine_ratio_y: float = Field(1.0, ge=1.0, le=1e4, description="the same along y")

    @model_validator(mode="after")
    def _node_lines(self):
        for axis, start, length in (("x", self.origin[0], self.lx), ("y", self.origin[1], self.ly)):
            for key in (f"lines_{axis}", f"refine_{axis}"):
                for i, v in enumerate(getattr(self, key)):
                    if not math.isfinite(v) or not -1e-9 * length <= v - start <= length * (1 + 1e-9):
                        raise ValueError(f"{key}[{i}] = {v} lies outside the rectangle ({axis} from {start:.9g} to "
                                         f"{start + length:.9g}); give {axis} within it (absolute coordinates, "
                                         "origin included)")
            refine, ratio = getattr(self, f"refine_{axis}"), getattr(self, f"refine_ratio_{axis}")
            if refine and ratio == 1.0:
                raise ValueError(f"refine_{axis} needs refine_ratio_{axis} > 1 (the longest element over the "
                                 f"shortest), e.g. refine_ratio_{axis} = 4")
            if ratio != 1.0 and not refine:
                raise ValueError(f"refine_ratio_{axis} = {ratio} needs refine_{axis}: the node lines to refine "
                                 f"towards, e.g. refine_{axis} = [{start:.6g}, {start + length:.6g}] for both edges")
            if getattr(self, f"grading_{axis}") != 1.0 and (refine or getattr(self, f"lines_{axis}")):
                raise ValueError(f"grading_{axis} grades from one edge and cannot be combined with lines_{axis} or "
                                 f"refine_{axis}; refine towards that edge with refine_{axis} = [{start:.6g}] and "
                                 f"refine_ratio_{axis} instead")
        return self


class CylinderMesh(MeshBase):
    type: Literal["cylinder"]
    radius: PositiveFloat = Field(description="radius of the reference face (length)")
    angle_start: float = Field(0.0, description=(
        "angle of the first edge (degrees, from +x towards +y; axis y: towards +z)"))
    angle_end: float = Field(description="angle of the last edge (degrees); |angle_end - angle_start| ≤ 360")
    width: PositiveFloat = Field(description="length along the axis (length)")
    n_arc: PositiveInt = Field(description="elements along the arc")
    n_width: PositiveInt = Field(1, description="elements along the axis")
    normal: Literal["inward", "outward"] = Field(
        "inward", description="'inward': reference face outside (A3 towards the axis)")
    axis: Literal["z", "y"] = Field("z", description=(
        "cylinder axis: 'z' (arc in the x-y plane) or 'y' (arc in the x-z plane)"))

    @model_validator(mode="after")
    def _span(self):
        span = abs(self.angle_end - self.angle_start)
        if not 0 < span <= 360:
            raise ValueError(f"angle_end - angle_start must be non-zero and at most 360 degrees in magnitude (got "
                             f"angle_start = {self.angle_start}, angle_end = {self.angle_end})")
        return self


class MeridianSegment(Strict):
    elements: PositiveInt = Field(description="elements along this segment")
    set: str | None = Field(None, description="element set of the segment's elements (segments may share a name)")
    arc_center: Annotated[list[float], Field(min_length=2, max_length=2)] | None = Field(
        None, description="[r, z] centre of a circular arc between the segment's end points (the shorter arc); "
                          "default: straight")


class RevolutionMesh(MeshBase):
    type: Literal["revolution"]
    meridian_r: list[float] = Field(min_length=2, description=(
        "distances r ≥ 0 of the meridian points from the z axis (length)"))
    meridian_z: list[float] = Field(min_length=2, description="heights z of the meridian points (length)")
    n_meridian: PositiveInt | None = Field(
        None, description="elements of equal length along the meridian polyline (or give 'segments')")
    n_circ: PositiveInt = Field(description="elements around the axis")
    angle: float = Field(360.0, gt=0, le=360, description="angle of revolution (degrees); 360: closed")
    normal: Literal["inward", "outward"] = Field("outward", description=(
        "side of the reference face's normal A3 (where the material lies): 'outward' away from the axis / upward "
        "on a cap"))
    segments: list[MeridianSegment] | None = Field(
        None, description="one per pair of consecutive meridian points: {elements, set, arc_center}")
    meridian_thickness: list[PositiveFloat] | None = Field(
        None, description="a value per meridian point, linear along the meridian; layer thickness formulas "
                          "read it as h_meridian")

    @model_validator(mode="after")
    def _same_length(self):
        if len(self.meridian_r) != len(self.meridian_z):
            raise ValueError(f"meridian_r and meridian_z must have the same length (got {len(self.meridian_r)} "
                             f"and {len(self.meridian_z)}); give one (r, z) pair per meridian point")
        if any(r < 0 for r in self.meridian_r):
            raise ValueError(f"meridian_r must not be negative (got {self.meridian_r}); r is the distance from the axis")
        pts = list(zip(self.meridian_r, self.meridian_z))
        if any(a == b for a, b in zip(pts, pts[1:])):
            raise ValueError("consecutive meridian points (meridian_r[i], meridian_z[i]) must differ; remove the "
                             "repeated point")
        if (self.n_meridian is None) == (self.segments is None):
            raise ValueError("give either n_meridian (equal elements along the whole meridian) or segments (one "
                             "{elements = n} per pair of consecutive meridian points), not both or neither")
        if self.segments is not None and len(self.segments) != len(pts) - 1:
            raise ValueError(f"segments: give one entry per pair of consecutive meridian points, i.e. "
                             f"{len(pts) - 1} for {len(pts)} points (got {len(self.segments)})")
        if self.meridian_thickness is not None and len(self.meridian_thickness) != len(pts):
            raise ValueError(f"meridian_thickness: give one value per meridian point ({len(pts)}), got "
                             f"{len(self.meridian_thickness)}")
        return self


class PlateWithCircleMesh(MeshBase):
    type: Literal["plate_with_circle"]
    lx: PositiveFloat = Field(description="length along x (length)")
    ly: PositiveFloat = Field(description="length along y (length)")
    origin: Vec3 = Field([0.0, 0.0, 0.0], description="[x, y, z] of the corner with the smallest x and y (length)")
    normal: Literal["+z", "-z"] = Field("+z", description="'+z': reference face at the bottom; '-z': on top")
    center: Annotated[list[float], Field(min_length=2, max_length=2)] = Field(description=(
        "[x, y] of the circle's (ellipse's) centre (length, absolute coordinates, origin included)"))
    radius: PositiveFloat | None = Field(None, description="radius of the circle (length); or semi_axes")
    semi_axes: Annotated[list[PositiveFloat], Field(min_length=2, max_length=2)] | None = Field(None, description=(
        "[a, b]: semi-axes of an ellipse along x and y (length); or radius"))
    front_size: PositiveFloat = Field(description=(
        "element length along the front (corner to corner, nodes every front_size / 2): each quarter of the "
        "ellipse gets the fewest equal elements no longer than this"))
    ring_width: PositiveFloat = Field(description=(
        "width of the refined ring of elements outside the front (length): it ends on the ellipse with the "
        "semi-axes enlarged by ring_width"))
    ring_layers: PositiveInt = Field(description="element layers across the ring (equal)")
    outer_layers: PositiveInt | None = Field(None, description=(
        "element layers from the ring to the plate edges, growing geometrically from about a ring layer's "
        "thickness (default: as many as a growth of 1.3 per layer needs)"))

    @model_validator(mode="after")
    def _fits(self):
        if (self.radius is None) == (self.semi_axes is None):
            raise ValueError("give either radius (a circle) or semi_axes = [a, b] (an ellipse), not both or neither")
        sizes = {"lx": self.lx, "ly": self.ly, "radius": self.radius, "front_size": self.front_size,
                 "ring_width": self.ring_width, "semi_axes": max(self.semi_axes or [0.0])}
        for name, v in sizes.items():
            if v is not None and not math.isfinite(v):
                raise ValueError(f"{name} must be a finite number (got {v}); give a length in the model's units")
        a, b = (self.radius, self.radius) if self.radius is not None else self.semi_axes
        x0, y0 = self.origin[0], self.origin[1]
        cx, cy = self.center
        key = "radius" if self.radius is not None else "semi_axes"
        gaps = {"xmin": cx - a - x0, "xmax": x0 + self.lx - cx - a, "ymin": cy - b - y0, "ymax": y0 + self.ly - cy - b}
        edge, gap = min(gaps.items(), key=lambda kv: kv[1])
        if not all(math.isfinite(v) for v in (cx, cy)) or gap <= 0:
            raise ValueError(f"the {'circle' if key == 'radius' else 'ellipse'} (center = [{cx:.6g}, {cy:.6g}], "
                             f"{key} = {self.radius if key == 'radius' else self.semi_axes}) leaves the plate "
                             f"x from {x0:.6g} to {x0 + self.lx:.6g}, y from {y0:.6g} to {y0 + self.ly:.6g} "
                             f"(past the {edge} edge by {-gap:.6g}); move center or reduce {key} so that it lies "
                             "inside, with room for the ring")
        if self.ring_width >= gap:
            raise ValueError(f"ring_width = {self.ring_width:.6g} is wider than the space between the front and the "
                             f"{edge} edge ({gap:.6g}); give ring_width below {gap:.6g} (e.g. {0.5 * gap:.3g}), "
                             f"leaving room for the transition to the edges")
        return self


class FileMesh(MeshBase):
    type: Literal["file"]
    path: str = Field(description="mesh file read with meshio (Gmsh .msh, .vtu, ...), relative to the model file")
    scale: PositiveFloat = Field(1.0, description="factor on the file's coordinates (e.g. 0.001: mm → m)")


Mesh = Annotated[Union[RectangleMesh, CylinderMesh, RevolutionMesh, PlateWithCircleMesh, FileMesh], Field(discriminator="type")]


# ------------------------------------------------------------------ materials and layers
class Isotropic(Strict):
    type: Literal["isotropic"]
    E: float = Field(description="Young's modulus (force/area)")
    nu: float = Field(description="Poisson's ratio, -1 < nu < 0.5")
    density: float = Field(0.0, ge=0, description="mass per volume (for gravity loads)")


class OrthotropicMat(Strict):
    type: Literal["orthotropic"]
    E1: float = Field(description="Young's modulus along material axis 1 (force/area)")
    E2: float = Field(description="Young's modulus along material axis 2 (force/area)")
    E3: float = Field(description="Young's modulus along the normal, axis 3 (force/area)")
    G12: float = Field(description="in-plane shear modulus (force/area)")
    G23: float = Field(description="transverse shear modulus in the 2-3 plane (force/area)")
    G31: float = Field(description="transverse shear modulus in the 3-1 plane (force/area)")
    nu12: float = Field(description="Poisson's ratio: strain along 2 from stress along 1 is -nu12/E1")
    nu23: float = Field(description="Poisson's ratio: strain along 3 from stress along 2 is -nu23/E2")
    nu31: float | None = Field(None, description=(
        "Poisson's ratio: strain along 1 from stress along 3 is -nu31/E3 (or give nu13)"))
    nu13: float | None = Field(None, description="give nu13 instead of nu31 (nu31 = nu13 E3/E1)")
    density: float = Field(0.0, ge=0, description="mass per volume (for gravity loads)")

    @model_validator(mode="after")
    def _one_of(self):
        if (self.nu31 is None) == (self.nu13 is None):
            raise ValueError("give exactly one of nu31 and nu13 (nu31 = nu13 E3/E1)"
                             + (", not both" if self.nu31 is not None else ""))
        return self


class ConcreteMat(Strict):
    type: Literal["concrete"]
    strength_class: str | None = Field(None, description=(
        "strength class 'C12/15' ... 'C90/105' (EN 1992 / fib Model Code 2010): every constant below from the "
        "Model Code's mean values; needs [model] units"))
    f_ck: PositiveFloat | None = Field(None, description="characteristic cylinder strength in MPa (instead of the class)")
    E: PositiveFloat | None = Field(None, description="Young's modulus (force/area); default E_ci of the class")
    nu: float | None = Field(None, description="Poisson's ratio, 0 <= nu < 0.5; default 0.2")
    f_c: PositiveFloat | None = Field(None, description="uniaxial compressive strength, positive (force/area); default f_cm")
    f_ct: PositiveFloat | None = Field(None, description="uniaxial tensile strength (force/area); default f_ctm")
    G_F: PositiveFloat | None = Field(None, description="tensile fracture energy (force/length); default fib MC2010")
    G_c: PositiveFloat | None = Field(None, description="compressive fracture energy (force/length)")
    eps_c1: PositiveFloat | None = Field(None, description="strain at the compressive peak, positive")
    shear_retention: float | None = Field(None, description=(
        "fraction 0..1 of the shear modulus an open crack keeps across its plane; default 0"))
    aggregate_size: PositiveFloat | None = Field(None, description=(
        "largest aggregate size d_agg (length, e.g. 16 mm): an open crack keeps Walraven's aggregate "
        "interlock, a shear stiffness that falls with its width, in layers whose bars hold the cracks (a crack "
        "spacing); instead of shear_retention; needs [model] units"))
    density: float = Field(0.0, ge=0, description="mass per volume (for gravity loads)")

    @model_validator(mode="after")
    def _strength(self):
        own = ("E", "f_c", "f_ct", "G_F", "G_c", "eps_c1")
        missing = [k for k in own if getattr(self, k) is None]
        if self.strength_class is None and self.f_ck is None and missing:
            given = f" (given: {', '.join(k for k in own if k not in missing)}; missing: {', '.join(missing)})" \
                if len(missing) < len(own) else ""
            raise ValueError("a concrete needs a strength: give strength_class = 'C30/37' (or f_ck = 30, in MPa; "
                             "the other constants then default to the fib Model Code 2010 mean values), or all of "
                             f"E, f_c, f_ct, G_F, G_c and eps_c1 in the model's units{given}")
        if self.strength_class is not None and self.f_ck is not None:
            raise ValueError("give strength_class or f_ck, not both")
        return self


class SteelMat(Strict):
    type: Literal["steel"]
    grade: str | None = Field(None, description="reinforcing steel grade 'B500A', 'B500B' or 'B500C' (needs [model] units)")
    E: PositiveFloat | None = Field(None, description="Young's modulus (force/area); default 200 GPa")
    f_y: PositiveFloat | None = Field(None, description="yield strength (force/area)")
    E_h: float | None = Field(None, ge=0, description="hardening modulus after yield (force/area)")
    eps_u: PositiveFloat | None = Field(None, description="strain at rupture (none: no rupture)")
    density: float = Field(0.0, ge=0, description="mass per volume")

    @model_validator(mode="after")
    def _strength(self):
        if self.grade is None and (self.E is None or self.f_y is None):
            raise ValueError("a steel needs a grade = 'B500B' or E and f_y in the model's units")
        return self


class TextileMat(Strict):
    type: Literal["textile"]
    fibre: Literal["carbon", "AR-glass"] | None = Field(None, description="typical values of a carbon or AR-glass "
                                                                          "textile (needs [model] units)")
    E: PositiveFloat | None = Field(None, description="Young's modulus of the yarns (force/area)")
    f_t: PositiveFloat | None = Field(None, description="tensile strength of the yarns in the textile (force/area)")
    density: float = Field(0.0, ge=0, description="mass per volume")

    @model_validator(mode="after")
    def _strength(self):
        if self.fibre is None and (self.E is None or self.f_t is None):
            raise ValueError("a textile needs fibre = 'carbon' or 'AR-glass', or E and f_t in the model's units")
        return self


Material = Annotated[Union[Isotropic, OrthotropicMat, ConcreteMat, SteelMat, TextileMat], Field(discriminator="type")]


class ReinforcementDef(Strict):
    material: str = Field(description="name of a [materials.NAME] table of type 'steel' or 'textile'")
    height: PositiveFloat = Field(description=(
        "distance of the sheet from the layer's bottom face, the face towards the reference face (length); where "
        "the mesh normal points down (normal = '-z') that face is the layer's physical top"))
    area: PositiveFloat | None = Field(None, description=(
        "cross-section area per unit width (length²/length); or give bar_diameter and spacing"))
    bar_diameter: PositiveFloat | None = Field(None, description="bar diameter (length), with spacing")
    spacing: PositiveFloat | None = Field(None, description="bar spacing (length), with bar_diameter")
    direction: Vec3 | None = Field(None, description="global direction of the bars, projected on the surface "
                                                     "(default: the first coordinate line)")
    angle: FiniteFloat = Field(0.0, description="angle in degrees about the normal from 'direction'")
    name: str | None = Field(None, description="name in the outputs (default: material and direction)")

    @model_validator(mode="after")
    def _area(self):
        bars = (self.bar_diameter is not None, self.spacing is not None)
        if self.area is None and not all(bars):
            raise ValueError("give the reinforcement's 'area' per unit width, or 'bar_diameter' and 'spacing'")
        if self.area is not None and any(bars):
            raise ValueError("give either 'area' or 'bar_diameter' with 'spacing', not both")
        return self

    def area_per_width(self) -> float:
        if self.area is not None:
            return self.area
        return math.pi * self.bar_diameter ** 2 / 4.0 / self.spacing


class PlyDef(Strict):
    material: str = Field(description="name of a [materials.NAME] table")
    angle: FiniteFloat = Field(0.0, description=(
        "ply angle in degrees about the normal from the layer's material axis 1 (its 'direction', or the first "
        "coordinate line), added to the layer's 'angle'"))
    thickness: PositiveFloat = Field(description="ply thickness (length)")

    @field_validator("angle", mode="before")
    @classmethod
    def _number(cls, v):
        if isinstance(v, str) or not isinstance(v, (int, float)):
            raise ValueError(f"the ply angle must be a number of degrees (got {v!r}); write e.g. angle = 45 or "
                             "angle = -45, without quotes or units")
        return v


class LayerDef(Strict):
    name: str = Field(min_length=1, description="name of the layer, used by stacks, supports, loads and probes")
    material: str | None = Field(None, description="name of a [materials.NAME] table (not with 'plies')")
    thickness: NumOrFormula | None = Field(None, description=(
        "layer thickness (length); a formula is evaluated at the nodes. With 'plies' it may be left out (the "
        "sum of the ply thicknesses); if given it must equal that sum"))
    directors: int = Field(3, ge=0, le=4, description=(
        "polynomial order d of the displacement through the layer: u = Σ_{l=0..d} (Θ³)^l u_l"))
    angle: FiniteFloat = Field(0.0, description="material angle ω in degrees about the normal")
    direction: Vec3 | None = Field(None, description="global direction projected on the surface as material axis 1")
    plies: list[PlyDef] | None = Field(None, min_length=1, description=(
        "ply stack inside the layer, bottom to top, instead of 'material': [{material = 'cfrp', angle = 0, "
        "thickness = 0.125}, ...]; integrated ply by ply under the layer's directors, stresses per ply"))
    reinforcement: list[ReinforcementDef] = Field(default_factory=list, description=(
        "steel bars or textile inside the layer: [{material = 'b500', height = 0.03, bar_diameter = 0.01, spacing "
        "= 0.2, direction = [1, 0, 0]}, ...], bonded to the layer (no extra unknowns)"))
    crack_spacing: FiniteFloat | None = Field(None, ge=0.0, description=(
        "concrete layer: the spacing of the cracks its bars distribute (length), the least in-plane band over "
        "which a crack's opening is smeared (elements shorter than it take it as their band; crushing keeps the "
        "element). Left out: the mean crack spacing s_r,max/1.7 of EN 1992-1-1 §7.3.4 of its steel bars given "
        "by bar_diameter and spacing (none without them); 0: the element band"))

    @field_validator("thickness")
    @classmethod
    def _positive(cls, v):
        if isinstance(v, (int, float)) and not (v > 0 and math.isfinite(v)):
            raise ValueError(f"must be positive and finite (got {v}); give the layer thickness as a positive "
                             "number or a formula in x, y, z")
        return v


def _check_layer_material(ly: LayerDef, i: int) -> None:
    """One material or a ply stack, and a layer thickness that the plies agree with."""
    at = f"layers[{i}]"
    if ly.plies is None:
        if ly.material is None:
            raise ValueError(f"'{at}.material': required key is missing; give the layer a 'material' (a "
                             "[materials.NAME] table) or a ply stack 'plies = [{material = ..., angle = ..., "
                             "thickness = ...}, ...]'")
        if ly.thickness is None:
            raise ValueError(f"'{at}.thickness': required key is missing; add 'thickness = ...' (a number or a "
                             "formula in x, y, z) to the layer")
        return
    if ly.material is not None:
        raise ValueError(f"'{at}.material': a layer has either one material or a ply stack, but this one has "
                         f"material = '{ly.material}' and 'plies'; each ply names its own material, so leave out "
                         "the layer's 'material' (or give the layer one material and no 'plies')")
    total = sum(p.thickness for p in ly.plies)
    if isinstance(ly.thickness, str):
        raise ValueError(f"'{at}.thickness': a layer with 'plies' is {total:.12g} thick (the sum of its plies), so "
                         f"its thickness cannot be the formula '{ly.thickness}'; leave 'thickness' out or give "
                         f"thickness = {total:.12g}")
    if ly.thickness is not None and abs(ly.thickness - total) > 1e-9 * ly.thickness:
        listed = " + ".join(f"{p.thickness:g}" for p in ly.plies)
        raise ValueError(f"'{at}.thickness': the plies are {listed} = {total:.12g} thick together, but the layer "
                         f"thickness is {ly.thickness:.12g} (they must agree to 1e-9 relative); fix the ply "
                         "thicknesses, or leave out the layer's 'thickness' so that it follows from the plies")


class StackDef(Strict):
    layers: list[str] = Field(min_length=1, description="layer names from the reference face outward")
    where: str | None = Field(None, description=(
        "the elements whose centre satisfies this condition (on a rectangle mesh its boundary must lie on element "
        "edges: node lines by lines_x/lines_y); a stack without where and set takes the elements of no other stack"))
    set: str | None = Field(None, description=_SET_E)


# ------------------------------------------------------------------ supports
Component = Literal["x", "y", "z"]


class FixDef(Strict):
    type: Literal["fix"]
    where: str | None = Field(None, description=_NODES)
    set: str | None = Field(None, description=_SET_N)
    point: Vec3 | None = Field(None, description=_POINT)
    layer: str | None = Field(
        None, description="layer name, or 'all': every layer at the nodes (a support through the whole thickness); "
                          "default: the layer at the reference face")
    directors: Union[Literal["all"], list[int]] = Field(
        [0], description="director vectors u_l held (u_0: the layer's bottom face); not with 'face'/'height'")
    components: list[Component] = Field(["x", "y", "z"], description="global displacement components held")
    face: Literal["bottom", "top"] | None = Field(
        None, description="the support acts on this face of 'layer' (Σ_l (Θ_L³)^l u_l · e = 0; a bonded face "
                          "is shared with the neighbour layer), e.g. layer = 'concrete', face = 'bottom' for a "
                          "bearing under the concrete while another layer lies below it. 'bottom' is the face at "
                          "Θ³ = 0, 'top' at Θ³ = H: counted along the normal, so with [mesh] normal = '-z' "
                          "'bottom' is the physical top (a warning says so)")
    height: float | None = Field(
        None, description="Θ³ (from the reference face, length) at which the support acts, inside 'layer' (default: "
                          "the layer containing it; at an interface the upper one)")
    direction: Vec3 | None = Field(
        None, description="held direction (global vector, e.g. [0, 0, 1] for a bearing); instead of 'components'")
    value: list[FiniteFloat] | None = Field(
        None, description="prescribed displacement instead of zero: one value per entry of 'components' (or one "
                          "for 'direction'; length units), multiplied by the load factor λ when 'scaled' "
                          "(displacement control); the reaction there is f_int − F_ext. It moves the held point "
                          "(the face, the height, or director 0); with 'directors' the other held directors stay "
                          "zero (the section translates); without director 0 in 'directors' each held director "
                          "takes the value in its own units. On a bonded layer's face it moves the neighbour's "
                          "face too")
    scaled: bool = Field(True, description="with 'value': multiplied by the load factor λ (false: constant)")


class SymmetryDef(Strict):
    type: Literal["symmetry"]
    where: str | None = Field(None, description=_NODES)
    set: str | None = Field(None, description=_SET_N)
    point: Vec3 | None = Field(None, description=_POINT)
    normal: Vec3 = Field(description=(
        "normal of the symmetry plane [x, y, z] (any length): the displacement along it is zero for every "
        "director and layer"))


class HingeDef(Strict):
    type: Literal["hinge"]
    where: str | None = Field(None, description=_NODES)
    set: str | None = Field(None, description=_SET_N)
    point: Vec3 | None = Field(None, description=_POINT)
    direction: Union[Vec3, Literal["edge-normal"]] = Field(
        description="hinge direction: a global vector (any, the thickness direction included) or 'edge-normal', the "
                    "in-plane normal of the boundary edge at each node (local direction, (3.84)-(3.90))")
    height: float | None = Field(None, description=(
        "Θ³ of the hinge line (length, from the reference face); default: mid-thickness"))
    fixed: bool = Field(True, description="fixed hinge (u0 of the first layer along 'direction' only) or sliding")


Support = Annotated[Union[FixDef, SymmetryDef, HingeDef], Field(discriminator="type")]


# ------------------------------------------------------------------ loads
class SurfaceLoadDef(Strict):
    type: Literal["surface"]
    face: str = Field("reference", description="'reference', 'top' or 'layer:<name>' (bottom face of that layer)")
    where: str | None = Field(None, description=_ELEMS)
    set: str | None = Field(None, description=_SET_E)
    direction: Union[Vec3, Literal["normal"]] = Field(description="global vector or 'normal' (A3)")
    magnitude: NumOrFormula = Field(description=(
        "force per reference area (force/area)"))
    scaled: bool = Field(True, description=_SCALED)


class EdgeLoadDef(Strict):
    type: Literal["edge"]
    where: str | None = Field(None, description="boundary edges whose three nodes satisfy this formula")
    set: str | None = Field(None, description=_SET_N + "; the loaded edges are the boundary edges whose three "
                            "nodes are in it")
    direction: Vec3 = Field(description="global direction of the traction [x, y, z] (normalised)")
    distribution: NumOrFormula = Field(
        description="traction through the thickness (force/area), a number or a formula in t (Θ³ from the "
                    "reference face), x, y, z; with 'face': a line force per edge length on that face")
    face: Literal["top", "reference"] | None = Field(
        None, description="apply a line force on the edge of the top (opposite) or reference face, (2.175)/(2.180)")
    height: float | None = Field(
        None, description="a line force per edge length at this Θ³ (from the reference face, length), split into "
                          "director forces (Θ_L³)^l q of the layer containing it (the upper one at an interface)")
    scaled: bool = Field(True, description=_SCALED)


class VolumeLoadDef(Strict):
    type: Literal["volume"]
    where: str | None = Field(None, description=_ELEMS)
    set: str | None = Field(None, description=_SET_E)
    layer: str | None = Field(None, description="only this layer; default: every layer")
    value: Vec3 = Field(description="force per volume [x, y, z] (force/length³)")
    scaled: bool = Field(True, description=_SCALED)


class GravityDef(Strict):
    type: Literal["gravity"]
    where: str | None = Field(None, description=_ELEMS)
    set: str | None = Field(None, description=_SET_E)
    g: Vec3 = Field([0.0, 0.0, -9.81], description=(
        "acceleration of gravity [x, y, z] (length/time², in the units that make density × g a force per volume)"))
    scaled: bool = Field(True, description=_SCALED)


class NodalLoadDef(Strict):
    type: Literal["nodal"]
    where: str | None = Field(None, description=_NODES)
    set: str | None = Field(None, description=_SET_N)
    point: Vec3 | None = Field(None, description=_POINT)
    layer: str | None = Field(None, description=(
        "layer whose director is loaded; default: the layer at the reference face"))
    director: int = Field(0, ge=0, le=4, description="director l loaded (0: the layer's bottom face)")
    value: Vec3 = Field(description="force [x, y, z] at each selected node (director 0), or director force (force × length^director), global")
    height: float | None = Field(
        None, description="Θ³ (from the reference face, length) at which the force acts, e.g. the mid-surface; it is "
                          "split into the director forces (Θ_L³)^l F of the layer containing it (the upper one at "
                          "an interface, or 'layer'); not with 'director'")
    face: str | None = Field(
        None, description="'reference', 'top' or 'layer:<name>' (the bottom face of that layer): the force acts on "
                          "that face (split into director forces like 'height')")
    scaled: bool = Field(True, description=_SCALED)


Load = Annotated[Union[SurfaceLoadDef, EdgeLoadDef, VolumeLoadDef, GravityDef, NodalLoadDef],
                 Field(discriminator="type")]


# ------------------------------------------------------------------ stepping and probes
class Steps(Strict):
    n: PositiveInt = Field(1, le=100_000, description="equal load steps from 0 to lambda_end")
    lambda_end: FiniteFloat = Field(1.0, description="load factor λ of the last step (the loads are λ × their values)")
    factors: list[float] | None = Field(None, description="explicit load factors (instead of n/lambda_end)")
    tolerance: PositiveFloat = Field(1e-8, description=(
        "Newton convergence: residual norm ≤ tolerance × norm of the applied load vector λF (relative, "
        "dimensionless); each entry of the residual less its round-off, 2 ε Σ_j |K_ij u_j| (the entries of "
        "the quadratic directors of a thick layer carry force × length² and stall far above the others)"))
    max_iterations: PositiveInt = Field(25, le=10_000, description=(
        "Newton iterations per load increment before it is bisected (a re-solution at the same load after "
        "new debonding, which cannot be bisected, gets 4 ×)"))
    max_bisections: int = Field(8, ge=0, le=30, description=(
        "halvings of a load increment that does not converge before the run stops"))
    max_contact_iterations: PositiveInt = Field(
        100, le=100_000, description="models with contact: Newton iterations per equilibrium solve in all "
        "(semi-smooth and active-set loops) before the load increment is bisected (a re-solution at the same "
        "load after new debonding: 4 ×)")
    stabilize: float = Field(
        0.0, ge=0, le=10, description="control = 'load' (fixed or adaptive steps) with cohesive interfaces: when "
        "a step fails through all its bisections (cuts), the viscous regularisation (interfaces' 'viscosity') is switched on from there with the "
        "time η = stabilize × the step's load-factor increment (0.02 is a good value) and the step is solved "
        "again; the run warns, summary.json names the load factor and the viscous share ('stabilized') and the "
        "energy ledger the viscous dissipation. 0 (default): off, the run stops at such a step")
    stabilize_limit: float = Field(
        0.05, gt=0, le=1, description="stabilised runs stop at a step whose viscous dissipation exceeds this "
        "share of the step's dissipation: the regularisation, not the interface, then carries the load, past a "
        "limit point of the load or a snap-back; follow the path with control = 'arc_length' or refine the mesh")
    unstable: Literal["stop", "relax"] = Field(
        "stop", description="control = 'load' (fixed or adaptive steps) with cohesive interfaces: a step that "
        "fails through all its bisections (cuts) has no equilibrium of the rate-independent law nearby - a "
        "snap-back of the path under displacement control (the crack front jumps), or a limit point under force "
        "control. 'relax': the damage relaxes at the load of the smallest cut to the next equilibrium (a viscous "
        "law in pseudo-time at the fixed load, until it holds without viscosity), as a specimen snaps in a test; "
        "the energy the jump releases is booked as viscous dissipation, each jump is a warning and an entry of "
        "summary.json 'relaxations'; where the interfaces separate completely (a limit point) the run stops. "
        "'stop' (default): the run stops at such a step. To trace the snap-back instead, use control = "
        "'arc_length' (also with prescribed displacements)")
    solver: Literal["auto", "superlu", "pardiso"] = Field("auto", description=(
        "sparse linear solver; auto: PARDISO where installed, else SuperLU"))
    reuse_factorization: Literal["auto", "always", "never"] = Field(
        "auto", description="PARDISO: solve a Newton iteration's tangent first by GMRES preconditioned with the "
        "last factorisation (of an earlier iteration), and factorise only where GMRES would spend more than a "
        "factorisation costs; 'auto' (default): on models whose factorisation costs at least 16 GMRES "
        "iterations (about 15 000 DOFs and up), 'always', 'never'. The answer is the same to the Newton "
        "tolerance; summary.json 'linear_solves' counts factorisations and GMRES solves")
    integration: Literal["implex", "implicit"] = Field("implex", description=(
        "concrete layers: 'implex' (default): each increment acts with the damage extrapolated from the last two "
        "converged increments and commits the implicit update (Oliver, Huespe & Cante 2008; robust: no "
        "loading/unloading switches within the Newton iterations; the error shrinks with the increment); "
        "'implicit': damage updated in every iteration with the consistent tangent"))
    control: Literal["load", "arc_length"] = Field(
        "load", description="'load': the load factor λ is stepped (it scales forces and prescribed support "
        "displacements alike: displacement control is a [[supports]] 'fix' with 'value'); 'arc_length': λ is an "
        "unknown of every increment (Crisfield's cylindrical arc length, switching to the dissipation-based "
        "constraint once energy is dissipated), so the path may pass limit points and snap-backs (λ decreases); "
        "λ scales the forces and the prescribed displacements alike, so a displacement-controlled test traced by "
        "arc length passes the snap-backs where the prescribed displacement must fall while a crack grows; "
        "the first increment is lambda_end/n, the run ends at λ = lambda_end, when λ falls below 0.1 % of its "
        "peak (complete failure) or after max_steps increments; the steps are sized automatically")
    adaptive: bool = Field(
        False, description="control = 'load': automatic step size - the first increment is lambda_end/n, it grows "
        "(at most 2×) after increments with few Newton iterations and is halved after a failed one, up to "
        "increment_max; every converged increment is a step in probes.csv")
    increment_max: PositiveFloat | None = Field(
        None, description="adaptive load control: the largest load-factor increment (default 10 × lambda_end/n)")
    arc_length: PositiveFloat | None = Field(
        None, description="control = 'arc_length': the first arc length, the norm of the increment of the "
        "independent DOFs in length units (each director coefficient u_l times t^l, t the layer's thickness: "
        "how far it moves the layer's far face; default: that of the linear predictor for Δλ = lambda_end/n)")
    arc_length_min: PositiveFloat | None = Field(
        None, description="control = 'arc_length': the smallest arc length before the run stops (default "
        "arc_length/1000)")
    arc_length_max: PositiveFloat | None = Field(
        None, description="control = 'arc_length': the largest arc length (default 10 × arc_length); "
        "it also bounds the increments under the dissipation constraint (the next dissipation increment is "
        "scaled down where an increment was longer)")
    dissipation: bool = Field(
        True, description="control = 'arc_length': switch to the dissipation-based constraint (Gutiérrez 2004; "
        "Verhoosel, Remmers & Gutiérrez 2009) once an increment dissipates energy (damage with secant unloading)")
    dissipation_threshold: PositiveFloat = Field(
        1e-3, description="the switch: an increment's dissipation ½F̂ᵀ(λ₀Δu − Δλu₀) above this fraction of the "
        "elastic energy ½λF̂ᵀu")
    target_iterations: PositiveInt = Field(
        8, le=100, description="control = 'arc_length' or adaptive: the Newton iterations (active-set loops "
        "included) of a normal increment; the next increment is scaled by target_iterations / iterations, within "
        "[1/2, 2] (adaptive: an increment cut below 1/16 of the first whose iterations do not follow its size "
        "grows 1.5x instead). Larger: fewer, longer increments (fewer points on the path, often fewer iterations "
        "in all: "
        "the force-loaded DCB on 200 elements by arc length took 101 increments and 759 iterations with 8, 55 "
        "and 593 with 16)")
    max_steps: PositiveInt = Field(
        1000, le=1_000_000, description="control = 'arc_length' or adaptive: the most increments of the run")
    jump_area: float | None = Field(
        0.2, gt=0, le=1, description="warn (console and summary.json 'warnings') when the debonded area grows by "
        "more than this fraction of the interface in one step; adaptive and arc-length control cut such a step "
        "first")
    jump_ratio: float | None = Field(
        3.0, gt=1, description="warn when a probe grows more than this many times as fast as λ in one step "
        "(|v/v_prev| > jump_ratio · max(1, λ/λ_prev)); adaptive and arc-length control cut such a step first. A "
        "debonded_area probe only once it exceeds jump_area of the interface area it watches (it grows by whole "
        "nodal areas)")
    energy_tolerance: float = Field(
        0.02, ge=0, lt=1, description="control = 'arc_length', cohesive interfaces: once the run's energy balance "
        "error (external work − stored energy − dissipated, summary.json 'energy') exceeds 0.5 %, an increment "
        "that adds more to it than this share of the increment's energy (the larger of its external work and its "
        "dissipation; the share falls to a tenth of it as the run's error nears 1 %) is cut, up to 3 times, and "
        "the next one is shortened to aim below it; 0: off. The interface ledger follows each point along the "
        "straight separation path between converged states, so long increments of a front whose mode ratio turns "
        "book too little (examples/mmb_cohesive.toml: the balance error reached 3.3 % with 0 in 54 increments, "
        "0.64 % with the default in 189). Load (displacement) control is not cut for it: a node row that "
        "releases within a step there is a jump of the path")


class ProbeDef(Strict):
    name: str = Field(min_length=1, pattern=r"^[A-Za-z_][A-Za-z0-9_]*$", description=(
        "column name in probes.csv and summary.json"))
    quantity: Literal["displacement", "stress", "traction", "debonded_area", "interface_damage", "load_factor",
                      "reaction", "resultant", "crack_width", "rebar_stress", "rebar_strain"] = Field(
        description="crack_width, rebar_stress, rebar_strain: over the integration points of the concrete layer / "
                    "the reinforcement of `layer` (component: the reinforcement's name, default all) whose element "
                    "centre satisfies `where`, reduced by `reduce` (default max); "
                    "debonded_area: released area of the interface below `layer` (within `where`, a formula "
                    "of the interface points' x, y, z); interface_damage: the largest committed damage (0 intact, "
                    "1 debonded; past the peak of a cohesive law above 0) of the interface below `layer` (within "
                    "`where`); load_factor: λ (× scale, e.g. the load in force units); "
                    "reaction: force (component x|y|z) or moment about the origin (mx|my|mz) that the supports "
                    "exert at the selected nodes (where/set/point), R = f_int − F_ext summed over the nodes' "
                    "rigid-body modes; resultant: stress resultant per unit width at `point`, integrated through "
                    "all layers (component n|m|q|nt|mt on the section whose normal is `direction`)")
    point: Vec3 | None = Field(None, description=(
        "displacement: the nearest node; stress, traction: a point on the reference surface"))
    where: str | None = Field(None, description="displacement: node selection (use with reduce); debonded_area, "
                                                "interface_damage: interface points counted")
    set: str | None = Field(None, description="displacement: " + _SET_N)
    component: str | None = Field(
        None, description="displacement: x|y|z|magnitude; stress: 11|22|33|23|13|12|p1|p2|p3|von_mises; "
                          "traction: 13|23|33|shear")
    measure: Literal["cauchy", "pk2"] = Field("cauchy", description=(
        "stress measure: Cauchy (true) or second Piola-Kirchhoff"))
    sampling: Literal["recovered", "raw"] = Field(
        "recovered", description="stress/traction: 'recovered' (default): transverse stresses σ13, σ23, σ33 from "
        "the 3D equilibrium integrated through the thickness over patch-smoothed in-plane stresses (continuous "
        "through the layers, accurate at element edges and nodes; small strains, plates and shallow shells); "
        "'raw': every component from the displacement derivatives at the point (σ13, σ23 exact only at the "
        "reduced Gauss points)")
    frame: Literal["material", "global"] = Field(
        "material", description="stress/traction components: 'material' (default): in the layer's material "
        "axes M_1, M_2, M_3 (in a 90° ply σ13 is τ_yz and σ23 is -τ_xz); 'global': in the global x, y, z axes "
        "(11 = xx, 23 = yz, 13 = xz; traction 13|23|33 = the x, y, z components of σ·n)")
    theta3: Union[float, Annotated[list[float], Field(min_length=3, max_length=3)]] = Field(
        0.0, description="Θ³ from the reference face, or [start, end, n] to sample (with reduce)")
    layer: str | None = Field(None, description=(
        "the layer meant (where theta3 lies on a layer boundary); traction, debonded_area and interface_damage: the "
        "layer above the "
        "interface; reaction: only the force on that layer at the nodes (default: all layers). Displacement, "
        "stress and traction probes must lie where the layer exists ([[stacks]]); a point on the end of the "
        "layer reads an element that holds it"))
    reduce: Literal["max", "min", "absmax", "mean", "none"] = Field("none", description=(
        "how the values at several nodes or heights become one number"))
    scale: FiniteFloat = Field(1.0, description="factor on the value (e.g. -1 for a downward deflection)")
    direction: Vec3 | None = Field(
        None, description="resultant: normal of the section (a global vector, projected on the tangent plane); n, m: "
                          "normal force and moment of the stresses along it, q: transverse shear, nt/mt: in-plane "
                          "shear and twisting moment; per unit width")
    about: FiniteFloat | None = Field(
        None, description="resultant: Θ³ (from the reference face) of the axis of m and mt; default: mid-height of "
                          "the stack at the point. m > 0 puts the side of larger Θ³ in tension")
    unit: str | None = Field(
        None, description="unit of the probe's value (after 'scale') written on plot axes, e.g. 'mm' or 'kN'; "
                          "default: the unit system of [model] units")

    @field_validator("theta3")
    @classmethod
    def _theta3(cls, v):
        if isinstance(v, list):
            a, b, n = v
            if not (math.isfinite(a) and math.isfinite(b)):
                raise ValueError(f"[start, end, n]: start and end must be finite numbers (got {v})")
            if not (math.isfinite(n) and n == int(n) and 1 <= n <= 100_000):
                raise ValueError(f"[start, end, n]: n must be a whole number of samples from 1 to 100000 (got {n})")
        elif not math.isfinite(v):
            raise ValueError(f"must be a finite number (got {v}); give Θ³ from the reference face")
        return v


class PlotDef(Strict):
    """A figure plot_<name>.png of one probe against another over the converged steps."""

    name: str = Field(min_length=1, pattern=r"^[A-Za-z_][A-Za-z0-9_]*$", description="file name: plot_<name>.png")
    x: str = Field(description="probe on the horizontal axis (e.g. the midspan deflection in mm)")
    y: str = Field(description="probe on the vertical axis (e.g. a load_factor probe scaled to the load in kN/m²)")
    title: str = Field("", description="figure title (default: 'y against x')")


class ProfileDef(Strict):
    """Stress along the thickness at a point, one CSV column per layer, and a PNG plot."""

    name: str = Field(min_length=1, pattern=r"^[A-Za-z_][A-Za-z0-9_]*$", description=(
        "file names profile_<name>.csv / .png"))
    point: Vec3 = Field(description="point on the reference surface")
    component: str = Field("11", description="11|22|33|23|13|12|p1|p2|p3|von_mises")
    measure: Literal["cauchy", "pk2"] = Field("cauchy", description=(
        "stress measure: Cauchy (true) or second Piola-Kirchhoff"))
    sampling: Literal["recovered", "raw"] = Field(
        "recovered", description="'recovered' (default) transverse stresses σ13, σ23, σ33 from the equilibrium "
        "through the thickness, or 'raw' values from the displacement derivatives (as [[probes]] sampling)")
    frame: Literal["material", "global"] = Field(
        "material", description="components in the layers' material axes (default) or the global x, y, z axes")
    points_per_layer: int = Field(21, ge=2, le=1001, description="sampling points through each layer (through each ply of a "
                                  "layer with 'plies')")


class LineDef(Strict):
    """A displacement, stress or traction component along a polyline on the reference surface:
    line_<name>.csv (distance along the line s, the point x, y, z, one column per component) and
    line_<name>.png, at the last converged step."""

    name: str = Field(min_length=1, pattern=r"^[A-Za-z_][A-Za-z0-9_]*$", description=(
        "file names line_<name>.csv / .png"))
    points: list[Vec3] = Field(min_length=2, description=(
        "vertices [x, y, z] of the polyline on the reference surface (model coordinates), e.g. [[0, 0.5, 0], "
        "[4, 0.5, 0]] along a span; on a curved shell close enough that each straight segment stays within 5 % "
        "of its length of the surface"))
    samples: int = Field(21, ge=2, le=10_000, description=(
        "sample points per segment, its ends included (a shared vertex once), each moved to the nearest point "
        "of the reference surface"))
    quantity: Literal["displacement", "stress", "traction"] = Field(description=(
        "displacement, stress at theta3, or traction: the interface stresses on the bottom face of `layer`"))
    components: list[str] = Field(min_length=1, description=(
        "one CSV column and one curve each: displacement: x|y|z|magnitude; stress: "
        "11|22|33|23|13|12|p1|p2|p3|von_mises; traction: 13|23|33|shear (as [[probes]])"))
    theta3: FiniteFloat = Field(0.0, description="displacement, stress: Θ³ from the reference face")
    layer: str | None = Field(None, description=(
        "the layer meant (traction: the layer above the interface, required); where [[stacks]] leave it out the "
        "CSV cells are empty and the curve has a gap"))
    measure: Literal["cauchy", "pk2"] = Field("cauchy", description="stress measure (as [[probes]])")
    sampling: Literal["recovered", "raw"] = Field("recovered", description=(
        "stress/traction: 'recovered' or 'raw' transverse stresses (as [[probes]])"))
    frame: Literal["material", "global"] = Field("material", description=(
        "stress/traction components in the material axes or the global x, y, z axes (as [[probes]])"))
    scale: FiniteFloat = Field(1.0, description="factor on the values (e.g. -1 for a downward deflection)")
    unit: str | None = Field(None, description=(
        "unit of the values (after 'scale') on the figure's axis; default: from [model] units (length for "
        "displacements, force/length² for stresses)"))


class InitialZone(Strict):
    """Initially debonded region of an interface: nodes selected by a formula, a set, or a circle."""

    where: str | None = Field(None, description=_NODES)
    set: str | None = Field(None, description=_SET_N)
    circle: Annotated[list[float], Field(min_length=3, max_length=4)] | None = Field(
        None, description="[x, y, radius] (or [x, y, z, radius]) on the reference surface")
    mu0: float | None = Field(None, ge=0, le=1, description="friction in the zone (default: the interface's)")
    mu: float | None = Field(None, gt=0, le=1, description=(
        "residual friction ratio in the zone (default: the interface's)"))
    gT_mu: Union[PositiveFloat, Literal["inf"]] | None = Field(None, description=(
        "slip of the residual friction in the zone (length; default: the interface's)"))


class InterfaceDef(Strict):
    """Interface below layer ``layer`` (MODEL.md §9-§10)."""

    layer: str = Field(description="the layer above the interface")
    sigma_max: PositiveFloat = Field(description="tensile strength σ33_max (force/area, 4.15)")
    tau_max: PositiveFloat = Field(description="shear strength τ_max (force/area, 4.15)")
    p: float = Field(2.0, ge=1.0, description="exponent of the failure surface (4.19)")
    mu0: float = Field(0.95, ge=0, le=1, description="friction right after fracture (4.70)")
    mu: float = Field(0.2, gt=0, le=1, description="residual friction ratio at g_T = gT_mu (4.77)")
    gT_mu: Union[PositiveFloat, Literal["inf"]] = Field("inf", description=(
        "slip of the residual friction (length, 4.76)"))
    mu_coulomb: float = Field(0.0, ge=0, description="Coulomb coefficient of the fallback (4.84)")
    alpha_N: PositiveFloat | None = Field(None, description=(
        "normal contact penalty (force/length³; default 100 E3/H_min)"))
    alpha_T: PositiveFloat | None = Field(
        None, description="tangential stick penalty of the regularised friction (stress/length). Thesis law: "
                          "default G13/H of the thinner layer. Cohesive law: default K0, and at a point whose slip "
                          "limit is below tau_max scaled by limit/tau_max, so that every point sticks over a slip "
                          "of at least tau_max/alpha_T (a fixed penalty made low-pressure points rigid-plastic and "
                          "stalled Newton at peaks, docs/performance.md)")
    open_gap: PositiveFloat | None = Field(
        None, description="a debonded point whose gap exceeds this is open: no friction there (default 0.1 × the "
                          "upper layer's thickness; an addition, the thesis's friction stops at any opening)")
    initially_debonded: list[InitialZone] = Field([], description=(
        "zones debonded from the start: {where | set | circle, mu0, mu, gT_mu}"))
    law: Literal["thesis", "cohesive"] = Field(
        "thesis", description="\"thesis\": bond released node by node by the stress criterion (4.15) (MODEL.md §9); "
                              "\"cohesive\": both layers keep their own DOFs, coupled by a damaging cohesive law "
                              "with onset by sigma_max/tau_max/p and propagation by G_Ic, G_IIc")
    G_Ic: float | None = Field(None, description="cohesive: mode I fracture energy (energy per area, e.g. kN/m = N/mm)")
    G_IIc: float | None = Field(None, description="cohesive: mode II fracture energy (energy per area)")
    eta: PositiveFloat = Field(2.0, description="cohesive: Benzeggagh–Kenane exponent η of G_c = G_Ic + (G_IIc - G_Ic) B^η")
    onset: Literal["thesis", "quadratic"] = Field(
        "thesis", description="cohesive: damage onset by the thesis's criterion (4.15) (sigma_max, tau_max, p) or the "
                              "quadratic one (σ/sigma_max)² + (τ/tau_max)² = 1")
    softening: Literal["bilinear", "exponential"] = Field("bilinear", description="cohesive: shape of the softening branch")
    K0: PositiveFloat | None = Field(
        None, description="cohesive: initial penalty stiffness per area in the normal and tangential directions "
                          "(stress/length; default alpha · E3/H of the thinner adjacent layer, Turon et al. 2007)")
    alpha: PositiveFloat = Field(50.0, description="cohesive: factor α of the default K0 = α E3/H")
    K0_check: bool = Field(
        True, description="cohesive: refuse a K0 that makes the interface more than 3 % as compliant as the two "
                          "layers (a penalty that softens the bonded structure); false where K0 is the measured "
                          "elastic stiffness of the bond itself, e.g. τ_f/δ_1 of a bond-slip law, whose slip is "
                          "part of the physics (examples/lapshear_cohesive.toml)")
    viscosity: float = Field(
        0.0, ge=0, description="cohesive: viscous regularisation time η in load-factor units (Gao & Bower 2004; 0 = "
                               "off): the damage follows the rate-independent one with ḋ = (d_inviscid - d)/η; its "
                               "extra dissipation is reported as dissipated_viscous")
    rule: Literal["lobatto", "gauss"] | None = Field(
        None, description="interface integration at the nodes (\"lobatto\", Newton–Cotes) or at the 3×3 face Gauss "
                          "points (\"gauss\"; tractions oscillate with stiff penalties, Schellekens & de Borst 1993). "
                          "Cohesive law: the whole interface (default \"lobatto\"). Thesis law: the penalty contact and "
                          "friction between debonded layers (the stress criterion stays at the Gauss points). Left "
                          "out, the contact starts at the thesis's face Gauss points and moves to the nodes, with a "
                          "warning, where a solve finds no equilibrium there (on refined meshes the Gauss points' "
                          "contact set can cycle); \"gauss\" keeps the Gauss points (the run then stops), "
                          "\"lobatto\" uses the nodes from the start")


class DelaminationDef(Strict):
    stresses: Literal["raw", "recovered"] = Field(
        "raw", description="interface tractions the failure criterion (4.15) sees: 'raw' (default, the thesis): "
        "from the displacement derivatives at the face Gauss points; 'recovered': σ13, σ23, σ33 from the 3D "
        "equilibrium through the thickness, as in the outputs (less mesh-dependent onset; the recovery treats "
        "the stack as bonded)")
    friction: Literal["return_mapping", "explicit"] = Field(
        "return_mapping", description="friction as a penalty return mapping (implicit), or as explicit loads (thesis)")
    max_release: PositiveInt | None = Field(None, description="nodes released per re-solution (largest V first)")
    max_resolves: PositiveInt = Field(
        1000, description="most re-solutions (release, solve again) per load step: a limit on the cost of a "
        "cascade (each re-solution releases at least one node, so a cascade ends by itself; the CFRP plate on "
        "24 x 16 needs more than 130 at one load)")
    max_debond_fraction: float | None = Field(
        None, gt=0, le=1,
        description="step cutting: a load increment whose re-solutions debond more than this fraction of the "
                    "interface area is undone and halved (the delamination state is then updated at every "
                    "sub-step); off when not given")
    max_debond_cuts: int = Field(4, ge=0, le=20, description="most halvings per load step for max_debond_fraction")
    reequilibrate: bool = Field(
        True, description="solve the same load level again after releases until nothing new fails (recommended); "
                          "false: the thesis's procedure, releases act from the next load step on (the front then "
                          "lags by up to one step per release and depends more on the step size)")


class OutputDef(Strict):
    vtu: bool = Field(True, description="write the ParaView files (*.vtu, *.pvd)")
    sampling: Literal["recovered", "raw"] = Field(
        "recovered", description="stresses in the solid and interface ParaView files: 'recovered' (default) "
        "transverse stresses σ13, σ23, σ33 from the equilibrium through the thickness, or 'raw' values from the "
        "displacement derivatives (as [[probes]] sampling)")
    frame: Literal["material", "global"] = Field(
        "material", description="stress components in the ParaView files: the layers' material axes (default) "
        "or the global x, y, z axes")
    plots: bool = Field(True, description="write the PNG figures")
    every: PositiveInt = Field(1, description="write ParaView files every n-th step (the last is always written)")
    zone_steps: list[PositiveInt] | None = Field(
        None, description="load steps (1 = first, as in probes.csv) whose debonded zones are drawn in "
                          "debonded_zone_<interface>.png; default: the first step with new debonding and the last")

    @field_validator("zone_steps")
    @classmethod
    def _distinct(cls, v):
        if v is not None and len(set(v)) != len(v):
            raise ValueError(f"steps must not repeat (got {v}); list each load step once")
        return sorted(v) if v is not None else v


class ImperfectionDef(Strict):
    mode: PositiveInt | None = Field(None, description=(
        "buckling mode (1 = the lowest) from 'folder', written by `layershell buckle`: the nodes move along "
        "the reference face's normal by the mode's normal displacement, scaled to a largest offset of "
        "'amplitude'; instead of 'formula'"))
    folder: str | None = Field(None, description=(
        "with 'mode': the results folder of `layershell buckle` for this mesh (holding buckling_modes.npz), "
        "relative to the model file"))
    formula: str | None = Field(None, description=(
        "instead of 'mode': the normal offset as a formula in x, y, z (length, multiplied by 'amplitude'), "
        "e.g. 'sin(pi*x/100)'"))
    amplitude: FiniteFloat = Field(description=(
        "with 'mode': the largest normal offset of a node (length; the sign flips the mode); with 'formula': "
        "the factor on it"))

    @model_validator(mode="after")
    def _one_shape(self):
        if (self.mode is None) == (self.formula is None):
            raise ValueError("'imperfection': give either 'mode' (with 'folder') or 'formula', not both nor neither")
        if self.mode is not None and self.folder is None:
            raise ValueError("'imperfection.folder': 'mode' needs the results folder of `layershell buckle` that "
                             "holds the modes, e.g. folder = 'results/plate_buckle'")
        return self


class ModelFile(Strict):
    model: ModelSettings = ModelSettings()
    mesh: Mesh
    materials: dict[str, Material] = Field(min_length=1)
    layers: list[LayerDef] = Field(min_length=1)
    stacks: list[StackDef] | None = None
    supports: list[Support] = []
    loads: list[Load] = []
    steps: Steps = Steps()
    probes: list[ProbeDef] = []
    profiles: list[ProfileDef] = []
    lines: list[LineDef] = []
    plots: list[PlotDef] = []
    interfaces: list[InterfaceDef] = []
    delamination: DelaminationDef = DelaminationDef()
    output: OutputDef = OutputDef()
    imperfection: ImperfectionDef | None = None

    @model_validator(mode="after")
    def _names(self):
        names = [ly.name for ly in self.layers]
        dup = {n for n in names if names.count(n) > 1}
        if dup:
            raise ValueError(f"'layers': layer names must be unique, but {sorted(dup)} appear more than once; "
                             "rename the layers")
        for i, ly in enumerate(self.layers):
            _check_layer_material(ly, i)
            used = [(f"layers[{i}].material", ly.material)] if ly.plies is None else [
                (f"layers[{i}].plies[{j}].material", p.material) for j, p in enumerate(ly.plies)]
            for at, mat in used:
                if mat not in self.materials:
                    raise ValueError(f"'{at}': unknown material '{mat}'; defined: {sorted(self.materials)} (fix the "
                                     f"name or add a [materials.{mat}] table)")
                kind = self.materials[mat].type
                if kind in ("steel", "textile"):
                    raise ValueError(f"'{at}': material '{mat}' is a {kind}, which acts in one direction only and "
                                     "is placed inside a layer: give the layer a concrete or elastic material and "
                                     f"add reinforcement = [{{material = '{mat}', height = ..., area = ...}}]")
                if kind == "concrete" and ly.plies is not None:
                    raise ValueError(f"'{at}': a ply stack takes elastic plies only, but '{mat}' is a concrete; "
                                     "make the concrete its own layer")
            for j, r in enumerate(ly.reinforcement):
                at = f"layers[{i}].reinforcement[{j}].material"
                if r.material not in self.materials:
                    raise ValueError(f"'{at}': unknown material '{r.material}'; defined: {sorted(self.materials)} "
                                     f"(fix the name or add a [materials.{r.material}] table of type 'steel' or "
                                     "'textile')")
                if self.materials[r.material].type not in ("steel", "textile"):
                    raise ValueError(f"'{at}': reinforcement is of a material of type 'steel' or 'textile', but "
                                     f"'{r.material}' is of type '{self.materials[r.material].type}'")
        zs = self.output.zone_steps
        n_steps = len(self.steps.factors) if self.steps.factors is not None else self.steps.n
        if zs and max(zs) > n_steps:
            raise ValueError(f"'output.zone_steps': step {max(zs)} does not exist, the model has {n_steps} load "
                             f"step(s); give step numbers from 1 to {n_steps}")
        pn = [p.name for p in self.probes]
        dup = {n for n in pn if pn.count(n) > 1}
        if dup:
            raise ValueError(f"'probes': probe names must be unique, but {sorted(dup)} appear more than once; "
                             "rename the probes")
        for i, pl in enumerate(self.plots):
            for axis in ("x", "y"):
                if getattr(pl, axis) not in pn:
                    raise ValueError(f"'plots[{i}].{axis}': unknown probe '{getattr(pl, axis)}'; defined: {pn} (add a "
                                     "[[probes]] table, e.g. quantity = 'load_factor' with scale = the load)")
        return self
