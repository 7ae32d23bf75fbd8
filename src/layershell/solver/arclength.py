"""Path following: adaptive load stepping and arc-length control with step-size control.

* Load control with automatic step size: Δλ grows after easy increments and is halved after a
  failed one, bounded by ``increment_max`` and ``increment_min``.
* Arc-length control (Riks 1979; Crisfield 1981, "A fast incremental/iterative solution
  procedure that handles snap-through", Comput. Struct. 13): the load factor is an unknown and
  the increment satisfies ‖w ∘ Δu_r‖² + ψ² Δλ² ‖q‖² = Δl² (ψ = 0: cylindrical, ψ = 1:
  spherical), q = Tᵀ F_scaled (Tᵀ(F_scaled − K g) where λ scales prescribed displacements g:
  displacement control by arc length, :func:`load_rate`), with w the length of each DOF (:func:`arc_weights`: t^l for a
  director coefficient u_l, so that Δl is a displacement). Each iteration solves
  K_r [a, b] = [r, q] with one factorisation (bordering by superposition, δu = a + δλ b); δλ is
  the root of the quadratic constraint closest to the previous increment (Crisfield). Predictor
  sign: the previous increment's direction (sign Δuₚᵣₑᵥ · δu_t > 0; Feng, Perić & Owen 1996); on
  the first increment and after an increment that changed the state (debonding) the work
  criterion sign(Δλ) = sign(qᵀδu_t)
  (load further where the current state is stable under load control, unload where it is not).
* Dissipation-based control (Gutiérrez 2004, Int. J. Numer. Meth. Engng 59; Verhoosel,
  Remmers & Gutiérrez 2009, Int. J. Numer. Meth. Engng 77): for damage with secant unloading the
  energy dissipated in an increment from (u₀, λ₀) is ΔG = ½ F̂ᵀ(λ₀ Δu − Δλ u₀), linear in the
  unknowns (where λ scales prescribed displacements g, plus ½(R₀ Δλ − λ₀ ΔR) with the reaction
  R = gᵀ f_int, :func:`dissipation_increment`); the constraint ΔG = Δτ replaces the arc length
  once a converged increment dissipated more than ``dissipation_threshold`` × the elastic energy
  ½ λ (F̂ᵀu + R) (Verhoosel's switch); where an increment cannot dissipate (elastic unloading,
  or a separated interface under prescribed displacements) it goes back to the arc length.

After a converged increment ``on_step_end(problem, u, λ)`` may change the state (debonding,
damage history); a True return re-solves the same increment (from the same start and with the
same constraint) in the new state. An increment whose debonded area grows by more than
``jump_area`` of the interface, or in which a watched probe grows more than ``jump_ratio`` times
faster than λ, is undone and cut; where cutting down to the minimum size does not help, it is
accepted with a warning (:func:`jump_warnings`).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from enum import Enum
from typing import Callable, Iterator

import numpy as np

from . import linear
from .newton import (FRICTION_STAGNATION, MAX_REFREEZE, RELAX_AFTER_CUTS, ActiveSetLoop, ConvergenceError,
                     NewtonResult, NewtonSettings, StepResult, active_set_blocks, at_round_off_floor,
                     check_stabilised_step, cohesive_hint, contact_hint, contact_to_nodes, dissipation_so_far, early_blocks, early_refreeze,
                     friction_acts, newton, reaction_scale, record_scale, relax, resolve, stabilise, stagnates,
                     implex_checked, next_increment, start_inertia)
from .path_state import End, PathState, Reason
from .problem import Problem, commit_state


#: default [steps] energy_tolerance (see :func:`increment_energy_error`)
ENERGY_TOLERANCE = 0.02


class PathError(ValueError):
    """A path-following setting that does not fit the model."""


@dataclass
class PathSettings:
    """[steps] settings of path following (see the model-file keys of the same names)."""

    control: str = "load"  # "load" (adaptive Δλ) or "arc_length"
    lambda_end: float = 1.0
    increment: float = 0.1  # first Δλ (load control); arc length: sets the first arc length
    increment_max: float | None = None  # default 10 × increment (load control)
    arc_length: float | None = None  # first Δl; default: ‖w ∘ Δu_r‖ of the linear predictor for ``increment``
    arc_length_min: float | None = None  # default arc_length / 1000
    arc_length_max: float | None = None  # default 10 × arc_length
    psi: float = 0.0
    dissipation: bool = True
    dissipation_threshold: float = 1e-3
    target_iterations: int = 8  # Newton iterations of a 'normal' increment: ×(8/its), within [½, 2]
    max_steps: int = 1000
    end_fraction: float = 1e-3  # arc length: the path ends when λ falls below this fraction of its peak
    # ... or when, past the peak and below STALL_FRACTION of it, λ has changed by less than
    # end_fraction × its peak over this many increments (the path stalls: complete failure)
    stall_increments: int = 25
    # a stuck arc length (a crawl, or an increment failing at its smallest size) tries one
    # load-controlled increment (λ + increment, halved on failure) before it stops
    load_rescue: bool = True
    max_cuts: int = 12
    max_jump_cuts: int = 5  # a jump that persists after this many halvings is accepted (with a warning)
    # NewtonSettings.unstable = "relax", load control: relax at the load of the increment after
    # this many cuts (or at the last cut)
    relax_after_cuts: int = RELAX_AFTER_CUTS
    jump_area: float | None = 0.2
    jump_ratio: float | None = 3.0
    # an increment whose energy balance error exceeds this share of its energy (the larger of its
    # external work and its dissipation, :func:`increment_energy_error`) is cut (at most
    # ``max_energy_cuts`` times), and the next increment is shortened to aim below it; None: off
    energy_tolerance: float | None = ENERGY_TOLERANCE
    max_energy_cuts: int = 3


@dataclass
class Attempt:
    converged: bool
    u: np.ndarray
    lam: float
    iterations: int
    residuals: list[float] = field(default_factory=list)
    message: str = ""
    # the constrained iterations' iterate of the smallest residual: (residual, u, λ, Δu_r, Δλ)
    best: tuple | None = None
    # the last constrained iterations ended early, near their solution, where the frozen sets no
    # longer held (EARLY_REFREEZE): not a converged state
    early: bool = False
    reason: Reason = Reason.NOT_CONVERGED  # why it did not converge (the branches of path_steps decide by it)


def check_path(problem: Problem, ps: PathSettings) -> None:
    """Raise PathError where arc-length control cannot work on ``problem``: λ must scale a load,
    forces (scaled [[loads]]) or prescribed displacements (a [[supports]] 'fix' with 'value')."""
    if ps.control != "arc_length":
        return
    if not np.any(problem.F_scaled) and prescribed_direction(problem) is None:
        raise PathError("'steps.control' = 'arc_length' scales the loads with the load factor λ, but the model has "
                        "no load with scaled = true (or its loads sum to zero) and no prescribed displacement "
                        "scaled by λ; add a scaled [[loads]] table or a [[supports]] type = 'fix' with 'value'")


def prescribed_direction(problem: Problem) -> np.ndarray | None:
    """g: the prescribed displacements per unit load factor (full space, u = T u_r + λ g + g_c),
    None where λ scales forces only."""
    g = getattr(getattr(problem, "op", None), "g_scaled", None)
    return g if g is not None and np.any(g) else None


#: the finite-difference step of :func:`stiffness_along`, relative to the displacements
FD_STEP = 1e-7


def stiffness_along(problem: Problem, u: np.ndarray, g: np.ndarray, f: np.ndarray | None = None) -> np.ndarray:
    """K(u) g (full space): the change of the internal force f_int along the prescribed
    displacements g, by a forward difference of step FD_STEP × max(|u|, |g|) / |g| (∞-norms).
    Exact to round-off on a linear bulk (f_int = K u); within the frozen cohesive sets of an
    active-set solve the interface law is smooth. It enters the Jacobian of the bordered system
    only (the column ∂r/∂λ, :func:`load_rate`), not the residual that decides convergence.
    ``f``: f_int(u) where known."""
    asm = problem.assembler
    if f is None:
        f, _ = asm.evaluate(u, tangent=False)
    gmax = float(np.abs(g).max())
    h = FD_STEP * max(float(np.abs(u).max()), gmax) / gmax
    f1, _ = asm.evaluate(u + h * g, tangent=False)
    return (f1 - f) / h


def load_rate(problem: Problem, u: np.ndarray, f: np.ndarray | None = None) -> np.ndarray:
    """−∂r/∂λ in full space at ``u``, r = F_ext(λ) − f_int(u(λ)) along u = T u_r + λ g + g_c: the
    scaled forces F̂, less K(u) g where λ scales prescribed displacements g (displacement control
    by arc length; :func:`stiffness_along`). The bordered arc-length system solves
    K_r [a, b] = [r, Tᵀ(F̂ − K g)] and steps u by T(a + δλ b) + δλ g."""
    g = prescribed_direction(problem)
    if g is None:
        return problem.F_scaled
    return problem.F_scaled - stiffness_along(problem, u, g, f)


def conjugates(problem: Problem, u: np.ndarray, f: np.ndarray | None = None) -> tuple[float, float]:
    """(v, R): the displacement work-conjugate to λ of the scaled forces, v = F̂ᵀu, and the force
    work-conjugate to λ of the prescribed displacements, R = gᵀ f_int(u) (their reaction; 0
    without). The external work rate is λ v̇ + R λ̇ (F̂ and g on different DOFs), and on a linear
    bulk at equilibrium the stored energy is ½ λ (v + R) - the terms of the dissipation
    constraint (:func:`dissipation_increment`). ``f``: f_int(u) where known."""
    v = float(problem.F_scaled @ u)
    g = prescribed_direction(problem)
    if g is None:
        return v, 0.0
    if f is None:
        f, _ = problem.assembler.evaluate(u, tangent=False)
    return v, float(g @ f)


def balance_terms(problem: Problem, u: np.ndarray) -> tuple[float, float, float, float] | None:
    """(external work W, energy dissipated D, balance error E = W − U − E_I − D, and E relative
    to the run's energy as summary.json reports it) of the cohesive energy ledger at the committed
    state ``u``; None without cohesive interfaces."""
    energies = getattr(problem.interfaces, "energies", None)
    e = energies(problem, u) if energies is not None else None
    if e is None:
        return None
    D = e["dissipated_fracture"] + e["dissipated_friction"] + e["dissipated_viscous"]
    return (e["external_work"], D, e["external_work"] - e["strain_energy"] - e["interface_elastic_energy"] - D,
            e["balance_error"])


#: an increment whose energy is below this share of the external work so far is not judged by
#: :func:`increment_energy_error` (round-off of the ledger, not an error of the path)
ENERGY_FLOOR = 1e-3
#: the energy-error step control acts once the run's balance error exceeds this (half the 1 %
#: at which the runner warns, ENERGY_WARN)
ENERGY_CONTROL_FROM = 0.005
#: |external work - stored - dissipated| / external work above which a run warns (runner._balance)
ENERGY_WARN = 0.01


def increment_energy_error(b0: tuple | None, b1: tuple | None) -> float:
    """The energy balance error an increment adds, |Δ(W − U − E_I − D)|, relative to its energy
    max(|ΔW|, ΔD) (at least ENERGY_FLOOR × |W|): 0 exactly on a path that the ledger follows.
    The trapezoidal work of the converged states and the interface ledger, which follows each
    interface point along the straight separation path between them, disagree where a point's
    path between two states is not straight (a mixed-mode front point that starts damaging in
    shear and fails open within one increment: examples/mmb_cohesive.toml, 7-26 % of the
    increment's energy on its default increments, always of one sign) or where a node row
    releases within one increment (the force-loaded DCB: up to 2 %, of either sign, so that the
    run's balance stays within 0.25 %). The error of an increment shrinks with its length, first
    order relative to its energy, so that the step-size control can aim at a tolerance."""
    if b0 is None or b1 is None:
        return 0.0
    dW, dD, de = b1[0] - b0[0], b1[1] - b0[1], b1[2] - b0[2]
    return abs(de) / max(abs(dW), dD, ENERGY_FLOOR * abs(b1[0]), 1e-300)


def energy_control(b0: tuple | None, b1: tuple | None, tolerance: float) -> float:
    """How far an increment from the ledger terms ``b0`` to ``b1`` (:func:`balance_terms`) exceeds
    the energy tolerance: its :func:`increment_energy_error` over the tolerance that applies (≤ 1
    is within), where the step control should act on it: the run's balance error is above
    ENERGY_CONTROL_FROM and this increment made it larger; else 0 (errors of either sign that
    cancel, as the DCB's, cost no increments). The tolerance falls linearly from ``tolerance`` at
    ENERGY_CONTROL_FROM to a tenth of it at the 1 % where the runner warns, so that the run's
    balance error approaches that limit ever more slowly."""
    if b0 is None or b1 is None or abs(b1[3]) <= ENERGY_CONTROL_FROM or abs(b1[2]) <= abs(b0[2]):
        return 0.0
    room = (ENERGY_WARN - abs(b1[3])) / (ENERGY_WARN - ENERGY_CONTROL_FROM)
    return increment_energy_error(b0, b1) / (tolerance * min(1.0, max(0.1, room)))


def dissipation_increment(problem: Problem, u0: np.ndarray, lam0: float, du: np.ndarray, dlam: float,
                          f_itf0: np.ndarray | None = None, reactions: tuple[float, float] | None = None,
                          friction: tuple[float, float] | None = None) -> float:
    """ΔG = ½ F̂ᵀ(λ₀ Δu − Δλ u₀): energy dissipated by secant-unloading damage in the increment
    (Gutiérrez 2004, eq. (19); Verhoosel et al. 2009, eq. (20)); where λ scales prescribed
    displacements g, their reaction R = gᵀf_int adds ½(R₀ Δλ − λ₀ ΔR) (the same derivation with λ
    as the displacement and R as the force: external work ½(R₀ + R₁)Δλ less the change of the
    stored ½ λ R; :func:`conjugates`; ``reactions``: (R₀, R₁) where known). With ``f_itf0`` (the
    interface forces at u₀, :func:`interface_form`) the interface form ½(f_I(u₀)·u − f_I(u)·u₀)
    instead. ``friction``: (c₀, c₁) of :func:`friction_excess` at the start and the end, whose
    difference the friction's stick springs add (they do not store the secant energy)."""
    extra = friction[1] - friction[0] if friction is not None else 0.0
    if f_itf0 is not None:
        f1, _ = interface_forces(problem, u0 + du)
        return 0.5 * (float(f_itf0 @ (u0 + du)) - float(f1 @ u0)) + extra
    F = problem.F_scaled
    dG = 0.5 * (lam0 * float(F @ du) - dlam * float(F @ u0))
    if prescribed_direction(problem) is not None:
        R0, R1 = reactions if reactions is not None else (conjugates(problem, u0)[1], conjugates(problem, u0 + du)[1])
        dG += 0.5 * (R0 * dlam - lam0 * (R1 - R0))
    return dG + extra


def friction_excess(problem: Problem, u: np.ndarray, gradient: bool = False) -> tuple[float, np.ndarray | None]:
    """c(u): the secant energy ½ uᵀf that the friction on the damaged share of the cohesive
    interfaces counts beyond what its stick springs store
    (:meth:`~layershell.cohesive.CohesiveBlock.friction_excess`), and (``gradient``) ∂c/∂u in
    the full space (zeros where no friction acts). Both forms of the dissipation constraint take
    the stored energy to be the secant one; the dissipation of an increment is ΔG + c(u) − c(u₀).
    Without Δc friction alone can meet the constraint: the lap shear with stiff friction
    (alpha_T = 1e6) at a tenth of the example's arc length would have 264 of its increments refused
    as friction's (FRICTION_REFUSED) and stop on its plateau, 1.3 % below its peak; with Δc 13 are,
    and the path goes on (tests/test_lapshear.py)."""
    c, grad = 0.0, (np.zeros(problem.dm.n_full) if gradient else None)
    for b in problem.assembler.extra:
        if not hasattr(b, "friction_excess"):
            continue
        cb, ge = b.friction_excess(u, gradient)
        c += cb
        if gradient and ge is not None:
            grad += np.bincount(b.dofs.ravel(), weights=np.asarray(ge).ravel(), minlength=problem.dm.n_full)
    return c, grad


def interface_form(problem: Problem) -> bool:
    """Is the dissipation of an increment measured at the interfaces? On a geometrically nonlinear
    model with cohesive interfaces. Gutiérrez's ΔG = ½ F̂ᵀ(λ₀ Δu − Δλ u₀) takes the stored energy
    to be ½ λ F̂ᵀu, true of a linear bulk only: on a nonlinear one an elastic increment 'dissipates'
    (the §5.1 plate with MITC9 on 6 × 6: Gutiérrez's form shrinks the dissipation-controlled
    increments to 10⁻⁷ of the first at λ = 0.895 and the path never reaches λ = 1).
    The energy the interfaces take, less what they store, does not involve the bulk:

        ΔG = ½(f_I(u₀) + f_I(u))·Δu − (ψ_I(u) − ψ_I(u₀)) = ½(f_I(u₀)·u − f_I(u)·u₀)

    (trapezoidal work of the interface forces f_I; ψ_I = ½ f_I·u for the secant law of
    :mod:`layershell.cohesive` and penalty contact, the separation linear in u). On a linear
    bulk at equilibrium (f_I = λF̂ − K_L u, K_L symmetric) it equals Gutiérrez's form exactly,
    which is kept there (linear in the unknowns)."""
    if not getattr(getattr(problem, "model", None), "nonlinear", False):
        return False
    from ..cohesive import CohesiveBlock

    return any(isinstance(b, CohesiveBlock) for b in problem.assembler.extra)


def interface_forces(problem: Problem, u: np.ndarray, v: np.ndarray | None = None
                     ) -> tuple[np.ndarray, np.ndarray | None]:
    """The interface blocks' internal force f_I(u) (full space) and, given ``v``, K_I(u)ᵀ v
    (their tangent at u, in its current frozen state, transposed, applied to v)."""
    n = problem.dm.n_full
    f = np.zeros(n)
    kv = None if v is None else np.zeros(n)
    for b in problem.assembler.extra:
        fe, Ke = b.response(u, tangent=v is not None)
        dofs = b.dofs
        f += np.bincount(dofs.ravel(), weights=np.asarray(fe).ravel(), minlength=n)
        if v is not None:
            kv += np.bincount(dofs.ravel(), weights=np.einsum("eij,ei->ej", Ke, v[dofs]).ravel(), minlength=n)
    return f, kv


def _frozen_blocks(problem: Problem) -> list:
    """The blocks with an active set. Contact: taken from the current gap in every iteration
    (semi-smooth; unfrozen here). Cohesive interfaces (``smooth_when_frozen``): returned, for the
    active-set loop of :func:`arc_attempt`, as in :func:`~layershell.solver.newton.newton` (the
    semi-smooth iteration cycles at the kink of the law at the onset of damage)."""
    blocks, cohesive_only = active_set_blocks(problem)
    for b in blocks:
        b.unfreeze()
    return blocks if cohesive_only else []


def arc_attempt(problem: Problem, u0: np.ndarray, lam0: float, size: float, mode: str,
                du_prev: np.ndarray | None, s: NewtonSettings, ps: PathSettings, lam_ref: float,
                f_itf0: np.ndarray | None = None) -> Attempt:
    """One increment from the equilibrium (u0, λ0) under the arc-length (``mode = "arc"``, Δl =
    ``size``) or the dissipation constraint (``"dissipation"``, Δτ = ``size``).

    Cohesive interfaces: an active-set loop around the constrained iterations, as in
    :func:`~layershell.solver.newton.newton`. The tension state and the loading set are frozen
    at u0 for the predictor (the points softening there keep softening in it), then at the
    predictor's end (the points ahead of the front that it overloads load from the first
    iteration on: the force-loaded DCB on 200 elements takes 101 instead of 118 increments and
    759 instead of 923 iterations), the constrained Newton iterations converge on the then
    smooth problem, the sets are checked at the solution and, where they changed, frozen there
    and the same increment iterated on, at most ``max_active_set_loops`` times. A frozen opening
    point that an iterate closes leaves the sets (:func:`_release_closed`). ``f_itf0``: the
    interface forces at u0 where the dissipation is measured at the interfaces
    (:func:`interface_form`). Where friction acts on a damaged share the dissipation
    constraint adds the change of :func:`friction_excess`."""
    op, asm = problem.op, problem.assembler
    blocks = _frozen_blocks(problem)
    loop = ActiveSetLoop(blocks, True)
    loop.freeze(u0)
    refreeze = MAX_REFREEZE
    early = early_blocks(problem, blocks)  # the friction caps change at commits only
    g = prescribed_direction(problem)  # λ scales prescribed displacements (displacement control)
    f0 = asm.evaluate(u0, tangent=False)[0] if g is not None else None
    rate0 = load_rate(problem, u0, f0)  # F̂ - K g
    q = op.reduce(rate0)
    R0 = float(g @ f0) if g is not None else 0.0  # the reaction at u0 (conjugates)
    qq = float(q @ q)
    solver = problem.linear_solver(s.backend, s.reuse_factorization)
    att = Attempt(False, u0, lam0, 0)
    fric_c0 = friction_excess(problem, u0)[0] if mode == "dissipation" and _friction_acts(problem) else None
    try:
        _, Kr = asm.evaluate_reduced(u0, op, forces=False)
        dut = problem.solve_tangent(Kr, q, s.backend, s.reuse_factorization)  # at the committed state
    except linear.SingularSystemError as exc:
        att.message = f"singular tangent ({exc})"
        return _unfrozen(att, blocks)
    dUt = op.expand(dut)  # the full-space predictor per unit λ
    if g is not None:
        dUt = dUt + g
    if mode == "arc":
        wt = dut * arc_weights(problem)
        dlam = size / math.sqrt(float(wt @ wt) + ps.psi**2 * qq)
        wf = full_weights(problem)
        if (float((du_prev * wf) @ (dUt * wf)) if du_prev is not None else float(q @ dut)) < 0.0:
            dlam = -dlam
    elif f_itf0 is not None:  # interface form (interface_form): ΔG ≈ ½(f_I(u₀) − K_Iᵀu₀)·Δu
        _, kv = interface_forces(problem, u0, u0)
        a1, a2 = 0.5 * float(f_itf0 @ dUt), 0.5 * float(kv @ dUt)
        if fric_c0 is not None:  # + Δc ≈ ∂c/∂u·Δu
            a1 += float(friction_excess(problem, u0, True)[1] @ dUt)
        if abs(a1 - a2) <= 1e-6 * (abs(a1) + abs(a2)):
            att.message, att.reason = Reason.NO_DISSIPATION.message, Reason.NO_DISSIPATION
            return _unfrozen(att, blocks)
        dlam = size / (a1 - a2)
    else:
        F = problem.F_scaled
        terms = [lam0 * float(F @ dUt), -float(F @ u0)]
        if fric_c0 is not None:  # + Δc ≈ ∂c/∂u·Δu (terms are halved below)
            terms.append(2.0 * float(friction_excess(problem, u0, True)[1] @ dUt))
        if g is not None:  # ½(R₀ Δλ − λ₀ ΔR), ΔR ≈ (K g)·Δu (dissipation_increment)
            terms += [R0, -lam0 * float((F - rate0) @ dUt)]
        den = 0.5 * sum(terms)
        # (displacement control: an interface that has separated leaves no reaction and nothing to
        # dissipate, and the predictor would move λ by more than its largest value so far)
        if (abs(den) <= 1e-6 * 0.5 * sum(abs(x) for x in terms)
                or (g is not None and abs(size) > lam_ref * abs(den))):
            att.message, att.reason = Reason.NO_DISSIPATION.message, Reason.NO_DISSIPATION
            return _unfrozen(att, blocks)
        dlam = size / den
    dur = dlam * dut
    if blocks:  # the sets where the predictor ends: the front points it overloads load from the start
        loop.freeze(u0 + op.expand(dur) + (dlam * g if g is not None else 0.0))
    for k in range(s.max_active_set_loops if blocks else 1):
        if k > 0 and not loop.freeze(att.u):
            att.message = "the cohesive loading set cycles (no consistent set near this increment)"
            return _unfrozen(att, blocks, loop, problem)
        left = s.max_contact_iterations - att.iterations if blocks else s.max_iterations
        att.best, att.early = None, False
        dur, dlam, ok = _constrained_iterations(problem, att, u0, lam0, size, mode, dur, dlam, s, ps, lam_ref,
                                                min(s.max_iterations, left),
                                                stagnation_window(s, blocks), f_itf0,
                                                early=early, at_start=(q, R0), fric_c0=fric_c0)
        if (not ok and refreeze > 0 and att.best is not None and att.iterations < s.max_contact_iterations
                and any(b.set_changed(att.best[1]) for b in blocks)):
            # as newton(): the frozen problem has no solution near this increment (its path turns
            # back before it), while the actual one goes on with other sets - freeze them again at
            # the best iterate, where they no longer hold, and iterate on from there
            refreeze -= 1
            _, att.u, att.lam, dur, dlam = att.best
            continue
        if not ok:
            return _unfrozen(att, blocks, loop, problem)
        if att.early:
            continue  # near the frozen problem's solution the sets changed: freeze them there
        if loop.consistent(att.u, (att.u, att.lam)):
            att.converged = True
            return _unfrozen(att, blocks, loop, problem)
    att.converged = False
    att.message = "cohesive loading set still changing after the allowed active-set loops"
    return _unfrozen(att, blocks, loop, problem)


def _unfrozen(att: Attempt, blocks: list, loop: ActiveSetLoop | None = None, problem: Problem | None = None) -> Attempt:
    """Unfreeze the blocks; a failed attempt takes the loop's accepted state, if any
    (:class:`~layershell.solver.newton.ActiveSetLoop`)."""
    if loop is not None and not att.converged:
        accepted = loop.accept(problem)
        if accepted is not None:
            att.u, att.lam = accepted
            att.converged, att.message = True, loop.accepted_message()
    for b in blocks:
        b.unfreeze()
    return att


def _constrained_iterations(problem: Problem, att: Attempt, u0: np.ndarray, lam0: float, size: float, mode: str,
                            dur: np.ndarray, dlam: float, s: NewtonSettings, ps: PathSettings, lam_ref: float,
                            max_iterations: int, stagnation: int = 0,
                            f_itf0: np.ndarray | None = None, early: list | None = None, *,
                            at_start: tuple[np.ndarray, float],
                            fric_c0: float | None = None) -> tuple[np.ndarray, float, bool]:
    """Newton iterations on equilibrium and the constraint from the increment (``dur``, ``dlam``);
    updates ``att`` (state, iterations, residuals, message); returns the increment and whether
    it converged. ``stagnation``: give up after that many iterations in a row without progress
    (:func:`~layershell.solver.newton.stagnates`; used with frozen cohesive sets). ``at_start``: the
    reduced load column q and the reaction R (0 without prescribed displacements) at u0, as
    :func:`arc_attempt` has them from the committed state. ``fric_c0``: :func:`friction_excess` at
    u0, where friction acts (the dissipation constraint adds c(u) − c(u0), linearised)."""
    op, asm = problem.op, problem.assembler
    g = prescribed_direction(problem)  # λ scales prescribed displacements: q = Tᵀ(F̂ − K g) per iteration
    q, R0 = at_start
    qq = float(q @ q)
    nq = math.sqrt(qq)
    Fc_r = op.reduce(problem.F_const)
    solver = problem.linear_solver(s.backend, s.reuse_factorization)
    start = att.iterations
    first = len(att.residuals)  # this call's residuals: att.residuals[first:]
    e0: float | None = None
    wr = arc_weights(problem)
    friction = _friction_acts(problem)  # its slip limits change at commits only
    for it in range(max_iterations + 1):
        lam = lam0 + dlam
        u = u0 + op.expand(dur)
        if g is not None:
            u = u + dlam * g
        _release_closed(asm, u)  # frozen opening points that the iterate closed
        f, _ = asm.evaluate(u, tangent=False)  # the tangent only where an iteration follows
        Fext = problem.external(lam)
        r = op.reduce(Fext - f)
        rn = float(np.linalg.norm(r))
        att.residuals.append(rn)
        att.u, att.lam, att.iterations = u, lam, start + it
        if np.isfinite(rn) and (att.best is None or rn < att.best[0]):
            att.best = (rn, u, lam, dur.copy(), dlam)
        if not np.isfinite(rn):
            att.message = "residual is not finite"
            return dur, dlam, False
        scale = nq * max(abs(lam), 1e-2 * lam_ref, 1e-300) + float(np.linalg.norm(Fc_r))
        if g is not None:  # as newton_fixed_set under displacement control: the reactions set the scale
            scale = reaction_scale(problem, f, Fext, float(np.linalg.norm(op.reduce(Fext))))
        if it > 0 and rn <= s.tol_residual * scale:
            if g is not None:
                record_scale(problem, scale)  # the floor of the residual's scale once the reactions vanish
            return dur, dlam, True
        if it > 0 and early_refreeze(early, u, rn, s.tol_residual * scale):
            att.early = True  # the sets changed near the frozen problem's solution
            return dur, dlam, True
        if it == max_iterations:
            break
        if stagnates(att.residuals[first:], stagnation):
            att.message = f"no progress in the last {stagnation} of {it} iterations (residual {rn:.3e})"
            return dur, dlam, False
        rate = None
        if g is not None:  # the column ∂r/∂λ at this iterate (after the checks: the last evaluation is at u)
            rate = load_rate(problem, u, f)
            q = op.reduce(rate)
        try:
            _, Kr = asm.evaluate_reduced(u, op, forces=False)
            ab = solver.solve(Kr, np.column_stack([r, q]))
        except linear.SingularSystemError as exc:
            att.message = f"singular tangent ({exc})"
            return dur, dlam, False
        a, b = ab[:, 0], ab[:, 1]
        # the round-off floor of the Newton iterations (at_round_off_floor): the equilibrium
        # correction a carries the energy; a negligible one ends the iterations where the
        # residual is within tol_floor (the §5.1 plate: 1.1e-8 of the load at λ = 0.04, MITC9)
        en = abs(float(a @ r))
        e0 = en if e0 is None else e0
        if it > 0 and at_round_off_floor(att.residuals[first:], scale, en, e0, a, u, s,
                                         lambda: abs(float(f @ u))):
            att.message = "converged at the round-off floor"
            return dur, dlam, True
        if mode == "arc":
            # ‖w ∘ (dur + a + δλ b)‖² + ψ²(Δλ + δλ)² qq = Δl²  (Crisfield 1981), the increments in
            # length units: each director's coefficient times t^l (arc_weights)
            w, bw, dw = (dur + a) * wr, b * wr, dur * wr
            A = float(bw @ bw) + ps.psi**2 * qq
            B = 2.0 * float(w @ bw) + 2.0 * ps.psi**2 * qq * dlam
            C = float(w @ w) + ps.psi**2 * qq * dlam**2 - size**2
            disc = B * B - 4.0 * A * C
            if disc < 0.0:  # no intersection: the point of the line closest to the constraint
                roots = [-B / (2.0 * A)]
            else:
                sq = math.sqrt(disc)
                roots = [(-B + sq) / (2.0 * A), (-B - sq) / (2.0 * A)]
            # the root whose increment keeps the direction of the current one
            dl = max(roots, key=lambda x: float((w + x * bw) @ dw) + ps.psi**2 * qq * (dlam + x) * dlam)
        elif f_itf0 is not None:
            # interface form (interface_form): g = ½(f_I(u₀)·u − f_I(u)·u₀) − Δτ, linearised with
            # ∂g/∂u = ½(f_I(u₀) − K_I(u)ᵀu₀): g + c·(A + δλ B) = 0 for δu = A + δλ B
            fI, kv = interface_forces(problem, u, u0)
            gc = 0.5 * (float(f_itf0 @ u) - float(fI @ u0)) - size
            c = 0.5 * (f_itf0 - kv)
            if fric_c0 is not None:  # + c(u) − c(u₀), linearised with ∂c/∂u
                cf, gf = friction_excess(problem, u, True)
                gc, c = gc + cf - fric_c0, c + gf
            cA, cB = float(c @ op.expand(a)), float(c @ (op.expand(b) + (g if g is not None else 0.0)))
            if cB == 0.0:
                att.message = "the dissipation constraint does not depend on λ here"
                return dur, dlam, False
            dl = -(gc + cA) / cB
        else:
            # ½ F̂ᵀ(λ₀ (Δu + a + δλ b) − (Δλ + δλ) u₀) = Δτ  (linear in δλ)
            F = problem.F_scaled
            A, B, dU = op.expand(a), op.expand(b), op.expand(dur)
            if g is not None:
                B, dU = B + g, dU + dlam * g
            Fa, Fb = float(F @ A), float(F @ B)
            Fu0, Fdu = float(F @ u0), float(F @ dU)
            gc = 0.5 * (lam0 * (Fdu + Fa) - dlam * Fu0) - size
            dg = 0.5 * (lam0 * Fb - Fu0)
            if fric_c0 is not None:  # + c(u) − c(u₀), linearised with ∂c/∂u
                cf, gf = friction_excess(problem, u, True)
                gc += cf - fric_c0 + float(gf @ A)
                dg += float(gf @ B)
            if g is not None:  # + ½(R₀ Δλ − λ₀ ΔR), R = gᵀf_int linearised with K g = F̂ − rate
                kg = F - rate
                gc += 0.5 * (R0 * dlam - lam0 * (float(g @ f) - R0)) - 0.5 * lam0 * float(kg @ A)
                dg += 0.5 * (R0 - lam0 * float(kg @ B))
            if dg == 0.0:
                att.message = "the dissipation constraint does not depend on λ here"
                return dur, dlam, False
            dl = -gc / dg
        eta = reversal_step(problem, u, op.expand(a + dl * b) + (dl * g if g is not None else 0.0)) if friction else 1.0
        if eta < 1.0:
            dur = dur + eta * (a + dl * b)
            dlam += eta * dl
        else:  # (the full correction, in the same floating-point order as without friction)
            dur = dur + a + dl * b
            dlam += dl
    att.message = f"no convergence in {max_iterations} iterations (last residual {att.residuals[-1]:.3e})"
    return dur, dlam, False


#: the smallest fraction of a Newton correction that :func:`reversal_step` takes
REVERSAL_STEP_MIN = 0.05


def reversal_step(problem: Problem, u: np.ndarray, dU: np.ndarray) -> float:
    """The fraction of the correction ``dU`` (full space) at the iterate ``u`` that the Newton
    iterations take: where friction acts on the damaged share of a cohesive interface, the
    largest that carries no sliding point past its anchor
    (:meth:`~layershell.cohesive.CohesiveBlock.reversal_step`), at least
    :data:`REVERSAL_STEP_MIN`; 1 elsewhere. The stopped point then sticks, and the next
    iteration has its stick stiffness. (Without it the TRC slab by arc length on 8 × 6
    stalls at 306.68 kN/m² on its snap-back, its residual at 0.25 kN, as about 30 sliding points
    reverse together from one iterate to the next.)"""
    eta = 1.0
    for blk in problem.assembler.extra:
        if hasattr(blk, "reversal_step"):
            eta = min(eta, blk.reversal_step(u, dU))
    return max(eta, REVERSAL_STEP_MIN)


def _friction_acts(problem: Problem) -> bool:
    """Does friction act on the damaged share of a cohesive interface of ``problem``?"""
    return friction_acts(active_set_blocks(problem)[0])


def stagnation_window(s: NewtonSettings, blocks: list) -> int:
    """Iterations without progress after which a frozen cohesive solve of an arc-length increment
    gives up (:func:`~layershell.solver.newton.stagnates`): ``stagnation_iterations``, at least
    :data:`~layershell.solver.newton.FRICTION_STAGNATION` where friction acts on a damaged share
    (its limited steps make slower progress), 0 (never) without cohesive blocks."""
    if not blocks:
        return 0
    if s.stagnation_iterations > 0 and friction_acts(blocks):
        return max(s.stagnation_iterations, FRICTION_STAGNATION)
    return s.stagnation_iterations


def _release_closed(asm, u: np.ndarray) -> None:
    """Before the forces at a new iterate: frozen cohesive points that it closes leave the
    opening and loading sets (:meth:`~layershell.cohesive.CohesiveBlock.release_closed`: the
    frozen law jumps there). Arc length only: in the load-controlled loop of
    :func:`~layershell.solver.newton.newton` it would make the displacement-controlled DCB stop
    early (δ = 4.2 instead of 10 mm on 150 elements, its loop cycling)."""
    for b in asm.extra:
        if getattr(b, "frozen", None) is not None and hasattr(b, "release_closed"):
            b.release_closed(u)


def jump_warnings(step: int, lam: float, lam_prev: float, area: float | None, area_prev: float | None,
                  probes: dict[str, float] | None, probes_prev: dict[str, float] | None,
                  jump_area: float | None, jump_ratio: float | None,
                  scales: dict[str, float] | None = None, floors: dict[str, float] | None = None) -> list[str]:
    """Warnings for a step in which the debonded fraction of the interface grew by more than
    ``jump_area`` or a probe grew more than ``jump_ratio`` times as fast as the load factor
    (|v/v_prev| > jump_ratio · max(1, |λ/λ_prev|), only where |v_prev| > 0). ``scales``: the
    largest |value| of each probe so far; a probe whose two values are both below 10⁻⁹ of it is
    round-off (a reaction after complete separation), not a jump. ``floors``: the noise floor of
    each probe, the size below which the solver does not resolve it (a reaction: the Newton
    tolerance times the run's force scale, see ``runner._ProbeFloors``); a probe whose two
    values are both below it is round-off too - e.g. the sum of the reactions that equilibrium
    makes zero, whose own largest value is round-off as well."""
    out = []
    if jump_area is not None and area is not None and area_prev is not None and area - area_prev > jump_area:
        out.append(f"step {step} (λ = {lam:.6g}): the debonded area jumped from {100 * area_prev:.3g} % to "
                   f"{100 * area:.3g} % of the interface in one step; reduce the step size or use control = "
                   "'arc_length' to follow the debonding")
    if jump_ratio is not None and probes and probes_prev:
        grow = max(1.0, abs(lam / lam_prev)) if lam_prev else 1.0
        for k, v in probes.items():
            v0 = probes_prev.get(k)
            if v0 is None or not np.isfinite(v) or not np.isfinite(v0) or abs(v0) <= 1e-12 * max(abs(v), 1e-300):
                continue
            if scales and max(abs(v), abs(v0)) <= 1e-9 * scales.get(k, 0.0):
                continue
            if floors and max(abs(v), abs(v0)) <= floors.get(k, 0.0):
                continue
            if abs(v / v0) > jump_ratio * grow:
                out.append(f"step {step} (λ = {lam:.6g}): probe '{k}' jumped from {v0:.6g} to {v:.6g} "
                           f"({abs(v / v0):.3g}× while λ changed {grow:.3g}×)")
    return out


def probe_scales(scales: dict[str, float], probes: dict[str, float] | None) -> dict[str, float]:
    """``scales`` updated with the |values| of ``probes`` (the largest of each so far)."""
    for k, v in (probes or {}).items():
        if np.isfinite(v):
            scales[k] = max(scales.get(k, 0.0), abs(float(v)))
    return scales


def path_steps(problem: Problem, s: NewtonSettings, ps: PathSettings, u0: np.ndarray | None = None,
               lam0: float = 0.0, step0: int = 0, state: PathState | None = None,
               on_step_end: Callable[[Problem, np.ndarray, float], bool] | None = None,
               measure: Callable[[Problem], float] | None = None,
               watch: Callable[[np.ndarray, float], dict[str, float]] | None = None,
               max_resolves: int = 200,
               floors: Callable[[np.ndarray], dict[str, float]] | None = None) -> Iterator[StepResult]:
    """Converged increments along the equilibrium path (see the module docstring); each
    :class:`StepResult` carries ``state`` (a :class:`PathState`) and ``warnings``. Ends at
    λ = ``lambda_end`` (load control, or arc length on a rising branch: the last increment is a
    load-controlled one to λ_end exactly), when λ falls below ``end_fraction`` of its peak
    (complete failure), or after
    ``max_steps`` increments. ``watch(u, λ)``: the probe values that the jump check watches;
    ``floors(u)``: their noise floors at the state u (:func:`jump_warnings`)."""
    check_path(problem, ps)
    u = np.zeros(problem.dm.n_full) if u0 is None else u0.copy()
    lam = lam0
    st = state or PathState()
    if st.finished:
        return
    arc = ps.control == "arc_length"
    if not st.mode:
        st.mode = "arc" if arc else "load"
        st.size = ps.increment
        if arc:
            st.arc_length = st.size = ps.arc_length if ps.arc_length is not None else _first_arc_length(problem, u, s, ps)
            st.arc_length0 = st.arc_length
    l0 = st.arc_length0
    # the smallest arc length (a user setting; the force-loaded 100-element DCB stops at δ = 10.7 mm
    # with this default)
    dl_min = ps.arc_length_min if ps.arc_length_min is not None else l0 / 1000.0
    dl_max = ps.arc_length_max if ps.arc_length_max is not None else 10.0 * l0
    inc_max = ps.increment_max if ps.increment_max is not None else 10.0 * ps.increment
    # the smallest Δλ: well below what max_cuts halvings of the first increment reach, since the
    # step-size control may already have shrunk the increment before a failure (a DCB's crack
    # advancing node by node needs 20-40 iterations a step, and each such step halves it)
    inc_min = ps.increment * 0.5 ** (ps.max_cuts + 8)
    area_prev = measure(problem) if measure is not None else None
    probes_prev = watch(u, lam) if watch is not None else None
    st.scales = probe_scales(st.scales, probes_prev)
    end = ps.lambda_end
    itf_form = interface_form(problem)  # the dissipation measured at the interfaces
    # λ scales prescribed displacements: after complete separation the path goes on elastically
    # (no reaction) to λ_end, under the arc length again (below)
    displacement_path = arc and prescribed_direction(problem) is not None
    for n in range(step0 + 1, ps.max_steps + 1):
        t0 = time.perf_counter()
        problem.begin_step()  # its first solve, at u, keeps the inertia of its tangent (stability.py)
        total_it, cuts, resolves = 0, 0, 0
        grown, size_refused = 0, 0.0  # growths of an increment refused as friction's (FRICTION_REFUSED)
        e0 = dissipation_so_far(problem)
        residuals: list[float] = []
        allow_jump = tried_dissipation = False
        warns: list[str] = []
        size0 = st.size
        f_itf0 = interface_forces(problem, u)[0] if itf_form else None  # the start's (committed) state
        # friction on a damaged share (its limits change at commits only): c of friction_excess at
        # the start, and at the end of the increment before its commit moves anchors and limits
        friction = arc and _friction_acts(problem)
        fric_c0 = friction_excess(problem, u)[0] if friction else None
        fric_c1 = fric_c0
        b0 = (balance_terms(problem, u) if arc and ps.energy_tolerance is not None and on_step_end is not None
              else None)  # the ledger at the start (energy_control)
        # the interfaces' ledger at the start (all dissipation, by damage): CONSTRAINT_BOOKED, unloading
        ledger0 = (ledger_booked(problem)
                   if on_step_end is not None and hasattr(problem.interfaces, "dissipation") else None)
        mat0 = material_booked(problem)  # the layers' materials' (cracking, yielding) at the start
        while True:
            snap = problem.snapshot() if on_step_end is not None else None
            att, to_end = _try_increment(problem, st, s, ps, u, lam, cuts, f_itf0)
            e_rel = 0.0
            total_it += att.iterations
            residuals += att.residuals
            ok, why, msg = att.converged, att.reason, att.message
            if ok and friction:
                fric_c1 = friction_excess(problem, att.u)[0]
            if ok and on_step_end is not None:
                a0 = measure(problem) if measure is not None else None
                while on_step_end(problem, att.u, att.lam):
                    resolves += 1
                    if (not allow_jump and a0 is not None and ps.jump_area is not None
                            and measure(problem) - a0 > ps.jump_area):
                        ok, why, msg = False, Reason.DEBONDING_JUMP, Reason.DEBONDING_JUMP.message
                        break
                    if resolves > max_resolves:
                        ok, why = False, Reason.STILL_CHANGING
                        msg = f"the state still changes after {max_resolves} re-solutions"
                        break
                    if st.mode == "load" or to_end:
                        # as load_steps (contact_to_nodes); a failure cuts the increment instead of settling
                        u_new, res = resolve(problem, att.u, att.lam, s, may_settle=False)
                        att = Attempt(res.converged, u_new, att.lam, res.iterations, res.residuals, res.message)
                    else:  # the same increment again under the same constraint in the new state
                        att = arc_attempt(problem, u, lam, st.size, st.mode, None, s, ps,
                                          max(st.lam_peak, abs(lam)), f_itf0)  # sign: the work criterion in the new state
                    total_it += att.iterations
                    residuals += att.residuals
                    if not att.converged:
                        ok, why, msg = False, att.reason, att.message
                        break
                    if friction:
                        fric_c1 = friction_excess(problem, att.u)[0]
            refused = (_constraint_refusal(problem, st, att, u, lam, to_end, cuts, (ledger0, mat0),
                                           displacement_path) if ok else None)
            if refused is not None:  # it meets its constraint for the wrong reason
                ok, why, msg = False, refused, refused.message
            refused = (_jumped(problem, st, ps, att, n, lam, measure, area_prev, watch, probes_prev, floors)
                       if ok and not allow_jump else None)
            if refused is not None:
                ok, why, msg = False, refused, refused.message
            if ok and b0 is not None and (st.mode != "load" or not st.rescue):
                # (b0: arc-length control; its stretches of load-controlled increments too - the
                # MMB's second rise to λ = 1, its crack still growing, takes increments too long for
                # the ledger without it: balance 1.8 % - but not a rescue, where a load-controlled increment
                # is the last resort: a node row that releases within it is a jump of the path,
                # which shorter increments do not resolve)
                e_rel = energy_control(b0, balance_terms(problem, att.u), ps.energy_tolerance)
                if e_rel > 1.0 and cuts < ps.max_energy_cuts:
                    ok, why, msg = False, Reason.ENERGY_BALANCE, Reason.ENERGY_BALANCE.message
            if ok:
                break
            if snap is not None:
                problem.restore(snap)
            if why is Reason.ENERGY_BALANCE:  # a converged increment too long for the ledger: shorter, same control
                cuts += 1
                st.size *= max(0.25, min(0.5, 0.8 / e_rel))
                continue
            if why is Reason.FRICTION_REFUSED and _friction_acts(problem):
                # too short an increment to damage: the constraint (secant unloading) is met by
                # the energy that the friction's stick springs and the contact give back - a longer
                # one damages. On the TRC slab's snap-back (16 × 12, 305.90 kN/m²) increments of
                # Δτ = 10⁻¹¹-10⁻⁷ book 2·10⁻¹¹-4·10⁻¹⁰ of damage, 10⁻⁶ to 10⁻³ book 81-100 %.
                # Where growing does not help (elastic unloading), cut from the refused size. An
                # increment longer than the last accepted one goes astray instead (the same slab
                # at 300.14 kN/m² after a node has debonded fully: Δτ = 8·10⁻⁵ ends at 143.7
                # kN/m², grown ones at -305 and -132): it is cut
                if grown < GROW_REFUSED and increment_length(problem, att.u - u) < st.arc_length:
                    size_refused = size_refused or st.size
                    grown += 1
                    st.size *= GROW_FACTOR
                    continue
                if size_refused:
                    st.size, size_refused = size_refused, 0.0
            if st.mode == "dissipation" and why is Reason.NO_DISSIPATION:
                # elastic branch: back to the arc length, its direction by the work criterion -
                # the previous direction (a snap-back: load and displacement falling while the
                # crack grew) would now follow elastic unloading down to λ = 0 (the DCB on 100
                # elements: 50 % of its interface debonded, then unloaded and "failed")
                st.mode, st.size, st.changed = "arc", st.arc_length, True
                continue
            if (st.mode == "arc" and ps.dissipation and not tried_dissipation and lam != 0.0
                    and not implex_only(problem)):
                # e.g. at a peak where damage starts: the arc length cannot pick the branch, the
                # dissipation constraint can (its predictor sign follows from the tangent)
                tried_dissipation = True
                st.mode = "dissipation"
                st.size = _first_dissipation(problem, u, lam, st.size)
                continue
            if st.mode == "dissipation" and tried_dissipation and cuts >= 3:
                # it did not help: the arc length again, cut - from at least arc_length_restart, not
                # from the length of the last accepted increment, which dissipation increments of
                # Δτ ~ 10⁻⁸ may have left at its smallest: a single try there stops the cohesive slab
                # on 8 × 6 on its plateau at 258.63 kN/m²
                st.mode, st.size = "arc", arc_length_restart(st.arc_length, st.arc_length0, dl_max)
            cuts += 1
            small = ((st.mode == "load" and st.size * 0.5 < inc_min)
                     or (st.mode == "arc" and st.size * 0.5 < dl_min))
            jump = why.jump
            limit = cuts > ps.max_cuts or small or (jump and cuts > ps.max_jump_cuts)
            if arc and st.mode == "load" and not st.rescue and (jump or cuts > STRETCH_CUTS or limit):
                # a stretch of load-controlled increments ends where one does not converge within
                # STRETCH_CUTS halvings, or jumps (a snap-back, or a peak): the arc length again
                # from the last state, its direction by the work criterion
                if st.stretch_accepted:
                    warns.append(f"step {n}: load-controlled increments took the path from load factor "
                                 f"{st.stretch_from:.6g} to {lam:.6g}; from there the arc length again (the next "
                                 f"load-controlled increment: {msg})")
                # (no new stretch until the arc length has passed the load the last failed increment aimed at)
                st.stretch_block, st.stretch_accepted = lam + st.size, 0
                st.mode, st.size, st.changed, cuts = "arc", st.arc_length, True, 0
                continue
            if st.mode == "load" and s.unstable == "relax" and not jump and (cuts > ps.relax_after_cuts or limit):
                # a step without equilibrium nearby fails at every size (the 100-element DCB spends
                # ~100 iterations on each of up to 20 cuts of the step before a snap-back): relax
                # at the load of the smallest cut to the next equilibrium
                rel = relax(problem, u, lam, lam + st.size, s, on_step_end)
                if rel is not None:
                    att = Attempt(True, rel.u, rel.load_factor, rel.iterations, rel.residuals)
                    total_it += rel.iterations
                    residuals += rel.residuals
                    st.size = size0  # the jump is behind: the size before the cuts, halved below
                    break
            if limit:
                then = _at_the_limit(problem, st, s, ps, n, lam, u, step0, cuts, jump, msg, size0, residuals)
                if then is _Then.END:
                    return  # complete failure: nothing left to carry the load (the tangent is singular)
                if then is _Then.ACCEPT_JUMP:
                    allow_jump = True  # cutting does not help: accept the jump, with a warning
                else:
                    cuts, tried_dissipation = 0, tried_dissipation or then is _Then.ARC
                continue
            st.size *= 0.5
        # accepted increment
        commit_state(problem, att.u)
        st.implex_mode, st.implex_size = st.mode, abs(att.lam - lam) if st.mode == "load" else st.size
        du = att.u - u
        dlam = att.lam - lam
        conj = conjugates(problem, att.u) if displacement_path else None  # (v, R) at the new state
        if displacement_path and math.isnan(st.reaction):
            st.reaction = conjugates(problem, u)[1]  # R at the start (first increment)
        dG = dissipation_increment(problem, u, lam, du, dlam, f_itf0,
                                   None if conj is None else (st.reaction, conj[1]),
                                   (fric_c0, fric_c1) if friction else None)
        st.dissipated += dG
        # the damage the interfaces' ledger and the layers' materials booked in this increment
        # (None: neither ledger)
        dD, damage = damage_booked(problem, ledger0, mat0)
        area = measure(problem) if measure is not None else None
        probes = watch(att.u, att.lam) if watch is not None else None
        warns += jump_warnings(n, att.lam, lam, area, area_prev, probes, probes_prev, ps.jump_area, ps.jump_ratio,
                               probe_scales(st.scales, probes), floors(att.u) if floors is not None else None)
        area_prev, probes_prev = area, probes
        # step-size control: grow after easy increments, shrink after hard ones (Crisfield 1981)
        _next_size(problem, st, ps, att, abs(dlam) if st.mode == "load" else st.size, cuts, e_rel, dG, du, conj,
                   friction, displacement_path, (inc_min, inc_max, dl_min, dl_max))
        if st.mode == "dissipation" and implex_only(problem):
            st.mode, st.size = "arc", st.arc_length  # the arc length alone (implex_only)
        st.du_prev = du
        # the next direction by the work criterion: after a re-solution (debonding), and always on
        # IMPL-EX layers alone (implex_only), whose tangent within an increment is positive definite
        st.changed = resolves > 0 or implex_only(problem)
        _stretch_bookkeeping(st, n, lam, att.lam, cuts, arc, warns)
        u, lam = att.u, att.lam
        st.reaction = conj[1] if conj is not None else math.nan
        peak_before, st.lam_peak = st.lam_peak, max(st.lam_peak, abs(lam))
        if (st.mode in ("arc", "dissipation") and stretch_may_start(ps, arc, displacement_path, cuts, lam, dlam,
                                                                     peak_before, st.stretch_block)):
            st.mode, st.size, st.stretch_accepted = "load", _rescue_increment(ps, lam), 0
        end_reason, crawl = _path_end(problem, st, ps, n, lam, dlam, du, dG, dD, damage, to_end, displacement_path,
                                      residuals, warns)
        if crawl and _may_rescue(ps, arc, lam):
            # one load-controlled increment next (Newton with its own active-set loop, which passes states
            # where the constrained iterations on frozen sets have no solution), as long as λ rises
            st.rescue, st.mode, st.size = crawl, "load", _rescue_increment(ps, lam)
            st.recent_lams, st.recent_dG = [], []
        check_stabilised_step(problem, n, lam, e0, s.stabilize_limit)
        res = StepResult(n, lam, u.copy(), total_it, residuals, cuts, time.perf_counter() - t0,
                         start_inertia(problem))
        res.state = st.copy()  # the state after this increment (the checkpoint stores it whole)
        res.warnings = warns
        res.dissipation = dG
        res.end = end_reason  # why the path ends here (an End), else None
        yield res
        if st.finished:
            return
        if crawl and not st.rescue:  # after the step is kept: the path cannot go on from it
            raise ConvergenceError(crawl, lam, residuals[-1] if residuals else float("nan"))


class _Then(Enum):
    """What follows an increment cut to its limit (:func:`_at_the_limit`)."""

    ACCEPT_JUMP = 1  # cutting does not help: accept the jump, with a warning
    ARC = 2  # the arc length alone from here, uncut
    RETRY = 3  # the same increment again, uncut, in a changed setting (constraint, stabilisation, contact)
    END = 4  # complete failure: the path ends


def _at_the_limit(problem: Problem, st: PathState, s: NewtonSettings, ps: PathSettings, n: int, lam: float,
                  u: np.ndarray, step0: int, cuts: int, jump: bool, msg: str, size0: float,
                  residuals: list[float]) -> "_Then":
    """An increment from (``u``, ``lam``) cut ``cuts`` times to its limit (``jump``: it jumped;
    ``msg``: why its last try failed; ``size0``: its size before the cuts): what follows, or
    ConvergenceError where nothing is left to try."""
    arc = ps.control == "arc_length"
    dl_max = ps.arc_length_max if ps.arc_length_max is not None else 10.0 * st.arc_length0
    if jump and st.rescue:  # a load-controlled rescue may not jump a snap-back
        raise ConvergenceError(
            st.rescue + f"; a load-controlled increment from it jumps ({msg} at every size down to "
            f"Δλ = {st.size:.3g}): the path snaps back there. Load control with [steps] unstable = "
            "'relax' passes the jump at a fixed load and reports the energy it releases",
            lam, residuals[-1] if residuals else float("nan"))
    if jump:
        return _Then.ACCEPT_JUMP
    if st.mode == "dissipation":  # once per increment: then the arc length alone
        # its direction by the work criterion, as after "no dissipation" above: past a
        # snap-back the previous direction follows elastic unloading down to λ = 0.
        # Its length: at least ARC_AFTER_DISSIPATION of the first (arc_length_restart)
        st.mode, st.changed = "arc", True
        st.size = arc_length_restart(st.arc_length, st.arc_length0, dl_max)
        return _Then.ARC
    if st.lam_peak > 0 and abs(lam) <= ps.end_fraction * st.lam_peak and n > step0 + 1:
        return _Then.END
    if st.mode == "load" and stabilise(problem, s, ps.increment, lam):
        st.size = ps.increment  # as load_steps: viscous from the converged state on
        return _Then.RETRY
    if contact_to_nodes(problem, u, lam, f"from load factor {lam:.6g} after {cuts} step cuts: {msg}"):
        st.size = size0  # as load_steps: the thesis's contact at the nodes from here on
        return _Then.RETRY
    if st.rescue:  # the load-controlled increment did not pass either
        raise ConvergenceError(st.rescue + f"; a load-controlled increment from it found no equilibrium "
                               f"either ({msg})", lam, residuals[-1] if residuals else float("nan"))
    stop = (f"step {n}: no equilibrium from load factor {lam:.6g} after {cuts} step cuts ({msg}); the "
            f"last converged load factor is {lam:.6g}"
            + (cohesive_hint(problem, s) if st.mode == "load" else "") + contact_hint(problem))
    if st.mode != "load" and _may_rescue(ps, arc, lam):
        st.rescue, st.mode, st.size = stop, "load", _rescue_increment(ps, lam)  # as after a crawl
        return _Then.RETRY
    raise ConvergenceError(stop, lam, residuals[-1] if residuals else float("nan"))


def _try_increment(problem: Problem, st: PathState, s: NewtonSettings, ps: PathSettings, u: np.ndarray, lam: float,
                   cuts: int, f_itf0: np.ndarray | None) -> tuple[Attempt, bool]:
    """One try of the next increment from (``u``, ``lam``) under the constraint ``st.mode`` of
    size ``st.size`` (``cuts``: its halvings so far): the Attempt, and whether it ends at λ_end
    (an arc-length increment that passes λ_end is replaced by a load-controlled one to it)."""
    end = ps.lambda_end
    to_end = False
    # IMPL-EX: the damage rate of the last accepted increment scaled to this one's size
    next_increment(problem, ratio=(st.size / st.implex_size if st.implex_mode == st.mode
                                   and st.implex_size > 0 else 1.0))
    if st.mode == "load":
        dlam = min(st.size, end - lam)
        to_end = lam + dlam >= end - 1e-12 * max(1.0, abs(end))
        trial = end if to_end else lam + dlam
        u_new, res = implex_checked(problem, newton(problem, u, trial, s), cuts)
        att = Attempt(res.converged, u_new, trial, res.iterations, res.residuals, res.message)
    else:
        att = arc_attempt(problem, u, lam, st.size, st.mode, None if st.changed else st.du_prev, s, ps,
                          max(st.lam_peak, abs(lam)), f_itf0)
        if att.converged:
            _, chk = implex_checked(problem, (att.u, NewtonResult(True, att.iterations, att.residuals)), cuts)
            if not chk.converged:
                att = Attempt(False, att.u, att.lam, att.iterations, att.residuals, chk.message)  # (IMPL-EX)
        if att.converged and att.lam > end and lam < end:  # passes λ_end: the last increment to it
            u_new, res = newton(problem, u, end, s)
            if res.converged:
                att = Attempt(True, u_new, end, att.iterations + res.iterations,
                              att.residuals + res.residuals)
                to_end = True
            elif st.end_cuts < END_CUTS:
                st.end_cuts += 1
                # load control has no equilibrium at λ_end from here: the increment passed a
                # snap-back on its way beyond λ_end (the MITC9 plate on 12 × 12: from 0.982
                # through the flap's debonding to 1.0245 in one increment). Shorter ones end
                # past the snap-back and below λ_end, from where λ_end is reached
                att = Attempt(False, att.u, att.lam, att.iterations + res.iterations,
                              att.residuals + res.residuals,
                              f"the increment passes λ_end = {end:g} (to {att.lam:.6g}), where load "
                              f"control from {lam:.6g} finds no equilibrium ({res.message})",
                              reason=Reason.PASSES_END)
    return att, to_end


def _jumped(problem: Problem, st: PathState, ps: PathSettings, att: Attempt, n: int, lam: float,
            measure: Callable | None, area_prev: float | None, watch: Callable | None,
            probes_prev: dict | None, floors: Callable | None) -> Reason | None:
    """Whether the converged increment ``att`` (number ``n``, from ``lam``) jumps: a stretch's
    load-controlled increment whose debonded area (``measure``) grew by more than ``jump_area``
    since ``area_prev``, or a watched probe that grew more than ``jump_ratio`` times faster than λ
    (:func:`jump_warnings`)."""
    if (ps.control == "arc_length" and st.mode == "load" and measure is not None and ps.jump_area is not None
            and area_prev is not None and measure(problem) - area_prev > ps.jump_area):
        # a rescue's (a stretch's) Newton solve updates the cohesive sets itself: a snap-back
        # it passes (half of the slab's interface debonding at once, no re-solution to see
        # it in) shows only in the converged increment's debonded area
        return Reason.DEBONDING_JUMP
    if (watch is not None and ps.jump_ratio is not None
            and jump_warnings(n, att.lam, lam, None, None, watch(att.u, att.lam), probes_prev, None, ps.jump_ratio,
                              st.scales, floors(att.u) if floors is not None else None)):
        return Reason.PROBE_JUMP
    return None


def _constraint_refusal(problem: Problem, st: PathState, att: Attempt, u: np.ndarray, lam: float, to_end: bool,
                        cuts: int, ledgers: tuple[tuple[float, float] | None, float | None],
                        displacement_path: bool) -> Reason | None:
    """Why the converged increment ``att`` from (``u``, ``lam``) is refused although it meets its
    constraint (it turned back, unloads elastically from a damaging state, or met the dissipation
    constraint without damage), else None. ``ledgers``: the interfaces' ledger and the layers'
    materials' dissipation at its start (:func:`ledger_booked`, :func:`material_booked`)."""
    ledger0, mat0 = ledgers
    if (st.mode == "arc" and not to_end and st.du_prev is not None and not st.changed and cuts < 3
            and float(((att.u - u) * (wf := full_weights(problem))) @ (st.du_prev * wf)) < 0.0):
        return Reason.TURNED_BACK  # cut; accepted after 3 cuts
    if (st.mode == "arc" and not displacement_path and lam == st.lam_damaged
            and elastic_unloading(problem, att.lam - lam, att.u - u, ledger0, mat0, att.u)):
        # from a state whose increment damaged, the arc length found the elastic unloading
        # branch (the work criterion's direction at an indefinite tangent; the MMB on 100
        # elements, its crack past the load point, would go from λ = 0.6078 down so,
        # 'unloads without damage'): the dissipation constraint next, which demands damage
        return Reason.ELASTIC_UNLOADING
    if (ledger0 is not None or mat0 is not None) and st.mode == "dissipation":
        # the constraint takes the stored energy to be the secant one; where the structure
        # unloads stiffer than the secant (crack faces closing, contact, friction) an
        # elastic path meets it without damage - the prescribed opening of the DCB on 100
        # elements would 'converge' from δ = 6.2 mm back to 0 in one increment. The interfaces'
        # and the layers' materials' own ledgers must book the dissipation (McNeice's cracking
        # slab by arc length met the constraint while it unloaded from 4.2 to 2.9 kN, and later
        # from 4.9 to 0.1 kN, its materials booking nothing). On displacement paths
        # all of it counts; on force paths only damage, and only where the load falls (friction's work on
        # sliding points meets the constraint while the cohesive slab on 16 × 12 unloads
        # from 180.8 kN/m², its fracture ledger flat to 10⁻⁷, while load control
        # rises smoothly through 180 to 325; docs/performance.md); a snap-back books damage.
        # (Counting rising force increments too would refuse the lap shear with friction's
        # unloading past its peak, which `unloading` below stops with a clearer message.)
        # A refused increment is cut, then tried by the arc length, then by a rescue
        if displacement_path:
            bulk = material_booked(problem, att.u) - mat0 if mat0 is not None else 0.0  # (its trial state)
            booked = (ledger_booked(problem)[0] - ledger0[0] if ledger0 is not None else 0.0) + bulk
            if booked < CONSTRAINT_BOOKED * st.size:
                return Reason.CLOSURE_REFUSED
        elif att.lam < lam:
            dD, _ = damage_booked(problem, ledger0, mat0, att.u)
            if dD is not None and dD < CONSTRAINT_BOOKED * st.size:
                cohesive = ledger0 is not None and problem.interfaces.cohesive()
                return Reason.FRICTION_REFUSED if cohesive else Reason.UNBOOKED
    if st.mode == "dissipation" and lam * att.lam < 0.0:
        # ΔG = ½F̂ᵀ(λ₀Δu − Δλu₀) is the dissipation of damage with secant unloading; past
        # λ = 0 the crack faces close and are stiffer than the secant, so an elastic path
        # through closure meets the constraint without any damage (the force-loaded DCB
        # on 150 elements would 'converge' from λ = 0.42 to -0.03 with its arms shut)
        return Reason.CROSSED_ZERO
    return None


def _next_size(problem: Problem, st: PathState, ps: PathSettings, att: Attempt, used: float, cuts: int,
               e_rel: float, dG: float, du: np.ndarray, conj: tuple[float, float] | None, friction: bool,
               displacement_path: bool, bounds: tuple[float, float, float, float]) -> None:
    """The constraint and size of the next increment after an accepted one of size ``used`` (Δλ,
    Δl or Δτ) in ``att.iterations`` Newton iterations and ``cuts`` halvings: grow after easy
    increments, shrink after hard ones (Crisfield 1981), aim below the energy tolerance
    (``e_rel``), switch to the dissipation constraint where the increment dissipated (Verhoosel et
    al. 2009) and back to the arc length where nothing is left to dissipate. ``bounds``: the
    smallest and largest Δλ and Δl."""
    inc_min, inc_max, dl_min, dl_max = bounds
    arc = ps.control == "arc_length"
    its = max(att.iterations, 1)
    history = st.recent if st.recent_mode == st.mode else []  # the last ones under this constraint
    fac = min(2.0, max(0.5, ps.target_iterations / its))
    if cuts:
        fac = min(fac, 1.0)  # no growth right after a cut
    elif (st.mode == "dissipation" and friction and used < DISSIPATION_INSENSITIVE_BELOW * st.dissipation_max
          and size_insensitive(used, its, st.recent_dissipation, ps.target_iterations)):
        # as below, where friction acts: each commit moves the friction's anchors and limits,
        # and the count no longer falls with the size (without this the lap shear with alpha_T = 1e5
        # holds Δτ at 0.2-0.7, 1/100 of its largest, by 8 iterations each: 703 instead of 142 increments)
        fac = max(fac, INSENSITIVE_GROWTH)
    elif (st.mode in ("load", "arc")
          # below INSENSITIVE_BELOW of the first increment; a stretch of load-controlled
          # increments at any size (the slab on 16 × 12 takes 6-10 iterations at Δλ = 0.4-5
          # kN/m², and the plain rule would shrink them from 5 to 0.4)
          and (used < INSENSITIVE_BELOW * (st.arc_length0 if st.mode == "arc" else ps.increment)
               or (arc and st.mode == "load"))
          and size_insensitive(used, its, history, ps.target_iterations)):
        fac = max(fac, INSENSITIVE_GROWTH)
    if st.mode in ("load", "arc"):
        st.recent = (history + [(used, its)])[-(ARC_WINDOW if arc else 1):]
        st.recent_mode = st.mode
    elif friction:
        st.recent_dissipation = (st.recent_dissipation + [(used, its)])[-ARC_WINDOW:]
        st.dissipation_max = max(st.dissipation_max, used)
    if e_rel > 0.5:
        fac = min(fac, max(0.25, 0.8 / e_rel))  # aim below the energy tolerance (its error ∝ the length)
    if st.mode == "load":
        st.size = min(max(st.size * fac, inc_min), inc_max)
    elif st.mode == "arc":
        st.size = st.arc_length = min(max(st.size * fac, dl_min), dl_max)
        elastic = 0.5 * abs(att.lam * sum(conj if conj is not None else conjugates(problem, att.u)))
        floor = ELASTIC_INCREMENT * st.dissipated if displacement_path else 0.0
        if ps.dissipation and dG > ps.dissipation_threshold * elastic and dG > floor:
            st.mode, st.size = "dissipation", dG  # Verhoosel et al. 2009: energy is dissipated
    else:  # arc_length_max bounds the dissipation-controlled increments too: the next Δτ is scaled
        # down where this one was longer (else a short bond's peak lies inside one increment)
        dun = increment_length(problem, du)
        st.size = st.size * fac * min(1.0, dl_max / max(dun, 1e-300))
        st.arc_length = max(min(dun, dl_max), dl_min)
        if displacement_path and dG <= ELASTIC_INCREMENT * st.dissipated:
            # nothing left to dissipate (the interface has separated, the reaction vanished):
            # the prescribed displacement goes on elastically, by the arc length
            st.mode, st.size = "arc", st.arc_length


def _stretch_bookkeeping(st: PathState, n: int, lam: float, lam_new: float, cuts: int, arc: bool,
                         warns: list[str]) -> None:
    """After increment ``n`` from ``lam`` to ``lam_new``: a load-controlled rescue that passed
    starts a stretch of load-controlled increments under arc-length control; a stretch counts
    its increments and ends (the arc length again) at one that needed a cut. Warnings to ``warns``."""
    if st.rescue:  # the load-controlled increment passed the crawl: a stretch of them goes on
        warns.append(f"step {n}: the arc length could not go on from load factor {lam:.6g} (its increments "
                     f"crawled or found no equilibrium); one load-controlled increment passed it to "
                     f"{lam_new:.6g} (a rising branch, where the constrained iterations on frozen cohesive sets "
                     "had no solution); load-controlled increments go on while they converge without a jump")
        st.rescue, st.stretch_from, st.stretch_accepted = "", lam, 1
    elif arc and st.mode == "load":
        if not st.stretch_accepted:
            st.stretch_from = lam
        st.stretch_accepted += 1
        if cuts:  # a load-controlled increment that needed a halving: near a peak (Zeno's approach
            # to it otherwise: the slab on 16 × 12 would go 323.5, 324.9, 325.29, 325.44, 325.456,
            # 325.465 kN/m², each with 1-2 halvings and 100-200 iterations): the arc length from here
            which = "one load-controlled increment" if st.stretch_accepted == 1 else "load-controlled increments"
            warns.append(f"step {n}: {which} took the path from load factor {st.stretch_from:.6g} to {lam_new:.6g}, "
                         f"on a rising branch where the arc length's increments needed cuts; from there the "
                         f"arc length again (this increment needed {cuts} halving(s))")
            st.stretch_block, st.stretch_accepted = lam_new + abs(lam_new - lam), 0
            st.mode, st.size, st.changed = "arc", st.arc_length, True
        elif st.stretch_accepted == 1:
            warns.append(f"step {n}: from load factor {lam:.6g}, on a rising branch where the arc length's "
                         f"increments needed cuts, load-controlled increments go on while they converge "
                         f"without a jump (to {lam_new:.6g} in this one)")


def _path_end(problem: Problem, st: PathState, ps: PathSettings, n: int, lam: float, dlam: float, du: np.ndarray,
              dG: float, dD: float | None, damage: float | None, to_end: bool, displacement_path: bool,
              residuals: list[float], warns: list[str]) -> tuple[End | None, str]:
    """After increment ``n`` (to ``lam``, by ``dlam`` and ``du``, dissipating ``dG``; ``dD``: the
    damage the interfaces' ledger booked in it, of ``damage`` so far): whether the path ends here
    (``st.finished`` and the End, else None), and the stop message where its increments crawl
    ("" otherwise). ConvergenceError where a force path unloads without damage."""
    end = ps.lambda_end
    grew = dD is not None and not displacement_path and beyond_round_off(dD, damage)
    if grew:
        st.lam_damaged = lam  # on the debonding branch (a stretch's load-controlled increments too)
    if st.mode == "load":
        st.finished = lam >= end - 1e-12 * max(1.0, abs(end))
    else:
        st.finished = (to_end or lam >= end  # complete failure: λ fell in an increment that damaged
                       or complete_failure(lam, dlam, st.lam_peak, dG if dD is None else dD,
                                           st.dissipated, ps.end_fraction))
        if (dD is not None and not displacement_path and not grew and not st.finished
                and unloading(lam, dlam, float(problem.F_scaled @ du), st.lam_damaged, st.lam_peak)):
            raise ConvergenceError(
                f"step {n}: from load factor {st.lam_damaged:.6g} the path unloads without damage "
                f"(λ = {lam:.6g} now, {100 * (st.lam_damaged - lam) / st.lam_peak:.3g} % of its peak "
                f"{st.lam_peak:.6g} lower; friction or elastic unloading only): the arc length has lost "
                f"the branch on which the interfaces debond - past a snap-back its constrained "
                f"iterations found no state with damage growth. The states up to here are kept; the "
                f"last with damage growth is at load factor {st.lam_damaged:.6g}. Load control "
                f"(control = 'load') with [steps] unstable = 'relax' passes the snap-back at a fixed "
                f"load and reports the energy it releases; or refine the mesh along the debonding front",
                lam, residuals[-1] if residuals else float("nan"))
    st.recent_lams = (st.recent_lams + [lam])[-ps.stall_increments:] if ps.stall_increments > 0 else []
    st.recent_dG = (st.recent_dG + [abs(dG)])[-ps.stall_increments:] if ps.stall_increments > 0 else []
    recent, recent_dG = st.recent_lams, st.recent_dG
    crawl = (not st.finished and st.mode != "load" and n < ps.max_steps
             and crawling(recent, recent_dG, ps.stall_increments, st.lam_peak, st.dissipated, ps.end_fraction))
    if (not st.finished and st.mode != "load"
            and stalled(recent, ps.stall_increments, st.lam_peak, ps.end_fraction)):
        st.finished = True
        warns.append(f"step {n}: the load factor stayed within {max(recent) - min(recent):.3g} of "
                     f"{lam:.4g} ({100 * abs(lam) / st.lam_peak:.2g} % of its peak {st.lam_peak:.4g}) over the "
                     f"last {len(recent)} increments: the path ends as complete failure")
    end_reason = None
    if st.finished:
        end_reason = End.LAMBDA_END if lam >= end - 1e-12 * max(1.0, abs(end)) else End.COMPLETE_FAILURE
    elif n == ps.max_steps:
        st.finished, end_reason = True, End.MAX_STEPS
    if not crawl:
        return end_reason, ""
    return end_reason, (
        f"step {n + 1}: the path no longer advances from load factor {lam:.6g} ({100 * abs(lam) / st.lam_peak:.3g} % "
        f"of its peak): over the last {len(recent)} increments λ stayed within {max(recent) - min(recent):.3g} "
        f"and they dissipated {sum(recent_dG):.3g}, {100 * sum(recent_dG) / st.dissipated:.2g} % of the energy "
        f"dissipated so far; the constrained iterations fail at every larger increment. The last converged "
        f"state is kept. Where the path is expected to rise to the design load, load control "
        f"(control = 'load') with [steps] stabilize passes such a state; else refine the mesh at the "
        f"debonding front")


def increment_length(problem: Problem, du: np.ndarray) -> float:
    """The length of the increment ``du`` (full space) in the arc length's measure: the
    independent DOFs, each director's coefficient times t^l (:func:`arc_weights`)."""
    return float(np.linalg.norm(du[problem.op.independent] * arc_weights(problem)))


def _may_rescue(ps: PathSettings, arc: bool, lam: float) -> bool:
    """May a stuck arc length (a crawl, or an increment that fails at its smallest size) try one
    load-controlled increment? ``PathSettings.load_rescue`` (on; not a model-file key), arc-length
    control, a positive load factor (the increment raises it)."""
    return ps.load_rescue and arc and lam > 0.0


#: an increment that passes λ_end where load control from its start has no equilibrium at λ_end is
#: cut, at most this many times in a run (past that, the path ends where the increment does,
#: beyond λ_end; a bound over the run, since shorter increments that end below λ_end approach
#: it Zeno-like where no start has load control reach it)
END_CUTS = 8


#: a stretch of load-controlled increments under arc-length control ends at the first increment
#: that does not converge within this many halvings (or jumps), or after one that needed them
STRETCH_CUTS = 1


def stretch_may_start(ps: PathSettings, arc: bool, displacement_path: bool, cuts: int, lam: float, dlam: float,
                      peak_before: float, block: float) -> bool:
    """After an accepted arc-length (or dissipation-controlled) increment: do load-controlled
    increments take over? On a force path (not a prescribed displacement), where the increment
    needed ``cuts`` and raised λ above its peak so far (a rising branch) and above ``block``,
    where the last stretch ended. On such a branch the equilibria of load control are the arc
    length's, and load control's Newton with its own active-set loop steps over the local
    snap-backs of single interface points that the arc length traces one by one: the cohesive
    slab on 16 × 12 (test_slab_trc_soffit.py) rises from 242.44 kN/m² by 5 kN/m² in one
    load-controlled increment (11 iterations), where its arc-length increments advance
    0.04-0.5 kN/m² each, with 4-7 cuts in every few. The stretch ends where a load-controlled
    increment fails within STRETCH_CUTS halvings or jumps, or after one that needed a halving
    (near a peak or a snap-back): the arc length traces it from there. (On displacement paths
    load control is the displacement control that the arc length's users chose not to run.)"""
    return (_may_rescue(ps, arc, lam) and not displacement_path and cuts > 0 and dlam > 0.0
            and lam >= peak_before and lam > block)


def _rescue_increment(ps: PathSettings, lam: float) -> float:
    """The first Δλ of a load-controlled rescue: the run's first increment (its cuts halve it)."""
    return max(ps.increment, abs(lam) * ps.end_fraction)


#: under displacement control by arc length, a dissipation-controlled increment that dissipated
#: less than this share of the energy dissipated so far was elastic (the interface has separated
#: completely): the arc length takes over again, and only an increment dissipating more switches
#: back to the dissipation constraint
ELASTIC_INCREMENT = 1e-6


def ledger_booked(problem: Problem) -> tuple[float, float]:
    """The energy the cohesive interfaces' ledger has booked as dissipated so far: in all
    (fracture, viscous, friction), and by damage alone (fracture and its viscous regularisation,
    not friction)."""
    return problem.interfaces.dissipated_total(), float(sum(problem.interfaces.dissipation()))


#: the refusal of a force path's dissipation-controlled increment that the interfaces booked as
#: friction rather than damage (:data:`CONSTRAINT_BOOKED`)
FRICTION_REFUSED = Reason.FRICTION_REFUSED  # (the message: FRICTION_REFUSED.message)
#: such an increment is grown by GROW_FACTOR up to GROW_REFUSED times before it is cut
GROW_FACTOR = 8.0
GROW_REFUSED = 6

#: under displacement control by arc length, a dissipation-controlled increment whose interfaces
#: booked less than this share of the prescribed dissipation Δτ (:func:`ledger_booked`) is not
#: accepted (closure)
CONSTRAINT_BOOKED = 0.5

#: load control and arc length: the growth of an increment whose iterations do not depend on its size
#: (:func:`size_insensitive`)
INSENSITIVE_GROWTH = 1.5
#: ... only for increments cut below this share of the first (the crawl after a jump). Above it
#: the plain rule keeps its finer steps where a crack front passes node by node (10-12
#: iterations at any size there): without the bound the ENF example takes 52 instead of 73 steps,
#: and its sampled peak falls from 721.8 to 715.8 N
INSENSITIVE_BELOW = 1.0 / 16.0


#: where friction acts, dissipation-controlled increments grow so below this share of the largest
#: so far: with 1/16 (as INSENSITIVE_BELOW) the lap shear with alpha_T = 1e6 at a quarter of the arc
#: length holds Δτ at 1/5-1/20 of its largest with 10-12 iterations at any size there, 735
#: increments (254 with 1/2; the peaks within 0.03 % of P_u)
DISSIPATION_INSENSITIVE_BELOW = 0.5


def size_insensitive(size: float, its: int, recent: list[tuple[float, int]], target: int) -> bool:
    """Does the iteration count of an increment not depend on its size? Against the last
    increments ``recent`` ((size, iterations) pairs: the last one under load control, the last
    ARC_WINDOW under the same constraint under arc-length control): at least 10 % longer than
    the shortest of them and no more than one iteration more than the most, or at least 10 %
    shorter than the longest and no more than one iteration fewer than the fewest; in both
    cases within twice the target. The
    step-size rule (size × target/its) assumes that a shorter increment converges in fewer
    iterations. Where a state that each commit changes sets the count, it does not:
    - load control: the thesis's slip-softening friction relaxing after the Gmsh plate's
      debonding jump at λ = 0.496 (increments of 10⁻⁵ to 3·10⁻⁴ all take 6-12 iterations, the
      first residual set by the committed friction, not by Δλ) would hold Δλ near 10⁻⁵ for 1000
      increments;
    - arc length: the cohesive slab on 16 × 12 (test_slab_trc_soffit.py) from 225 kN/m²,
      arc lengths of 8·10⁻⁶, 8·10⁻⁵ and 8·10⁻⁴ take 5, 7-9 and 9 iterations (the first
      iteration halves the residual, whatever its size, and every other increment's sets change
      once at its solution): 8·10⁻⁵, 1 % of the first, with 0.04 kN/m² per increment. Its
      counts alternate (7, 9, 7, ...), hence the window of two.
    Such increments, where cut below INSENSITIVE_BELOW of the first (in a stretch of
    load-controlled increments under arc-length control: at any size), grow by
    INSENSITIVE_GROWTH until the count rises with the size, exceeds twice the target, or an
    increment fails."""
    recent = [(x, n) for x, n in recent if x > 0.0]
    if not recent or its > 2 * target:
        return False
    sizes, counts = [x for x, _ in recent], [n for _, n in recent]
    return ((size >= 1.1 * min(sizes) and its <= max(counts) + 1)
            or (size * 1.1 <= max(sizes) and its >= min(counts) - 1))


#: arc-length control: the increments :func:`size_insensitive` compares with
ARC_WINDOW = 2


#: where the dissipation constraint fails through its cuts, the arc length takes over from at
#: least this share of its first length (:func:`arc_length_restart`)
ARC_AFTER_DISSIPATION = 1.0 / 16.0


def arc_length_restart(arc_length: float, arc_length0: float, arc_length_max: float = np.inf) -> float:
    """The length from which the arc length takes over an increment that the dissipation
    constraint could not make at any of its sizes: the length of the last accepted increment,
    but at least ARC_AFTER_DISSIPATION × the first arc length. After a crawl of short dissipation
    increments the last length is the smallest the arc length may take (arc_length_min, 1/1000 of
    the first by default), and it got a single try before the run stopped: the cohesive TRC slab
    by arc length on 8 × 6 stopped so at 266.28 kN/m² on its snap-back (Δτ down to 2·10⁻⁸ failed,
    then the arc length at 4.5·10⁻⁶ of the first 4.5·10⁻³), where arc lengths of 3·10⁻⁵ to 10⁻³
    from the same state converge in 10-32 iterations (either predictor direction). From the
    longer start the usual halvings still reach the smallest length. Never above
    ``arc_length_max`` (a user's maximum below 1/16 of the first length)."""
    return min(max(arc_length, ARC_AFTER_DISSIPATION * arc_length0), arc_length_max)


#: a stalled path (:func:`stalled`) ends as complete failure only below this fraction of its peak
STALL_FRACTION = 0.05


def stalled(recent: list[float], n: int, lam_peak: float, end_fraction: float) -> bool:
    """Has the path stalled after its peak? The last ``n`` accepted increments (load factors
    ``recent``) all lie below STALL_FRACTION of the peak and within ``end_fraction`` × the peak
    of each other. The DCB on 200 elements, its crack at the clamped end (99.4 % of the
    interface debonded), crawled at λ = 1.5 % of its peak through 1700 increments: the last
    bonded row holds an arm that is almost free, each increment's size is cut to nothing, and
    λ never falls below ``end_fraction`` × the peak."""
    return (n > 0 and len(recent) >= n and lam_peak > 0 and max(abs(x) for x in recent) <= STALL_FRACTION * lam_peak
            and max(recent) - min(recent) <= end_fraction * lam_peak)


def crawling(recent: list[float], recent_dG: list[float], n: int, lam_peak: float, dissipated: float,
             end_fraction: float) -> bool:
    """Has the path stopped advancing (anywhere, unlike :func:`stalled`)? Over the last ``n``
    accepted increments λ stayed within ``end_fraction`` × its peak and they dissipated less
    than ``end_fraction`` of the energy dissipated so far: the increments have been cut to
    nothing. (A plateau of the load, such as a long bond's debonding at P_u, dissipates a good
    share per increment and goes on.) The geometrically nonlinear §5.1 plate with friction
    (MITC9, 6 × 6) crawled at λ = 0.8953 through increments of 10⁻⁷ of the first; it reaches
    λ = 1 without friction or without geometric nonlinearity."""
    return (n > 0 and len(recent) >= n and len(recent_dG) >= n and lam_peak > 0 and dissipated > 0
            and max(recent) - min(recent) <= end_fraction * lam_peak
            and sum(recent_dG) <= end_fraction * dissipated)


def complete_failure(lam: float, dlam: float, lam_peak: float, dG: float, dissipated: float,
                     end_fraction: float) -> bool:
    """Does an accepted increment end the path by complete failure? λ fell (Δλ < 0) below
    ``end_fraction`` of its peak in an increment that dissipated energy: not elastic unloading
    (ΔG at round-off), which can take λ to 0 as well - the DCB on 100 elements, half its
    interface debonded, unloaded along its secant and was reported as failed."""
    return (lam_peak > 0 and dlam < 0 and lam <= end_fraction * lam_peak
            and beyond_round_off(dG, dissipated))


#: a force path by arc length whose load factor fell by this share of its peak since the last
#: increment that damaged an interface has left the debonding branch (:func:`unloading`)
UNLOADING_FRACTION = 0.05


def unloading(lam: float, dlam: float, work_rate: float, lam_damaged: float, lam_peak: float) -> bool:
    """Does a force path unload without damage? In this increment the load and its work-conjugate
    displacement both fell (Δλ < 0, ``work_rate`` = F̂·Δu < 0), and λ lies by more than
    :data:`UNLOADING_FRACTION` of its peak below the λ of the last increment that booked damage.
    On a force path by arc length the load and the displacement fall together where the
    interfaces debond (a snap-back) or after complete failure; a path that does so without
    damage follows elastic or frictional unloading, an equilibrium path but not the structure's
    response to its load: the cohesive soffit slab (docs/performance.md, with a release rule not
    kept) went from λ = 278 to 0 so (its friction met the dissipation constraint) and ended as
    'complete failure' with 1.5 % of its interface debonded. (Past an elastic limit point,
    buckling, the load falls while the displacement grows: not unloading.)"""
    return (dlam < 0 and work_rate < 0 and lam_peak > 0 and math.isfinite(lam_damaged)
            and lam < lam_damaged - UNLOADING_FRACTION * lam_peak)


def elastic_unloading(problem: Problem, dlam: float, du: np.ndarray, ledger0: tuple[float, float] | None,
                      mat0: float | None = None, u: np.ndarray | None = None) -> bool:
    """Does a converged force-path increment (Δλ = ``dlam``, Δu = ``du``, to ``u``) unload
    without damage? The load and its work-conjugate displacement fall (Δλ < 0, F̂·Δu < 0) while
    the cohesive interfaces and the layers' materials book no damage since ``ledger0`` and
    ``mat0`` (:func:`damage_booked`; neither ledger: False). From a state on the damaging branch
    both branches are equilibria; arc-length control is to follow the one that damages
    (:func:`unloading` ends a path that has followed the other far)."""
    if dlam >= 0.0:
        return False
    dD, damage = damage_booked(problem, ledger0, mat0, u)
    return dD is not None and float(problem.F_scaled @ du) < 0.0 and not beyond_round_off(dD, damage)


def implex_only(problem: Problem) -> bool:
    """Do only layers integrated by IMPL-EX dissipate (no cohesive interface)? Then the arc length
    alone follows the path, without Verhoosel's switch to the dissipation constraint. Within an
    increment such a layer acts with the damage extrapolated from the last increments, so the
    damage the increment adds is set before its iterations, and the constraint ΔG = Δτ can only
    choose λ to match it: on McNeice's cracking slab by arc length every dissipation-controlled
    increment from 7.2 kN on converged with λ falling (from λ = 0.600, Δτ = 11.4 to 0.582, half
    of it to 0.286, and so on down with each cut), its layers booking no dissipation, while the
    arc length's increments rise with load control's in 3 iterations each."""
    mats = getattr(getattr(problem, "assembler", None), "materials", None)
    if mats is None or not mats.active or getattr(mats, "integration", "") != "implex":
        return False
    cohesive = getattr(getattr(problem, "interfaces", None), "cohesive", None)
    return not (cohesive is not None and cohesive())


def material_booked(problem: Problem, u: np.ndarray | None = None) -> float | None:
    """The energy the layers' materials (concrete cracking and crushing, steel yielding) have
    dissipated: committed, or in the trial state at ``u`` before its commit; None where no layer
    has a material with a history."""
    asm = getattr(problem, "assembler", None)
    mats = getattr(asm, "materials", None)
    if mats is None or not mats.active:
        return None
    return asm.material_dissipation(u)


def damage_booked(problem: Problem, ledger0: tuple[float, float] | None, mat0: float | None,
                  u: np.ndarray | None = None) -> tuple[float | None, float | None]:
    """(booked in the increment, booked so far) of the damage energy: the cohesive interfaces'
    ledger since ``ledger0`` (:func:`ledger_booked`) and the layers' materials' dissipation
    since ``mat0`` (:func:`material_booked`, at the trial state ``u`` where given); (None, None)
    where there is neither ledger."""
    cohesive = ledger0 is not None and problem.interfaces.cohesive()
    if not cohesive and mat0 is None:
        return None, None
    so_far = ledger_booked(problem)[1] if cohesive else 0.0
    dD = so_far - ledger0[1] if cohesive else 0.0
    if mat0 is not None:
        m = material_booked(problem, u)
        so_far, dD = so_far + m, dD + m - mat0
    return dD, so_far


def beyond_round_off(booked: float, total: float) -> bool:
    """Did an increment book ``booked`` (dissipated or damage energy) beyond round-off of the
    ``total`` booked so far?"""
    return booked > 1e-9 * max(total, 1e-300)


def full_weights(problem: Problem) -> np.ndarray:
    """Per full-space DOF the length by which its coefficient moves its layer's far face: t^l
    for director l of a layer of (nodal) thickness t (u = Σ (Θ³)^l u_l, 0 ≤ Θ³ ≤ t; MODEL.md
    (2.17)), 1 for the displacements u_0 and for DOFs of no layer. Built once per problem (the
    DOF map does not change; the turn-back check and every arc attempt use it)."""
    w = getattr(problem, "_full_weights", None)
    if w is not None:
        return w
    w = np.ones(problem.dm.n_full)
    for ld, ly in zip(problem.dm.layer_dofs, problem.model.layers):
        t = np.broadcast_to(np.asarray(ly.thickness, float), (ld.shape[0],))
        for l in range(1, ld.shape[1]):
            idx = ld[:, l, :]
            ok = idx >= 0
            w[idx[ok]] = np.broadcast_to((t**l)[:, None], idx.shape)[ok]
    problem._full_weights = w
    return w


def arc_weights(problem: Problem) -> np.ndarray:
    """:func:`full_weights` of the reduced (independent) DOFs: the arc length and the sizes of
    the path increments are measured in length units, ‖w ∘ Δu_r‖. The director coefficients
    u_l carry length^(1-l): in the plain DOF norm the cubic director of the 10 mm TRC layer of the
    §5.1 plate (MITC9, 12 × 12) made up 99.97 % of an increment, so the constraint controlled
    that layer's thickness change instead of the plate's deflection, and the second increment
    converged at λ = -0.39 from +0.04 with the same Δu. Cached per constraint operator."""
    op = problem.op
    cache = getattr(problem, "_arc_weights", None)
    if cache is not None and cache[0] is op:
        return cache[1]
    wr = full_weights(problem)[op.independent]
    problem._arc_weights = (op, wr)
    return wr


def _first_dissipation(problem: Problem, u: np.ndarray, lam: float, dl: float) -> float:
    """A first Δτ: the elastic energy ½ λ F̂ᵀu times the relative size of the arc length."""
    un = increment_length(problem, u)  # the state's length from 0
    return 0.5 * abs(lam * sum(conjugates(problem, u))) * min(1.0, dl / max(un, 1e-300)) * 0.5


def _first_arc_length(problem: Problem, u: np.ndarray, s: NewtonSettings, ps: PathSettings) -> float:
    """‖w ∘ δu_r‖ (:func:`arc_weights`) of the linear predictor for the load increment ``ps.increment``."""
    _, Kr = problem.assembler.evaluate_reduced(u, problem.op, forces=False)
    dut = problem.solve_tangent(Kr, problem.op.reduce(load_rate(problem, u)), s.backend, s.reuse_factorization)
    return abs(ps.increment) * float(np.linalg.norm(dut * arc_weights(problem)))
