"""Linear (eigenvalue) buckling of the layered shell, bonded or with initial delaminations.

The prestress state u₀ is the geometrically linear solution under the model's loads and
prescribed displacements at load factor λ = 1: K₀ u₀ = F with u = T u_r + g (constraints.py).
Along the straight path u = λ u₀ the tangent of the nonlinear (Green-Lagrange) kinematics is

    K_T(λ u₀) = K₀ + λ K₁ + O(λ²),   K₁ = dK_T/dλ at λ = 0,

with K₁ the initial-stress (geometric) stiffness of the second Piola-Kirchhoff stresses of u₀
plus the initial-displacement part, both linear in u₀ (Wriggers, Nonlinear Finite Element
Methods, 2008, §7.3: the "linear buckling" eigenproblem). The element kernels give K_T exactly,
and K_T(u) is a quadratic polynomial in u (the strains, full and MITC9-tied, are quadratic in the
nodal vectors), so the central difference K₁ = (K_T(u₀) − K_T(−u₀)) / 2 is exact to round-off;
the kernels stay the vectorised ones of the nonlinear analysis. Buckling load factors λ_k and
modes φ_k solve (K₀ + λ K₁) φ = 0 in the reduced space (Tᵀ K T). They are found as the largest
eigenvalues μ = 1/λ of K₀⁻¹(−K₁) by SciPy's Lanczos (``eigsh``) with K₀ factorised once -
shift-invert about λ = 0, so the smallest positive buckling loads converge first.

A model with [[interfaces]] is analysed in its initial bond state, the state a run starts from
(:meth:`Problem.build <layershell.solver.problem.Problem.build>` with its interface controller):
bonded points are tied as in the bonded stack, points of an initially debonded zone leave both
layers free, and no contact acts there - the linear buckling of the open delamination (contact
would only stiffen a mode that closes the gap; an opening mode, as the local buckling of a
sub-laminate, is unaffected). A cohesive interface's intact points are tied as well, not held
by their penalty stiffness: the penalty approximates the tie (the default softens the stack
by at most about 2 %, ``cohesive_softening_estimate``), the tie is its exact limit, and the
cohesive law - stiff in compression, soft in tension where damaged - is not the quadratic
polynomial in u that the central difference for K₁ needs. Loads and prescribed displacements
that do not scale with λ (``scaled = false``) are refused, since the buckling factor multiplies
the whole load.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .model import Model
from .solver import linear
from .solver.problem import Problem


class BucklingError(ValueError):
    """A model that the linear buckling analysis cannot treat, with the reason and the fix."""


@dataclass
class BucklingResult:
    load_factors: np.ndarray  # (k,) the smallest positive buckling load factors, ascending
    modes: np.ndarray  # (k, n_full) full-space modes, largest face translation +1
    prestress: np.ndarray  # (n_full,) the linear state u₀ at λ = 1
    problem: Problem  # the tied problem (nonlinear kinematics, initial bond state) the modes belong to


def initial_bond_state(problem: Problem) -> None:
    """Turn a problem built with interface laws into the tied problem of its initial bond state:
    the bond flags of the run's start (thesis law: bonded except the initially debonded nodes),
    a cohesive interface tied except at its fully damaged (initially debonded) points; the
    contact and cohesive blocks removed (no contact, no penalty)."""
    from .solver.interface_state import CohesiveRun

    for r in problem.interfaces.runs:
        if isinstance(r, CohesiveRun):
            cb = r.block.contact
            free = np.zeros(problem.model.mesh.n_nodes, bool)
            free[cb.conn[:, cb.region][r.initial]] = True
            up, lo = cb.itf.upper, cb.itf.lower
            problem.bonded[up] = problem.dm.present[up] & problem.dm.present[lo] & ~free
    problem.interfaces, problem.extra_blocks, problem.F_friction = None, [], None
    problem.assembler.add_blocks([])
    problem.rebuild_constraints()


def _nonlinear_problem(model: Model) -> Problem:
    problem = Problem.build(dataclasses.replace(model, nonlinear=True))
    if problem.interfaces is not None:
        initial_bond_state(problem)
    if problem.extra_blocks or problem.assembler.extra:
        raise BucklingError("buckling analyses the bonded layer stack without contact or spring blocks; remove "
                            "them for the buckling analysis")
    if np.any(problem.F_const) or (problem.op.g_const is not None and np.any(problem.op.g_const)):
        raise BucklingError("buckling multiplies the whole load by the buckling factor, but the model has loads or "
                            "prescribed displacements with scaled = false; make them scaled (scaled = true) for "
                            "the buckling analysis")
    if not np.any(problem.F_scaled) and not problem.prescribed:
        raise BucklingError("the model has no loads and no prescribed displacements, so there is no prestress to "
                            "buckle under; add [[loads]] (the buckling factor multiplies them)")
    return problem


def _factorised(K: sp.spmatrix, backend: str):
    """A solve with the factorised, symmetric positive definite K₀ (BucklingError otherwise)."""
    if linear.backend_name(backend) == "pardiso":
        p = linear.PardisoSymmetric()
        try:
            p.solve(K, np.zeros(K.shape[0]))
        except linear.SingularSystemError as exc:
            raise BucklingError(f"the linear stiffness is singular ({exc}); the supports must prevent every "
                                "rigid-body motion") from None
        b = np.random.default_rng(0).standard_normal(K.shape[0])
        singular = p.info.perturbed_pivots and np.linalg.norm(K @ p.apply(b) - b) > 1e-6 * np.linalg.norm(b)
        if p.info.negative_pivots or singular:
            raise BucklingError("the linear stiffness is not positive definite (a rigid-body motion or mechanism "
                                "is not supported); check the supports with 'layershell check'")
        return p.apply
    try:
        lu = spla.splu(sp.csc_matrix(K), permc_spec="COLAMD")
    except RuntimeError as exc:
        raise BucklingError(f"the linear stiffness is singular ({exc}); the supports must prevent every "
                            "rigid-body motion") from None
    return lu.solve


def prestress(problem: Problem, solve0) -> np.ndarray:
    """u₀ = T u_r + g at λ = 1 from K₀ (the tangent at u = 0) and the factorised reduced K₀."""
    g = problem.impose(np.zeros(problem.dm.n_full), 1.0)
    _, K = problem.assembler.evaluate(np.zeros(problem.dm.n_full))
    r = problem.op.reduce(problem.external(1.0) - K @ g)
    return problem.op.expand(solve0(r)) + g


def reduced_tangent(problem: Problem, u: np.ndarray) -> sp.csr_matrix:
    """Tᵀ K_T(u) T as a plain CSR copy (the assembler may lend its arrays)."""
    _, K = problem.assembler.evaluate_reduced(u, problem.op, forces=False)
    return sp.csr_matrix((K.data.copy(), K.indices.copy(), K.indptr.copy()), shape=K.shape)


def stress_stiffness(problem: Problem, u0: np.ndarray) -> sp.csr_matrix:
    """K₁ = dK_T/dλ along u = λ u₀: (K_T(u₀) − K_T(−u₀)) / 2, exact for the quadratic K_T(u)."""
    return 0.5 * (reduced_tangent(problem, u0) - reduced_tangent(problem, -u0))


def normalised(problem: Problem, phi_r: np.ndarray) -> np.ndarray:
    """The full-space mode of reduced ``phi_r``, scaled to a largest face translation of +1."""
    phi = problem.op.expand(phi_r)
    dofs = problem.dm.translations()
    big = dofs[np.argmax(np.abs(phi[dofs]))]
    return phi / phi[big]


def linear_buckling(model: Model, n_modes: int = 1, backend: str = "auto") -> BucklingResult:
    """The ``n_modes`` smallest positive buckling load factors of ``model`` and their modes."""
    if n_modes < 1:
        raise BucklingError(f"the number of modes must be at least 1, got {n_modes}")
    problem = _nonlinear_problem(model)
    K0 = reduced_tangent(problem, np.zeros(problem.dm.n_full))
    n = K0.shape[0]
    if n_modes >= n:
        raise BucklingError(f"asked for {n_modes} modes, but the model has only {n} unknowns; ask for fewer modes")
    solve0 = _factorised(K0, backend)
    u0 = prestress(problem, solve0)
    K1 = stress_stiffness(problem, u0)
    scale = float(abs(K1).max())
    if scale == 0.0:
        raise BucklingError("the loads cause no stresses (the prestress state is stress-free), so nothing can "
                            "buckle; check the loads and supports")
    k = min(n - 1, max(2 * n_modes, n_modes + 4))  # a few more: the positive ones among the largest μ
    Minv = spla.LinearOperator((n, n), matvec=solve0, dtype=float)
    try:
        mu, vec = spla.eigsh(-K1 / scale, k=k, M=K0, Minv=Minv, which="LA", tol=1e-12)
    except (spla.ArpackNoConvergence, spla.ArpackError) as exc:
        raise BucklingError(f"the eigensolver did not converge ({exc}); ask for fewer modes (--modes)") from None
    mu = mu * scale
    keep = np.flatnonzero(mu > 1e-12 * np.max(np.abs(mu)))
    if keep.size == 0:
        raise BucklingError("the loads do not cause buckling (no positive buckling load factor: the stresses "
                            "stabilise the shell, e.g. tension); reverse the loads to study compression")
    order = keep[np.argsort(-mu[keep])][:n_modes]
    lam = 1.0 / mu[order]
    modes = np.stack([normalised(problem, vec[:, j]) for j in order])
    return BucklingResult(lam, modes, u0, problem)
