"""Model file → validated :class:`~layershell.model.Model` and run settings.

Every error is an :class:`InputError` with one paragraph naming the field and the fix.
"""
from __future__ import annotations

import contextlib
import difflib
import importlib.util
import io
import math
import re
import tomllib
import warnings
from dataclasses import dataclass, field, replace
from pathlib import Path
from types import UnionType
from typing import Annotated, Union, get_args, get_origin

import numpy as np
from pydantic import BaseModel, ValidationError

from .. import mesh as meshmod
from ..element.shape import EDGES
from ..formula import FormulaError
from ..material import MaterialError, Orthotropic, laminate_equivalent
from ..model import EdgeLoad, Fix, Hinge, Layer, Model, NodalLoad, Ply, Reinforcement, SurfaceLoad, Symmetry, Tie
from ..solver.newton import NewtonSettings
from . import schema
from .errors import XYZ, InputError  # defined apart: io/probes.py needs them without importing this module
from .errors import formula as _formula


def _path_settings(st: schema.Steps, model: Model):
    """PathSettings for [steps] control = 'arc_length' or adaptive = true (None: fixed steps)."""
    if st.control == "load" and not st.adaptive:
        return None
    from ..solver.arclength import PathSettings

    if st.factors is not None:
        raise InputError("'steps.factors': explicit load factors fix the steps; with control = 'arc_length' or "
                         "adaptive = true give 'n' and 'lambda_end' instead (the first increment is lambda_end/n)")
    if st.lambda_end <= 0:
        raise InputError(f"'steps.lambda_end': {st.lambda_end} must be positive with control = 'arc_length' or "
                         "adaptive = true")
    if st.control == "arc_length":
        scaled = [ld for ld in (*model.surface_loads, *model.edge_loads, *model.nodal_loads) if ld.scaled]
        prescribed = [fx for fx in model.fixes if fx.value is not None and fx.scaled]
        if not scaled and not prescribed:
            raise InputError("'steps.control': 'arc_length' scales the loads with the load factor λ, but the model "
                             "has no load with scaled = true and no prescribed displacement scaled by λ; add a "
                             "scaled [[loads]] table, or a [[supports]] type = 'fix' with 'value' (displacement "
                             "control; arc length then follows the path through snap-backs of the prescribed "
                             "displacement)")
    inc = st.lambda_end / st.n
    return PathSettings(control=st.control, lambda_end=st.lambda_end, increment=inc,
                        increment_max=st.increment_max, arc_length=st.arc_length, arc_length_min=st.arc_length_min,
                        arc_length_max=st.arc_length_max, dissipation=st.dissipation,
                        dissipation_threshold=st.dissipation_threshold, target_iterations=st.target_iterations,
                        max_steps=st.max_steps,
                        max_cuts=max(st.max_bisections, 1), jump_area=st.jump_area, jump_ratio=st.jump_ratio,
                        energy_tolerance=st.energy_tolerance or None)


@dataclass
class RunSpec:
    model: Model
    load_factors: np.ndarray
    newton: NewtonSettings
    probes: list  # list[Probe]
    output: schema.OutputDef
    source: schema.ModelFile
    path: Path | None = None
    profiles: list = field(default_factory=list)
    lines: list = field(default_factory=list)  # io.lines.Line
    warnings: list[str] = field(default_factory=list)  # input that is valid but almost surely not meant
    path_following: object = None  # solver.arclength.PathSettings ([steps] control/adaptive), None: fixed steps

    def model_text(self) -> str | None:
        """The model file's text as run (summary.json ``model_text``; the restart check compares
        it), None without a readable file."""
        try:
            return self.path.read_text(encoding="utf-8") if self.path is not None else None
        except (OSError, UnicodeDecodeError):
            return None


def _fmt_loc(loc) -> str:
    out = ""
    for p in loc:
        out += f"[{p}]" if isinstance(p, int) else (f".{p}" if out else str(p))
    return out


# -- pydantic error locations -> model-file field names ----------------------------------------
def _members(tp) -> list:
    """``Annotated``/``Optional``/``Union`` unwrapped into the candidate types."""
    origin = get_origin(tp)
    if origin is Annotated:
        return _members(get_args(tp)[0])
    if origin in (Union, UnionType):
        return [m for a in get_args(tp) for m in _members(a)]
    return [tp]


def _models(tp) -> list[type[BaseModel]]:
    return [m for m in _members(tp) if isinstance(m, type) and issubclass(m, BaseModel)]


def _item_type(tp):
    """The table type of a section: the element type of ``list[...]`` / ``dict[str, ...]``, else ``tp``."""
    for m in _members(tp):
        if get_origin(m) in (list, dict):
            return get_args(m)[-1]
    return tp


def _header(section: str) -> str:
    """How a top-level section is written: ``[mesh]``, ``[[layers]]``, ``[materials.<name>]``."""
    origins = [get_origin(m) for m in _members(schema.ModelFile.model_fields[section].annotation)]
    if list in origins:
        return f"[[{section}]]"
    return f"[{section}.<name>]" if dict in origins else f"[{section}]"


def _type_tags(tp) -> list[str]:
    """The ``type = ...`` values of a discriminated union (table kinds such as mesh types)."""
    tags = []
    for m in _models(tp):
        f = m.model_fields.get("type")
        if f is not None:
            tags += [a for a in get_args(f.annotation) if isinstance(a, str)]
    return tags


def _resolve_loc(loc) -> tuple[tuple, object]:
    """Drop pydantic's union-member tags (``'rectangle'``, ``'float'``, ...) from an error location.

    Returns the location as the user wrote it and the schema type found there (None if unknown).
    """
    tp: object = schema.ModelFile
    out: list = []
    for p in loc:
        if tp is None:
            out.append(p)
            continue
        models = _models(tp)
        dicts = [m for m in _members(tp) if get_origin(m) is dict]
        lists = [m for m in _members(tp) if get_origin(m) is list]
        field = next((m.model_fields[p] for m in models if isinstance(p, str) and p in m.model_fields), None)
        if field is not None:
            out.append(p)
            tp = field.annotation
        elif isinstance(p, int) and lists:
            out.append(p)
            tp = get_args(lists[0])[0]
        elif isinstance(p, str) and dicts:
            out.append(p)
            tp = get_args(dicts[0])[1]
        elif isinstance(p, str) and p in _type_tags(tp):  # discriminator tag: the table kind
            tp = next(m for m in models if p in _type_tags(m))
        elif isinstance(p, str) and models:  # a key the table does not have (unknown or missing)
            out.append(p)
            tp = None
        # else: the tag of a union member ('float', 'str', 'list[float]', ...): not a field
    return tuple(out), tp


def _suggest(word: str, choices) -> str:
    close = difflib.get_close_matches(str(word), [str(c) for c in choices], n=1, cutoff=0.6)
    return f"did you mean '{close[0]}'? " if close else ""


def _describe_error(err: dict) -> tuple[str, str]:
    """(field, message with the fix) for one pydantic error."""
    loc, tp = _resolve_loc(err["loc"])
    kind = err["type"]
    msg = err["msg"].removeprefix("Value error, ").removeprefix("Assertion failed, ")
    inp = err.get("input")
    got = "" if isinstance(inp, dict) else f" (got {inp!r})"
    if kind == "extra_forbidden":
        parent_loc, parent = _resolve_loc(err["loc"][:-1])
        allowed = [k for m in _models(parent) for k in m.model_fields] if parent is not None else []
        allowed = list(dict.fromkeys(allowed))
        hint = _suggest(loc[-1], allowed) if loc else ""
        if not hint and loc and len(parent_loc) == 0:  # a key of a section, written at the top level?
            homes = [_header(n) for n, f in schema.ModelFile.model_fields.items()
                     if any(loc[-1] in m.model_fields for m in _models(_item_type(f.annotation)))]
            hint = f"'{loc[-1]}' is a key of {' or '.join(homes)}; " if homes else ""
        where = f"[{_fmt_loc(parent_loc)}]" if parent_loc else "the top level"
        keys = f"allowed keys in {where}: {', '.join(allowed)}" if allowed else "check the spelling"
        return _fmt_loc(loc), f"unknown key; {hint}{keys}"
    if kind == "missing":
        name = loc[-1] if loc else ""
        if len(loc) == 1 and name in schema.ModelFile.model_fields:
            ann = schema.ModelFile.model_fields[name].annotation
            kinds = _type_tags(_item_type(ann))
            extra = f" with type = one of {', '.join(repr(t) for t in kinds)} and its parameters" if kinds else ""
            return _fmt_loc(loc), f"required section is missing; add a {_header(name)} table{extra} (see examples/)"
        parent = _fmt_loc(loc[:-1])
        return _fmt_loc(loc), f"required key is missing; add '{name} = ...' to [{parent}]"
    if kind == "union_tag_not_found":
        tags = _type_tags(tp)
        return _fmt_loc(loc + ("type",)), ("required key is missing; add type = one of "
                                           + ", ".join(f"'{t}'" for t in tags))
    if kind == "union_tag_invalid":
        tags = _type_tags(tp)
        tag = err.get("ctx", {}).get("tag", inp.get("type") if isinstance(inp, dict) else inp)
        return _fmt_loc(loc + ("type",)), (f"unknown type '{tag}'; {_suggest(tag, tags)}use one of "
                                           + ", ".join(f"'{t}'" for t in tags))
    if kind in ("value_error", "assertion_error"):
        return _fmt_loc(loc), msg
    if kind in ("float_parsing", "int_parsing") and inp in ("true", "false"):  # see schema.Strict
        return _fmt_loc(loc), f"Input should be a number, not the boolean {inp}"
    if kind in ("greater_than", "greater_than_equal", "less_than", "less_than_equal"):
        info = _field_info(err["loc"])
        if info is not None and info.description:
            return _fmt_loc(loc), f"{msg}{got}; {loc[-1]}: {_first_sentence(info.description)}"
    return _fmt_loc(loc), msg + got


def _field_info(loc):
    """The schema's field (pydantic FieldInfo) at the innermost key of an error location, or None."""
    for i in range(len(loc), 0, -1):
        if not isinstance(loc[i - 1], str):
            continue
        _, tp = _resolve_loc(loc[:i - 1])
        for m in _models(tp) if tp is not None else ():
            if loc[i - 1] in m.model_fields:
                return m.model_fields[loc[i - 1]]
    return None


def _first_sentence(text: str, limit: int = 240) -> str:
    """A field's description up to its first full stop (and at most ``limit`` characters)."""
    head = text.split(". ")[0]
    return head if len(head) <= limit else head[:limit].rsplit(" ", 1)[0] + " …"


def _validation_message(exc: ValidationError, limit: int = 8) -> str:
    """All errors of ``exc`` as one paragraph: ``'field': message; 'field': message``."""
    by_field: dict[str, list[str]] = {}
    for err in exc.errors():
        field, msg = _describe_error(err)
        msgs = by_field.setdefault(field, [])
        if msg not in msgs:
            msgs.append(msg)
    parts = []
    for field, msgs in by_field.items():
        if len(msgs) > 1 and all(m.startswith("Input should be ") for m in msgs):
            got = re.search(r" \(got .*\)$", msgs[0])
            tail = got.group(0) if got and all(m.endswith(got.group(0)) for m in msgs) else ""
            heads = [m.removeprefix("Input should be ").removesuffix(tail) for m in msgs]
            text = "Input should be " + " or ".join(heads) + tail
        else:
            text = "; ".join(msgs)
        parts.append(f"'{field}': {text}" if field else text)
    more = f"; … and {len(parts) - limit} more" if len(parts) > limit else ""
    return "; ".join(parts[:limit]) + more


def parse(text: str, name: str = "model file") -> schema.ModelFile:
    text = text.removeprefix("\ufeff")  # a UTF-8 byte-order mark (Windows editors) is not part of the TOML
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{name}: not valid TOML: {exc}; fix the syntax there (strings need quotes, "
                         "tables are written [name] or [[name]], one key = value per line)") from None
    try:
        return schema.ModelFile.model_validate(data)
    except ValidationError as exc:
        raise InputError(f"{name}: " + _validation_message(exc)) from None


def load(path: str | Path) -> RunSpec:
    path = Path(path)
    if path.is_dir():
        raise InputError(f"model file '{path}' is a folder; give the path of a .toml model file")
    if not path.is_file():
        raise InputError(f"model file '{path}' does not exist; check the path (examples are in examples/)")
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(f"model file '{path}' is not UTF-8 text ({exc.reason} at byte {exc.start}); "
                         "save it as UTF-8") from None
    except OSError as exc:
        raise InputError(f"model file '{path}' cannot be read: {exc.strerror or exc}") from None
    mf = parse(text, str(path))
    try:
        with np.errstate(all="ignore"):  # huge/odd values are checked explicitly, without numpy's warnings
            spec = build(mf, path.parent)
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None
    spec.path = path
    return spec


# ------------------------------------------------------------------ helpers
def _field_fn(value, field: str, variables=XYZ):
    """Number or formula -> vectorised callable of keyword arrays."""
    if isinstance(value, (int, float)):
        v = float(value)
        return lambda **kw: np.full(np.broadcast(*kw.values()).shape if kw else (), v)
    f = _formula(value, variables, field)
    return lambda **kw: f(**kw)


def _span(x: np.ndarray) -> str:
    """The coordinate ranges of points ``x (n, 3)``: 'x ∈ [0, 10], y ∈ [...], z ∈ [...]'."""
    lo, hi = x.min(0), x.max(0)
    return ", ".join(f"{c} ∈ [{a:.6g}, {b:.6g}]" for c, a, b in zip(XYZ, lo, hi))


def _condition(m: meshmod.Mesh, where: str, field: str, x: np.ndarray) -> np.ndarray:
    """A selection formula evaluated at the points ``x (n, 3)``: a boolean mask.

    The formula must be a condition (a comparison, near(...), and/or/not): a number such as
    ``where = "x"`` is an error, not 'true where non-zero'."""
    f = _formula(where, XYZ, field)
    try:
        v = np.asarray(f(tol=1e-6 * m.size(), x=x[:, 0], y=x[:, 1], z=x[:, 2]))
    except FormulaError as exc:
        raise InputError(f"'{field}': {exc}") from None
    if v.dtype != bool:
        raise InputError(f"'{field}': '{where}' is a number, not a condition; a selection must be true or false at "
                         "each point: compare coordinates, e.g. 'x > 0', 'near(x, 0)' (equal within a tolerance) or "
                         "'0 < y and y < 2', and combine with and/or/not")
    return np.broadcast_to(v, (x.shape[0],))


def _node_selection(m: meshmod.Mesh, sel, field: str, required: bool = True) -> np.ndarray:
    where, set_, point = getattr(sel, "where", None), getattr(sel, "set", None), getattr(sel, "point", None)
    given = [g for g in (where, set_, point) if g is not None]
    if len(given) != 1:
        raise InputError(f"'{field}': give exactly one of 'where', 'set' or 'point' to select nodes")
    x = m.nodes
    span = _span(x)
    if point is not None:
        diff = x - np.asarray(point, float)
        big = float(np.abs(diff).max(initial=0.0))
        if not np.isfinite(big):
            raise InputError(f"'{field}.point': {list(point)} is not a point of finite coordinates; give [x, y, z] "
                             f"near the mesh, which spans {span}")
        d = np.linalg.norm(diff / big, axis=1) if big > 0 else np.zeros(len(x))  # scaled: no overflow
        return np.array([int(np.argmin(d))])
    if set_ is not None:
        if set_ not in m.node_sets:
            raise InputError(f"'{field}.set': the mesh has no node set '{set_}'; "
                             f"available: {sorted(m.node_sets) or 'none'}")
        nodes = np.asarray(m.node_sets[set_])
    else:
        nodes = np.flatnonzero(_condition(m, where, f"{field}.where", x))
    if required and nodes.size == 0:
        raise InputError(f"'{field}': the selection '{where or set_}' selects no node; the model spans {span} "
                         "(use near(x, value) to compare coordinates with a tolerance)")
    return nodes


def _element_selection(m: meshmod.Mesh, sel, field: str) -> np.ndarray:
    where, set_ = getattr(sel, "where", None), getattr(sel, "set", None)
    if where is None and set_ is None:
        return np.arange(m.n_elements)
    if set_ is not None:
        if set_ not in m.element_sets:
            raise InputError(f"'{field}.set': the mesh has no element set '{set_}'; "
                             f"available: {sorted(m.element_sets) or 'none'}")
        return np.asarray(m.element_sets[set_])
    c = m.nodes[m.elements[:, 8]]
    el = np.flatnonzero(_condition(m, where, f"{field}.where", c))
    if el.size == 0:
        span = _span(c)
        raise InputError(f"'{field}.where': '{where}' selects no element (it is tested at the element centres, "
                         f"which span {span}); widen the condition or use near(x, value)")
    return el


def _stack_boundaries_on_node_lines(m: meshmod.Mesh, mf: schema.ModelFile) -> None:
    """On a rectangle mesh, every [[stacks]] 'where' boundary must follow element edges: a stack
    takes whole elements by their centres, so a boundary through elements would move silently to
    their edges. InputError naming the lines_x/lines_y that put node lines there."""
    for i, sd in enumerate(mf.stacks or []):
        if sd.where is None:
            continue
        field = f"stacks[{i}].where"

        def inside(x, where=sd.where, field=field):
            return _condition(m, where, field, x)

        cut = meshmod.elements_cut_by(m, inside)
        if cut.size == 0:
            continue
        xs, ys = meshmod.axis_crossings(m, inside, cut)
        fix = " and ".join(f"{k} = [{', '.join(f'{v:.9g}' for v in sorted({*getattr(mf.mesh, k), *vs}))}]"
                           for k, vs in (("lines_x", xs), ("lines_y", ys)) if vs.size)
        c = m.nodes[m.elements[cut[0], 8]].round(6).tolist()
        raise InputError(f"'{field}': the boundary of '{sd.where}' runs through {cut.size} element(s) (e.g. element "
                         f"{cut[0]} with centre {c}) instead of along element edges, and a stack takes whole "
                         f"elements by their centres, so its region would not be the one written; put node lines "
                         f"on the boundary: {fix or 'lines_x/lines_y at its coordinates'} in [mesh] (nx, ny: enough "
                         "elements for them)")


def nodal_normals(m: meshmod.Mesh) -> np.ndarray:
    """(n_nodes, 3) unit normals A3 at the nodes, averaged over the elements sharing each node."""
    from ..element.geometry import surface_points
    from ..element.shape import NODE_XI

    E = m.elements
    sp = surface_points(m.nodes[E], np.broadcast_to(NODE_XI[:, 0], E.shape), np.broadcast_to(NODE_XI[:, 1], E.shape),
                        per_element=True)
    acc = np.zeros((m.n_nodes, 3))
    np.add.at(acc, E.ravel(), sp.A3.reshape(-1, 3))
    return acc / np.linalg.norm(acc, axis=1, keepdims=True)


def boundary_edges(m: meshmod.Mesh) -> np.ndarray:
    """(n, 3) node triples of edges that belong to one element only."""
    tri = m.elements[:, EDGES].reshape(-1, 3)
    mids, counts = np.unique(tri[:, 1], return_counts=True)
    single = set(mids[counts == 1].tolist())
    return np.array([t for t in tri if t[1] in single], dtype=np.int64).reshape(-1, 3)


#: largest generated mesh: more elements do not fit the memory of a workstation anyway
MAX_ELEMENTS = 2_000_000


def _mesh_size(md) -> tuple[int, str] | None:
    """Elements of a generated mesh before it is built (None for mesh files)."""
    if md.type == "rectangle":
        return md.nx * md.ny, "nx × ny"
    if md.type == "cylinder":
        return md.n_arc * md.n_width, "n_arc × n_width"
    if md.type == "revolution":
        segs = getattr(md, "segments", None)
        n_mer = md.n_meridian if md.n_meridian is not None else sum(s.elements for s in (segs or []))
        return n_mer * md.n_circ, "(elements along the meridian) × n_circ"
    if md.type == "plate_with_circle":
        a, b = (md.radius, md.radius) if md.radius is not None else md.semi_axes
        around = min(math.pi * (a + b) / md.front_size, 1e12)  # elements along the front, about
        count = around * (around / 8 + md.ring_layers + (md.outer_layers or 10))
        return int(min(count, 1e18)), "(elements along the front) × (layers across the plate)"
    return None


def _mesh(md, base: Path) -> meshmod.Mesh:
    size = _mesh_size(md)
    if size is not None and size[0] > MAX_ELEMENTS:
        raise InputError(f"'mesh': {size[1]} = {size[0]} elements is more than layershell can handle (at most "
                         f"{MAX_ELEMENTS}); use fewer elements")
    if md.type == "rectangle":
        return meshmod.rectangle(md.lx, md.ly, md.nx, md.ny, md.origin, md.normal, md.grading_x, md.grading_y,
                                 md.lines_x, md.lines_y, md.refine_x, md.refine_y, md.refine_ratio_x,
                                 md.refine_ratio_y)
    if md.type == "cylinder":
        return meshmod.cylinder(md.radius, md.angle_start, md.angle_end, md.width, md.n_arc, md.n_width,
                                md.normal, md.axis)
    if md.type == "revolution":
        segs = None if md.segments is None else [
            meshmod.MeridianSegment(sg.elements, sg.set, None if sg.arc_center is None else tuple(sg.arc_center))
            for sg in md.segments]
        return meshmod.revolution(md.meridian_r, md.meridian_z, md.n_meridian, md.n_circ, md.angle, md.normal,
                                  segments=segs, thickness=md.meridian_thickness)
    if md.type == "plate_with_circle":
        from ..mesh_circle import plate_with_ellipse
        axes = (md.radius, md.radius) if md.radius is not None else md.semi_axes
        key = "radius" if md.radius is not None else "semi_axes"
        try:
            return plate_with_ellipse(md.lx, md.ly, md.center, axes, md.front_size, md.ring_width, md.ring_layers,
                                      md.outer_layers, md.origin, md.normal)
        except meshmod.MeshError as exc:
            raise InputError(f"'mesh' (plate_with_circle: center, {key}, front_size, ring_width): {exc}") from None
    path = base / md.path
    if not path.is_file():
        raise InputError(f"'mesh.path': the mesh file '{md.path}' does not exist (looked for {path}); "
                         "give the path relative to the model file")
    try:
        from .meshfile import read_mesh
    except ImportError as exc:
        raise InputError(f"'mesh.type': mesh files cannot be read in this installation ({exc}); "
                         "use a 'rectangle', 'cylinder' or 'revolution' mesh") from None
    said = io.StringIO()  # meshio prints its read errors (and may call sys.exit): keep them for the message
    try:
        with contextlib.redirect_stdout(said), contextlib.redirect_stderr(said):
            return read_mesh(path, md.scale)
    except (InputError, meshmod.MeshError):
        raise
    except (Exception, SystemExit) as exc:  # meshio's ReadError, KeyError, sys.exit, ... on a broken file
        detail = " ".join(said.getvalue().split()) or f"{type(exc).__name__}: {exc}"
        raise InputError(f"'mesh.path': cannot read '{md.path}' ({detail}); give a mesh file of 9-node "
                         "quadrilaterals that meshio can read (Gmsh .msh, .vtu, ...)") from None


def _stand_in(law, density: float = 0.0) -> Orthotropic:
    """The initial elastic constants of a material law (estimates, mass): isotropic E, ν (a sheet's
    ν = 0: it is not a layer material)."""
    return Orthotropic.isotropic(law.E, getattr(law, "nu", 0.0), density, name=law.name)


def _material(name: str, md) -> Orthotropic:
    bad = [k for k, v in md.model_dump().items() if isinstance(v, float) and not math.isfinite(v)]
    if bad:
        raise InputError(f"'materials.{name}': {', '.join(bad)} must be {'a finite number' if len(bad) == 1 else 'finite'}"
                         f" (got {', '.join(f'{k} = {getattr(md, k)}' for k in bad)})")
    try:
        if md.type == "isotropic":
            mat = Orthotropic.isotropic(md.E, md.nu, md.density, name)
        elif md.nu31 is not None:
            mat = Orthotropic(md.E1, md.E2, md.E3, md.G12, md.G23, md.G31, md.nu12, md.nu23, md.nu31, md.density,
                              name)
        else:
            mat = Orthotropic.from_nu13(md.E1, md.E2, md.E3, md.G12, md.G23, md.G31, md.nu12, md.nu23, md.nu13,
                                        md.density, name)
        mat.check()
    except (MaterialError, ZeroDivisionError, ArithmeticError) as exc:
        raise InputError(f"'materials.{name}': {exc}") from None
    return mat


def _nodal_values(m: meshmod.Mesh, value, field: str, points: np.ndarray | None = None, **extra) -> np.ndarray:
    """A number or formula evaluated at ``points`` (default: the nodes), as a float array."""
    x = m.nodes if points is None else points
    fn = _field_fn(value, field, XYZ + tuple(extra))
    try:
        v = fn(x=x[:, 0], y=x[:, 1], z=x[:, 2], **extra)
        return np.array(np.broadcast_to(v, np.broadcast_shapes(x[:, 0].shape, *(np.shape(e) for e in extra.values()))),
                        dtype=float)
    except (FormulaError, ValueError, TypeError) as exc:
        raise InputError(f"'{field}': cannot evaluate {value!r} ({exc})") from None


def _require_finite(vals: np.ndarray, value, field: str, where: str) -> None:
    if not np.all(np.isfinite(vals)):
        raise InputError(f"'{field}': {value!r} is not finite (NaN or infinite) at some {where}; "
                         "give a formula that is defined over the loaded region (check log, sqrt, division)")


def _vec(v, field: str) -> np.ndarray:
    """Unit vector along ``v`` (scaled by its largest component first: no overflow for huge entries)."""
    a = np.asarray(v, float)
    if not np.all(np.isfinite(a)):
        raise InputError(f"'{field}': the direction vector must be finite (got {list(v)}); give a non-zero "
                         "vector [x, y, z] of finite numbers")
    big = np.abs(a).max(initial=0.0)
    if not big > 0:
        raise InputError(f"'{field}': the direction vector must not be zero (got {list(v)}); give a non-zero "
                         "vector [x, y, z]")
    a = a / big
    return a / np.linalg.norm(a)


# ------------------------------------------------------------------ build
def _edge_normals(m: meshmod.Mesh, nodes: np.ndarray, field: str) -> np.ndarray:
    """In-plane unit normal of the boundary edge through each node: A3 × edge tangent."""
    from ..element.shape import line3

    be = boundary_edges(m)
    lookup = {}
    for e, conn in enumerate(m.elements):
        for tri in EDGES:
            lookup[(conn[tri[0]], conn[tri[1]], conn[tri[2]])] = e
    out = np.zeros((len(nodes), 3))
    pos = {int(n): i for i, n in enumerate(nodes)}
    found = np.zeros(len(nodes), bool)
    for tri in be:
        for k, node in enumerate(tri):
            i = pos.get(int(node))
            if i is None or found[i]:
                continue
            s = np.array([-1.0, 0.0, 1.0])[k]
            _, dN = line3(np.array([s]))
            t = dN[0] @ m.nodes[tri]
            e = lookup.get(tuple(int(v) for v in tri), lookup.get(tuple(int(v) for v in tri[::-1])))
            c = m.nodes[m.elements[e]]
            n3 = np.cross(c[1] - c[0], c[3] - c[0])
            v = np.cross(n3, t)
            out[i] = v / np.linalg.norm(v)
            found[i] = True
    if not found.all():
        raise InputError(f"'{field}.direction': 'edge-normal' needs nodes on the mesh boundary; "
                         f"{int((~found).sum())} selected node(s) are not on a boundary edge")
    return out


def _heights(model: Model, nodes: np.ndarray, height: float | None, face: str | None, k_given: int | None,
             f: str, index: dict) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """Where a force at Θ³ = ``height`` or on ``face`` acts: ``(layer, mask of nodes, Θ_L³)``
    per layer (the layer containing the height; the upper one at an interface)."""
    layers = model.layers
    tol = 1e-9 * model.mesh.size()
    present = model.layers_present()[:, nodes]
    if face is not None:
        if face == "reference":
            h = np.zeros(nodes.size)
        elif face == "top":
            h = model.total_thickness()[nodes]
        elif face.startswith("layer:") and face.split(":", 1)[1] in index:
            k_given = index[face.split(":", 1)[1]]
            h = model.offset(k_given)[nodes]
        else:
            raise InputError(f"'{f}.face': unknown face '{face}'; use 'reference', 'top' or 'layer:<name>' with a "
                             f"layer of {list(index)}")
    else:
        h = np.full(nodes.size, float(height))
    out, done = [], np.zeros(nodes.size, bool)
    order = [k_given] if k_given is not None else sorted(range(len(layers)), key=lambda j: -model.offset(j)[nodes].max())
    for k in order:
        off = model.offset(k)[nodes]
        inside = present[k] & ~done & (off - tol <= h) & (h <= off + layers[k].thickness[nodes] + tol)
        if inside.any():
            out.append((k, inside, np.clip(h - off, 0.0, None)[inside]))
            done |= inside
    if not done.all():
        bad = int(np.flatnonzero(~done)[0])
        raise InputError(f"'{f}': Θ³ = {h[bad]:g} lies outside "
                         + (f"layer '{layers[k_given].name}'" if k_given is not None else "the shell")
                         + f" at node {nodes[bad]} (total thickness {model.total_thickness()[nodes[bad]]:.6g}); give a "
                         "height inside the shell")
    return out


def _downward_face_note(m: meshmod.Mesh, nodes: np.ndarray, face: str, f: str) -> list[str]:
    """'bottom' and 'top' count along the normal A3 (Θ³); where A3 points down they are the
    physical top and bottom: say so, since a bearing then sits on the other side."""
    if face not in ("bottom", "top") or not np.all(nodal_normals(m)[nodes, 2] < -0.5):
        return []
    other = "top" if face == "bottom" else "bottom"
    where = "upper" if face == "bottom" else "lower"
    return [f"'{f}.face' = '{face}' is the face at Θ³ = {'0' if face == 'bottom' else 'H'} of the layer, counted "
            f"along the normal A3, which points down (−z) at these nodes: it is the physically {where} face. For "
            f"the other side write face = '{other}'"]


def _default_layer(model: Model, nodes: np.ndarray, first: int) -> int:
    """The layer a support without 'layer' holds: the first stack's bottom layer where it exists at
    every selected node, else the lowest layer that does (the layer at the reference face there)."""
    present = model.layers_present()[:, nodes].all(axis=1)
    if present[first]:
        return first
    here = np.flatnonzero(present)
    return int(min(here, key=lambda j: model.offset(j)[nodes].mean())) if here.size else first


def _require_present(model: Model, k: int, nodes: np.ndarray, f: str) -> None:
    """A support on layer ``k`` must select nodes where that layer exists: elsewhere it would
    hold nothing."""
    present = model.layers_present()[:, nodes]
    if present[k].all():
        return
    name = model.layers[k].name
    first_bad = int(np.flatnonzero(~present[k])[0])
    bad = nodes[~present[k]]
    x = model.mesh.nodes[bad[0]]
    there = [model.layers[j].name for j in np.flatnonzero(present[:, first_bad])]
    raise InputError(
        f"'{f}': layer '{name}' does not exist at {bad.size} of the {nodes.size} selected node(s) (first at "
        f"({x[0]:g}, {x[1]:g}, {x[2]:g}); '[[stacks]]' leaves it out there), so the support would hold nothing "
        f"there. Select only nodes where '{name}' exists, or name a layer present there ('layer' = "
        f"{' or '.join(repr(t) for t in there) or 'none'}; 'all' holds every layer present)")


def _ties(model: Model, sd, nodes: np.ndarray, f: str, index: dict, first: int) -> list[Tie]:
    """A fix on a face, at a height, in a direction or through all layers (``layer = 'all'``) as
    linear supports Σ_l c_l u_l · e = 0 (see :func:`layershell.constraints.apply_ties`)."""
    layers = model.layers
    if sd.direction is not None and "components" in sd.model_fields_set:
        raise InputError(f"'{f}': give 'direction' (one held direction) or 'components' (global x, y, z), not both")
    if sd.direction is not None:
        dirs = [_vec(sd.direction, f + ".direction")]
    else:
        if not sd.components:
            raise InputError(f"'{f}.components': give at least one of 'x', 'y', 'z' (or a 'direction')")
        dirs = [np.eye(3)["xyz".index(c)] for c in dict.fromkeys(sd.components)]
    values = _tie_values(sd, f, len(dirs))
    placed = sd.face is not None or sd.height is not None
    if placed and sd.directors != [0]:
        raise InputError(f"'{f}.directors': a support on a face or at a height holds the displacement there; "
                         "remove 'directors'")
    if sd.face is not None and sd.height is not None:
        raise InputError(f"'{f}': give 'face' or 'height', not both")
    out = []
    if sd.layer == "all":
        if placed:
            raise InputError(f"'{f}': layer = 'all' holds the layers' director vectors through the whole thickness; "
                             "remove 'face'/'height' or name one layer")
        for k, ly in enumerate(layers):
            dirs_k = range(ly.directors + 1) if sd.directors == "all" else sd.directors
            if any(l > ly.directors or l < 0 for l in dirs_k):
                raise InputError(f"'{f}.directors': layer '{ly.name}' has directors 0..{ly.directors}, got "
                                 f"{list(dirs_k)}")
            for l in dirs_k:
                c = np.zeros((nodes.size, ly.directors + 1))
                c[:, l] = 1.0
                moved = values is not None and (l == 0 or 0 not in dirs_k)  # as a fix: the section translates
                out += [Tie(nodes, k, c, np.tile(e, (nodes.size, 1)), _tie_value(values, j, nodes.size, moved),
                            sd.scaled) for j, e in enumerate(dirs)]
        return out
    if sd.layer is not None and sd.layer not in index:
        raise InputError(f"'{f}.layer': unknown layer '{sd.layer}'; defined: {list(index)} (or 'all')")
    k = index.get(sd.layer, first) if sd.layer is not None else None
    if sd.height is not None:
        h = float(sd.height)
        if k is None:  # the layer containing the height at the nodes (the upper one at an interface)
            present = model.layers_present()[:, nodes].all(axis=1)
            cands = [j for j in range(len(layers))
                     if present[j]
                     and np.all((model.offset(j)[nodes] <= h + 1e-9 * model.mesh.size())
                               & (h <= (model.offset(j) + layers[j].thickness)[nodes] + 1e-9 * model.mesh.size()))]
            if not cands:
                raise InputError(f"'{f}.height': no layer contains Θ³ = {h:g} at all selected nodes (total thickness "
                                 f"{model.total_thickness()[nodes].min():.6g} to "
                                 f"{model.total_thickness()[nodes].max():.6g}); give a height inside the shell or "
                                 "name the 'layer'")
            k = max(cands, key=lambda j: model.offset(j)[nodes].mean())
        _require_present(model, k, nodes, f)
        theta = h - model.offset(k)[nodes]
        H = layers[k].thickness[nodes]
        if np.any(theta < -1e-9 * model.mesh.size()) or np.any(theta > H + 1e-9 * model.mesh.size()):
            raise InputError(f"'{f}.height': Θ³ = {h:g} lies outside layer '{layers[k].name}' at some selected nodes; "
                             "give a height inside the layer or leave 'layer' out")
    else:
        k = _default_layer(model, nodes, first) if k is None else k
        _require_present(model, k, nodes, f)
        theta = (layers[k].thickness[nodes] if sd.face == "top" else np.zeros(nodes.size))
    if sd.directors != [0] and not placed:
        d = layers[k].directors
        dl = range(d + 1) if sd.directors == "all" else sd.directors
        if any(l > d or l < 0 for l in dl):
            raise InputError(f"'{f}.directors': layer '{layers[k].name}' has directors 0..{d}, got {list(dl)}")
        cs, moved = [], []
        for l in dl:
            c = np.zeros((nodes.size, d + 1))
            c[:, l] = 1.0
            cs.append(c)
            moved.append(values is not None and (l == 0 or 0 not in dl))
    else:
        cs, moved = [theta[:, None] ** np.arange(layers[k].directors + 1)], [values is not None]
    return [Tie(nodes, k, c, np.tile(e, (nodes.size, 1)), _tie_value(values, j, nodes.size, mv), sd.scaled)
            for c, mv in zip(cs, moved) for j, e in enumerate(dirs)]


def _tie_values(sd, f: str, n_dirs: int) -> list[float] | None:
    """The prescribed values of a linear support: one per held direction, or None."""
    if sd.value is None:
        return None
    if len(sd.value) != n_dirs:
        what = "'direction' (one value)" if sd.direction is not None else f"'components' ({n_dirs})"
        raise InputError(f"'{f}.value': give one prescribed displacement per entry of {what}, got "
                         f"{len(sd.value)}")
    return [float(x) for x in sd.value]


def _tie_value(values: list[float] | None, j: int, n: int, moved: bool) -> np.ndarray | None:
    """Per node the prescribed value of held direction ``j`` (None: zero, a plain support)."""
    if values is None or not moved or values[j] == 0.0:
        return None
    return np.full(n, values[j])


def _cohesive_law(idf, f: str, gT: float, model, upper: int, lower: int):
    """CohesiveLaw of ``[[interfaces]] law = "cohesive"`` with its input checks (issue 13)."""
    from ..cohesive import CohesiveLaw
    from ..interfaces import Interface
    from ..solver.interface_state import cohesive_softening_estimate, default_cohesive_stiffness

    missing = [k for k in ("G_Ic", "G_IIc") if getattr(idf, k) is None]
    if missing:
        raise InputError(f"'{f}': law = \"cohesive\" needs the fracture energies {' and '.join(missing)} (energy per "
                         "area in the model's units, e.g. kN/m for kN, m): add them to the interface, e.g. from a "
                         "DCB (G_Ic) and an ENF or shear bond test (G_IIc)")
    law = CohesiveLaw(idf.G_Ic, idf.G_IIc, idf.sigma_max, idf.tau_max, idf.eta, idf.p, idf.onset, idf.softening,
                      idf.K0, idf.alpha, idf.viscosity, idf.mu0, idf.mu, gT, idf.mu_coulomb, idf.alpha_T,
                      idf.rule or "lobatto")
    try:
        law.check(f)
    except ValueError as exc:
        raise InputError(str(exc)) from None
    itf = Interface(upper, lower, "", np.zeros(0, int))
    K = law.K0 if law.K0 is not None else default_cohesive_stiffness(model, itf, law)
    soft = cohesive_softening_estimate(model, itf, K)
    if soft > 0.03 and idf.K0_check:
        raise InputError(f"'{f}.K0' = {K:.4g}: this penalty stiffness makes the interface {100 * soft:.3g} % as "
                         "compliant as the two layers through their thickness, so it softens the bonded structure by "
                         "more than a few percent; raise K0 (or leave it out for the default alpha · E3/H, Turon et "
                         "al. 2007), or set K0_check = false if K0 is the elastic stiffness of the bond itself "
                         "(τ_f/δ_1 of a bond-slip law)")
    K_ref = default_cohesive_stiffness(model, itf, replace(law, alpha=1.0))
    if K > 1e5 * K_ref:
        raise InputError(f"'{f}.K0' = {K:.4g} is more than 1e5 × E3/H of the adjacent layers ({K_ref:.4g}): such a "
                         "penalty spoils the conditioning of the equations without changing the result; lower it "
                         "(or leave it out for the default alpha · E3/H)")
    return law


def _interfaces(mf: schema.ModelFile, model, index: dict, layers) -> None:
    """Interface laws, initially debonded zones and delamination settings (MODEL.md §9-§10)."""
    from ..delamination import InterfaceLaw
    from ..solver.interface_state import DelaminationSettings

    if not mf.interfaces:
        return
    below = model.below()
    m = model.mesh
    for i, idf in enumerate(mf.interfaces):
        f = f"interfaces[{i}]"
        if idf.layer not in index:
            raise InputError(f"'{f}.layer': unknown layer '{idf.layer}'; defined: {list(index)}")
        k = index[idf.layer]
        if k not in below:
            raise InputError(f"'{f}.layer': layer '{idf.layer}' lies directly on the reference face in every "
                             "stack, so it has no interface below it; name the upper layer of the interface")
        if k in model.interface_laws:
            raise InputError(f"'{f}.layer': the interface below '{idf.layer}' is defined twice")
        gT = float("inf") if idf.gT_mu == "inf" else float(idf.gT_mu)
        if idf.law == "cohesive":
            law = _cohesive_law(idf, f, gT, model, k, below[k])
        else:
            law = InterfaceLaw(idf.sigma_max, idf.tau_max, idf.p, idf.mu0, idf.mu, gT, idf.mu_coulomb,
                               idf.alpha_N, idf.alpha_T, idf.open_gap, idf.rule or "gauss",
                               rule_auto=idf.rule is None)
            try:
                law.check(f)
            except ValueError as exc:
                raise InputError(str(exc)) from None
        model.interface_laws[k] = law
        nodes = []
        zone_law = None
        for j, z in enumerate(idf.initially_debonded):
            fz = f"{f}.initially_debonded[{j}]"
            if z.circle is not None:
                c = np.asarray(z.circle[:-1], float)
                r = z.circle[-1]
                d = np.linalg.norm(m.nodes[:, : c.size] - c, axis=1)
                sel = np.flatnonzero(d <= r * (1 + 1e-9))
                if sel.size == 0:
                    raise InputError(f"'{fz}.circle': the circle {z.circle} contains no node")
            else:
                sel = _node_selection(m, z, fz)
            nodes.append(sel)
            if any(v is not None for v in (z.mu0, z.mu, z.gT_mu)):
                gz = gT if z.gT_mu is None else (float("inf") if z.gT_mu == "inf" else float(z.gT_mu))
                zone_law = replace(law, mu0=law.mu0 if z.mu0 is None else z.mu0,
                                  mu=law.mu if z.mu is None else z.mu, gT_mu=gz)
        if nodes:
            model.initially_debonded[k] = np.unique(np.concatenate(nodes))
            if zone_law is not None:
                model.initial_laws[k] = zone_law
    d = mf.delamination
    if not d.reequilibrate and d.max_debond_fraction is not None:
        raise InputError("'delamination.max_debond_fraction' measures the debonding of the re-solutions at one "
                         "load level; with 'delamination.reequilibrate = false' there are none: remove one of them")
    model.delamination = DelaminationSettings(d.max_release, d.max_resolves, d.friction,
                                             d.max_debond_fraction, d.max_debond_cuts, d.reequilibrate,
                                             stresses=d.stresses)


def _zero_load(ld) -> bool:
    """A load whose value is the number 0 (formulas and other load types: not known to be zero)."""
    value = {"surface": "magnitude", "edge": "distribution", "volume": "value", "nodal": "value"}.get(ld.type)
    v = getattr(ld, value, None) if value else None
    if isinstance(v, (int, float)):
        return v == 0
    return isinstance(v, list) and all(isinstance(c, (int, float)) and c == 0 for c in v)


def _check_gravity(model: Model, el: np.ndarray, g: np.ndarray, field: str) -> None:
    """A gravity load acts on the density of the layers: with g = 0 or no mass it is silently zero."""
    if not np.abs(g).max() > 0:
        raise InputError(f"'{field}.g': the gravity vector is {g.tolist()}, so the load is "
                         "zero; give the acceleration of gravity as a non-zero vector, e.g. g = [0, 0, -9.81]")
    present = {k for s in np.unique(model.element_stack[el]) for k in model.stacks[s]}
    if not any(model.layers[k].material.density > 0 for k in present):
        mats = sorted({model.layers[k].material.name for k in present})
        raise InputError(f"'{field}': a gravity load acts on the materials' density, but every layer it loads "
                         f"({', '.join(repr(model.layers[k].name) for k in sorted(present))}) is made of material(s) "
                         f"with density 0 ({', '.join(repr(n) for n in mats)}), so the load is zero; give "
                         f"'density' (mass per volume, in the model's units) in [materials.{mats[0]}], or remove "
                         "the gravity load")


#: largest total thickness of the laminate, as a fraction of the model size (bounding-box diagonal)
MAX_THICKNESS_RATIO = 1.0


def _check_slender(model: Model) -> None:
    """A shell is thin compared with its extent: a laminate thicker than the whole model is a unit
    mistake (mm vs m), and its stiffness is singular or meaningless, which the solver would
    otherwise report as free rigid-body motions of the supports."""
    tot = model.total_thickness()
    size = model.mesh.size()
    j = int(np.argmax(tot))
    if tot[j] > MAX_THICKNESS_RATIO * size:
        stacks = np.unique(model.element_stack[np.any(model.mesh.elements == j, axis=1)])
        present = sorted({k for s in stacks for k in model.stacks[s]})
        k = max(present, key=lambda i: model.layers[i].thickness[j])
        ly = model.layers[k]
        raise InputError(f"'layers[{k}].thickness': the laminate is {tot[j]:.6g} thick at node {j} "
                         f"{model.mesh.nodes[j].round(6).tolist()} (layer '{ly.name}': {ly.thickness[j]:.6g}), more than "
                         f"the size of the whole model ({size:.6g}, the diagonal of the mesh's bounding box); a "
                         "shell must be thin compared with its span: check the units of the thickness and of the "
                         "mesh (e.g. mm against m, or the mesh file's 'scale')")


def _law(name: str, md, units: str | None):
    """The material law of a ``concrete``, ``steel`` or ``textile`` table (:mod:`layershell.laws`),
    with the code defaults of its class or grade in the model's units."""
    from .. import laws
    from ..units import Units, si_factors

    need_units = getattr(md, "strength_class", None) or getattr(md, "f_ck", None) or getattr(md, "grade", None) \
        or getattr(md, "fibre", None) or getattr(md, "aggregate_size", None)
    mpa, metre = 1.0, 1.0
    if need_units:
        try:
            mpa, metre = si_factors(Units.parse(units))
        except ValueError:
            raise InputError(f"'materials.{name}': the defaults of a strength class, grade or fibre and the "
                             "interlock relation of aggregate_size are in MPa and metres, so the model needs its "
                             "units: add units = 'N, mm' (or 'kN, m', ...) to [model], or give every constant of "
                             "the material in the model's units") from None
    given = {k: v for k, v in md.model_dump(exclude={"type", "strength_class", "f_ck", "grade", "fibre",
                                                       "density"}).items() if v is not None}
    try:
        if md.type == "concrete":
            f_ck = md.f_ck if md.f_ck is not None else (_class_strength(name, md.strength_class)
                                                        if md.strength_class is not None else None)
            law = (laws.ConcreteLaw.from_class(f_ck, mpa, metre, name=name, **given) if f_ck is not None
                   else laws.ConcreteLaw(name=name, nu=given.pop("nu", 0.2), stress_unit=mpa if need_units else 0.0,
                                         length_unit=metre if need_units else 0.0, **given))
        elif md.type == "steel":
            law = (laws.SteelLaw.from_grade(md.grade, mpa, name=name, **given) if md.grade is not None
                   else laws.SteelLaw(name=name, **given))
        else:
            law = (laws.TextileLaw.from_fibre(md.fibre, mpa, name=name, **given) if md.fibre is not None
                   else laws.TextileLaw(name=name, **given))
        law.check()
    except (MaterialError, ValueError) as exc:
        raise InputError(f"'materials.{name}': {exc}") from None
    return law


def _class_strength(name: str, cls: str) -> float:
    """f_ck in MPa of a strength class 'C30/37' (the cylinder strength before the slash)."""
    import re

    mt = re.fullmatch(r"\s*C\s*(\d+)\s*/\s*(\d+)\s*", cls)
    if mt is None or not 12 <= int(mt.group(1)) <= 100:
        raise InputError(f"'materials.{name}.strength_class': '{cls}' is no concrete strength class; write e.g. "
                         "'C30/37' (cylinder/cube strength in MPa, C12/15 to C100/115), or give f_ck = 30")
    return float(mt.group(1))


def _reinforcement(ld: schema.LayerDef, i: int, laws: dict) -> tuple[Reinforcement, ...]:
    out = []
    for j, r in enumerate(ld.reinforcement):
        direction = tuple(float(x) for x in r.direction) if r.direction is not None else None
        name = r.name or f"{r.material} {j + 1}"
        out.append(Reinforcement(name, laws[r.material], float(r.height), float(r.area_per_width()), float(r.angle),
                                 direction, r.bar_diameter))
    return tuple(out)


#: the longest side over the shortest of an element beyond which a concrete layer's crack band
#: (13/18 √area) differs from the element's length along a crack normal by more than a factor √2
BAND_ASPECT = 2.0
#: relative round-off allowed on BAND_ASPECT: node lines such as 381 and 419.1 give sides twice as
#: long as others to within 1e-15, not exactly
BAND_ASPECT_ROUNDOFF = 1e-9


def crack_band_notes(model: Model) -> list[str]:
    """A note per concrete layer on elements elongated beyond :data:`BAND_ASPECT`: the crack band
    there is not the element's length along the crack normal."""
    notes = []
    X = model.mesh.nodes[model.mesh.elements[:, :4]]
    sides = np.linalg.norm(np.roll(X, -1, axis=1) - X, axis=2)
    aspect = sides.max(axis=1) / np.maximum(sides.min(axis=1), 1e-300)
    for k, ly in enumerate(model.layers):
        if ly.law is None or not hasattr(ly.law, "f_ct"):
            continue
        el = model.layer_elements(k)
        bad = el[aspect[el] > BAND_ASPECT * (1.0 + BAND_ASPECT_ROUNDOFF)]
        if bad.size:
            notes.append(f"layer '{ly.name}': {bad.size} element(s) are elongated (sides up to {aspect[bad].max():.3g} "
                         f"times as long as the shortest, element {bad[np.argmax(aspect[bad])]}); a concrete layer's "
                         "crack band is 13/18 √(element area), so there a crack dissipates G_F times the band over the "
                         "element's length along the crack normal instead of G_F: use elements whose sides differ "
                         f"by at most a factor {BAND_ASPECT:g} where the concrete cracks")
    return notes


#: elements whose crack band is shorter than this fraction of the bars' mean crack spacing keep
#: too much tension between cracks (where the layer takes the element band): the RC strip's moment
#: at first yield rose 6 % at 0.47 s_rm
BAND_PER_SPACING = 0.5


def _steel_bars(reinforcement) -> tuple[list, list]:
    """The steel sheets of a layer given as bars (bar_diameter) and those given by area only."""
    from ..laws.uniaxial import SteelLaw

    steel = [r for r in reinforcement if isinstance(r.law, SteelLaw)]
    return [r for r in steel if r.bar_diameter], [r for r in steel if not r.bar_diameter]


def bars_crack_spacing(reinforcement, thickness: float) -> float | None:
    """The least mean crack spacing s_rm (EN 1992-1-1 §7.3.4,
    :func:`layershell.analytic.crack_spacing.mean_crack_spacing`) of the steel bars among
    ``reinforcement`` (cover to the nearer face of a layer ``thickness`` deep); None without bars
    given by bar_diameter."""
    from ..analytic.crack_spacing import mean_crack_spacing

    bars, _ = _steel_bars(reinforcement)
    if not bars:
        return None
    t = float(thickness)
    return min(mean_crack_spacing(max(min(r.height, t - r.height) - 0.5 * r.bar_diameter, 1e-3 * t),
                                  r.bar_diameter, r.area, t) for r in bars)


def _layer_crack_spacing(ld: schema.LayerDef, i: int, law, reinforcement, th: np.ndarray):
    """The concrete ``law`` of layer ``i`` with its crack spacing: ``crack_spacing`` as given, else
    :func:`bars_crack_spacing` of its bars (0 without)."""
    if not hasattr(law, "crack_spacing"):
        if ld.crack_spacing is not None:
            raise InputError(f"'layers[{i}].crack_spacing': sets the crack band of a concrete layer, but layer "
                             f"'{ld.name}' has no concrete material; remove 'crack_spacing' from it")
        return law
    given = ld.crack_spacing is not None
    s = float(ld.crack_spacing) if given else bars_crack_spacing(reinforcement, float(np.median(th))) or 0.0
    try:
        out = replace(law, crack_spacing=s)
        out.check()
    except MaterialError as exc:
        if given:
            raise InputError(f"'layers[{i}].crack_spacing': {exc}") from None
        raise InputError(f"'layers[{i}]': the mean crack spacing of the bars of layer '{ld.name}', {s:.4g} (EN "
                         f"1992-1-1 §7.3.4), over which its cracks' opening is smeared: {exc} (set it as the layer's "
                         "crack_spacing); check G_F and its units (force/length: N/mm for 'N, mm')") from None
    return out


def crack_spacing_notes(model: Model) -> list[str]:
    """A note per concrete layer with ``aggregate_size`` but no crack spacing (the interlock then does
    not act), and per concrete layer with steel bars whose crack band is the element's: where the bars
    are given by area only (no crack spacing known), and where ``crack_spacing = 0`` leaves elements
    with a band shorter than :data:`BAND_PER_SPACING` of the bars' mean crack spacing (EN 1992-1-1
    §7.3.4): with perfectly bonded bars every such element cracks and keeps the tension of its
    own short band."""
    from ..element.inelastic import in_plane_band

    notes = []
    for k, ly in enumerate(model.layers):
        if getattr(ly.law, "aggregate_size", 0.0) > 0 and ly.law.crack_spacing == 0.0:
            notes.append(f"layer '{ly.name}': aggregate_size has no effect here: the aggregate interlock acts where "
                         "bonded bars hold the cracks, in layers with a crack spacing (bars by bar_diameter and "
                         "spacing, or crack_spacing); this layer's cracks separate freely (docs/concrete.md)")
        bars, by_area = _steel_bars(ly.reinforcement)
        if getattr(ly.law, "crack_spacing", None) != 0.0 or not (bars or by_area):
            continue
        if by_area and not bars:
            notes.append(f"layer '{ly.name}': its steel bars are given by area, so their crack spacing is unknown and "
                         "a crack's band is the element's (13/18 √area); with perfectly bonded bars elements shorter "
                         "than the crack spacing each crack and keep the tension of their own short band, so the member "
                         "comes out too strong (docs/concrete.md, limits): give the bars by bar_diameter and spacing, "
                         "or the layer's crack_spacing")
            continue
        conn = model.mesh.elements[model.layer_elements(k)]
        band = in_plane_band(model.mesh.nodes[conn])
        s_rm = bars_crack_spacing(bars, float(np.median(ly.thickness[conn])))
        short = band < BAND_PER_SPACING * s_rm
        if short.any():
            notes.append(f"layer '{ly.name}': crack_spacing = 0 leaves {int(short.sum())} element(s) a crack band down "
                         f"to {band.min():.3g} (13/18 √area), less than half the mean crack spacing of its bars, "
                         f"{s_rm:.3g} (EN 1992-1-1 §7.3.4); with perfectly bonded bars every such element cracks and "
                         "keeps the tension of its own short band, so the member comes out too strong and may stop "
                         "(docs/concrete.md, limits): leave crack_spacing out (the bars' spacing) or give it")
    return notes


def _check_crack_band(model: Model) -> None:
    """The crack bands of every concrete layer stay below the snap-back limit of its softening
    (:meth:`layershell.laws.ConcreteLaw.check_band`), checked before the analysis."""
    from ..element.inelastic import BAND_FRACTION, in_plane_band

    for k, ly in enumerate(model.layers):
        if ly.law is None or not hasattr(ly.law, "check_band"):
            continue
        el = model.layer_elements(k)
        conn = model.mesh.elements[el]
        h_in = in_plane_band(model.mesh.nodes[conn])
        nz = max(model.n_thickness, ly.directors + (1 if model.element == "mitc" else 0))
        h_z = ly.thickness[conn].max(axis=1) / nz
        try:
            ly.law.check_band(h_in, h_z, ly.name)
        except MaterialError as exc:
            lim, hz = ly.law.max_band(), float(np.max(h_z))
            size = (f"; with these thickness points, elements up to {np.sqrt(lim**2 - hz**2) / BAND_FRACTION:.4g} "
                    "across (√area) keep the band below it" if lim > hz else
                    f"; the thickness-point spacing alone exceeds it, so both are needed (at least "
                    f"{int(hz * nz // lim) + 1} thickness points); a limit this small often means G_F in other "
                    "units than the model's force/length (N/mm for 'N, mm')")
            raise InputError(f"'layers[{k}]': {exc}{size}") from None


def _check_reinforcement(model: Model, mf: schema.ModelFile) -> None:
    """Each sheet lies inside its layer's thickness wherever the layer exists."""
    present = model.layers_present()
    for k, ly in enumerate(model.layers):
        for j, r in enumerate(ly.reinforcement):
            th = ly.thickness[present[k]]
            if th.size and not (r.height < th.min()):
                node = np.flatnonzero(present[k])[int(np.argmin(th))]
                raise InputError(f"'layers[{k}].reinforcement[{j}].height': {r.height:g} lies outside layer "
                                 f"'{ly.name}', which is {th.min():.6g} thick at node {node} "
                                 f"{model.mesh.nodes[node].round(6).tolist()}; give a height between 0 and the "
                                 "layer's thickness, measured from its bottom face")


def _layer(ld: schema.LayerDef, mats: dict, th: np.ndarray, mesh_type: str, laws: dict | None = None,
           i: int = 0) -> Layer:
    """The model's layer of ``ld`` (materials ``mats``, material laws ``laws``, nodal thickness
    ``th``); a ply stack takes its homogenised equivalent as the layer material (estimates only,
    :class:`Layer`); a concrete layer the law's initial elastic constants."""
    laws = laws or {}
    direction = tuple(ld.direction) if ld.direction is not None else None
    if direction is None and mesh_type == "plate_with_circle":
        direction = (1.0, 0.0, 0.0)  # its elements' first coordinate lines turn around the front
    if ld.plies is None:
        reinforcement = _reinforcement(ld, i, laws)
        law = laws.get(ld.material)
        return Layer(ld.name, mats[ld.material], ld.directors, th, ld.angle, direction,
                     law=_layer_crack_spacing(ld, i, law, reinforcement, th), reinforcement=reinforcement)
    _layer_crack_spacing(ld, i, None, (), th)  # a ply stack has no concrete law
    total = sum(p.thickness for p in ld.plies)
    plies = tuple(Ply(mats[p.material], p.angle, p.thickness / total) for p in ld.plies)
    equivalent = laminate_equivalent([(p.material, p.angle, p.fraction) for p in plies],
                                     name=f"plies of layer '{ld.name}'")
    return Layer(ld.name, equivalent, ld.directors, th, ld.angle, direction, plies)


def build(mf: schema.ModelFile, base: Path = Path(".")) -> RunSpec:
    try:
        with np.errstate(all="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            m = _mesh(mf.mesh, base)
            m.check()
    except meshmod.MeshError as exc:
        raise InputError(f"'mesh': {exc}") from None
    except (np.linalg.LinAlgError, ZeroDivisionError, FloatingPointError) as exc:
        raise InputError(f"'mesh': the mesh is degenerate ({exc}: elements of zero area); check the mesh "
                         "dimensions") from None
    if not np.all(np.isfinite(m.nodes)):
        raise InputError("'mesh': the mesh has nodes with non-finite coordinates; check the mesh dimensions")
    laws = {k: _law(k, v, mf.model.units) for k, v in mf.materials.items() if v.type in ("concrete", "steel", "textile")}
    mats = {k: _material(k, v) if k not in laws else _stand_in(laws[k], v.density) for k, v in mf.materials.items()}
    names = [ly.name for ly in mf.layers]
    index = {n: i for i, n in enumerate(names)}
    layers = []
    for i, ld in enumerate(mf.layers):
        given = ld.thickness if ld.plies is None or ld.thickness is not None else sum(p.thickness for p in ld.plies)
        th = _nodal_values(m, given, f"layers[{i}].thickness", **m.node_fields)  # h_meridian: revolution
        if not np.all((th > 0) & np.isfinite(th)):
            bad = np.flatnonzero(~((th > 0) & np.isfinite(th)))
            raise InputError(f"'layers[{i}].thickness': must be positive and finite at every node, but is "
                             f"{th[bad[0]]:.6g} at node {bad[0]} {m.nodes[bad[0]].round(6).tolist()} ({bad.size} of "
                             f"{m.n_nodes} nodes); give a positive number or a formula in x, y, z that is positive "
                             "over the whole mesh")
        ratio = th / m.size()
        if not np.all((ratio >= 1e-10) & (ratio <= 1e10)):
            j = int(np.argmax(np.abs(np.log10(ratio))))
            raise InputError(f"'layers[{i}].thickness': {th[j]:.6g} at node {j} is out of scale with the model size "
                             f"{m.size():.6g} (ratio {ratio[j]:.3g}, allowed 1e-10 to 1e10), so the stiffness cannot be "
                             "computed in floating point; check the units of the thickness and of the mesh")
        if ld.direction is not None:
            _vec(ld.direction, f"layers[{i}].direction")
        layers.append(_layer(ld, mats, th, mf.mesh.type, laws, i))

    def layer_idx(name, field):
        if name is None:
            return None
        if name not in index:
            raise InputError(f"'{field}': unknown layer '{name}'; defined: {names}")
        return index[name]

    # stacks
    if mf.stacks is None:
        stacks = [tuple(range(len(layers)))]
        element_stack = np.zeros(m.n_elements, np.int64)
    else:
        stacks, element_stack = [], np.full(m.n_elements, -1, np.int64)
        rest = [i for i, sd in enumerate(mf.stacks) if sd.where is None and sd.set is None]
        if len(rest) > 1:
            raise InputError(f"'stacks': stacks {rest} all have neither 'where' nor 'set', so each would take "
                             "every element not selected by another stack; keep one such stack (the rest of the "
                             "shell) and give the others a 'where' or 'set'")
        for i, sd in enumerate(mf.stacks):
            st = tuple(layer_idx(n, f"stacks[{i}].layers") for n in sd.layers)
            stacks.append(st)
            if i in rest:
                continue
            el = _element_selection(m, sd, f"stacks[{i}]")
            taken = el[element_stack[el] >= 0]
            if taken.size:
                j = int(element_stack[taken[0]])
                c = m.nodes[m.elements[taken[0], 8]].round(6).tolist()
                sel = lambda s: f"where = '{s.where}'" if s.where is not None else f"set = '{s.set}'"  # noqa: E731
                raise InputError(f"'stacks[{i}]': {taken.size} element(s) selected by stacks[{i}] "
                                 f"({sel(sd)}) are also selected by stacks[{j}] ({sel(mf.stacks[j])}), e.g. "
                                 f"element {taken[0]} with centre {c}; every element carries exactly one stack: "
                                 "make the selections disjoint (e.g. 'y < 2' and 'y >= 2'), or leave one stack "
                                 "without 'where' and 'set' to take the remaining elements")
            element_stack[el] = i
        if rest:
            element_stack[element_stack < 0] = rest[0]
        if np.any(element_stack < 0):
            bad = np.flatnonzero(element_stack < 0)
            raise InputError(f"'stacks': {bad.size} element(s) belong to no stack (first: element {bad[0]}); "
                             "add a stack without 'where' and 'set' (it takes the remaining elements) or widen "
                             "the selections")
        if mf.mesh.type == "rectangle":
            _stack_boundaries_on_node_lines(m, mf)
    model = Model(m, layers, stacks, element_stack, n_thickness=mf.model.thickness_points,
                  nonlinear=mf.model.nonlinear, units=mf.model.units, element=mf.model.element,
                  integration=mf.steps.integration)
    try:
        model.below()
    except ValueError as exc:
        raise InputError(f"'stacks': {exc}") from None
    _check_slender(model)
    _check_reinforcement(model, mf)
    _check_crack_band(model)
    first = stacks[0][0]
    if mf.mesh.surface == "middle":
        m.nodes = m.nodes - 0.5 * model.total_thickness()[:, None] * nodal_normals(m)

    # supports
    if not mf.supports:
        raise InputError("'supports': the model has no supports, so it can move as a rigid body; supports must "
                         "prevent every rigid-body motion (3 translations and 3 rotations): add [[supports]] "
                         "tables (type = 'fix', 'symmetry' or 'hinge'), see examples/")
    face_notes = []
    for i, sd in enumerate(mf.supports):
        f = f"supports[{i}]"
        nodes = _node_selection(m, sd, f)
        if getattr(sd, "face", None) is not None:
            face_notes += _downward_face_note(m, nodes, sd.face, f)
        if sd.type == "fix" and (sd.layer == "all" and "all" not in index or sd.face is not None
                                 or sd.height is not None or sd.direction is not None):
            model.ties.extend(_ties(model, sd, nodes, f, index, first))
        elif sd.type == "fix":
            k = layer_idx(sd.layer, f + ".layer")
            k = _default_layer(model, nodes, first) if k is None else k
            _require_present(model, k, nodes, f)
            d = layers[k].directors
            dirs = tuple(range(d + 1)) if sd.directors == "all" else tuple(sd.directors)
            if any(l > d or l < 0 for l in dirs):
                raise InputError(f"'{f}.directors': layer '{layers[k].name}' has directors 0..{d}, got {list(dirs)}")
            value = None
            if sd.value is not None:
                if len(sd.value) != len(sd.components):
                    raise InputError(f"'{f}.value': give one prescribed displacement per entry of 'components' "
                                     f"({len(sd.components)}: {list(sd.components)}), got {len(sd.value)}")
                value = tuple(float(x) for x in sd.value)
            model.fixes.append(Fix(nodes, k, dirs, tuple(XYZ.index(c) for c in sd.components), value, sd.scaled))
        elif sd.type == "symmetry":
            model.symmetries.append(Symmetry(nodes, _vec(sd.normal, f + ".normal")))
        else:
            if sd.direction == "edge-normal":
                dirs = _edge_normals(m, nodes, f)
            else:
                dirs = np.tile(_vec(sd.direction, f + ".direction"), (len(nodes), 1))
            model.hinges.append(Hinge(nodes, dirs, None if sd.height is None else np.full(len(nodes), sd.height),
                                      sd.fixed))
    # loads
    bedges = None
    for i, ld in enumerate(mf.loads):
        f = f"loads[{i}]"
        if ld.type == "surface":
            el = _element_selection(m, ld, f)
            face = ld.face
            if face.startswith("layer:"):
                face = f"layer:{layer_idx(face.split(':', 1)[1], f + '.face')}"
            elif face not in ("reference", "top"):
                raise InputError(f"'{f}.face': unknown face '{ld.face}'; use 'reference', 'top' or 'layer:<name>'")
            direction = None if ld.direction == "normal" else _vec(ld.direction, f + ".direction")
            if not isinstance(ld.magnitude, (int, float)):
                centres = m.nodes[m.elements[el, 8]]
                _require_finite(_nodal_values(m, ld.magnitude, f + ".magnitude", centres), ld.magnitude,
                                f + ".magnitude", "loaded element centre")
            model.surface_loads.append(SurfaceLoad(el, face, direction, _field_fn(ld.magnitude, f + ".magnitude"),
                                                   scaled=ld.scaled))
        elif ld.type in ("volume", "gravity"):
            el = _element_selection(m, ld, f)
            if ld.type == "volume":
                k = layer_idx(ld.layer, f + ".layer")
                v = np.asarray(ld.value, float)
                n = np.linalg.norm(v)
                model.surface_loads.append(SurfaceLoad(el, "volume", v / n if n else v,
                                                       lambda x, y, z, n=n: np.full(np.shape(x), n), k, ld.scaled))
            else:
                g = np.asarray(ld.g, float)
                gn = np.linalg.norm(g)
                _check_gravity(model, el, g, f)
                for k, ly in enumerate(layers):
                    if ly.material.density > 0 and gn > 0:
                        w = ly.material.density * gn
                        model.surface_loads.append(SurfaceLoad(el, "volume", g / gn,
                                                               lambda x, y, z, w=w: np.full(np.shape(x), w), k,
                                                               ld.scaled))
        elif ld.type == "edge":
            bedges = boundary_edges(m) if bedges is None else bedges
            nodes = _node_selection(m, ld, f)
            mask = np.zeros(m.n_nodes, bool)
            mask[nodes] = True
            edges = bedges[mask[bedges].all(1)]
            if edges.size == 0:
                raise InputError(f"'{f}': the selection '{ld.where or ld.set}' picks {nodes.size} node(s) but no "
                                 "complete boundary edge; an edge load needs all three nodes of an element edge on "
                                 "the mesh boundary, e.g. where = \"near(x, 10)\" for the whole edge at x = 10")
            dist = _field_fn(ld.distribution, f + ".distribution", ("t", "x", "y", "z"))
            if not isinstance(ld.distribution, (int, float)):
                mid = edges[:, 1]
                h = model.total_thickness()[mid]
                frac = (np.arange(4) + 0.5) / 4  # inside the thickness, where the quadrature points lie
                pts = np.repeat(m.nodes[mid], frac.size, axis=0)
                t = (h[:, None] * frac[None, :]).ravel()
                _require_finite(_nodal_values(m, ld.distribution, f + ".distribution", pts, t=t),
                                ld.distribution, f + ".distribution", "point of the loaded edges (t inside the "
                                "thickness)")
            if ld.height is not None and ld.face is not None:
                raise InputError(f"'{f}': give 'face' or 'height' for a line force, not both")
            model.edge_loads.append(EdgeLoad(edges, _vec(ld.direction, f + ".direction"),
                                             lambda theta3, dist=dist, **kw: dist(t=theta3, **kw), ld.scaled,
                                             at_face=ld.face, at_height=ld.height))
        elif ld.height is not None or ld.face is not None:  # nodal force at a height / on a face
            nodes = _node_selection(m, ld, f)
            if ld.director != 0:
                raise InputError(f"'{f}.director': a force at a height or on a face is split into director forces "
                                 "automatically; remove 'director'")
            if ld.height is not None and ld.face is not None:
                raise InputError(f"'{f}': give 'face' or 'height', not both")
            k_given = layer_idx(ld.layer, f + ".layer")
            for k, sel, th in _heights(model, nodes, ld.height, ld.face, k_given, f, index):
                fl = np.asarray(ld.value, float)
                for l in range(layers[k].directors + 1):
                    model.nodal_loads.append(NodalLoad(nodes[sel], k, l, th[:, None] ** l * fl, ld.scaled))
        else:  # nodal
            nodes = _node_selection(m, ld, f)
            k = layer_idx(ld.layer, f + ".layer")
            k = first if k is None else k
            if ld.director > layers[k].directors:
                raise InputError(f"'{f}.director': layer '{layers[k].name}' has directors 0..{layers[k].directors}")
            model.nodal_loads.append(NodalLoad(nodes, k, ld.director, np.asarray(ld.value, float), ld.scaled))

    notes = face_notes
    # prescribed displacements (a fix with a non-zero 'value') load the model as well
    moved = any(getattr(sd, "value", None) and any(v != 0 for v in sd.value) for sd in mf.supports)
    if not moved and not mf.loads:
        notes.append("the model has no [[loads]], so every displacement, stress and probe value is zero; add a "
                     "[[loads]] table (type = 'surface', 'edge', 'volume', 'gravity' or 'nodal'), see examples/")
    elif not moved and all(_zero_load(ld) for ld in mf.loads):
        notes.append("every [[loads]] entry is zero (magnitude, distribution or value 0), so every displacement, "
                     "stress and probe value is zero; give the loads their values")
    st = mf.steps
    if st.unstable == "relax" and st.stabilize > 0:
        raise InputError("'steps.unstable' = 'relax' and 'steps.stabilize' > 0 both handle a step without "
                         "equilibrium: relax lets the damage snap to the next equilibrium at that load, stabilize "
                         "keeps a viscous law on from there; choose one (remove the other key)")
    if st.unstable == "relax" and st.control == "arc_length":
        raise InputError("'steps.unstable' = 'relax' acts on load steps (control = 'load'); arc-length control "
                         "follows a snap-back along the path itself: remove 'unstable', or use control = 'load'")
    if st.factors is not None:
        lf = np.asarray(st.factors, float)
        if lf.size == 0:
            raise InputError("'steps.factors': give at least one load factor")
    else:
        lf = st.lambda_end * np.arange(1, st.n + 1) / st.n
    if st.solver == "pardiso" and importlib.util.find_spec("pypardiso") is None:
        raise InputError("'steps.solver': 'pardiso' needs the package pypardiso (pip install "
                         "pypardiso; x86-64 only); install it or use solver = 'auto' or 'superlu'")
    newton = NewtonSettings(tol_residual=st.tolerance, max_iterations=st.max_iterations,
                            max_bisections=st.max_bisections, backend=st.solver,
                            reuse_factorization=st.reuse_factorization,
                            max_contact_iterations=st.max_contact_iterations, stabilize=st.stabilize,
                            stabilize_limit=st.stabilize_limit, unstable=st.unstable)
    _interfaces(mf, model, index, layers)
    from .probes import build_probes

    probes = build_probes(mf, model, index, _node_selection)
    for i, pr in enumerate(mf.profiles):
        from ..results import locate
        from .probes import STRESS_COMPONENTS

        dist = locate(model, pr.point)[3]
        if not dist <= 1e-3 * m.size():
            raise InputError(f"'profiles[{i}].point': {pr.point} is {dist:.4g} away from the reference surface of "
                             f"the shell (the mesh spans {_span(m.nodes)}); give a point on the reference surface "
                             "(Θ³ = 0): the profile runs through the thickness from there")

        if pr.component not in (*STRESS_COMPONENTS, "p1", "p2", "p3", "von_mises"):
            raise InputError(f"'profiles[{i}].component': '{pr.component}' is not a stress component; use one of "
                             f"{[*STRESS_COMPONENTS, 'p1', 'p2', 'p3', 'von_mises']}")
    if mf.imperfection is not None:  # after every selection: supports, loads and probes find the perfect mesh
        from .imperfection import imperfect_nodes

        m.nodes = imperfect_nodes(m, mf.imperfection, base)
    spec = RunSpec(model, lf, newton, probes, mf.output, mf)
    spec.profiles = list(mf.profiles)
    from .lines import build_lines

    spec.lines = build_lines(mf, model, index)
    from .material_axes import material_axis_notes

    spec.warnings = (notes + material_axis_notes(model, mf.mesh.type) + crack_band_notes(model)
                     + crack_spacing_notes(model))
    spec.path_following = _path_settings(st, model)
    return spec
