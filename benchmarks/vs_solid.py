"""Accuracy per cost: layershell against a 3D solid model (scikit-fem quadratic hexahedra).

    pip install -e ".[bench]"            # scikit-fem, only for this benchmark
    python benchmarks/vs_solid.py [--case curved|plate|both] [--quick] [--repeats N] [--fine-reference]

Two problems, both linear (layershell with ``nonlinear = false``), both solved on the same machine
in the same run with the same direct solver (PARDISO through pypardiso for both):

1. **Curved beam in pure bending** (thesis §3.5.2, MODEL.md V4; ``examples/curved_beam_1layer.toml``):
   a = 2.5, b = 5 m, width 0.1 m, 180°, ν = 0, end moment as Girkmann's traction -σ_φ(r) e_y.
   Reference: Girkmann's closed form (3.94)-(3.95) (σ_φ(a) = 1.241, σ_r,max = 0.171 kN/m²).
   Quantities: σ_φ at the inner face and σ_r,max through the thickness, both at the crown.
2. **Thick two-layer bonded plate under pressure**: square L × L cantilever plate (clamped edge
   x = 0, all through-thickness points fixed), layers of different E and ν, L/h = 5, uniform pressure
   on the top face. Quantity: the interface shear stress σ_xz at (L/2, L/2) on the interface.
   Reference: the solid model on three nested meshes (4/8/16 elements along the span, 1/2/4 per
   layer; ``--fine-reference``: 8/16/32 and 2/4/8), Richardson-extrapolated with the observed order.

For each model a refinement family is run; the cost to reach 1 % error is the smallest DOF count
(and, separately, the smallest wall time) among the runs whose errors are all ≤ 1 %. The solid's
element stiffness matrices use scikit-fem's mesh, mapping, quadrature and basis gradients, but are
formed with one batched matrix product (the stock ``asm(linear_elasticity, ...)`` loops over the
81 × 81 basis-function pairs in Python and is ~100× slower at these sizes, which would flatter
layershell); the end tractions / pressure are integrated on the flat faces directly (Gauss 4 × 4).
DOFs are the unknowns of the solved system (layershell: reduced DOFs after bond and supports;
solid: free DOFs). Times are wall seconds from building the model to the stresses at the probe
points (layershell: model-file text → ``build`` → ``runner.run``, which also evaluates the residual
once more after the linear solve; solid: mesh → stiffness/load → solve → stress probes), after one
untimed warm-up run of each (Numba JIT, imports); the two smallest 1 %-runs are re-timed (best of
``--repeats``). layershell's probe-point location (``results.locate``: Newton projections on the
12 nearest elements in Python, ~0.2-2 s per probe on the shared machine, independent of the mesh) is
timed separately and also reported excluded ("nolocate").

Last line: ``vs_solid: dof_ratio_curved=... time_ratio_curved=... time_ratio_curved_nolocate=...
dof_ratio_plate=... time_ratio_plate=... time_ratio_plate_nolocate=...`` (layershell / solid; < 1
means layershell is cheaper; nan where a model did not reach 1 % in its family).
"""
from __future__ import annotations

import argparse
import re
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import scipy.sparse as sp

try:
    import skfem
    from skfem import Basis, ElementHex2, MeshHex, MeshHex2
except ImportError as exc:  # pragma: no cover - the benchmark needs the optional extra
    raise SystemExit('vs_solid needs scikit-fem: pip install -e ".[bench]"') from exc

import layershell.io.probes as _probes
from layershell.io.build import build, parse
from layershell.runner import run
from layershell.solver.linear import LinearSolver, backend_name

ROOT = Path(__file__).resolve().parents[1]

# layershell locates every probe point by Newton projections on the 12 nearest elements (pure
# Python, ~0.2-2 s per probe on the shared 2-core machine, independent of the mesh size); the
# benchmark measures that time so that it can be reported separately (the library is unchanged).
_LOCATE = {"seconds": 0.0}
_locate_orig = _probes.locate


def _timed_locate(*args, **kwargs):
    t0 = time.perf_counter()
    try:
        return _locate_orig(*args, **kwargs)
    finally:
        _LOCATE["seconds"] += time.perf_counter() - t0


_probes.locate = _timed_locate
TOL = 0.01  # the accuracy target: 1 % relative error


@dataclass
class Result:
    """One run of one model: configuration, cost, values and relative errors."""

    model: str
    config: str
    dofs: int
    seconds: float
    values: dict[str, float]
    errors: dict[str, float] = field(default_factory=dict)
    args: tuple = ()
    locate_seconds: float = 0.0  # layershell: time spent locating probe points (results.locate)

    @property
    def net_seconds(self) -> float:
        """Wall time without the probe-point location (a fixed per-probe cost, see the docs)."""
        return self.seconds - self.locate_seconds

    @property
    def ok(self) -> bool:
        return bool(self.errors) and max(self.errors.values()) <= TOL


# ---------------------------------------------------------------------------------------------
# Girkmann's curved beam in pure bending, (3.94)-(3.95)
A_IN, B_OUT, WIDTH, MOMENT = 2.5, 5.0, 0.1, 0.1
E_BEAM = 3.0e7


def _girkmann_d() -> float:
    a, b = A_IN, B_OUT
    return (b**2 - a**2) ** 2 - 4 * a**2 * b**2 * np.log(b / a) ** 2


def girkmann_sigma_phi(r: np.ndarray) -> np.ndarray:
    """σ_φ(r) of the curved beam in pure bending, thesis (3.95)."""
    a, b = A_IN, B_OUT
    return -4 * MOMENT / (WIDTH * _girkmann_d()) * ((b**2 - a**2) - a**2 * np.log(r / a) + b**2 * np.log(r / b)
                                                     - a**2 * b**2 / r**2 * np.log(b / a))


def girkmann_sigma_r(r: np.ndarray) -> np.ndarray:
    """σ_r(r) of the curved beam in pure bending, thesis (3.94)."""
    a, b = A_IN, B_OUT
    return -4 * MOMENT / (WIDTH * _girkmann_d()) * (-(a**2) * np.log(r / a) + b**2 * np.log(r / b)
                                                     + a**2 * b**2 / r**2 * np.log(b / a))


def girkmann_reference() -> dict[str, float]:
    """σ_φ(a) and σ_r,max (maximised on a fine grid; MODEL.md V4: 1.241 and 0.171)."""
    r = np.linspace(A_IN, B_OUT, 2_000_001)
    return {"sigma_phi_inner": float(girkmann_sigma_phi(np.array(A_IN))),
            "sigma_r_max": float(girkmann_sigma_r(r).max())}


# ---------------------------------------------------------------------------------------------
# the solid model: scikit-fem MeshHex2 / ElementHex2, linear isotropic elasticity
class Solid:
    """Quadratic-hexahedron solid on a structured box in parameter space mapped by ``to_xyz``.

    ``to_xyz`` maps parameter coordinates (3, n) to physical coordinates; it is applied to all 27
    nodes of every element, so curved boundaries are quadratic (isoparametric) surfaces.
    ``material(p_centroid)`` gives (E, ν) per element from its parameter-space centroid.
    """

    def __init__(self, p1: np.ndarray, p2: np.ndarray, p3: np.ndarray, to_xyz, material) -> None:
        self.box = MeshHex.init_tensor(p1, p2, p3)
        box2 = MeshHex2.from_mesh(self.box)
        self.param = box2.doflocs
        self.mesh = MeshHex2(to_xyz(box2.doflocs), box2.t)
        self.basis = Basis(self.mesh, ElementHex2(), intorder=4)  # 3 × 3 × 3 Gauss points
        self.to_xyz = to_xyz
        centroid = self.box.p[:, self.box.t].mean(axis=1)
        self.E, self.nu = material(centroid)
        self.ndof = 3 * self.basis.N

    def vector_dofs(self) -> np.ndarray:
        """(81, n_el) global DOFs; DOF 3·a + i is component i of scalar function a."""
        ed = self.basis.element_dofs
        return (3 * ed[:, None, :] + np.arange(3)[None, :, None]).reshape(81, -1)

    def stiffness(self, chunk: int = 4000) -> sp.csr_matrix:
        """K = ∫ ε(v) : C : ε(u) dV, batched over elements (λ, μ per element)."""
        ib = self.basis
        lam = self.E * self.nu / ((1 + self.nu) * (1 - 2 * self.nu))
        mu = self.E / (2 * (1 + self.nu))
        edofs = self.vector_dofs()
        rows, cols, vals = [], [], []
        eye = np.eye(3)
        for s in range(0, ib.nelems, chunk):
            sl = slice(s, min(s + chunk, ib.nelems))
            G = np.array([ib.basis[a][0].grad[:, sl] for a in range(27)])  # (27, 3, ne, nq)
            G = G * np.sqrt(ib.dx[sl])[None, None]
            ne, nq = G.shape[2], G.shape[3]
            Gm = G.transpose(2, 0, 1, 3).reshape(ne, 81, nq)
            T1 = (Gm @ Gm.transpose(0, 2, 1)).reshape(ne, 27, 3, 27, 3)  # Σ_q ∂_i N_a ∂_j N_b w
            T2 = T1.transpose(0, 1, 4, 3, 2)  # [a, j, b, i]
            T3 = np.einsum("eakbk,ij->eaibj", T1, eye)
            Ke = (lam[sl, None, None, None, None] * T1 + mu[sl, None, None, None, None] * (T2 + T3))
            Ke = Ke.reshape(ne, 81, 81)
            d = edofs[:, sl].T  # (ne, 81)
            rows.append(np.repeat(d, 81, axis=1).ravel())
            cols.append(np.tile(d, (1, 81)).ravel())
            vals.append(Ke.ravel())
        K = sp.coo_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                          shape=(self.ndof, self.ndof)).tocsr()
        return K

    def face_load(self, axis: int, value: float, t_fn) -> np.ndarray:
        """Consistent nodal loads of a traction on the box face ``param[axis] = value``.

        The face must map isometrically (rigid motion) from parameter to physical space (true for
        the curved beam's end faces x = ±r and the plate's top face). ``t_fn(param (3, n))`` gives
        the physical traction (3, n). Gauss 4 × 4 per quad9 face.
        """
        on = np.isclose(self.param[axis], value)
        other = [k for k in range(3) if k != axis]
        g1, g2 = (np.unique(np.round(self.param[k, on], 12)) for k in other)
        idx = np.full((g1.size, g2.size), -1)
        nodes = np.flatnonzero(on)
        idx[np.searchsorted(g1, np.round(self.param[other[0], nodes], 12)),
            np.searchsorted(g2, np.round(self.param[other[1], nodes], 12))] = nodes
        assert (idx >= 0).all()
        gp, gw = np.polynomial.legendre.leggauss(4)
        q, w = (gp + 1) / 2, gw / 2
        L = np.array([2 * (q - 0.5) * (q - 1), -4 * q * (q - 1), 2 * q * (q - 0.5)])  # (3 nodes, 4 points)
        e1, e2 = np.arange(0, g1.size - 1, 2), np.arange(0, g2.size - 1, 2)
        E1, E2 = np.meshgrid(e1, e2, indexing="ij")
        E1, E2 = E1.ravel(), E2.ravel()  # face elements: first node index along each axis
        h1, h2 = g1[E1 + 2] - g1[E1], g2[E2 + 2] - g2[E2]
        pts = np.zeros((3, E1.size, 4, 4))
        pts[axis] = value
        pts[other[0]] = g1[E1][:, None, None] + h1[:, None, None] * q[None, :, None]
        pts[other[1]] = g2[E2][:, None, None] + h2[:, None, None] * q[None, None, :]
        t = t_fn(pts.reshape(3, -1)).reshape(3, E1.size, 4, 4)
        wq = (h1 * h2)[:, None, None] * w[None, :, None] * w[None, None, :]
        f = np.zeros(self.ndof)
        for a in range(3):
            for b in range(3):
                Nab = L[a][None, :, None] * L[b][None, None, :] * wq  # (ne, 4, 4)
                node = idx[E1 + a, E2 + b]
                for c in range(3):
                    np.add.at(f, 3 * node + c, np.sum(Nab * t[c], axis=(1, 2)))
        return f

    def nearest_nodes(self, xyz: np.ndarray) -> np.ndarray:
        """Scalar node (DOF location) indices nearest to the points ``xyz`` (n, 3)."""
        loc = self.basis.doflocs
        return np.array([int(np.argmin(np.sum((loc - np.asarray(p)[:, None]) ** 2, axis=0))) for p in xyz])

    def solve(self, K: sp.csr_matrix, f: np.ndarray, fixed: np.ndarray) -> np.ndarray:
        """u with u[fixed] = 0, by layershell's own LinearSolver (symmetric PARDISO)."""
        free = np.setdiff1d(np.arange(self.ndof), fixed)
        u = np.zeros(self.ndof)
        u[free] = LinearSolver("auto").solve(K[free][:, free], f[free])
        return u

    def locate(self, param_points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Cell and reference coordinates (3, n, 1) of parameter points in the (affine) box."""
        P = self.box.p[:, self.box.t]  # (3, 8, n_el)
        lo, hi = P.min(axis=1), P.max(axis=1)
        tol = 1e-12 * (1 + np.abs(param_points).max())
        inside = np.all((param_points[:, :, None] >= lo[:, None, :] - tol)
                        & (param_points[:, :, None] <= hi[:, None, :] + tol), axis=0)
        assert inside.any(axis=1).all(), "a stress point lies outside the model"
        cells = np.argmax(inside, axis=1)
        X = self.box._mapping().invF(param_points[:, :, None], tind=cells)  # exact: the box is affine
        return cells, X

    def stress_at(self, u: np.ndarray, param_points: np.ndarray) -> np.ndarray:
        """Cauchy (small-strain) stress (n, 3, 3) at points given in parameter coordinates (3, n).

        The cell and the reference coordinates come from the (affine) parameter box; the curved
        mesh shares its connectivity and reference element, so the stress is evaluated at the
        image of the same reference point.
        """
        cells, X = self.locate(param_points)
        mapping = self.mesh._mapping()
        elem = ElementHex2()
        grad_u = np.zeros((param_points.shape[1], 3, 3))
        ed = self.basis.element_dofs[:, cells]  # (27, n)
        U = u.reshape(-1, 3)  # (N scalar, 3)
        invDF = mapping.invDF(X, tind=cells)  # (3, 3, n, 1), as in ElementH1.gbasis
        for a in range(27):
            g = np.einsum("ijkl,ikl->jk", invDF, elem.lbasis(X, a)[1])  # (3, n): ∇N_a
            grad_u += U[ed[a]][:, :, None] * g.T[:, None, :]  # ∂u_i/∂x_j
        eps = 0.5 * (grad_u + grad_u.transpose(0, 2, 1))
        E, nu = self.E[cells], self.nu[cells]
        lam = E * nu / ((1 + nu) * (1 - 2 * nu))
        mu = E / (2 * (1 + nu))
        tr = np.trace(eps, axis1=1, axis2=2)
        return lam[:, None, None] * tr[:, None, None] * np.eye(3) + 2 * mu[:, None, None] * eps


def _cyl(p: np.ndarray) -> np.ndarray:
    """(r, φ, z) → (x, y, z)."""
    return np.vstack([p[0] * np.cos(p[1]), p[0] * np.sin(p[1]), p[2]])


def solid_curved(n_r: int, n_phi: int, n_samples: int = 251) -> Result:
    """Curved beam as a solid: n_r elements through the thickness, n_phi (odd) along the arc."""
    assert n_phi % 2 == 1, "n_phi odd: the crown is the mid-plane of an element (nodes there)"
    t0 = time.perf_counter()
    s = Solid(np.linspace(A_IN, B_OUT, n_r + 1), np.linspace(0, np.pi, n_phi + 1), np.array([0.0, WIDTH]), _cyl,
              lambda c: (np.full(c.shape[1], E_BEAM), np.zeros(c.shape[1])))
    K = s.stiffness()

    def t_fn(p):  # end traction -σ_φ(r) e_y at both ends (MODEL.md E8); p = (r, φ, z)
        return np.stack([0 * p[0], -girkmann_sigma_phi(p[0]), 0 * p[0]])

    f = s.face_load(1, 0.0, t_fn) + s.face_load(1, np.pi, t_fn)
    # statically determinate support at the crown: A fully, B in x and z, C in x (6 rigid modes)
    nA, nB, nC = s.nearest_nodes(np.array([[0, B_OUT, 0], [0, A_IN, 0], [0, B_OUT, WIDTH]]))
    fixed = np.array([3 * nA, 3 * nA + 1, 3 * nA + 2, 3 * nB, 3 * nB + 2, 3 * nC])
    u = s.solve(K, f, fixed)
    r = np.linspace(A_IN, B_OUT, n_samples)
    pts = np.vstack([r, np.full_like(r, np.pi / 2), np.full_like(r, WIDTH / 2)])
    sig = s.stress_at(u, pts)  # at the crown e_φ = -e_x, e_r = e_y
    vals = {"sigma_phi_inner": float(sig[0, 0, 0]), "sigma_r_max": float(sig[:, 1, 1].max())}
    return Result("solid", f"n_r={n_r} n_phi={n_phi}", s.ndof - fixed.size, time.perf_counter() - t0, vals)


def shell_curved(n_arc: int, n_layers: int, directors: int) -> Result:
    """Curved beam in layershell: examples/curved_beam_1layer.toml, linear, n equal layers."""
    text = (ROOT / "examples" / "curved_beam_1layer.toml").read_text()
    text = text.replace("nonlinear = true", "nonlinear = false").replace("n_arc = 9", f"n_arc = {n_arc}")
    layers = "".join(f'[[layers]]\nname = "l{k}"\nmaterial = "mat"\nthickness = {2.5 / n_layers!r}\n'
                     f"directors = {directors}\n\n" for k in range(n_layers))
    text, n = re.subn(r"\[\[layers\]\].*?(?=# statically)", layers, text, flags=re.S)
    assert n == 1, "curved_beam_1layer.toml changed: [[layers]] block not found"
    _LOCATE["seconds"] = 0.0
    t0 = time.perf_counter()
    spec = build(parse(text, "curved_beam_vs_solid"), ROOT / "examples")
    res = run(spec, None, write_vtu=False)
    dt = time.perf_counter() - t0
    assert res.converged, res.message
    p = res.summary["probes"]
    vals = {"sigma_phi_inner": float(p["sigma_phi_inner"]), "sigma_r_max": float(p["sigma_r_max"])}
    return Result("layershell", f"n_arc={n_arc} layers={n_layers} d={directors}", int(res.summary["n_dofs"]),
                  dt, vals, locate_seconds=_LOCATE["seconds"])


# ---------------------------------------------------------------------------------------------
# the thick two-layer bonded cantilever plate under pressure
PL_L = 1.0  # span and width (m); half model 0 ≤ y ≤ L/2, symmetry plane y = L/2
PL_H1, PL_H2 = 0.1, 0.1  # bottom (reference face z = 0) and top layer thickness: L/h = 5
PL_MAT = {"bottom": (3.0e7, 0.2), "top": (1.0e7, 0.3)}  # (E kN/m², ν)
PL_P = 10.0  # pressure on the top face (kN/m²), downward
PL_POINT = (PL_L / 2, PL_L / 2)  # interface shear σ_xz at mid-span on the symmetry plane


def solid_plate(n_x: int, n_z1: int, n_z2: int) -> Result:
    """Plate as a solid: n_x × n_x/2 elements in plan, n_z1 / n_z2 through the layers."""
    assert n_x % 2 == 0
    t0 = time.perf_counter()
    z = np.concatenate([np.linspace(0, PL_H1, n_z1 + 1), np.linspace(PL_H1, PL_H1 + PL_H2, n_z2 + 1)[1:]])

    def material(c):
        bottom = c[2] < PL_H1
        return (np.where(bottom, PL_MAT["bottom"][0], PL_MAT["top"][0]),
                np.where(bottom, PL_MAT["bottom"][1], PL_MAT["top"][1]))

    s = Solid(np.linspace(0, PL_L, n_x + 1), np.linspace(0, PL_L / 2, n_x // 2 + 1), z, lambda p: p.copy(), material)
    K = s.stiffness()
    f = s.face_load(2, PL_H1 + PL_H2, lambda p: np.stack([0 * p[0], 0 * p[0], -PL_P + 0 * p[0]]))
    loc = s.basis.doflocs
    clamp = np.flatnonzero(np.isclose(loc[0], 0.0))
    sym = np.flatnonzero(np.isclose(loc[1], PL_L / 2))
    fixed = np.unique(np.concatenate([3 * clamp, 3 * clamp + 1, 3 * clamp + 2, 3 * sym + 1]))
    u = s.solve(K, f, fixed)
    # σ_xz on the upper side of the interface; x = L/2 is an element boundary: mean of both sides
    eps = 1e-9
    pts = np.array([[PL_POINT[0] - eps, PL_POINT[0] + eps], [PL_POINT[1]] * 2, [PL_H1 + eps] * 2])
    sig = s.stress_at(u, pts)
    vals = {"tau_xz_interface": float(sig[:, 0, 2].mean())}
    return Result("solid", f"n_x={n_x} n_y={n_x // 2} n_z={n_z1}+{n_z2}", s.ndof - fixed.size,
                  time.perf_counter() - t0, vals)


def plate_toml(n_x: int, n_sub: int, directors: int) -> str:
    """layershell model file of the plate: n_sub equal sublayers per material layer."""
    lines = ['[model]', 'title = "thick two-layer cantilever plate (vs_solid)"', 'units = "kN, m"',
             'nonlinear = false', f"thickness_points = {max(3, directors)}", "",
             "[mesh]", 'type = "rectangle"', f"lx = {PL_L}", f"ly = {PL_L / 2}", f"nx = {n_x}",
             f"ny = {max(1, n_x // 2)}", 'normal = "+z"', ""]
    for name, (E, nu) in PL_MAT.items():
        lines += [f"[materials.{name}]", 'type = "isotropic"', f"E = {E}", f"nu = {nu}", ""]
    layers = [(f"{m}{k}", m, hh / n_sub) for m, hh in (("bottom", PL_H1), ("top", PL_H2)) for k in range(n_sub)]
    for name, mat, hh in layers:
        lines += ["[[layers]]", f'name = "{name}"', f'material = "{mat}"', f"thickness = {hh!r}",
                  f"directors = {directors}", ""]
    for i, (name, _, _) in enumerate(layers):  # clamp: every point of the end section x = 0
        dirs = '"all"' if i == 0 else str(list(range(1, directors + 1)))  # u0 above follows the bond
        lines += ["[[supports]]", 'type = "fix"', 'where = "near(x, 0)"', f'layer = "{name}"',
                  f"directors = {dirs}", 'components = ["x", "y", "z"]', ""]
    lines += ["[[supports]]", 'type = "symmetry"', f'where = "near(y, {PL_L / 2})"', "normal = [0, 1, 0]", "",
              "[[loads]]", 'type = "surface"', 'face = "top"', "direction = [0, 0, -1]", f"magnitude = {PL_P}", "",
              "[steps]", "n = 1", "",
              "[[probes]]", 'name = "tau_xz_interface"', 'quantity = "traction"',
              f"point = [{PL_POINT[0]}, {PL_POINT[1]}, 0]", 'layer = "top0"', 'component = "13"', "",
              "[output]", "vtu = false", "plots = false"]
    return "\n".join(lines) + "\n"


def shell_plate(n_x: int, n_sub: int, directors: int) -> Result:
    """The plate in layershell (linear), from model-file text to the interface traction."""
    _LOCATE["seconds"] = 0.0
    t0 = time.perf_counter()
    spec = build(parse(plate_toml(n_x, n_sub, directors), "plate_vs_solid"), ROOT)
    res = run(spec, None, write_vtu=False)
    dt = time.perf_counter() - t0
    assert res.converged, res.message
    return Result("layershell", f"n_x={n_x} n_y={max(1, n_x // 2)} sublayers={n_sub} d={directors}",
                  int(res.summary["n_dofs"]), dt, {"tau_xz_interface": float(res.summary["probes"]["tau_xz_interface"])},
                  locate_seconds=_LOCATE["seconds"])


# ---------------------------------------------------------------------------------------------
# driver
def richardson(h_values: list[float]) -> tuple[float, float]:
    """Extrapolated value and observed order from three results on meshes refined by 2 each."""
    q1, q2, q3 = h_values
    p = float(np.log2(abs((q1 - q2) / (q3 - q2 if q3 != q2 else 1e-300))))
    return float(q3 + (q3 - q2) / (2**p - 1)), p


def with_errors(results: list[Result], ref: dict[str, float]) -> list[Result]:
    for r in results:
        r.errors = {k: abs(r.values[k] / ref[k] - 1) for k in ref}
    return results


def scan(fn, configs, ref: dict[str, float], label: str) -> list[Result]:
    out = []
    for c in configs:
        r = fn(*c)
        r.args = c
        with_errors([r], ref)
        errs = " ".join(f"{k}={r.values[k]:.5g} ({100 * r.errors[k]:.2f} %)" for k in ref)
        loc = f" (locate {r.locate_seconds:.2f})" if r.locate_seconds else ""
        print(f"  {label:6s} {r.model:10s} {r.config:38s} dofs={r.dofs:7d} t={r.seconds:7.2f} s{loc}  {errs}",
              flush=True)
        out.append(r)
    return out


def cheapest(fn, results: list[Result], repeats: int, n_candidates: int = 2) -> dict[str, Result] | None:
    """Among the 1 %-accurate runs: the fewest DOFs, the least wall time and the least wall time
    without probe location; the ``n_candidates`` smallest are re-timed (best of ``repeats``)."""
    ok = sorted((r for r in results if r.ok), key=lambda r: r.dofs)
    if not ok:
        return None
    for r in ok[:n_candidates]:
        for _ in range(repeats - 1):
            again = fn(*r.args)
            if again.seconds < r.seconds:
                r.seconds, r.locate_seconds = again.seconds, again.locate_seconds
    cand = ok[:n_candidates]
    return {"dofs": ok[0], "time": min(cand, key=lambda r: r.seconds), "net": min(cand, key=lambda r: r.net_seconds)}


def table(results: list[Result], keys: list[str]) -> str:
    head = ("| model | configuration | DOFs | seconds (without probe location) | "
            + " | ".join(f"{k} (error)" for k in keys) + " |")
    rows = [head, "|" + "---|" * (4 + len(keys))]
    for r in results:
        t = f"{r.seconds:.2f} ({r.net_seconds:.2f})" if r.locate_seconds else f"{r.seconds:.2f}"
        rows.append(f"| {r.model} | {r.config} | {r.dofs} | {t} | "
                    + " | ".join(f"{r.values[k]:.5g} ({100 * r.errors[k]:.2f} %)" for k in keys) + " |")
    return "\n".join(rows)


def compare(name: str, shell: dict[str, Result] | None, solid: dict[str, Result] | None) -> dict[str, float]:
    keys = [f"dof_ratio_{name}", f"time_ratio_{name}", f"time_ratio_{name}_nolocate"]
    if shell is None or solid is None:
        print(f"{name}: 1 % NOT reached by {'layershell' if shell is None else 'the solid'} in its family")
        return dict.fromkeys(keys, float("nan"))
    for label, m in (("layershell", shell), ("solid", solid)):
        print(f"{name}: {label:10s} fewest DOFs {m['dofs'].config}: {m['dofs'].dofs}; fastest {m['time'].config}: "
              f"{m['time'].seconds:.2f} s (without probe location: {m['net'].config}: {m['net'].net_seconds:.2f} s)")
    out = dict(zip(keys, (shell["dofs"].dofs / solid["dofs"].dofs, shell["time"].seconds / solid["time"].seconds,
                          shell["net"].net_seconds / solid["time"].seconds)))
    print(f"{name}: layershell / solid: DOFs {out[keys[0]]:.3f}, time {out[keys[1]]:.3f} "
          f"(without layershell's probe location {out[keys[2]]:.3f})")
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--case", choices=("curved", "plate", "both"), default="both")
    ap.add_argument("--quick", action="store_true", help="small families (a smoke test, ~1 min)")
    ap.add_argument("--repeats", type=int, default=2, help="timings of the cheapest runs: best of N")
    ap.add_argument("--fine-reference", action="store_true",
                    help="plate reference from solids 8/16/32 elements per span (~212k DOFs, 4.5 GB, minutes) "
                         "instead of 4/8/16")
    a = ap.parse_args()
    import os

    print(f"linear solver for both models: layershell LinearSolver -> {backend_name('auto')}; "
          f"scikit-fem {skfem.__version__}; load average {os.getloadavg()[0]:.1f} (2-core machine: timings noisy)")
    # warm-up (imports, Numba JIT, MKL), not timed
    shell_curved(3, 1, 2), solid_curved(2, 3), shell_plate(2, 1, 2), solid_plate(2, 1, 1)
    ratios: dict[str, float] = {}
    if a.case in ("curved", "both"):
        ref = girkmann_reference()
        print(f"\ncurved beam (§3.5.2, linear, ν = 0): Girkmann σ_φ(a) = {ref['sigma_phi_inner']:.5f}, "
              f"σ_r,max = {ref['sigma_r_max']:.5f} kN/m²")
        arcs = (9, 17) if a.quick else (9, 13, 15, 17, 21, 25)
        sh = scan(shell_curved, [(n, nl, d) for n in arcs for nl in ((1, 2) if a.quick else (1, 2, 3))
                                 for d in (3, 4)], ref, "curved")
        so = scan(solid_curved, [(nr, n) for n in arcs for nr in ((2, 8) if a.quick else (2, 4, 6, 8, 10, 12))],
                  ref, "curved")
        ratios |= compare("curved", cheapest(shell_curved, sh, a.repeats), cheapest(solid_curved, so, a.repeats))
        print("\n" + table(sorted(sh, key=lambda r: r.dofs) + sorted(so, key=lambda r: r.dofs), list(ref)) + "\n")
    if a.case in ("plate", "both"):
        print(f"\nplate (L = {PL_L}, h = {PL_H1}+{PL_H2}, E = {PL_MAT}, p = {PL_P}, clamped at x = 0): "
              "interface σ_xz at (L/2, L/2)")
        levels = [(8, 2, 2), (16, 4, 4), (32, 8, 8)] if a.fine_reference else [(4, 1, 1), (8, 2, 2), (16, 4, 4)]
        refruns = [solid_plate(*lv) for lv in levels]
        q = [r.values["tau_xz_interface"] for r in refruns]
        tau, order = richardson(q)
        for r in refruns:
            print(f"  reference  solid      {r.config:38s} dofs={r.dofs:7d} t={r.seconds:7.2f} s  "
                  f"tau_xz_interface={r.values['tau_xz_interface']:.6g}")
        print(f"  Richardson: tau_xz_interface = {tau:.6g} (observed order {order:.2f}; "
              f"finest mesh differs by {100 * abs(q[2] / tau - 1):.2f} %)")
        ref = {"tau_xz_interface": tau}
        nxs = (8, 16) if a.quick else (8, 16, 24, 32)
        sh = scan(shell_plate, [(n, s, d) for n in nxs for s, d in ((1, 2), (1, 3), (1, 4), (2, 3))
                                if s == 1 or n <= 16], ref, "plate")
        so = scan(solid_plate, [(n, z, z) for n in nxs for z in (1, 2, 3, 4) if n * z <= 128
                                and (n, z, z) not in levels], ref, "plate")
        ratios |= compare("plate", cheapest(shell_plate, sh, a.repeats), cheapest(solid_plate, so, a.repeats))
        print("\n" + table(sorted(sh, key=lambda r: r.dofs) + sorted(so, key=lambda r: r.dofs), list(ref)) + "\n")
    print("vs_solid: " + " ".join(f"{k}={v:.3f}" for k, v in ratios.items()))


if __name__ == "__main__":
    main()
