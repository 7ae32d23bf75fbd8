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
    title: str = ""
    units: str = Field("", description="unit system, for reports only (e.g. 'kN, m')")
    nonlinear: bool = Field(True, description="geometrically nonlinear (Green-Lagrange) or linear")
    thickness_points: PositiveInt = Field(
        3, le=10, description="Gauss points through each layer (at least d are used: d = 4 needs 4)")


# ------------------------------------------------------------------ meshes
class RectangleMesh(Strict):
    type: Literal["rectangle"]
    lx: PositiveFloat
    ly: PositiveFloat
    nx: PositiveInt
    ny: PositiveInt
    origin: Vec3 = [0.0, 0.0, 0.0]
    normal: Literal["+z", "-z"] = Field("+z", description="'+z': reference face at the bottom; '-z': on top")


class CylinderMesh(Strict):
    type: Literal["cylinder"]
    radius: PositiveFloat = Field(description="radius of the reference face")
    angle_start: float = 0.0
    angle_end: float = Field(description="degrees")
    width: PositiveFloat
    n_arc: PositiveInt
    n_width: PositiveInt = 1
    normal: Literal["inward", "outward"] = Field(
        "inward", description="'inward': reference face outside (A3 towards the axis)")
    axis: Literal["z", "y"] = "z"

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


class RevolutionMesh(Strict):
    type: Literal["revolution"]
    meridian_r: list[float] = Field(min_length=2)
    meridian_z: list[float] = Field(min_length=2)
    n_meridian: PositiveInt | None = Field(
        None, description="elements of equal length along the meridian polyline (or give 'segments')")
    n_circ: PositiveInt
    angle: float = Field(360.0, gt=0, le=360)
    normal: Literal["inward", "outward"] = "outward"
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


class FileMesh(Strict):
    type: Literal["file"]
    path: str = Field(description="mesh file read with meshio (Gmsh .msh, .vtu, ...), relative to the model file")
    scale: PositiveFloat = 1.0


Mesh = Annotated[Union[RectangleMesh, CylinderMesh, RevolutionMesh, FileMesh], Field(discriminator="type")]


# ------------------------------------------------------------------ materials and layers
class Isotropic(Strict):
    type: Literal["isotropic"]
    E: float
    nu: float
    density: float = Field(0.0, ge=0, description="mass per volume (for gravity loads)")


class OrthotropicMat(Strict):
    type: Literal["orthotropic"]
    E1: float
    E2: float
    E3: float
    G12: float
    G23: float
    G31: float
    nu12: float
    nu23: float
    nu31: float | None = None
    nu13: float | None = Field(None, description="give nu13 instead of nu31 (nu31 = nu13 E3/E1)")
    density: float = Field(0.0, ge=0, description="mass per volume (for gravity loads)")

    @model_validator(mode="after")
    def _one_of(self):
        if (self.nu31 is None) == (self.nu13 is None):
            raise ValueError("give exactly one of nu31 and nu13 (nu31 = nu13 E3/E1)"
                             + (", not both" if self.nu31 is not None else ""))
        return self


Material = Annotated[Union[Isotropic, OrthotropicMat], Field(discriminator="type")]


class LayerDef(Strict):
    name: str = Field(min_length=1)
    material: str
    thickness: NumOrFormula = Field(description="number or formula in x, y, z (evaluated at the nodes)")
    directors: int = Field(3, ge=0, le=4, description="d: u = Σ_{l=0..d} (Θ³)^l u_l")
    angle: FiniteFloat = Field(0.0, description="material angle ω in degrees about the normal")
    direction: Vec3 | None = Field(None, description="global direction projected on the surface as material axis 1")

    @field_validator("thickness")
    @classmethod
    def _positive(cls, v):
        if isinstance(v, (int, float)) and not (v > 0 and math.isfinite(v)):
            raise ValueError(f"must be positive and finite (got {v}); give the layer thickness as a positive "
                             "number or a formula in x, y, z")
        return v


class StackDef(Strict):
    layers: list[str] = Field(min_length=1, description="layer names from the reference face outward")
    where: str | None = Field(None, description="formula on element centres selecting the elements")
    set: str | None = None


# ------------------------------------------------------------------ supports
Component = Literal["x", "y", "z"]


class FixDef(Strict):
    type: Literal["fix"]
    where: str | None = None
    set: str | None = None
    point: Vec3 | None = None
    layer: str | None = Field(None, description="default: the layer at the reference face")
    directors: Union[Literal["all"], list[int]] = [0]
    components: list[Component] = ["x", "y", "z"]


class SymmetryDef(Strict):
    type: Literal["symmetry"]
    where: str | None = None
    set: str | None = None
    point: Vec3 | None = None
    normal: Vec3


class HingeDef(Strict):
    type: Literal["hinge"]
    where: str | None = None
    set: str | None = None
    point: Vec3 | None = None
    direction: Union[Vec3, Literal["edge-normal"]] = Field(
        description="hinge direction: a global vector (not the thickness direction) or 'edge-normal', the in-plane "
                    "normal of the boundary edge at each node (local direction, (3.84)-(3.90))")
    height: float | None = Field(None, description="Θ³ of the hinge; default mid-thickness")
    fixed: bool = Field(True, description="fixed hinge (u0 of the first layer along 'direction' only) or sliding")


Support = Annotated[Union[FixDef, SymmetryDef, HingeDef], Field(discriminator="type")]


# ------------------------------------------------------------------ loads
class SurfaceLoadDef(Strict):
    type: Literal["surface"]
    face: str = Field("reference", description="'reference', 'top' or 'layer:<name>' (bottom face of that layer)")
    where: str | None = None
    set: str | None = None
    direction: Union[Vec3, Literal["normal"]] = Field(description="global vector or 'normal' (A3)")
    magnitude: NumOrFormula = Field(description="force per reference area; number or formula in x, y, z")
    scaled: bool = Field(True, description="multiplied by the load factor λ")


class EdgeLoadDef(Strict):
    type: Literal["edge"]
    where: str | None = Field(None, description="boundary edges whose three nodes satisfy this formula")
    set: str | None = None
    direction: Vec3
    distribution: NumOrFormula = Field(
        description="traction per area through the thickness: formula in t (Θ³ from the reference face), x, y, z; "
                    "with 'face': a line force per edge length on that face")
    face: Literal["top", "reference"] | None = Field(
        None, description="apply a line force on the edge of the top (opposite) or reference face, (2.175)/(2.180)")
    scaled: bool = True


class VolumeLoadDef(Strict):
    type: Literal["volume"]
    where: str | None = None
    set: str | None = None
    layer: str | None = None
    value: Vec3 = Field(description="force per volume")
    scaled: bool = True


class GravityDef(Strict):
    type: Literal["gravity"]
    where: str | None = None
    set: str | None = None
    g: Vec3 = [0.0, 0.0, -9.81]
    scaled: bool = True


class NodalLoadDef(Strict):
    type: Literal["nodal"]
    where: str | None = None
    set: str | None = None
    point: Vec3 | None = None
    layer: str | None = None
    director: int = Field(0, ge=0, le=4)
    value: Vec3
    scaled: bool = True


Load = Annotated[Union[SurfaceLoadDef, EdgeLoadDef, VolumeLoadDef, GravityDef, NodalLoadDef],
                 Field(discriminator="type")]


# ------------------------------------------------------------------ stepping and probes
class Steps(Strict):
    n: PositiveInt = Field(1, le=100_000, description="equal load steps from 0 to lambda_end")
    lambda_end: FiniteFloat = 1.0
    factors: list[float] | None = Field(None, description="explicit load factors (instead of n/lambda_end)")
    tolerance: PositiveFloat = 1e-8
    max_iterations: PositiveInt = Field(25, le=10_000)
    max_bisections: int = Field(8, ge=0, le=30)
    max_contact_iterations: PositiveInt = Field(
        100, le=100_000, description="models with contact: Newton iterations per equilibrium solve in all "
        "(semi-smooth and active-set loops) before the load increment is bisected")
    solver: Literal["auto", "superlu", "pardiso"] = "auto"


class ProbeDef(Strict):
    name: str = Field(min_length=1, pattern=r"^[A-Za-z_][A-Za-z0-9_]*$")
    quantity: Literal["displacement", "stress", "traction", "debonded_area", "load_factor"] = Field(
        description="debonded_area: released area of the interface below `layer` (within `where`, a formula "
                    "of the interface points' x, y, z); load_factor: λ (× scale, e.g. the load in force units)")
    point: Vec3 | None = Field(None, description="displacement: nearest node; stress: point on the reference surface")
    where: str | None = Field(None, description="displacement: node selection (use with reduce); debonded_area: "
                                                "interface points counted")
    set: str | None = None
    component: str | None = Field(
        None, description="displacement: x|y|z|magnitude; stress: 11|22|33|23|13|12|p1|p2|p3|von_mises; "
                          "traction: 13|23|33|shear")
    measure: Literal["cauchy", "pk2"] = "cauchy"
    theta3: Union[float, Annotated[list[float], Field(min_length=3, max_length=3)]] = Field(
        0.0, description="Θ³ from the reference face, or [start, end, n] to sample (with reduce)")
    layer: str | None = None
    reduce: Literal["max", "min", "absmax", "mean", "none"] = "none"
    scale: FiniteFloat = 1.0

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


class ProfileDef(Strict):
    """Stress along the thickness at a point, one CSV column per layer, and a PNG plot."""

    name: str = Field(min_length=1, pattern=r"^[A-Za-z_][A-Za-z0-9_]*$")
    point: Vec3 = Field(description="point on the reference surface")
    component: str = Field("11", description="11|22|33|23|13|12|p1|p2|p3|von_mises")
    measure: Literal["cauchy", "pk2"] = "cauchy"
    points_per_layer: int = Field(21, ge=2, le=1001)


class InitialZone(Strict):
    """Initially debonded region of an interface: nodes selected by a formula, a set, or a circle."""

    where: str | None = None
    set: str | None = None
    circle: Annotated[list[float], Field(min_length=3, max_length=4)] | None = Field(
        None, description="[x, y, radius] (or [x, y, z, radius]) on the reference surface")
    mu0: float | None = Field(None, ge=0, le=1, description="friction in the zone (default: the interface's)")
    mu: float | None = Field(None, gt=0, le=1)
    gT_mu: Union[PositiveFloat, Literal["inf"]] | None = None


class InterfaceDef(Strict):
    """Interface below layer ``layer`` (MODEL.md §9-§10)."""

    layer: str = Field(description="the layer above the interface")
    sigma_max: PositiveFloat = Field(description="tensile strength σ33_max (4.15)")
    tau_max: PositiveFloat = Field(description="shear strength τ_max (4.15)")
    p: float = Field(2.0, ge=1.0, description="exponent of the failure surface (4.19)")
    mu0: float = Field(0.95, ge=0, le=1, description="friction right after fracture (4.70)")
    mu: float = Field(0.2, gt=0, le=1, description="residual friction ratio at g_T = gT_mu (4.77)")
    gT_mu: Union[PositiveFloat, Literal["inf"]] = Field("inf", description="slip of the residual friction (4.76)")
    mu_coulomb: float = Field(0.0, ge=0, description="Coulomb coefficient of the fallback (4.84)")
    alpha_N: PositiveFloat | None = Field(None, description="normal contact penalty (default 100 E3/H_min)")
    alpha_T: PositiveFloat | None = Field(
        None, description="tangential stick penalty of the regularised friction (default G13/H of the thinner layer)")
    open_gap: PositiveFloat | None = Field(
        None, description="a debonded point whose gap exceeds this is open: no friction there (default 0.1 × the "
                          "upper layer's thickness; an addition, the thesis's friction stops at any opening)")
    initially_debonded: list[InitialZone] = []
    law: Literal["thesis", "cohesive"] = Field(
        "thesis", description="\"thesis\": bond released node by node by the stress criterion (4.15) (MODEL.md §9); "
                              "\"cohesive\": both layers keep their own DOFs, coupled by a damaging cohesive law "
                              "with onset by sigma_max/tau_max/p and propagation by G_Ic, G_IIc (issue 13)")
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
    viscosity: float = Field(
        0.0, ge=0, description="cohesive: viscous regularisation time η in load-factor units (Gao & Bower 2004; 0 = "
                               "off): the damage follows the rate-independent one with ḋ = (d_inviscid - d)/η; its "
                               "extra dissipation is reported as dissipated_viscous")
    rule: Literal["lobatto", "gauss"] = Field(
        "lobatto", description="cohesive: interface integration at the nodes (Lobatto/Newton–Cotes, default) or at the "
                               "3×3 Gauss points (tractions oscillate with stiff penalties, Schellekens & de Borst 1993)")


class DelaminationDef(Strict):
    friction: Literal["return_mapping", "explicit"] = Field(
        "return_mapping", description="friction as a penalty return mapping (implicit), or as explicit loads (thesis)")
    max_release: PositiveInt | None = Field(None, description="nodes released per re-solution (largest V first)")
    max_resolves: PositiveInt = 100
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
    vtu: bool = True
    plots: bool = True
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
    interfaces: list[InterfaceDef] = []
    delamination: DelaminationDef = DelaminationDef()
    output: OutputDef = OutputDef()

    @model_validator(mode="after")
    def _names(self):
        names = [ly.name for ly in self.layers]
        dup = {n for n in names if names.count(n) > 1}
        if dup:
            raise ValueError(f"'layers': layer names must be unique, but {sorted(dup)} appear more than once; "
                             "rename the layers")
        for i, ly in enumerate(self.layers):
            if ly.material not in self.materials:
                raise ValueError(f"'layers[{i}].material': unknown material '{ly.material}'; defined: "
                                 f"{sorted(self.materials)} (fix the name or add a [materials.{ly.material}] table)")
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
        return self
