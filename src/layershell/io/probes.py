"""Probes: named scalar outputs evaluated after every converged step."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..element.shape import NODE_XI
from ..results import PointState, evaluate_points, locate

STRESS_COMPONENTS = {"11": (0, 0), "22": (1, 1), "33": (2, 2), "23": (1, 2), "13": (0, 2), "12": (0, 1)}
TRACTION_COMPONENTS = ("13", "23", "33", "shear")
FIELD_COMPONENTS = {"displacement": ("x", "y", "z", "magnitude"),
                    "stress": tuple(STRESS_COMPONENTS) + ("p1", "p2", "p3", "von_mises"),
                    "traction": TRACTION_COMPONENTS}


class ProbeError(ValueError):
    pass


#: probes over the integration points of inelastic layers (element/inelastic.py)
MATERIAL_QUANTITIES = ("crack_width", "rebar_stress", "rebar_strain")


@dataclass
class Probe:
    name: str
    quantity: str
    component: str
    measure: str
    elements: np.ndarray  # (p,) evaluation points
    xi: np.ndarray
    eta: np.ndarray
    theta: np.ndarray
    layer: int | None
    local_theta: bool
    reduce: str
    scale: float
    where: Callable | None = None  # debonded_area: selection of interface points (x, y, z)
    nodes: np.ndarray | None = None  # reaction: the support nodes
    direction: np.ndarray | None = None  # resultant: normal of the section
    about: float | None = None  # resultant: Θ³ of the moment axis (None: mid-height of the stack)
    unit: str | None = None  # label of the value on plot axes
    _cache: dict | None = None
    sampling: str = "recovered"  # stress/traction: "recovered" transverse stresses or "raw" (recovery.py)
    frame: str = "material"  # stress/traction components in the material frame or "global" x, y, z

    def points(self, model, dm, u, load_factor: float = 1.0) -> PointState:
        layers = None if self.layer is None else np.full(self.elements.size, self.layer)
        if self.quantity == "displacement":
            return evaluate_points(model, dm, u, self.elements, self.xi, self.eta, self.theta, layers, self.local_theta)
        from ..recovery import stress_points

        return stress_points(model, dm, u, self.elements, self.xi, self.eta, self.theta, layers, self.local_theta,
                             self.sampling, load_factor)

    def samples(self, model, dm, u, load_factor: float = 1.0) -> np.ndarray:
        ps = self.points(model, dm, u, load_factor)
        return self.scale * component_values(ps, self.quantity, self.component, self.measure, self.frame)

    def _selected(self, blk, values: np.ndarray) -> np.ndarray:
        """``values`` (e, q) of an interface block's points, False/0 outside ``where``."""
        if self.where is None:
            return values
        X = blk.X0
        inside = np.asarray(self.where(x=X[..., 0], y=X[..., 1], z=X[..., 2]), bool)
        return values * np.broadcast_to(inside, values.shape)

    def debonded_area(self, interfaces, whole: bool = False) -> float:
        """Released area of the interfaces below ``layer`` (points selected by ``where``);
        ``whole``: the area of all those points, released or not (the area the probe watches)."""
        area = 0.0
        for r in interfaces.runs if interfaces is not None else ():
            blk = r.block
            if blk.itf.upper != self.layer:
                continue
            counted = self._selected(blk, np.ones_like(blk.released) if whole else blk.released)
            area += float((blk.w0 * counted).sum())
        return area

    def interface_damage(self, interfaces) -> float:
        """The largest committed damage of the interface points below ``layer`` (selected by
        ``where``): a cohesive law's d (above 0 once a point passed the peak of its law), 0 or 1
        (released) for the thesis's law."""
        worst = 0.0
        for r in interfaces.runs if interfaces is not None else ():
            blk = r.block
            if blk.itf.upper != self.layer:
                continue
            d = getattr(blk, "d_old", None)
            d = blk.released.astype(float) if d is None else np.asarray(d, float)
            if d.size:
                worst = max(worst, float(self._selected(blk, d).max()))
        return worst

    # ------------------------------------------------------------ reaction
    def rigid_mode(self, model, dm) -> np.ndarray:
        """Full-space virtual displacement of the support nodes only: a rigid translation
        (component x|y|z) or rotation about the global axis through the origin (mx|my|mz) of
        every layer at those nodes: u_0L = e (× X_L), u_1L = e × A3 (rotation), higher
        directors 0 (MODEL.md (3.40)). Zero at all other nodes, so ρ·(f_int − F_ext) is the
        virtual work of the support forces at the nodes: bonds (satisfied by a rigid motion)
        and interface forces (equal and opposite at a node) drop out. With ``layer`` only that
        layer moves: the force on it alone, e.g. the opening force on one arm of a DCB whose arms
        are held apart by prescribed displacements (its interface forces then count: evaluate
        with the run's problem)."""
        c = self.component
        e = np.eye(3)["xyz".index(c[-1])]
        rho = np.zeros(dm.n_full)
        nodes = self.nodes
        X = model.mesh.nodes[nodes]
        A3 = _nodal_normals(model)[nodes] if c.startswith("m") else None
        for k, ly in enumerate(model.layers):
            if self.layer is not None and k != self.layer:
                continue
            sel = dm.present[k][nodes]
            if not sel.any():
                continue
            D = dm.layer_dofs[k][nodes[sel]]
            if c.startswith("m"):
                Xk = X[sel] + model.offset(k)[nodes[sel], None] * A3[sel]
                rho[D[:, 0, :]] = np.cross(e, Xk)
                if ly.directors >= 1:
                    rho[D[:, 1, :]] = np.cross(e, A3[sel])
            else:
                rho[D[:, 0, :]] = e
        return rho

    def reaction(self, model, dm, u, load_factor: float, problem=None) -> float:
        """Support force/moment at the nodes: ρ·(f_int(u) − F_ext(λ)) (the force the supports
        exert on the shell; with a ``problem`` its assembler, contact blocks and friction loads)."""
        if self._cache is None or self._cache.get("model") is not model:
            self._cache = {"model": model, "rho": self.rigid_mode(model, dm)}
        return float(self._cache["rho"] @ residual_forces(model, dm, u, load_factor, problem))

    # ------------------------------------------------------------ stress resultant
    def resultant(self, model, dm, u, n_gauss: int = 8) -> float:
        """Stress resultant per unit width at the probe's point: with e1 the section normal
        (``direction`` projected on the tangent plane), e3 = A3, e2 = e3 × e1:
        n = ∫ e1·σ·e1 dΘ³, m = ∫ e1·σ·e1 (Θ³ − Θ_m) dΘ³, q = ∫ e1·σ·e3 dΘ³, nt, mt with e2
        for the second index; Cauchy stresses, through all layers of the stack (Gauss points
        per ply of each layer), without the shifter (per unit width of the reference surface). A point on
        element boundaries gets the mean over the elements that share it (the stresses of the
        displacement element jump there)."""

        vals = [self._resultant_at(model, dm, u, int(e), float(x), float(y), n_gauss)
                for e, x, y in zip(self.elements, self.xi, self.eta)]
        return float(np.mean(vals))

    def _resultant_at(self, model, dm, u, e: int, xi: float, eta: float, n_gauss: int) -> float:
        from ..element.geometry import surface_points
        from ..element.quadrature import ply_rule

        stack = model.stacks[model.element_stack[e]]
        conn = model.mesh.elements[e]
        sp = surface_points(model.mesh.nodes[conn][None], np.array([[xi]]), np.array([[eta]]), per_element=True)
        th, wt, lay = [], [], []
        for k in stack:
            t, w, _ = ply_rule(n_gauss, [f for _, _, f in model.layers[k].ply_table()])  # Gauss points per ply
            off = float(sp.interpolate(model.offset(k)[conn][None])[0, 0])
            H = float(sp.interpolate(model.layers[k].thickness[conn][None])[0, 0])
            th.append(off + 0.5 * H * (t + 1.0))
            wt.append(0.5 * H * w)
            lay.append(np.full(t.size, k))
        th, wt, lay = np.concatenate(th), np.concatenate(wt), np.concatenate(lay)
        p = th.size
        ps = evaluate_points(model, dm, u, np.full(p, e), np.full(p, xi), np.full(p, eta), th, lay)
        n3 = sp.A3[0, 0]
        d = self.direction - (self.direction @ n3) * n3
        e1 = d / np.linalg.norm(d)
        e2 = np.cross(n3, e1)
        s11 = np.einsum("i,pij,j->p", e1, ps.sigma, e1)
        s12 = np.einsum("i,pij,j->p", e1, ps.sigma, e2)
        s13 = np.einsum("i,pij,j->p", e1, ps.sigma, n3)
        top = float(sum(wt))
        zm = 0.5 * top if self.about is None else float(self.about)
        c = self.component
        arm = th - zm
        val = {"n": wt @ s11, "m": wt @ (s11 * arm), "q": wt @ s13, "nt": wt @ s12, "mt": wt @ (s12 * arm)}[c]
        return float(val)

    def material_value(self, model) -> float:
        """A crack width or reinforcement stress/strain over the layer's points (committed state)."""
        from ..element.inelastic import layer_point_values

        v, el = layer_point_values(model, self.layer, self.quantity, self.component or None)
        if self.where is not None and v.size:
            c = model.mesh.nodes[model.mesh.elements[el]].mean(axis=1)
            v = v[np.asarray(self.where(x=c[:, 0], y=c[:, 1], z=c[:, 2]), bool)]
        if v.size == 0:
            return 0.0
        r = self.reduce if self.reduce != "none" else "max"
        if r == "absmax":
            return float(v[np.argmax(np.abs(v))])
        return float({"max": v.max, "min": v.min, "mean": v.mean}[r]())

    def value(self, model, dm, u, load_factor: float = 0.0, interfaces=None, problem=None) -> float:
        """The probe's value at displacements ``u`` (full vector), load factor and interface states."""
        if self.quantity == "reaction":
            return self.scale * self.reaction(model, dm, u, load_factor, problem)
        if self.quantity == "resultant":
            return self.scale * self.resultant(model, dm, u)
        if self.quantity == "load_factor":
            return self.scale * float(load_factor)
        if self.quantity == "debonded_area":
            return self.scale * self.debonded_area(interfaces)
        if self.quantity == "interface_damage":
            return self.scale * self.interface_damage(interfaces)
        if self.quantity in MATERIAL_QUANTITIES:
            return self.scale * self.material_value(model)
        v = self.samples(model, dm, u, load_factor)
        if self.reduce == "max":
            return float(v.max())
        if self.reduce == "min":
            return float(v.min())
        if self.reduce == "absmax":
            return float(v[np.argmax(np.abs(v))])
        if self.reduce == "mean":
            return float(v.mean())
        return float(v[0])


def component_values(ps: PointState, quantity: str, c: str, measure: str = "cauchy",
                     frame: str = "material") -> np.ndarray:
    """One component of a displacement, stress or traction at every point of ``ps``."""
    if quantity == "displacement":
        return np.linalg.norm(ps.u, axis=1) if c == "magnitude" else ps.u[:, "xyz".index(c)]
    if quantity == "traction":
        if c == "shear":  # the tangential part (frame-independent)
            tm = ps.traction()
            return np.hypot(tm[:, 0], tm[:, 1])
        return ps.traction(frame)[:, {"13": 0, "23": 1, "33": 2}[c]]
    T = ps.stress(measure, frame)
    if c in STRESS_COMPONENTS:
        i, j = STRESS_COMPONENTS[c]
        return T[:, i, j]
    if c in ("p1", "p2", "p3"):
        return np.linalg.eigvalsh(T)[:, ::-1][:, int(c[1]) - 1]
    dev = T - np.trace(T, axis1=1, axis2=2)[:, None, None] / 3 * np.eye(3)  # von_mises
    return np.sqrt(1.5 * np.einsum("pij,pij->p", dev, dev))


def residual_forces(model, dm, u: np.ndarray, load_factor: float, problem=None) -> np.ndarray:
    """f_int(u) − F_ext(λ) in the full space: the forces of the constraints (supports, bonds)
    on the shell. With a ``problem``, its assembler (contact, friction and cohesive forces
    included) and loads; without, an assembler of the bare elements kept on the model (contact
    and friction forces between layers act in equal and opposite pairs at a node and drop out of
    a reaction). The last result is reused for the same ``u`` and λ (all reaction probes of a
    step)."""
    cache = (model if problem is None else problem).__dict__.setdefault("_reaction_cache", {})
    if problem is None and cache.get("dm") is not dm:
        from ..assembly import Assembler
        from ..loads import external_forces

        cache.clear()
        cache.update(dm=dm, asm=Assembler(model, dm), F=external_forces(model, dm))
    if cache.get("lam") != load_factor or not np.array_equal(cache.get("u"), u):
        if problem is not None:
            f, _ = problem.assembler.evaluate(u, tangent=False)
            r = f - problem.external(load_factor)
        else:
            f, _ = cache["asm"].evaluate(u, tangent=False)
            r = f - (load_factor * cache["F"][0] + cache["F"][1])
        cache.update(u=u.copy(), lam=load_factor, r=r)
    return cache["r"]


def _nodal_normals(model) -> np.ndarray:
    """(n_nodes, 3) unit normal A3 of the reference surface at every node (from one element)."""
    from ..element.geometry import surface_points

    E = model.mesh.elements
    sp = surface_points(model.mesh.nodes[E], np.broadcast_to(NODE_XI[:, 0], E.shape),
                        np.broadcast_to(NODE_XI[:, 1], E.shape), per_element=True)
    out = np.zeros((model.mesh.n_nodes, 3))
    out[E.ravel()] = sp.A3.reshape(-1, 3)
    return out


def _node_points(model, nodes, layer: int | None = None):
    """An (element, ξ, η) for each node: the element of lowest index that holds the node (and,
    with ``layer``, that layer; where no element at the node holds it, one without it: see
    :func:`has_layer`)."""
    el_of = np.full(model.mesh.n_nodes, -1)
    loc_of = np.zeros(model.mesh.n_nodes, np.int64)
    E = model.mesh.elements
    order = np.arange(len(E))[::-1]
    if layer is not None:  # the elements with the layer are written last, so they win
        order = np.concatenate([order[~has_layer(model, order, layer)], order[has_layer(model, order, layer)]])
    el_of[E[order].ravel()] = np.repeat(order, 9)
    loc_of[E[order].ravel()] = np.tile(np.arange(9), len(order))
    return el_of[nodes], NODE_XI[loc_of[nodes], 0], NODE_XI[loc_of[nodes], 1]


def has_layer(model, elements, layer: int) -> np.ndarray:
    """Whether each of ``elements`` holds layer ``layer`` (its [[stacks]] entry names it)."""
    holds = np.array([layer in st for st in model.stacks], bool)
    return holds[model.element_stack[np.asarray(elements, np.int64)]]


def locate_points(model, points, layer: int | None = None, n_candidates: int = 12):
    """(element, ξ, η, distance, layer present) of the reference-surface point nearest to each of
    ``points (P, 3)``, all projected at once (Gauss-Newton on the ``n_candidates`` elements with
    the nearest centres, as :func:`layershell.results.locate`). A point that several elements
    contain (an element edge or corner) goes to the first of them in order of centre distance,
    element index on ties; with ``layer``, to the first of those that hold the layer, so a point on
    the end of a layer reads that layer whatever the mesh numbering; ``present`` is False where
    none of them holds it."""
    from scipy.spatial import cKDTree

    from ..element.geometry import surface_points

    P = np.atleast_2d(np.asarray(points, float))
    mesh = model.mesh
    centres = mesh.nodes[mesh.elements].mean(1)
    c = min(n_candidates, mesh.n_elements)
    _, cand = cKDTree(centres).query(P, k=c)
    cand = np.sort(np.asarray(cand, np.int64).reshape(len(P), c), axis=1)  # by index, then by centre distance
    dc = np.linalg.norm(centres[cand] - P[:, None], axis=2)
    cand = np.take_along_axis(cand, np.argsort(dc, axis=1, kind="stable"), 1)
    X = mesh.nodes[mesh.elements[cand.ravel()]]  # (P c, 9, 3)
    target = np.repeat(P, c, axis=0)
    x = np.zeros((X.shape[0], 2))
    for _ in range(30):
        sp = surface_points(X, x[:, :1], x[:, 1:], per_element=True)
        A = sp.A[:, 0]
        G = np.einsum("cia,cib->cab", A, A)
        step = -np.linalg.solve(G, np.einsum("cia,ci->ca", A, sp.X0[:, 0] - target)[..., None])[..., 0]
        x = np.clip(x + step, -1.0, 1.0)
        if np.abs(step).max() < 1e-13:
            break
    sp = surface_points(X, x[:, :1], x[:, 1:], per_element=True)
    dist = np.linalg.norm(sp.X0[:, 0] - target, axis=1).reshape(len(P), c)
    x = x.reshape(len(P), c, 2)
    contains = dist <= dist.min(1, keepdims=True) + 1e-9 * mesh.size()
    present = np.ones_like(contains) if layer is None else has_layer(model, cand, layer)
    wanted = contains & present
    present_any = wanted.any(1)
    pick = np.where(present_any, np.argmax(wanted, 1), np.argmax(contains, 1))
    rows = np.arange(len(P))
    return cand[rows, pick], x[rows, pick, 0], x[rows, pick, 1], dist[rows, pick], present_any


def build_probes(mf, model, layer_index, node_selection) -> list[Probe]:
    from .errors import InputError

    out = []
    for i, pd in enumerate(mf.probes):
        f = f"probes[{i}]"
        k = None
        if pd.layer is not None:
            if pd.layer not in layer_index:
                raise InputError(f"'{f}.layer': unknown layer '{pd.layer}'; defined: {list(layer_index)}")
            k = layer_index[pd.layer]
        if pd.quantity in ("reaction", "resultant"):
            out.append(_force_probe(pd, f, k, model, node_selection))
            continue
        if pd.direction is not None or pd.about is not None:
            raise InputError(f"'{f}': 'direction' and 'about' belong to resultant probes; remove them from this "
                             f"{pd.quantity} probe")
        if pd.quantity in ("debonded_area", "interface_damage", "load_factor", *MATERIAL_QUANTITIES):
            out.append(_global_probe(pd, f, k, model, node_selection))
            continue
        comp = pd.component
        if comp is None:
            raise InputError(f"'{f}.component': a {pd.quantity} probe needs a component")
        allowed = FIELD_COMPONENTS[pd.quantity]
        if comp not in allowed:
            raise InputError(f"'{f}.component': '{comp}' is not a {pd.quantity} component; use one of {list(allowed)}")
        if isinstance(pd.theta3, list):
            a, b, n = pd.theta3
            if n < 1 or int(n) != n:
                raise InputError(f"'{f}.theta3': [start, end, n] needs an integer n >= 1")
            th = np.linspace(a, b, int(n))
        else:
            th = np.array([float(pd.theta3)])
        local = False
        if pd.quantity == "traction":
            if k is None:
                raise InputError(f"'{f}.layer': a traction probe needs the layer whose bottom face is meant")
            th, local = np.zeros(1), True
        if pd.quantity == "displacement":
            nodes = node_selection(model.mesh, pd, f)
            el, xi, eta = _node_points(model, nodes, k)
            absent = np.zeros(el.size, bool) if k is None else ~has_layer(model, el, k)
            if absent.any():
                given = "where" if pd.where is not None else "set" if pd.set is not None else "point"
                _absent_layer(model, f, k, el[absent][0], model.mesh.nodes[nodes[absent][0]], given)
        else:
            if pd.point is None:
                raise InputError(f"'{f}.point': a {pd.quantity} probe needs a point on the reference surface")
            e, x, y, dist, present = locate_points(model, [pd.point], k)
            if dist[0] > 1e-3 * model.mesh.size():
                raise InputError(f"'{f}.point': {pd.point} is {dist[0]:.4g} away from the reference surface; "
                                 "give a point on the reference surface (Θ³ = 0) and the height in theta3")
            if not present[0]:
                _absent_layer(model, f, k, e[0], pd.point, "point")
            el, xi, eta = e, x, y
        if not local:
            _check_heights(model, f, el, xi, eta, th, k)
        P = el.size
        el_all = np.repeat(el, th.size)
        xi_all = np.repeat(xi, th.size)
        eta_all = np.repeat(eta, th.size)
        th_all = np.tile(th, P)
        out.append(Probe(pd.name, pd.quantity, comp, pd.measure, el_all, xi_all, eta_all, th_all, k, local,
                         pd.reduce, pd.scale, unit=pd.unit, sampling=pd.sampling, frame=pd.frame))
    return out


def _absent_layer(model, f: str, k: int, element: int, X, moved: str) -> None:
    """The error of a probe on a layer that the [[stacks]] leave out at its point."""
    from .errors import InputError

    there = [model.layers[j].name for j in model.stacks[model.element_stack[element]]]
    X = np.round(np.asarray(X, float), 6).tolist()
    raise InputError(f"'{f}.layer': layer '{model.layers[k].name}' is absent at the probe point {X} (the [[stacks]] "
                     f"leave it out there; the layers there are {there}), so the probe would read a layer that does "
                     f"not exist; move '{f}.{moved}' to where the layer lies, or name one of {there}")


REACTION_COMPONENTS = ("x", "y", "z", "mx", "my", "mz")
RESULTANT_COMPONENTS = ("n", "m", "q", "nt", "mt")


def _force_probe(pd, f: str, k: int | None, model, node_selection) -> Probe:
    """A reaction (support nodes) or stress-resultant (a point) probe."""
    from .errors import InputError

    allowed = REACTION_COMPONENTS if pd.quantity == "reaction" else RESULTANT_COMPONENTS
    if pd.component not in allowed:
        raise InputError(f"'{f}.component': a {pd.quantity} probe needs component = one of {list(allowed)} "
                         f"(got {pd.component!r})")
    unused = {"theta3": pd.theta3 if pd.theta3 != 0.0 else None,
              "reduce": pd.reduce if pd.reduce != "none" else None}
    if pd.quantity == "resultant":
        unused["layer"] = pd.layer
    if pd.quantity == "reaction":
        unused |= {"direction": pd.direction, "about": pd.about}
    else:
        unused |= {"where": pd.where, "set": pd.set}
    extra = [key for key, v in unused.items() if v is not None]
    if extra:
        raise InputError(f"'{f}': a {pd.quantity} probe takes no {', '.join(map(repr, extra))}; remove "
                         + ("them" if len(extra) > 1 else "it"))
    empty = np.zeros(0)
    if pd.quantity == "reaction":
        nodes = node_selection(model.mesh, pd, f)
        return Probe(pd.name, pd.quantity, pd.component, pd.measure, empty.astype(np.int64), empty, empty, empty,
                     k, False, "none", pd.scale, nodes=nodes, unit=pd.unit)
    if pd.point is None:
        raise InputError(f"'{f}.point': a resultant probe needs a point on the reference surface")
    if pd.direction is None:
        raise InputError(f"'{f}.direction': a resultant probe needs the normal of the section, e.g. "
                         "direction = [1, 0, 0] for the section x = const (m: the moment of σ_xx)")
    dvec = np.asarray(pd.direction, float)
    e, x, y, dist = locate(model, pd.point)
    if dist > 1e-3 * model.mesh.size():
        raise InputError(f"'{f}.point': {pd.point} is {dist:.4g} away from the reference surface; give a point on "
                         "the reference surface")
    els, xs, ys = _sharing(model, pd.point, e, dist)
    from ..element.geometry import surface_points

    sp = surface_points(model.mesh.nodes[model.mesh.elements[e]][None], np.array([[x]]), np.array([[y]]),
                        per_element=True)
    n3 = sp.A3[0, 0]
    nd = np.linalg.norm(dvec)
    if not nd > 0 or np.linalg.norm(dvec - (dvec @ n3) * n3) < 1e-6 * nd:
        raise InputError(f"'{f}.direction': {pd.direction} is zero or along the shell normal at the point; give "
                         "a direction in the tangent plane (the normal of the section)")
    return Probe(pd.name, pd.quantity, pd.component, pd.measure, els, xs, ys, np.zeros(els.size), None, False,
                 "none", pd.scale, direction=dvec / nd, about=pd.about, unit=pd.unit)


def _sharing(model, point, e0: int, d0: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every element whose reference surface contains ``point`` (as closely as the nearest,
    element ``e0`` at distance ``d0``): the elements around the nearest node of ``e0``,
    projected by Gauss-Newton iterations (as :func:`layershell.results.locate`)."""
    from ..element.geometry import surface_points

    mesh = model.mesh
    point = np.asarray(point, float)
    conn = mesh.elements[e0]
    node = conn[np.argmin(np.linalg.norm(mesh.nodes[conn] - point, axis=1))]
    cand = np.flatnonzero((mesh.elements == node).any(1))
    X = mesh.nodes[mesh.elements[cand]]
    x = np.zeros((cand.size, 2))
    for _ in range(30):
        sp = surface_points(X, x[:, :1], x[:, 1:], per_element=True)
        A = sp.A[:, 0]
        G = np.einsum("cia,cib->cab", A, A)
        step = -np.linalg.solve(G, np.einsum("cia,ci->ca", A, sp.X0[:, 0] - point)[..., None])[..., 0]
        x = np.clip(x + step, -1.0, 1.0)
        if np.abs(step).max() < 1e-13:
            break
    sp = surface_points(X, x[:, :1], x[:, 1:], per_element=True)
    dist = np.linalg.norm(sp.X0[:, 0] - point, axis=1)
    keep = dist <= d0 + 1e-9 * mesh.size()
    if not keep.any():
        return np.array([e0]), np.zeros(1), np.zeros(1)
    return cand[keep], x[keep, 0], x[keep, 1]


def _check_heights(model, f: str, el, xi, eta, th, k: int | None) -> None:
    """Θ³ of a probe must lie within the laminate (or the named layer) at its points: outside, the
    director polynomials are extrapolated and give arbitrary values."""
    from ..element.shape import quad9
    from .errors import InputError

    N = quad9(np.asarray(xi, float), np.asarray(eta, float))[0]  # (P, 9)
    conn = model.mesh.elements[el]
    stk = model.element_stack[el]
    lo, hi = np.full(el.size, -np.inf), np.full(el.size, np.inf)
    for s in np.unique(stk):
        st, sel = model.stacks[s], stk == s
        if k is not None and k not in st:
            continue
        lo_k, hi_k = (st[0], st[-1]) if k is None else (k, k)
        lo[sel] = np.einsum("pa,pa->p", N[sel], model.offset(lo_k)[conn[sel]])
        hi[sel] = np.einsum("pa,pa->p", N[sel], (model.offset(hi_k) + model.layers[hi_k].thickness)[conn[sel]])
    tol = 1e-6 * np.abs(hi[np.isfinite(hi)]).max(initial=0.0)
    out = (th[None, :] < lo[:, None] - tol) | (th[None, :] > hi[:, None] + tol)
    if out.any():
        p, t = np.argwhere(out)[0]
        X = (N[p] @ model.mesh.nodes[conn[p]]).round(6).tolist()
        what = "the laminate" if k is None else f"layer '{model.layers[k].name}'"
        raise InputError(f"'{f}.theta3': Θ³ = {th[t]:.6g} lies outside the shell at the probe point {X}, where "
                         f"{what} spans Θ³ = {lo[p]:.6g} to {hi[p]:.6g} (Θ³ is measured from the reference face); "
                         "values outside the thickness would be extrapolated, so give a height within it")


def _global_probe(pd, f: str, k: int | None, model, node_selection) -> Probe:
    """A probe of the whole state: the load factor, or a debonded area or the damage of an interface."""
    from .errors import XYZ, InputError
    from .errors import formula as _formula

    if pd.quantity in MATERIAL_QUANTITIES:
        return _material_probe(pd, f, k, model)
    unused = {"point": pd.point, "set": pd.set, "component": pd.component}
    if pd.quantity == "load_factor":
        unused |= {"layer": pd.layer, "where": pd.where}
    extra = [key for key, v in unused.items() if v is not None]
    extra += [key for key, v in (("theta3", pd.theta3 != 0.0), ("reduce", pd.reduce != "none")) if v]
    if extra:
        raise InputError(f"'{f}': a {pd.quantity} probe takes no {', '.join(map(repr, extra))}; remove "
                         + ("them" if len(extra) > 1 else "it"))
    where = None
    if pd.quantity in ("debonded_area", "interface_damage"):
        if k is None:
            raise InputError(f"'{f}.layer': a {pd.quantity} probe needs the layer above the interface")
        if k not in model.interface_laws:
            raise InputError(f"'{f}.layer': the interface below '{pd.layer}' has no [[interfaces]] entry, so it "
                             "never debonds; add one or name the layer of an [[interfaces]] entry")
        if pd.where is not None:
            node_selection(model.mesh, pd, f)  # checks the formula; it must select some part of the model
            fm, tol = _formula(pd.where, XYZ, f"{f}.where"), 1e-6 * model.mesh.size()

            def where(**xyz):
                return fm(tol=tol, **xyz)
    empty = np.zeros(0)
    return Probe(pd.name, pd.quantity, "", pd.measure, empty.astype(np.int64), empty, empty, empty, k, False,
                 pd.reduce, pd.scale, where, unit=pd.unit)


def _material_probe(pd, f: str, k: int | None, model) -> Probe:
    """A crack-width or reinforcement probe of layer ``k``, checked against the layer's law and sheets."""
    from .errors import XYZ, InputError
    from .errors import formula as _formula

    extra = [key for key, v in (("point", pd.point), ("set", pd.set), ("theta3", pd.theta3 != 0.0)) if v]
    if extra:
        raise InputError(f"'{f}': a {pd.quantity} probe takes no {', '.join(map(repr, extra))} (it reduces over "
                         "the layer's integration points; select elements with 'where')")
    if k is None:
        raise InputError(f"'{f}.layer': a {pd.quantity} probe needs the layer it reads")
    ly = model.layers[k]
    if pd.quantity == "crack_width" and ly.law is None:
        raise InputError(f"'{f}.layer': layer '{ly.name}' is not of a concrete material, so it has no cracks; name "
                         "a layer whose material has type = 'concrete'")
    if pd.quantity != "crack_width":
        names = [r.name for r in ly.reinforcement]
        if not names:
            raise InputError(f"'{f}.layer': layer '{ly.name}' has no reinforcement; name a layer with "
                             "reinforcement = [...]")
        if pd.component is not None and pd.component not in names:
            raise InputError(f"'{f}.component': layer '{ly.name}' has no reinforcement '{pd.component}'; its "
                             f"reinforcement is {names} (or leave component out for all)")
    where = None
    if pd.where is not None:
        fm, tol = _formula(pd.where, XYZ, f"{f}.where"), 1e-6 * model.mesh.size()

        def where(**xyz):
            return fm(tol=tol, **xyz)
    empty = np.zeros(0)
    return Probe(pd.name, pd.quantity, pd.component or "", pd.measure, empty.astype(np.int64), empty, empty, empty,
                 k, False, pd.reduce, pd.scale, where, unit=pd.unit)

