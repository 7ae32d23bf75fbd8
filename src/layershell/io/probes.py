"""Probes: named scalar outputs evaluated after every converged step."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from ..element.shape import NODE_XI
from ..results import PointState, evaluate_points, locate

STRESS_COMPONENTS = {"11": (0, 0), "22": (1, 1), "33": (2, 2), "23": (1, 2), "13": (0, 2), "12": (0, 1)}
TRACTION_COMPONENTS = ("13", "23", "33", "shear")


class ProbeError(ValueError):
    pass


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
        c = self.component
        if self.quantity == "displacement":
            vals = np.linalg.norm(ps.u, axis=1) if c == "magnitude" else ps.u[:, "xyz".index(c)]
        elif self.quantity == "traction":
            t = ps.traction(self.frame)
            if c == "shear":  # the tangential part (frame-independent)
                tm = ps.traction()
                vals = np.hypot(tm[:, 0], tm[:, 1])
            else:
                vals = t[:, {"13": 0, "23": 1, "33": 2}[c]]
        else:
            T = ps.stress(self.measure, self.frame)
            if c in STRESS_COMPONENTS:
                i, j = STRESS_COMPONENTS[c]
                vals = T[:, i, j]
            elif c in ("p1", "p2", "p3"):
                vals = np.linalg.eigvalsh(T)[:, ::-1][:, int(c[1]) - 1]
            else:  # von_mises
                dev = T - np.trace(T, axis1=1, axis2=2)[:, None, None] / 3 * np.eye(3)
                vals = np.sqrt(1.5 * np.einsum("pij,pij->p", dev, dev))
        return self.scale * vals

    def debonded_area(self, interfaces) -> float:
        """Released area of the interfaces below ``layer`` (points selected by ``where``)."""
        area = 0.0
        for r in interfaces.runs if interfaces is not None else ():
            blk = r.block
            if blk.itf.upper != self.layer:
                continue
            counted = blk.released
            if self.where is not None:
                X = blk.X0
                inside = np.asarray(self.where(x=X[..., 0], y=X[..., 1], z=X[..., 2]), bool)
                counted = counted & np.broadcast_to(inside, counted.shape)
            area += float((blk.w0 * counted).sum())
        return area

    def value(self, model, dm, u, load_factor: float = 0.0, interfaces=None) -> float:
        """The probe's value at displacements ``u`` (full vector), load factor and interface states."""
        if self.quantity == "load_factor":
            return self.scale * float(load_factor)
        if self.quantity == "debonded_area":
            return self.scale * self.debonded_area(interfaces)
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


def _node_points(model, nodes):
    """An (element, ξ, η) for each node."""
    el_of = np.full(model.mesh.n_nodes, -1)
    loc_of = np.zeros(model.mesh.n_nodes, np.int64)
    E = model.mesh.elements
    el_of[E[::-1].ravel()] = np.repeat(np.arange(len(E))[::-1], 9)
    loc_of[E[::-1].ravel()] = np.tile(np.arange(9), len(E))
    return el_of[nodes], NODE_XI[loc_of[nodes], 0], NODE_XI[loc_of[nodes], 1]


def build_probes(mf, model, layer_index, node_selection) -> list[Probe]:
    from .build import InputError

    out = []
    for i, pd in enumerate(mf.probes):
        f = f"probes[{i}]"
        k = None
        if pd.layer is not None:
            if pd.layer not in layer_index:
                raise InputError(f"'{f}.layer': unknown layer '{pd.layer}'; defined: {list(layer_index)}")
            k = layer_index[pd.layer]
        if pd.quantity in ("debonded_area", "load_factor"):
            out.append(_global_probe(pd, f, k, model, node_selection))
            continue
        comp = pd.component
        if comp is None:
            raise InputError(f"'{f}.component': a {pd.quantity} probe needs a component")
        allowed = {"displacement": ("x", "y", "z", "magnitude"),
                   "stress": tuple(STRESS_COMPONENTS) + ("p1", "p2", "p3", "von_mises"),
                   "traction": TRACTION_COMPONENTS}[pd.quantity]
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
            el, xi, eta = _node_points(model, nodes)
        else:
            if pd.point is None:
                raise InputError(f"'{f}.point': a {pd.quantity} probe needs a point on the reference surface")
            e, x, y, dist = locate(model, pd.point)
            if dist > 1e-3 * model.mesh.size():
                raise InputError(f"'{f}.point': {pd.point} is {dist:.4g} away from the reference surface; "
                                 "give a point on the reference surface (Θ³ = 0) and the height in theta3")
            el, xi, eta = np.array([e]), np.array([x]), np.array([y])
        P = el.size
        el_all = np.repeat(el, th.size)
        xi_all = np.repeat(xi, th.size)
        eta_all = np.repeat(eta, th.size)
        th_all = np.tile(th, P)
        out.append(Probe(pd.name, pd.quantity, comp, pd.measure, el_all, xi_all, eta_all, th_all, k, local,
                         pd.reduce, pd.scale, sampling=pd.sampling, frame=pd.frame))
    return out


def _global_probe(pd, f: str, k: int | None, model, node_selection) -> Probe:
    """A probe of the whole state: the load factor, or a debonded area of an interface."""
    from .build import XYZ, InputError, _formula

    unused = {"point": pd.point, "set": pd.set, "component": pd.component}
    if pd.quantity == "load_factor":
        unused |= {"layer": pd.layer, "where": pd.where}
    extra = [key for key, v in unused.items() if v is not None]
    extra += [key for key, v in (("theta3", pd.theta3 != 0.0), ("reduce", pd.reduce != "none")) if v]
    if extra:
        raise InputError(f"'{f}': a {pd.quantity} probe takes no {', '.join(map(repr, extra))}; remove "
                         + ("them" if len(extra) > 1 else "it"))
    where = None
    if pd.quantity == "debonded_area":
        if k is None:
            raise InputError(f"'{f}.layer': a debonded_area probe needs the layer above the interface")
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
                 pd.reduce, pd.scale, where)
