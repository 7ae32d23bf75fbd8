"""The validated physical model: mesh, layers, stacks, supports, constraints, loads.

Pure data; built by :mod:`layershell.io.build` from a model file or directly in Python.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .material import Orthotropic
from .mesh import Mesh


@dataclass(frozen=True)
class Ply:
    """One ply of a layer's ply stack: material, angle (degrees about the normal, added to the
    layer's angle) and its share of the layer thickness."""

    material: Orthotropic
    angle: float
    fraction: float


@dataclass(frozen=True)
class Reinforcement:
    """A reinforcement sheet inside a layer (rebar, textile): a uniaxial ``law``
    (:mod:`layershell.laws.uniaxial`) at ``height`` above the layer's bottom face, with the area
    ``area`` per unit width along the tangent-plane projection of ``direction`` (None: the first
    coordinate line) turned by ``angle`` degrees about the normal (:mod:`layershell.element.inelastic`);
    ``bar_diameter`` where the sheet was given as bars (for the crack spacing)."""

    name: str
    law: object
    height: float
    area: float
    angle: float = 0.0
    direction: tuple[float, float, float] | None = None
    bar_diameter: float | None = None


@dataclass(frozen=True)
class Layer:
    """One layer: material, number of directors d (MODEL.md §2: u = Σ (Θ_L³)^l u_l, l=0..d),
    nodal thickness ``(n_nodes,)`` and material orientation (angle ω about the normal from the
    tangent-plane projection of ``direction``, or from A_1 if ``direction`` is None).

    With ``plies`` (bottom to top) the layer is a ply stack under its own directors: the element
    integrates it ply by ply (:func:`layershell.element.quadrature.ply_rule`), stresses take the
    ply's material and angle at their height, and ``material`` is the stack's homogenised
    equivalent (:func:`layershell.material.laminate_equivalent`), used only by the estimates
    (penalty stiffnesses, process zone, mass)."""

    name: str
    material: Orthotropic
    directors: int
    thickness: np.ndarray
    angle: float = 0.0
    direction: tuple[float, float, float] | None = None
    plies: tuple[Ply, ...] = ()
    # an inelastic bulk law (:mod:`layershell.laws`; ``material`` is then its initial elastic
    # stand-in) and reinforcement sheets inside the layer
    law: object | None = None
    reinforcement: tuple[Reinforcement, ...] = ()

    @property
    def inelastic(self) -> bool:
        """The layer has a material law with a history or reinforcement sheets."""
        return self.law is not None or bool(self.reinforcement)

    def ply_table(self) -> tuple[tuple[Orthotropic, float, float], ...]:
        """(material, angle ω in degrees, thickness fraction) per ply, bottom to top; a layer
        without plies is one ply of its own material and angle."""
        if not self.plies:
            return ((self.material, self.angle, 1.0),)
        return tuple((p.material, self.angle + p.angle, p.fraction) for p in self.plies)


@dataclass(frozen=True)
class Fix:
    """Zero displacement of components ``components`` (0..2) of directors ``directors`` of
    layer ``layer`` at ``nodes``; with ``value`` (one number per component) a prescribed
    displacement instead, multiplied by the load factor when ``scaled`` (displacement control)."""

    nodes: np.ndarray
    layer: int
    directors: tuple[int, ...]
    components: tuple[int, ...]
    value: tuple[float, ...] | None = None
    scaled: bool = True


@dataclass(frozen=True)
class Tie:
    """Linear support of layer ``layer`` at ``nodes``: Σ_l c_l u_l · n = v per node, with
    ``coeffs (n_sel, d+1)`` (a face or height Θ_L³: c_l = (Θ_L³)^l, MODEL.md §2; one director:
    a unit vector) and unit ``direction (n_sel, 3)``. Applied after the bond, so a support on
    the bottom face of a bonded upper layer acts on the top face of the layer below."""

    nodes: np.ndarray
    layer: int
    coeffs: np.ndarray
    direction: np.ndarray
    value: np.ndarray | None = None  # (n_sel,) prescribed Σ_l c_l u_l · n (None: zero)
    scaled: bool = True  # value × load factor (displacement control)


@dataclass(frozen=True)
class Symmetry:
    """Symmetry plane with unit normal ``normal``: u_l · n = 0 for every director of every layer."""

    nodes: np.ndarray
    normal: np.ndarray


@dataclass(frozen=True)
class Hinge:
    """Hinged support at height ``height`` (Θ_1³; None = mid-thickness) in direction ``direction``
    (global vector, or ``None`` with ``local=True`` for the in-plane edge normal), MODEL.md §8,
    thesis (3.77)-(3.90). ``fixed``: u_0 of layer 1 also restricted to the hinge direction."""

    nodes: np.ndarray
    direction: np.ndarray  # (n_nodes_sel, 3) unit vectors, one per node
    height: np.ndarray | None = None
    fixed: bool = True


@dataclass(frozen=True)
class NodalLoad:
    """Director forces given directly: ``values (n_sel, 3)`` on director ``director`` of
    ``layer`` at ``nodes`` (already integrated, force units × length^director)."""

    nodes: np.ndarray
    layer: int
    director: int
    values: np.ndarray
    scaled: bool = True


@dataclass(frozen=True)
class SurfaceLoad:
    """Traction per unit reference area on face ``face`` ('reference', 'top' or 'layer:<k>'
    bottom face of layer k), direction 'global' vector or 'normal' (A_3), on elements
    ``elements``; ``magnitude`` is a callable of (x, y, z) arrays -> values. Volume loads use
    ``face='volume'`` (force per volume, per layer: thesis (2.183))."""

    elements: np.ndarray
    face: str
    direction: np.ndarray | None  # None -> along A_3
    magnitude: object
    layer: int | None = None  # for 'volume': layer index or None = all
    scaled: bool = True


@dataclass(frozen=True)
class EdgeLoad:
    """Traction through the thickness on a lateral face along mesh edges, MODEL.md §6: the
    traction per unit area is ``distribution(theta3, x, y, z)`` (Θ_1³ from the reference face)
    times the unit ``direction``; converted to director forces (2.167) per layer and integrated
    along the edge with the element shape functions."""

    edges: np.ndarray  # (n_edges, 3) node triples (start, mid, end) on the reference surface
    direction: np.ndarray
    distribution: object
    scaled: bool = True
    at_face: str | None = None  # 'top' | 'reference': a line force per edge length on that face (2.180)
    at_height: float | None = None  # a line force per edge length at this Θ_1³


@dataclass
class Model:
    mesh: Mesh
    layers: list[Layer]
    stacks: list[tuple[int, ...]]
    element_stack: np.ndarray  # (n_elements,) index into stacks
    fixes: list[Fix] = field(default_factory=list)
    symmetries: list[Symmetry] = field(default_factory=list)
    hinges: list[Hinge] = field(default_factory=list)
    ties: list[Tie] = field(default_factory=list)
    nodal_loads: list[NodalLoad] = field(default_factory=list)
    surface_loads: list[SurfaceLoad] = field(default_factory=list)
    edge_loads: list[EdgeLoad] = field(default_factory=list)
    n_thickness: int = 3
    nonlinear: bool = True
    element: str = "mitc"  # "mitc": MITC9 assumed strain (element/mitc.py); "full": fully integrated
    units: str = ""
    # concrete layers: "implex" (the damage of each increment extrapolated from the last two, the
    # implicit update committed: Oliver, Huespe & Cante 2008) or "implicit" (updated in every iteration)
    integration: str = "implex"
    # the committed point states of the inelastic layers, per layer: [(block, state), ...] (kept
    # here by Assembler.commit for the outputs, results.evaluate_points)
    point_states: dict = field(default_factory=dict, repr=False, compare=False)
    # delamination (MODEL.md §9-§10), keyed by the index of the layer above the interface
    interface_laws: dict = field(default_factory=dict)  # int -> InterfaceLaw
    initially_debonded: dict = field(default_factory=dict)  # int -> node indices
    initial_laws: dict = field(default_factory=dict)  # int -> InterfaceLaw of the initial zone
    delamination: object = None  # DelaminationSettings

    def below(self) -> dict[int, int]:
        """Layer index -> index of the layer directly below it (for layers that are not first)."""
        out: dict[int, int] = {}
        for st in self.stacks:
            for lo, up in zip(st[:-1], st[1:]):
                if out.setdefault(up, lo) != lo:
                    raise ValueError(
                        f"layer '{self.layers[up].name}' lies on '{self.layers[out[up]].name}' in one "
                        f"stack and on '{self.layers[lo].name}' in another; a layer must sit on the same "
                        "layer everywhere"
                    )
        return out

    def layer_elements(self, k: int) -> np.ndarray:
        """The elements whose stack carries layer ``k``."""
        return np.flatnonzero([k in self.stacks[s] for s in self.element_stack])

    def layers_present(self) -> np.ndarray:
        """(n_layers, n_nodes): layer k exists at the node (an element of a stack with k touches it)."""
        on = np.zeros((len(self.layers), self.mesh.n_nodes), bool)
        for si, st in enumerate(self.stacks):
            nodes = np.unique(self.mesh.elements[self.element_stack == si])
            on[np.ix_(list(st), nodes)] = True
        return on

    def offset(self, layer: int) -> np.ndarray:
        """Nodal Θ_1³ of the bottom face of ``layer`` (sum of the thicknesses below it)."""
        b = self.below()
        h = np.zeros(self.mesh.n_nodes)
        k = layer
        while k in b:
            k = b[k]
            h = h + self.layers[k].thickness
        return h

    def total_thickness(self) -> np.ndarray:
        """Nodal total thickness over the thickest stack at each node."""
        tot = np.zeros(self.mesh.n_nodes)
        for si, st in enumerate(self.stacks):
            nodes = np.unique(self.mesh.elements[self.element_stack == si])
            top = st[-1]
            t = self.offset(top) + self.layers[top].thickness
            tot[nodes] = np.maximum(tot[nodes], t[nodes])
        return tot
