"""Newton-Raphson with load stepping and automatic bisection, MODEL.md §5 (2.269)-(2.272).

Each iteration solves K_r Δu_r = Tᵀ(λ F_a - f(u)) and updates u = u + T Δu_r. Convergence:
relative residual ``‖r‖ ≤ tol_residual · ‖Tᵀ λF‖``; or, when the residual stalls at the
round-off floor of an ill-conditioned (slender, multi-layer) system, ``‖r‖ ≤ tol_floor · ‖Tᵀ λF‖``
together with a negligible energy ``|Δu·r| ≤ tol_energy · |Δu₀·r₀|`` - or, once the residual
has stalled (not halved by the last iteration), ``≤ tol_energy · |f·u|``, the work of the internal
forces on the displacements: the first correction alone made the test depend on the step size
(a bisected step's first correction is small, and the cohesive §5.1 plate on 12 × 12 (MITC9)
stalled at 1.1·10⁻⁸ > 10⁻⁸ with |Δu·r| ~ 10⁻²³ through all its bisections; there the round-off
of the penalty-coupled layers, ε K |u| per point, is of the order of the tolerance) - or a
negligible correction ``‖Δu‖ ≤ tol_displacement · ‖u‖``; or when the residual less each
entry's own round-off, ε Σ_j |K_gj u_j| (:func:`above_round_off`), is within the tolerance: the
entries of a director l carry units of force × length^l, so those of the quadratic directors of
a thick layer in mm (terms of 10¹¹ N·mm² at a few mm of deflection) stall far above the others
(a 160 mm slab under load: at 3.6·10⁻⁸ of the load; the cracked slab of a TRC strip at
1.1·10⁻⁵, above the tolerance 10⁻⁵ and tol_floor, tests/test_newton_floor.py).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from typing import Callable, Iterator

import numpy as np

from . import linear
from .problem import Problem, commit_state


#: the round-off of an internal-force entry in machine epsilons times Σ_j |K_gj u_j|: twice the
#: largest seen (the entries of a TRC strip's 160 mm slab at its quadratic directors stalled at
#: 0.06-0.93 of it, 1.1·10⁻⁵ of the load)
ROUND_OFF_TERMS = 2.0
#: the round-off floor decides only for residuals within this factor of the tolerance: a state
#: drifted along a mechanism (the free column of tests/test_settle.py, 10¹¹ mm) has a floor above
#: any residual (10⁶ times the tolerance there), while stalls at the floor lie 1-10³ times above it
ROUND_OFF_REACH = 1e4


@dataclass
class NewtonSettings:
    tol_residual: float = 1e-8
    tol_energy: float = 1e-20
    tol_displacement: float = 1e-10
    tol_floor: float = 1e-5
    max_iterations: int = 25
    max_bisections: int = 8
    backend: str = "auto"
    # GMRES on the last factorisation before a new one (solver/linear.py LinearSolver ``reuse``)
    reuse_factorization: str = "auto"
    max_active_set_loops: int = 12
    # contact: first up to this many semi-smooth iterations (contact set from the current gap in
    # every iteration); if they do not converge, the frozen active-set loop (see ``newton``)
    semismooth_iterations: int = 25
    # contact: at most this many iterations per equilibrium solve in all (semi-smooth attempt and
    # active-set loops); beyond, the increment counts as failed and is bisected - a solve that
    # wanders that long may end on another equilibrium branch (e.g. a buckled layer pressed flat)
    max_contact_iterations: int = 100
    line_search: bool = True
    max_line_search: int = 8
    # arc-length increments with cohesive active sets (smooth within their frozen sets): give up
    # when this many iterations in a row stay above 0.9 × the best residual before them
    # (:func:`stagnates`); 0: off. Newton converges in a few iterations on a smooth problem near
    # its solution; where it stalls or cycles it does so for good: the DCB by arc length spent
    # 88 % of its iterations in attempts that ran to max_iterations that way (a frozen loading
    # point whose normal separation crosses zero in a full step meets the mirror image of its
    # softening branch, and Newton ping-pongs between the two sides)
    stagnation_iterations: int = 3
    # load steps with cohesive interfaces: when a step fails through all its bisections, switch on
    # the viscous regularisation with the time η = stabilize × the step's load-factor increment and
    # solve the step again (InterfaceController.stabilize; 0: off, the run stops there). Where the
    # path of the frozen problem turns back (a local snap-back: the MITC9 plate at λ = 0.995 on
    # 12 × 12), no load step of the rate-independent law has an equilibrium nearby
    stabilize: float = 0.0
    # ... and the run stops at a stabilised step whose viscous dissipation exceeds this share of
    # the step's dissipation (fracture + viscous): the load is then carried by the regularisation,
    # past a limit point of the load (the force-loaded DCB past its peak: 1.3 % in the first step
    # beyond, 7.6 % in the second, 31 % at P = 70 N, 12 % above the peak, without this check) or a
    # snap-back (the displacement-controlled DCB on 100 elements: to δ = 10 mm with 28 % of the
    # dissipation viscous and the branch 27 % above beam theory, without it)
    stabilize_limit: float = 0.05
    # load steps with cohesive interfaces: a step that fails through all its cuts - no
    # equilibrium of the rate-independent law nearby, a snap-back of the path under this control
    # or a limit point of the load - is, with "relax", solved at the load of its smallest cut by
    # letting the damage relax at that fixed load to the next equilibrium (:func:`relax`), as a
    # test machine's specimen would snap dynamically; "stop" (default): the run stops there
    unstable: str = "stop"


@dataclass
class NewtonResult:
    converged: bool
    iterations: int
    residuals: list[float] = field(default_factory=list)
    message: str = ""
    best: np.ndarray | None = None  # a failed solve: the iterate with the smallest residual
    # ended near its solution where the frozen cohesive sets no longer held (EARLY_REFREEZE):
    # ``converged`` is True, but the state is not an equilibrium to accept
    early: bool = False


@dataclass
class StepResult:
    step: int
    load_factor: float
    u: np.ndarray  # full-space displacement
    iterations: int
    residuals: list[float]
    bisections: int
    wall_seconds: float
    # negative eigenvalues of the tangent at the state the step started from (the previous
    # converged state; PARDISO's inertia of the step's first solve), None where that solve was no
    # symmetric factorisation (GMRES on a kept one, or friction); stability.py
    negative_eigenvalues_start: int | None = None


def start_inertia(problem: Problem) -> int | None:
    """The negative eigenvalues of the tangent at the start of the current step (None: unknown;
    :meth:`Problem.solve_tangent`)."""
    return problem.start_inertia


def locate_inertia_change(problem: Problem, s: NewtonSettings, u_a: np.ndarray, lam_a: float, negative_a: int,
                          lam_b: float, rel_tol: float = 1e-4,
                          max_solves: int = 30) -> tuple[float, float, np.ndarray] | None:
    """Narrow the load factors between which the tangent's count of negative eigenvalues leaves
    ``negative_a`` (its value at the converged state ``u_a`` at ``lam_a``; a different count at
    ``lam_b``) by bisection: equilibrium at the midpoint by Newton from the last state below it,
    then the inertia of the tangent there (one factorisation, :meth:`Problem.inertia_at`), until
    the interval is ``rel_tol`` of |λ| or a solve fails. Only for models whose state is a function
    of λ (no interface laws: nothing to commit), so that a state may be solved again; returns
    (λ_lo, λ_hi, u_lo), the narrowed bracket and the state at its lower end, or None where not
    even the first midpoint was solved (an imperfect structure near its buckling load;
    stability.py)."""
    lo, hi, u_lo = float(lam_a), float(lam_b), u_a
    for _ in range(max_solves):
        if abs(hi - lo) <= rel_tol * max(abs(hi), abs(lo), 1e-300):
            break
        mid = 0.5 * (lo + hi)
        u_mid, res = newton(problem, u_lo, mid, s)
        if not res.converged:
            break
        n = problem.inertia_at(u_mid, s.backend)
        if n is None:
            break
        if n == negative_a:
            lo, u_lo = mid, u_mid
        else:
            hi = mid
    return (lo, hi, u_lo) if (lo, hi) != (float(lam_a), float(lam_b)) else None


def modes_near_zero(problem: Problem, u: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray] | None:
    """The ``k`` eigenpairs of the reduced tangent at ``u`` whose eigenvalues lie nearest zero
    (SciPy's shift-invert Lanczos, σ = 0): (eigenvalues, reduced eigenvectors as columns). None
    where the tangent is not symmetric, has no more than ``k`` rows, or the eigensolver fails."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    _, Kr = problem.assembler.evaluate_reduced(u, problem.op, forces=False)
    K = sp.csc_matrix(Kr)
    if K.shape[0] <= k or not linear.is_symmetric(K):
        return None
    try:
        return spla.eigsh(K, k=k, sigma=0.0, which="LM")
    except (RuntimeError, spla.ArpackError, spla.ArpackNoConvergence):
        return None


def critical_mode(problem: Problem, u: np.ndarray) -> np.ndarray | None:
    """The eigenvector of the reduced tangent at ``u`` whose eigenvalue lies nearest zero (SciPy's
    shift-invert Lanczos, σ = 0), expanded to the full DOFs and scaled to a largest face
    translation of 1: at a state just below a located bifurcation, its buckling mode. None where
    the tangent is not symmetric or the eigensolver fails."""
    modes = modes_near_zero(problem, u, 1)
    if modes is None:
        return None
    phi = problem.op.expand(modes[1][:, 0])
    dofs = problem.dm.translations()
    big = dofs[np.argmax(np.abs(phi[dofs]))]
    return phi / phi[big] if phi[big] != 0 else None


class ConvergenceError(RuntimeError):
    """Raised when a load increment does not converge after all bisections."""

    def __init__(self, message: str, load_factor: float, residual: float):
        super().__init__(message)
        self.load_factor = load_factor
        self.residual = residual


#: a contact set that still changes after ``max_active_set_loops`` is accepted where its last
#: state holds within this traction error (a fraction of the interface strength,
#: ContactBlock.set_violation): points at ḡ_N ≈ 0 flipping between equivalent states. Accepting
#: any last state would let the Gmsh plate (examples/plate_gmsh.toml) report at λ = 0.875 a state
#: with 8 released points interpenetrating by up to 0.24 mm (2.4 % of the TRC layer) without a
#: contact force
CONTACT_SET_TOL = 1e-3

#: re-freezings of the cohesive sets at the best iterate of a failed frozen solve, per call of :func:`newton`
MAX_REFREEZE = 3
#: the stagnation window of frozen cohesive solves in arc-length increments where friction acts
#: on a damaged share (arclength.stagnation_window): stick/slip switches make such solves
#: stagnate for a few iterations before they converge (the 8 × 6 TRC slab on its snap-back at
#: 306.68 kN/m² needs more than 3)
FRICTION_STAGNATION = 8
#: a frozen cohesive solve whose residual is within this multiple of the tolerance ends there if
#: the sets no longer hold at its iterate: the active-set loop freezes them again at once
#: instead of converging a frozen problem that it will discard. The frozen problems are nearly
#: linear (one iteration takes the residual from 10³ to 10⁻⁶-10⁻⁴ of the load), and their last
#: iteration, down to the tolerance, is one of the two or three of most loops (the DCB on 200
#: elements under displacement control: 521 iterations with it, 605 without; docs/performance.md). Only the
#: loop's last solve, whose sets hold, must converge to the tolerance. Not with friction on the
#: damaged share: stick and slip are not frozen, so the frozen problem is not smooth, and its
#: residual says less about how near its solution an iterate is (with early exits the lap shear
#: with μ0 = 0.95 by arc length takes an unloading increment before its peak, -3.7 %).
EARLY_REFREEZE = 1e3


def early_blocks(problem: Problem, blocks: list) -> list | None:
    """The frozen cohesive ``blocks`` of an active-set loop whose solves may end early
    (:func:`early_refreeze`), or None: only on a linear model (``nonlinear = false``) without
    friction acting on the damaged share, where the frozen problem is smooth and nearly linear.
    Not on a geometrically nonlinear model: on the MITC9 §5.1 plate (12 × 12, μ0 = 0, arc length)
    near λ = 0.995, where the frozen problems have no solution close by, early exits change the
    sets the loop tries and send the path down a snap-back to λ = 0.647 and up again (66
    increments instead of 38, w_front_max 2.5 % larger at λ = 1). Not with friction: see
    :data:`EARLY_REFREEZE`."""
    if not blocks or getattr(problem.model, "nonlinear", True) or friction_acts(blocks):
        return None
    return blocks


def early_refreeze(blocks: list | None, u: np.ndarray, rn: float, tol: float) -> bool:
    """Does a frozen solve at the iterate ``u`` (full space), residual ``rn``, end early
    (:data:`EARLY_REFREEZE`; ``tol``: its absolute convergence tolerance) because the frozen sets
    of ``blocks`` no longer hold there? Only by more than the consistency tolerance
    (``CONSISTENCY_TOL``): a state that violates them by less is converged, so that the loop can
    accept it where it cycles (:class:`ActiveSetLoop`)."""
    if not blocks or not tol < rn <= EARLY_REFREEZE * tol:
        return False
    return sets_violation(blocks, u) > min(getattr(b, "CONSISTENCY_TOL", 0.0) for b in blocks)


def sets_violation(blocks: list, u: np.ndarray, measured: bool = True) -> float:
    """How far the frozen sets of ``blocks`` are from holding at ``u``: the largest
    ``set_violation`` (a fraction of the strength, cohesive blocks; with ``measured``), infinite
    where a block without that measure has a changed set, 0 where every set holds."""
    v = 0.0
    for b in blocks:
        if measured and hasattr(b, "set_violation"):
            v = max(v, b.set_violation(u))
        elif b.set_changed(u):
            return float("inf")
    return v


#: the largest damage difference an IMPL-EX increment may leave between the damage it acted with
#: (extrapolated) and the implicit update: its error is first order in the increment, and a crack
#: onset taken in one coarse increment spreads over every point past the strength within it
#: (a tension bar: 17 % too much energy with 1/600 of the path per increment, the fully localised
#: crack's with increments cut to this bound; tests/test_concrete_layer.py)
IMPLEX_TOLERANCE = 0.05
#: cuts of an increment for IMPL-EX's tolerance before its error is accepted: at
#: a jump of the path (a crack band that must open at once: a local snap-back) no increment is
#: short enough
IMPLEX_CUTS = 5


def next_increment(problem: Problem, time: float | None = None, ratio: float | None = None) -> None:
    """Tell the IMPL-EX layers the pseudo-time the next increment goes to, or its size over the
    last one's (neither: one unit)."""
    nxt = getattr(getattr(problem, "assembler", None), "next_increment", None)
    if nxt is not None:
        nxt(time, ratio)


def implex_checked(problem: Problem, u_new_res: tuple[np.ndarray, NewtonResult],
                   cuts: int = 0) -> tuple[np.ndarray, NewtonResult]:
    """A converged increment whose IMPL-EX damage error exceeds :data:`IMPLEX_TOLERANCE` is
    reported as not converged, so that the caller cuts it, unless it has been cut
    :data:`IMPLEX_CUTS` times (``cuts``) already: then it is accepted."""
    u_new, res = u_new_res
    asm = getattr(problem, "assembler", None)
    if res.converged and cuts < IMPLEX_CUTS and getattr(asm, "extrapolated", None):
        err = asm.implex_error(u_new)
        if err > IMPLEX_TOLERANCE:
            return u_new, NewtonResult(False, res.iterations, res.residuals,
                                       f"the increment changes the damage by {err:.3g} beyond its extrapolation "
                                       f"(IMPL-EX, at most {IMPLEX_TOLERANCE:g})")
    return u_new, res


def tangent_predictor(problem: Problem, u: np.ndarray, lam: float, s: NewtonSettings) -> np.ndarray:
    """The first iterate towards ``lam`` from the converged ``u``: one linear step with the
    tangent at ``u``, K_r Δu_r = Tᵀ(F(λ) − f(u) − K Δg), Δg the change of the prescribed
    displacements. Imposing Δg alone would put the whole increment of a displacement-controlled
    step into the elements next to the supports that move, and a softening material there
    (cracking concrete) would see a trial state far off the path."""
    op = problem.op
    u_new = problem.impose(u, lam)
    f, K, Kr = problem.assembler.evaluate_both(u, op)
    r = op.reduce(problem.external(lam) - f - K @ (u_new - u))
    try:
        du = problem.solve_tangent(Kr, r, s.backend, s.reuse_factorization)
    except (ArithmeticError, ValueError, RuntimeError):  # a singular tangent: the plain first iterate
        return u_new
    return u_new + op.expand(du) if np.all(np.isfinite(du)) else u_new


def newton(problem: Problem, u: np.ndarray, lam: float, s: NewtonSettings) -> tuple[np.ndarray, NewtonResult]:
    """Equilibrium at load factor ``lam`` from ``u``. With contact: semi-smooth Newton first (the
    penalty force α_N ḡ_N at ḡ_N ≤ 0 is continuous and piecewise linear in u; the contact set is
    taken from the current gap in every iteration, so a converged residual is equilibrium with a
    consistent set); where that does not converge in ``semismooth_iterations``, makes no
    progress in 6 iterations or the set returns to an earlier one (points at ḡ_N ≈ 0 flipping),
    an active-set loop around :func:`newton_fixed_set` from the last iterate (the set is frozen
    during the iterations, then checked), at most ``max_contact_iterations`` iterations in all.
    Where the thesis's Gauss-point contact may still move to the nodes (:func:`contact_may_move`),
    a contact set frozen for the third time - a cycle - ends the solve at once, and the caller
    moves it (:func:`contact_to_nodes`). A contact set still changing after
    ``max_active_set_loops`` is accepted only within :data:`CONTACT_SET_TOL`.
    Both use the residual line search for contact (full Newton steps in the semi-smooth phase
    save about 10 % of the pull-off's time but take 2.5× the iterations in the §5.1 plate's first
    debonding step, and fail there without any line search).

    Cohesive interfaces (blocks with ``smooth_when_frozen``): no semi-smooth phase (it cycles at
    the kink of the law at the onset of damage); the active-set loop freezes the tension state
    and the loading set, iterates with full Newton steps on the then smooth problem (repeated
    with the residual line search where that fails while friction acts on the damaged share),
    and a set that has not settled after ``max_active_set_loops``, or cycles, is a failure (the
    step is cut) - unless a converged state of the loop violates the damage law by less than the
    consistency tolerance (:class:`ActiveSetLoop`), which is then accepted and counted.
    A frozen solve that does not converge, but whose best iterate no longer satisfies the frozen
    sets, freezes them again there and goes on (at most ``MAX_REFREEZE`` times per call): the
    frozen problem need not have a solution at the load (its path can turn back before it,
    while the actual one goes on with other sets). The cohesive §5.1 plate with MITC9 (12 × 12,
    μ0 = 0) stalled at λ = 0.995 with a residual of 4·10⁻⁵ of the load through 8 bisections; now
    it reaches λ = 1 (tests/test_cohesive_plate.py)."""
    if getattr(problem.assembler, "inelastic", False):
        u = tangent_predictor(problem, u, lam, s)
    u = problem.impose(u, lam)  # prescribed displacements at this load factor (displacement control)
    blocks, cohesive_only = active_set_blocks(problem)
    if not blocks:
        return newton_fixed_set(problem, u, lam, s)
    # cohesive interfaces: no semi-smooth iterations - they cycle at the onset of damage (the kink
    # at λ0); the active-set loop converges there, and as fast on the easy steps (DCB to
    # δ = 10 mm: 590 iterations against 879 with 8 semi-smooth ones first)
    n_semi = 0 if cohesive_only else min(s.semismooth_iterations, s.max_contact_iterations)
    total = NewtonResult(False, 0)
    if n_semi > 0:
        for b in blocks:
            b.unfreeze()
        seen: set[bytes] = set()
        last = b""

        def cycling(u_it: np.ndarray) -> bool:  # the contact set returns to an earlier one
            nonlocal last
            key = b"".join(np.packbits(b.released & (b.gap(u_it) <= 0.0)).tobytes() for b in blocks)
            again = key in seen and key != last
            seen.add(key)
            last = key
            return again

        u_new, res = newton_fixed_set(problem, u, lam, replace(s, max_iterations=n_semi),
                                      give_up_after=6, give_up_if=cycling)
        if res.converged:
            return u_new, res
        total.iterations, total.residuals = res.iterations, list(res.residuals)
        if res.residuals and np.isfinite(res.residuals[-1]) and res.residuals[-1] < res.residuals[0]:
            u = u_new  # go on from the semi-smooth iterate where it got closer
    # with its sets frozen a cohesive interface is smooth but softening: the residual line search
    # then stalls on the way through a softening point (the DCB's crack tip); full steps
    # converge there (contact blocks keep it: it helps at the stick/slip transitions)
    s_frozen = replace(s, line_search=False) if cohesive_only else s
    loop = ActiveSetLoop(blocks, cohesive_only)
    refreeze = MAX_REFREEZE
    early = early_blocks(problem, blocks) if cohesive_only else None  # the friction caps change at commits only
    # thesis-law contact at the Gauss points that may move to the nodes (contact_to_nodes): a
    # contact set frozen for the third time is a cycle - give up at once and let load_steps move it
    contact_sets: dict[bytes, int] | None = {} if not cohesive_only and contact_may_move(problem) else None
    for _ in range(s.max_active_set_loops):
        if not loop.freeze(u):
            total.message = "the cohesive loading set cycles (no consistent set near this increment)"
            break
        if contact_sets is not None:
            key = b"".join(np.packbits(b.active).tobytes() for b in blocks if getattr(b, "active", None) is not None)
            contact_sets[key] = contact_sets.get(key, 0) + 1
            if contact_sets[key] > 2:
                total.message = (f"the contact set at the face Gauss points cycles (a set frozen for the third time "
                                 f"after {total.iterations} iterations)")
                break
        left = s.max_contact_iterations - total.iterations
        if left <= 0:
            total.message = _contact_cap_message(total.iterations)
            break
        u_new, res = newton_fixed_set(problem, u, lam, replace(s_frozen, max_iterations=min(s.max_iterations, left)),
                                      stagnation=FROZEN_STAGNATION if cohesive_only and s.unstable == "relax" else 0,
                                      early=early)
        total.iterations += res.iterations
        total.residuals += res.residuals
        left -= res.iterations
        if not res.converged and cohesive_only and s.line_search and left > 0 and friction_acts(blocks):
            # friction on the damaged share (stick/slip) is not smooth within the frozen sets:
            # full steps can wander there (the §5.1 cohesive plate past its first full debonding
            # on 12 × 12 stalls at λ = 1.074 with them and reaches 1.2 with the line search);
            # the same solve again from the same start with the line search
            u_new, res = newton_fixed_set(problem, u, lam, replace(s, max_iterations=min(s.max_iterations, left)))
            total.iterations += res.iterations
            total.residuals += res.residuals
        total.message = res.message
        if (not res.converged and cohesive_only and refreeze > 0 and res.best is not None
                and total.iterations < s.max_contact_iterations):
            # the frozen problem has no solution near this load (its path turns back before it):
            # freeze the sets again at the best iterate, where they no longer hold
            if any(b.set_changed(res.best) for b in blocks):
                refreeze -= 1
                u = res.best
                continue
        if not res.converged:
            if total.iterations >= s.max_contact_iterations:
                total.message = _contact_cap_message(total.iterations)
            break
        u = u_new
        if res.early:
            continue  # the sets changed near the frozen problem's solution: freeze them there
        if loop.consistent(u, u):
            total.converged = True
            break
    else:
        # contact: where the set cycles between equivalent states (points at ḡ_N ≈ 0 flipping),
        # accept the last - if its set holds within CONTACT_SET_TOL of the strength; a cohesive
        # loading set that still changes is not an equilibrium of the damage law (cut the step)
        total.message = "contact set still changing after the allowed active-set loops"
        if not any(getattr(b, "smooth_when_frozen", False) for b in blocks):
            v = max(b.set_violation(u) for b in blocks)
            total.converged = v <= CONTACT_SET_TOL
            if not total.converged:
                total.message += (f" (its last state violates the contact condition by a traction of {v:.3g} × the "
                                  "interface strength)")
            elif v > 0 and hasattr(problem, "accepted_sets"):
                problem.accepted_sets += 1
                problem.accepted_violation = max(problem.accepted_violation, v)
    if not total.converged:
        accepted = loop.accept(problem)
        if accepted is not None:
            u, total.converged = accepted, True
            total.message = loop.accepted_message()
    for b in blocks:
        b.unfreeze()
    return u, total


class ActiveSetLoop:
    """Bookkeeping of one active-set loop (:func:`newton`, :func:`~layershell.solver.arclength.
    arc_attempt`): cycle detection through the loading sets frozen so far (:func:`freeze_sets`)
    and, for cohesive interfaces, the converged state whose sets violate the damage law least.

    Where the loop cycles (or a later solve fails), that state is accepted if its violation is
    within the blocks' ``CONSISTENCY_TOL`` (a fraction of the interface strength, see
    :meth:`~layershell.cohesive.CohesiveBlock.set_violation`): as the front of a crack passes a
    node, freezing the next point as loading can unload the points at the end of the process
    zone, and without them loading the next point stops loading - no set is exactly consistent
    at that load level (a snap-back on the scale of one node spacing), while the two states
    differ only by traction changes of 10⁻⁵-10⁻⁴ of the strength (the yield-surface tolerance of
    a return mapping, in the damage law's terms). Counted in ``problem.accepted_sets`` and
    ``problem.accepted_violation`` (summary.json "active_set")."""

    def __init__(self, blocks: list, cohesive_only: bool):
        self.blocks = blocks
        self.seen: dict[bytes, int] | None = {} if cohesive_only else None
        self.tol = min(getattr(b, "CONSISTENCY_TOL", 0.0) for b in blocks) if cohesive_only and blocks else 0.0
        self.best: tuple[float, object] | None = None

    def freeze(self, u: np.ndarray) -> bool:
        """Freeze the sets at ``u`` (:func:`freeze_sets`); False where the loop cycles - also,
        without further loops, where the sets of ``u`` were frozen before and a state within
        the tolerance is at hand (the limited changes of :func:`freeze_sets` would only look for
        an exactly consistent set near it)."""
        if (self.seen is not None and self.best is not None and self.best[0] <= self.tol
                and _sets_key([b.actual_sets(u) for b in self.blocks]) in self.seen):
            return False
        return freeze_sets(self.blocks, u, self.seen)

    def consistent(self, u: np.ndarray, state: object) -> bool:
        """Do the frozen sets hold at the converged ``u``? If not, ``state`` is remembered when
        its violation is the smallest so far."""
        v = sets_violation(self.blocks, u, self.tol > 0)
        if v == 0.0:
            return True
        if self.best is None or v < self.best[0]:
            self.best = (v, state)
        return False

    def accept(self, problem: Problem) -> object | None:
        """The remembered state if its violation is within the tolerance (counted on ``problem``), else None."""
        if self.best is None or not self.best[0] <= self.tol:
            return None
        if hasattr(problem, "accepted_sets"):
            problem.accepted_sets += 1
            problem.accepted_violation = max(problem.accepted_violation, self.best[0])
        return self.best[1]

    def accepted_message(self) -> str:
        return (f"cohesive loading set cycles; accepted the converged state whose sets violate the damage law by "
                f"{self.best[0]:.2e} of the strength (tolerance {self.tol:g})")


def friction_acts(blocks: list) -> bool:
    """Does a cohesive block carry friction on its damaged share (a slip limit above 0 somewhere)?"""
    return any(getattr(getattr(b, "contact", None), "cap", None) is not None and np.any(b.contact.cap > 0)
               for b in blocks)


def active_set_blocks(problem: Problem) -> tuple[list, bool]:
    """The blocks with an active set (contact, cohesive interfaces: ``freeze``) and whether all
    of them are cohesive (``smooth_when_frozen``: active-set loop only, no semi-smooth phase)."""
    blocks = [b for b in problem.assembler.extra if hasattr(b, "freeze")]
    return blocks, bool(blocks) and all(getattr(b, "smooth_when_frozen", False) for b in blocks)


def freeze_sets(blocks: list, u: np.ndarray, seen: dict[bytes, int] | None) -> bool:
    """Freeze the active sets of ``blocks`` at ``u`` for the next iterations of an active-set
    loop. Cohesive blocks (``seen``: the loading sets frozen so far in this loop): where the sets
    they would take now were frozen before - the loop cycles - only the most violated points
    change (:meth:`~layershell.cohesive.CohesiveBlock.freeze` with ``limited``). Returns False
    where a state is frozen for the third time: the loop only repeats itself (no consistent set
    near this increment - a node of a crack front with a local snap-back; the caller fails the
    increment, which is then cut, instead of iterating to ``max_active_set_loops``). The state is
    what the blocks freeze (``frozen_key``): with friction on a cohesive interface its stick
    state too - counted by the loading sets alone, a loop in which only stick points go over
    their limits, one or two per solve, repeats its key and 'cycles' after two refreezes (on the
    TRC slab's snap-back, 8 × 6, most refused increments would be such false cycles)."""
    if seen is None:
        for b in blocks:
            b.freeze(u)
        return True
    limited = _sets_key([b.actual_sets(u) for b in blocks]) in seen
    for b in blocks:
        b.freeze(u, limited=limited)
    seen.setdefault(_sets_key([b.frozen for b in blocks]), 0)  # the loading sets (for ``limited``)
    # the count: of the whole frozen state, the friction's stick state included (frozen_key)
    # (``seen`` is kept only where every block is cohesive: active_set_blocks' ``cohesive_only``)
    key = b"F" + b"".join(b.frozen_key() for b in blocks)
    seen[key] = seen.get(key, 0) + 1
    return seen[key] <= 2


def _sets_key(sets: list[tuple[np.ndarray, np.ndarray]]) -> bytes:
    """The (tension, loading) sets of all blocks as one hashable key."""
    return b"".join(np.packbits(a).tobytes() for t, l in sets for a in (t, l))


def _contact_cap_message(iterations: int) -> str:
    return f"no equilibrium after {iterations} iterations with contact ([steps] max_contact_iterations)"


def stagnates(residuals: list[float], n: int) -> bool:
    """The last ``n`` residuals all stay above 0.9 × the smallest one before them (a Newton
    iteration that stalls or cycles; ``n`` = 0: never)."""
    return n > 0 and len(residuals) > n + 1 and min(residuals[-n:]) >= 0.9 * min(residuals[:-n])


def newton_fixed_set(problem: Problem, u: np.ndarray, lam: float, s: NewtonSettings,
                     give_up_after: int | None = None,
                     give_up_if: Callable[[np.ndarray], bool] | None = None,
                     stagnation: int = 0, early: list | None = None) -> tuple[np.ndarray, NewtonResult]:
    """Equilibrium iterations at fixed load factor ``lam`` starting from ``u`` (full space).
    ``give_up_after``: stop (not converged, returning the current iterate) when that many
    iterations have not brought the residual below its starting value; ``give_up_if(u)``: stop
    when it returns True for the current iterate; ``stagnation``: stop when that many iterations
    in a row stay above 0.9 × the best residual before them (:func:`stagnates`; 0: never);
    ``early``: the frozen cohesive blocks of an active-set loop, end near the solution where
    their sets no longer hold (:func:`early_refreeze`; ``res.early``)."""
    op = problem.op
    u = problem.impose(u, lam)
    Fext = problem.external(lam)
    ref = np.linalg.norm(op.reduce(Fext))
    pv = getattr(problem, "pseudo", None)  # pseudo-transient damping (None: the static problem)
    pres = op.prescribed  # displacement control: the reactions there set the force scale
    res = NewtonResult(False, 0)
    e0 = en = None
    monitor = getattr(problem, "monitor", None)  # progress/run.log: (iteration, λ, ‖r‖, reference, energy norm, u)
    # contact is non-smooth; so are the loading/unloading switches of softening materials
    globalise = s.line_search and (bool(problem.assembler.extra) or getattr(problem.assembler, "inelastic", False))
    # forces first, the tangent only where an iteration needs it: an iteration that converges,
    # and every trial step of the line search, costs one force evaluation (about 1/15 of a
    # tangent evaluation on the pull-off model) instead of a tangent that is thrown away
    asm = problem.assembler
    f, _ = asm.evaluate(u, tangent=False)
    best: tuple[float, np.ndarray | None] = (np.inf, None)
    for it in range(s.max_iterations + 1):
        r = _residual(problem, Fext, f, u)
        rn = float(np.linalg.norm(r))
        res.residuals.append(rn)
        if not np.isfinite(rn):
            res.message = "residual is not finite"
            return u, res
        if rn < best[0]:
            best = (rn, u)
        if pres is not None:
            scale = reaction_scale(problem, f, Fext, ref)
        else:
            scale = ref if ref > 0 else max(float(np.linalg.norm(op.reduce(f))), 1e-300)
            scale = max(scale, 1e-3 * getattr(problem, "force_scale", 0.0))
        if monitor is not None:
            monitor(it, lam, rn, scale, en, u)
        if it > 0 and rn <= s.tol_residual * scale:
            res.converged, res.iterations = True, it
            record_scale(problem, scale)
            return u, res
        if it > 0 and early_refreeze(early, u, rn, s.tol_residual * scale):
            res.converged = res.early = True
            res.iterations = it
            return u, res
        if it == s.max_iterations:
            break
        if give_up_after is not None and it >= give_up_after and min(res.residuals[1:]) >= res.residuals[0]:
            res.iterations = it
            res.message = f"no progress in {it} iterations (residual {rn:.3e})"
            return u, res
        if give_up_if is not None and give_up_if(u):
            res.iterations = it
            res.message = f"given up after {it} iterations (residual {rn:.3e})"
            return u, res
        if stagnates(res.residuals, stagnation):
            res.iterations = it
            res.message = f"no progress in the last {stagnation} of {it} iterations (residual {rn:.3e})"
            res.best = best[1]
            return u, res
        # K_r = Tᵀ K T (3.69)-(3.72) through the reduced scatter map cached per bond state
        _, Kr = asm.evaluate_reduced(u, op, forces=False)
        if (it > 0 and rn <= ROUND_OFF_REACH * s.tol_residual * scale
                and above_round_off(r, Kr, u[op.independent]) <= s.tol_residual * scale):
            res.converged, res.iterations = True, it
            res.message = "converged at the round-off floor of its entries"
            record_scale(problem, scale)
            return u, res
        if pv is not None:
            Kr = pv.tangent(Kr)
        try:
            du = problem.solve_tangent(Kr, r, s.backend, s.reuse_factorization)
        except linear.SingularSystemError as exc:
            res.message = f"singular tangent ({exc}); check that supports prevent every rigid-body motion"
            return u, res
        dU = op.expand(du)
        en = abs(float(du @ r))
        e0 = en if e0 is None else e0
        if it > 0 and at_round_off_floor(res.residuals, scale, en, e0, dU, u, s, lambda: abs(float(f @ u))):
            res.converged, res.iterations = True, it  # round-off floor reached
            res.message = "converged at the round-off floor"
            record_scale(problem, scale)
            return u + dU, res
        f, _ = asm.evaluate(u + dU, tangent=False)
        if globalise and _residual_norm(problem, Fext, f, u + dU) > rn:
            eta, f_eta = _line_search(problem, u, dU, Fext, rn, s)
            if eta != 1.0:
                dU, f = eta * dU, f_eta
        u = u + dU
    res.iterations = s.max_iterations
    res.message = f"no convergence in {s.max_iterations} iterations (last residual {res.residuals[-1]:.3e})"
    res.best = best[1]
    return u, res


def above_round_off(r: np.ndarray, Kr, ur: np.ndarray) -> float:
    """‖r‖ with each entry less its round-off, ROUND_OFF_TERMS · ε · Σ_j |K_gj u_j| (the sum
    of the magnitudes of the terms that make up the internal force there; an entry within it is
    zero to working precision). ``Kr`` the reduced tangent, ``ur`` the reduced displacements."""
    floor = ROUND_OFF_TERMS * np.finfo(float).eps * (abs(Kr) @ np.abs(ur))
    return float(np.linalg.norm(np.maximum(np.abs(r) - floor, 0.0)))


def at_round_off_floor(residuals: list[float], scale: float, en: float, e0: float, dU: np.ndarray, u: np.ndarray,
                       s: NewtonSettings, work: Callable[[], float]) -> bool:
    """The round-off floor test of the Newton iterations (module docstring): the last of the
    ``residuals`` within ``tol_floor`` with a negligible correction - its energy ``en`` = |Δu·r|
    within ``tol_energy`` of the first correction's ``e0``, or, once the residual has stalled (not
    halved by the last iteration), of the work f·u of the state (``work()``, evaluated only then);
    or its size within ``tol_displacement`` of the displacements. (The work alone would end
    iterations that still converge: with a tolerance of 10⁻¹² the Gmsh plate and its generator
    twin would differ by 9·10⁻⁸.)"""
    rn = residuals[-1]
    if rn > s.tol_floor * scale:
        return False
    if en <= s.tol_energy * e0 or np.abs(dU).max() <= s.tol_displacement * max(np.abs(u).max(), 1e-300):
        return True
    return len(residuals) > 2 and rn > 0.5 * residuals[-2] and en <= s.tol_energy * work()


def reaction_scale(problem: Problem, f: np.ndarray, Fext: np.ndarray, ref: float) -> float:
    """The scale of the residual under prescribed displacements: the larger of the reduced applied
    loads ``ref`` and the reactions ‖f_int − F_ext‖ at the prescribed DOFs, with a floor of 10⁻³
    of the largest force scale of the run so far (it acts only where the forces have almost
    vanished, e.g. a cohesive interface separated completely; :func:`record_scale`)."""
    pres = problem.op.prescribed
    return max(ref, float(np.linalg.norm(f[pres] - Fext[pres])), 1e-3 * getattr(problem, "force_scale", 0.0), 1e-300)


def record_scale(problem: Problem, scale: float) -> None:
    if hasattr(problem, "force_scale"):
        problem.force_scale = max(problem.force_scale, scale)


def _residual(problem: Problem, Fext: np.ndarray, f: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Tᵀ(F_ext − f) at ``u``, less the pseudo-transient damping force where it acts."""
    r = problem.op.reduce(Fext - f)
    pv = getattr(problem, "pseudo", None)
    return r if pv is None else r - pv.force(problem.op, u)


def _residual_norm(problem: Problem, Fext: np.ndarray, f: np.ndarray, u: np.ndarray) -> float:
    """‖:func:`_residual`‖."""
    return float(np.linalg.norm(_residual(problem, Fext, f, u)))


def _line_search(problem: Problem, u: np.ndarray, dU: np.ndarray, Fext: np.ndarray, rn: float,
                 s: NewtonSettings) -> tuple[float, np.ndarray | None]:
    """Backtracking on the residual norm after the full Newton step increased it: halve the step
    (at most ``max_line_search`` times) until the residual decreases; returns that step length
    and the internal force there. If no step length helps, ``(1, None)`` (the full step is kept;
    Newton may still recover)."""
    eta = 0.5
    for _ in range(s.max_line_search - 1):
        f, _ = problem.assembler.evaluate(u + eta * dU, tangent=False)
        r = _residual_norm(problem, Fext, f, u + eta * dU)
        if r <= rn:
            return eta, f
        eta *= 0.5
    return 1.0, None


#: a re-solution at the same load after new releases (the thesis law's re-equilibration) cannot
#: be cut into shorter load increments, so it gets this many times a load step's iterations
#: (max_iterations, max_contact_iterations, max_active_set_loops): after the first cascade of the
#: §5.1 plate with strong friction on 12 × 12 (contact at the nodes) one frozen solve needed 30
#: iterations and the step's re-solutions 314 (tests/test_delamination.py)
REEQUILIBRATION_BUDGET = 4


def reequilibration_settings(s: NewtonSettings) -> NewtonSettings:
    """The Newton settings of a re-solution at the same load (:data:`REEQUILIBRATION_BUDGET`)."""
    k = REEQUILIBRATION_BUDGET
    return replace(s, max_iterations=k * s.max_iterations, max_contact_iterations=k * s.max_contact_iterations,
                   max_active_set_loops=k * s.max_active_set_loops)


def reequilibration_error(problem: Problem, n: int, lam: float, res: NewtonResult) -> ConvergenceError:
    """The error of step ``n`` whose re-solution at ``lam`` after new releases failed; where the
    releases have debonded every interface point, the message says that the run has reached
    complete separation (:func:`separated_hint`)."""
    hint = separated_hint(problem, lam, resolution=True) or contact_hint(problem)
    return ConvergenceError(f"step {n}: re-equilibration at load factor {lam:.6g} failed: {res.message}" + hint,
                            lam, res.residuals[-1] if res.residuals else float("nan"))


@dataclass
class DebondCut:
    """Step cutting on large debonding jumps: if the re-solutions after one converged (sub)step
    release more than ``max_fraction`` of the interface area, the increment is undone and
    halved, at most ``max_cuts`` times per load step. The delamination state is then updated at
    every converged sub-step, so the debonding front follows the load more closely and the result
    depends less on the step size. ``measure(problem)`` gives the debonded fraction."""

    max_fraction: float
    max_cuts: int
    measure: Callable[[Problem], float]


def load_steps(
    problem: Problem,
    load_factors: np.ndarray,
    settings: NewtonSettings | None = None,
    u0: np.ndarray | None = None,
    lam0: float = 0.0,
    step0: int = 0,
    on_step_end: Callable[[Problem, np.ndarray, float], bool] | None = None,
    cut: DebondCut | None = None,
) -> Iterator[StepResult]:
    """Generator over converged load steps to the target factors ``load_factors``.

    A diverging increment is bisected up to ``max_bisections`` times; converged substeps are
    not reported separately (the step is reported when its target factor is reached).
    ``on_step_end(problem, u, lam)`` may change the problem state (delamination) and returns
    True when the same load level must be solved again. Without ``cut`` it runs once the target
    factor is reached; with ``cut`` (:class:`DebondCut`) after every converged sub-step, and a
    sub-step that debonds too much at once is undone and halved.
    """
    s = settings or NewtonSettings()
    s_re = reequilibration_settings(s)
    u = np.zeros(problem.dm.n_full) if u0 is None else u0.copy()
    lam = prev_target = lam0
    committed = {"u": u}  # the state of the interfaces' last commit (contact_to_nodes re-anchors on it)
    if on_step_end is not None:
        user_end = on_step_end

        def on_step_end(pb: Problem, u_c: np.ndarray, lam_c: float) -> bool:
            committed["u"] = u_c
            return user_end(pb, u_c, lam_c)

    for n, target in enumerate(load_factors, start=step0 + 1):
        t0 = time.perf_counter()
        problem.begin_step()  # its first solve keeps the inertia of the start's tangent (stability.py)
        total_it, bis, cuts, halved = 0, 0, 0, 0
        e0 = dissipation_so_far(problem)
        residuals: list[float] = []
        inc = target - lam
        while True:
            trial = target if abs(target - (lam + inc)) <= 1e-12 * max(1.0, abs(target)) else lam + inc
            snap = problem.snapshot() if cut is not None and on_step_end is not None else None
            u_snap = committed["u"]
            next_increment(problem, trial)
            u_new, res = implex_checked(problem, newton(problem, u, trial, s), bis + cuts)
            total_it += res.iterations
            residuals += res.residuals
            if res.converged and snap is not None:
                a0 = cut.measure(problem)
                may_cut = cuts < cut.max_cuts and bis + cuts < s.max_bisections
                while on_step_end(problem, u_new, trial):
                    if may_cut and cut.measure(problem) - a0 > cut.max_fraction:
                        res = NewtonResult(False, 0, message="debonding jump")
                        break
                    u_new, res = resolve(problem, u_new, trial, s_re, may_move=not may_cut)
                    total_it += res.iterations
                    residuals += res.residuals
                    if not res.converged:
                        if may_cut:
                            break
                        raise reequilibration_error(problem, n, trial, res)
                if not res.converged:  # undo the increment and halve it
                    problem.restore(snap)
                    committed["u"] = u_snap
                    cuts += 1
                    inc *= 0.5
                    continue
            if res.converged:
                u, lam = u_new, trial
                commit_state(problem, u, lam)
                if trial == target:
                    break
                inc = min(inc, target - lam) if inc > 0 else max(inc, target - lam)
                continue
            if snap is not None:
                problem.restore(snap)  # the failed Newton solve may have changed contact states
                committed["u"] = u_snap
            bis += 1
            late = bis > min(s.max_bisections, RELAX_AFTER_CUTS)
            if late and contact_to_nodes(problem, committed["u"], lam,
                                         f"towards load factor {trial:.6g} after {bis} bisections: {res.message}"):
                halved, bis, inc = halved + bis, 0, target - lam  # the rest of the step with the contact at the nodes
                continue
            if late and s.unstable == "relax":
                rel = relax(problem, u, lam, trial, s, on_step_end)  # the next equilibrium at this load
                if rel is not None:
                    total_it += rel.iterations
                    residuals += rel.residuals
                    u, lam = rel.u, trial
                    commit_state(problem, u, lam)
                    halved, bis = halved + bis, 0
                    if trial == target:
                        break
                    inc = target - lam
                    continue
            if bis > s.max_bisections and stabilise(problem, s, abs(target - prev_target), lam):
                halved, bis, inc = s.max_bisections, 0, target - lam  # the step again, viscous from the converged state on
                continue
            if bis > s.max_bisections:
                hint = separated_hint(problem, lam) or cohesive_hint(problem, s) + contact_hint(problem)
                raise ConvergenceError(
                    f"step {n}: no convergence towards load factor {trial:.6g} after {s.max_bisections} "
                    f"bisections ({res.message}); the last converged load factor is {lam:.6g}{hint}",
                    trial, res.residuals[-1] if res.residuals else float("nan"))
            inc *= 0.5
        if on_step_end is not None and cut is None:
            while on_step_end(problem, u, lam):
                u, res = resolve(problem, u, lam, s_re)
                total_it += res.iterations
                residuals += res.residuals
                if not res.converged:
                    raise reequilibration_error(problem, n, lam, res)
                commit_state(problem, u, lam)
        check_stabilised_step(problem, n, lam, e0, s.stabilize_limit)
        prev_target = target
        yield StepResult(n, lam, u.copy(), total_it, residuals, bis + cuts + halved, time.perf_counter() - t0,
                         start_inertia(problem))


# relax(): pseudo-time of the first increment (in units of the unit viscous time η = 1), its
# bounds, the lag max |d - d_v| below which the relaxation ends, and the increments it may take
RELAX_DT0 = 0.05
RELAX_DT_MIN = 1e-7
RELAX_DT_MAX = 1e4
RELAX_LAG = 1e-3
RELAX_MAX_INCREMENTS = 400
# with unstable = "relax", a frozen cohesive solve gives up after this many iterations in a row
# without progress (:func:`stagnates`) and the step is cut (or relaxed): before a snap the
# 100-element DCB's frozen solves cycle with period 4 through all 25 iterations (a solve that
# converges after its residual first grew takes 4 such iterations); the 200-element ENF reaches
# its end in 878 iterations without a relaxation, against 2 994 to 99.8 % of it without the rule.
# Not the default: with it the 150-element DCB stops at a step that the full solves pass
FROZEN_STAGNATION = 8
# load_steps: relax after this many bisections of a step (or after max_bisections, if fewer)
RELAX_AFTER_CUTS = 4


@dataclass
class Relaxation:
    """A load step carried past an unstable jump by :func:`relax`."""

    u: np.ndarray
    load_factor: float
    iterations: int
    residuals: list[float]


def relax(problem: Problem, u: np.ndarray, lam_from: float, lam: float, s: NewtonSettings,
          on_step_end: Callable[[Problem, np.ndarray, float], bool] | None) -> Relaxation | None:
    """The next equilibrium at the fixed load factor ``lam`` past an unstable jump of the cohesive
    damage (``NewtonSettings.unstable = "relax"``), from the converged state ``u`` at
    ``lam_from`` where no step of the rate-independent law converges any more.

    The viscous law of Gao & Bower (2004) is switched on with the unit time η = 1 and the damage
    relaxes at the fixed load in pseudo-time increments (``CohesiveBlock.relax_time``; first
    RELAX_DT0, doubled after each converged increment, quartered after a failed one), each
    committed (``on_step_end``), until the acting damage d_v is within RELAX_LAG of the
    rate-independent damage d everywhere. Then the law is switched back and the state must be an
    equilibrium of the rate-independent law: a Newton solve at ``lam`` that converges there with
    its damage within RELAX_LAG of the relaxed one ends the relaxation (else it relaxes on). This
    is the dynamic snap of a displacement-controlled test at a snap-back (or the collapse of a
    force-controlled one past a limit point) without inertia: the energy the jump releases is dissipated by the viscous law, booked as
    ``dissipated_viscous`` in the energy ledger, and recorded per event
    (``InterfaceController.relaxations``: load factors, increments, the released energy, the
    debonded fraction before and after). None: nothing to relax (the setting is off, or no
    cohesive interface without a viscosity of its own). ConvergenceError: the damage does not
    settle (RELAX_MAX_INCREMENTS, or a pseudo-time step below RELAX_DT_MIN), or the interfaces
    separate completely - the structure cannot carry ``lam`` (a limit point of the load)."""
    ctl = problem.interfaces
    if s.unstable != "relax" or on_step_end is None or not hasattr(ctl, "relax_begin"):
        return None
    snap = problem.snapshot()
    if not ctl.relax_begin():
        return None
    viscous0 = ctl.dissipation()[1]
    area0 = ctl.debonded_fraction()
    dt, its, residuals = RELAX_DT0, 0, []
    why = f"it did not settle in {RELAX_MAX_INCREMENTS} increments"

    def fail(reason: str) -> ConvergenceError:
        ctl.relax_end()
        problem.restore(snap)
        return ConvergenceError(
            f"no equilibrium of the cohesive law beyond load factor {lam_from:.6g}, and the relaxation of the "
            f"damage at load factor {lam:.6g} failed: {reason}", lam_from, residuals[-1] if residuals else float("nan"))

    def solve(u_from: np.ndarray) -> tuple[np.ndarray, NewtonResult]:
        nonlocal its
        u_to, res = newton(problem, u_from, lam, s)
        its += res.iterations
        residuals.extend(res.residuals)
        return u_to, res

    def commit(u_c: np.ndarray) -> np.ndarray:
        """Commit the damage (and any other interface state), re-solving where it asks to."""
        while on_step_end(problem, u_c, lam):
            u_c, res = solve(u_c)
            if not res.converged:
                raise fail(f"re-equilibration failed ({res.message})")
        return u_c

    for k in range(1, RELAX_MAX_INCREMENTS + 1):
        ctl.relax_time(dt)
        u_new, res = solve(u)
        if not res.converged:
            dt *= 0.25
            if dt < RELAX_DT_MIN:
                why = f"no equilibrium even for a pseudo-time step of {dt:.1e} ({res.message})"
                break
            continue
        u = commit(u_new)
        if ctl.debonded_fraction() >= 1.0 - 1e-9:
            why = "the interfaces separated completely: the structure cannot carry this load (a limit point)"
            break
        if ctl.viscous_lag() <= RELAX_LAG:
            ctl.relax_end()  # relaxed: does the rate-independent law hold here?
            u_ri, res = solve(u)
            # ... and without moving on: a solve that converges to more damage has found the rest
            # of the jump, whose released energy no ledger would see (the 100-element DCB: two
            # jumps with 1.0 of their 1.1 units of energy there, the balance error 1.5 %)
            if res.converged and ctl.damage_change(u_ri) <= RELAX_LAG:
                u_ri = commit(u_ri)
                ctl.relaxations.append({"load_factor": float(lam), "from_load_factor": float(lam_from),
                                        "increments": k, "iterations": its,
                                        "energy_released": ctl.dissipation()[1] - viscous0,
                                        "debonded_fraction_before": area0,
                                        "debonded_fraction_after": ctl.debonded_fraction()})
                return Relaxation(u_ri, lam, its, residuals)
            ctl.relax_begin()  # not yet an equilibrium of the rate-independent law: relax on
        dt = min(2.0 * dt, RELAX_DT_MAX)
    raise fail(why)


def cohesive_hint(problem: Problem, s: NewtonSettings) -> str:
    """The end of the message of a load step that failed on a model with cohesive interfaces
    and neither way past such a step switched on ('' otherwise)."""
    if s.stabilize > 0 or s.unstable != "stop" or not getattr(problem.interfaces, "cohesive", lambda: False)():
        return ""
    return ("; a model with cohesive interfaces passes such a step (a snap-back where the crack front jumps) with "
            "[steps] control = 'arc_length' (λ becomes an unknown and may fall: the path through the snap-back is "
            "traced, for prescribed displacements as for forces), unstable = 'relax' (the damage snaps to the "
            "next equilibrium at that load, the energy released reported) or stabilize = 0.02 (viscous "
            "regularisation from there on, its share reported)")


def separated_hint(problem: Problem, lam: float, resolution: bool = False) -> str:
    """The end of the message of a load step that failed after every interface point had
    debonded (a thesis-law cascade through the whole bond, or a cohesive interface damaged
    completely): the layers are then held by contact and friction alone, and a load beyond what
    they carry has no equilibrium - the structure's limit point (the pull-off refined to 18 × 16
    debonds its whole bond at λ = 0.3 and has no equilibrium at 0.300098), not a failure of the
    solver. ``resolution``: the re-solution at ``lam`` after the releases that completed the
    debonding failed (settling included) - the run has reached complete separation there.
    '' otherwise."""
    fraction = getattr(problem.interfaces, "debonded_fraction", None)
    if fraction is None or fraction() < 1.0 - 1e-9:
        return ""
    if resolution:
        return (f"; its releases had debonded every interface point: the run has reached complete separation at load "
                f"factor {lam:.6g}, where the layers, held by contact and friction alone, found no equilibrium (the "
                "end of the debonding; the results up to the last converged step are kept)")
    return (f"; every interface point had debonded at load factor {lam:.6g}: the layers are held by contact and "
            "friction alone, and a larger load has no equilibrium (a limit point of the structure - the end of "
            "the debonding, not a failure of the solver; arc length (control = 'arc_length') traces the path "
            "past it where one exists)")


def contact_to_nodes(problem: Problem, u: np.ndarray, lam: float, reason: str = "") -> bool:
    """Move the thesis-law contact whose rule the model file left open from the face Gauss points
    to the nodes (:meth:`~layershell.solver.interface_state.InterfaceController.contact_to_nodes`;
    ``u``: the state of the interfaces' last commit). False where nothing moved (no such
    interface, already moved, cohesive interfaces only): the caller fails as before."""
    move = getattr(problem.interfaces, "contact_to_nodes", None)
    return bool(move is not None and move(problem, u, lam, reason))


def contact_may_move(problem: Problem) -> bool:
    """Is there thesis-law contact at the face Gauss points that :func:`contact_to_nodes` would
    move (its rule left open in the model file, not moved yet)?"""
    movable = getattr(problem.interfaces, "movable_contact", None)
    return movable is not None and bool(movable())


def resolve(problem: Problem, u: np.ndarray, lam: float, s: NewtonSettings,
            may_move: bool = True, may_settle: bool | None = None) -> tuple[np.ndarray, NewtonResult]:
    """The re-solution at ``lam`` after new releases, from the just committed ``u``; where it
    fails with the thesis's Gauss-point contact (and ``may_move``), once more with the contact at
    the nodes (:func:`contact_to_nodes`); where that fails too (or nothing moved), and
    ``may_settle`` (default: ``may_move``), by pseudo-transient settling (:func:`settle`) - the
    last resort before the run stops, since a re-solution at the same load cannot be cut into
    load increments (a caller that can cut the increment instead passes False). The result counts
    the iterations of all solves."""
    u_r, r = newton(problem, u, lam, s)
    if not r.converged and may_move and contact_to_nodes(problem, u, lam, f"its re-solution after new releases: "
                                                                           f"{r.message}"):
        u_r, r2 = newton(problem, u, lam, s)
        r = _joined(r, r2)
    if not r.converged and (may_move if may_settle is None else may_settle):
        u_s, r3 = settle(problem, u, lam, s, why=r.message)
        r3 = _joined(r, r3)
        if r3.converged:
            return u_s, r3
        r3.message = f"{r.message}; then {r3.message}"
        r = r3
    return u_r, r


def _joined(first: NewtonResult, then: NewtonResult) -> NewtonResult:
    """``then`` with the iterations and residuals of ``first`` before its own."""
    then.iterations += first.iterations
    then.residuals = first.residuals + then.residuals
    return then


# settle(): the first pseudo-time step (in units of the damping D = |diag K_r|: with Δt = 1 the
# damping is as stiff as the tangent's diagonal), its bounds, the increments and the Newton
# iterations per increment it may take, and the damping force (a share of the load) below which
# a static solve is tried
SETTLE_DT0 = 1.0
SETTLE_DT_MIN = 1e-6
SETTLE_DT_MAX = 1e12
SETTLE_MAX_INCREMENTS = 200
SETTLE_ITERATIONS = 25
SETTLE_STATIC = 1e-2
# ... where it stops on an unstable equilibrium (a saddle of the potential, where the damping
# force vanishes: started on one, or a static solve converged onto one), it is pushed along the
# tangent's most negative mode by this share of the model's size and settles again, at most
# SETTLE_PUSHES times (the imperfect column started on its unstable near-straight state at
# 1.1 P_E: one push, then the elastica; tests/test_settle.py)
SETTLE_PUSH = 1e-3
SETTLE_PUSHES = 3
# ... and where the state moves without stiffness it stops early, without an equilibrium: over
# the last SETTLE_RUNAWAY converged increments Δt grew at least SETTLE_RUNAWAY_GROWTH-fold (or
# reached SETTLE_DT_MAX) while the damping force fell less than SETTLE_RUNAWAY_FALL-fold, and
# the state has moved farther than the model's size from where the settling started (the
# completely debonded CFRP plate on 24 × 16: its loose sublaminate drifted 5·10⁵ mm under a
# constant damping force, and the settling ran on to its 200th increment; tests/test_settle.py)
SETTLE_RUNAWAY = 6
SETTLE_RUNAWAY_GROWTH = 8.0
SETTLE_RUNAWAY_FALL = 2.0


@dataclass
class PseudoViscosity:
    """The damping term of pseudo-transient continuation: a reduced force (D/Δt)(u_r − u_r,n)
    on every independent DOF, with D = |diag K_r| of the state the settling started from and
    ``u_n`` the state at the start of the pseudo-time increment (``Problem.pseudo`` while set)."""

    diag: np.ndarray  # D, per reduced DOF
    u_n: np.ndarray  # full state at the start of the increment
    rate: float  # 1/Δt

    def force(self, op, u: np.ndarray) -> np.ndarray:
        ind = op.independent
        return self.rate * self.diag * (u[ind] - self.u_n[ind])

    def tangent(self, Kr):
        """K_r + D/Δt; in K_r's own pattern where it knows it (assembly.ReducedTangent), so that
        the solver keeps its symbolic analysis and upper-triangle map (a new CSR matrix per
        iteration would make the solver repeat its symbolic analysis every other solve, and sort
        and check the symmetry every solve: 35.0 s instead of 26.2 s for four damped increments of
        the CFRP plate on 24 × 16)."""
        import scipy.sparse as sp

        rs = getattr(Kr, "scatter", None)
        pos = rs.diagonal_positions() if rs is not None else None
        if pos is not None and Kr.indices is rs.indices and Kr.indptr is rs.indptr:
            data = Kr.data.copy()
            data[pos] += self.rate * self.diag
            return rs.matrix_from_values(data, symmetric=getattr(Kr, "known_symmetric", False))
        return Kr + sp.diags(self.rate * self.diag, format="csr")


def moves_without_stiffness(history: list[tuple[float, float]]) -> bool:
    """Whether the damped increments move without stiffness: ``history`` holds (Δt, damping
    force) of the consecutive converged increments; over the last SETTLE_RUNAWAY of them Δt grew
    SETTLE_RUNAWAY_GROWTH-fold (or reached SETTLE_DT_MAX) while the damping force fell less than
    SETTLE_RUNAWAY_FALL-fold. An implicit Euler increment Δt cuts the damping force of a mode of
    stiffness k and damping D by 1 + kΔt/D, so a force that did not halve while Δt grew to Δt_1
    leaves k < D/Δt_1 (the last increment's factor alone stayed below 2): along that motion the
    tangent has next to no stiffness (D/Δt_1 ≤ 10⁻¹² D at the bound of Δt)."""
    if len(history) <= SETTLE_RUNAWAY:
        return False
    (dt0, f0), (dt1, f1) = history[-SETTLE_RUNAWAY - 1], history[-1]
    return f1 * SETTLE_RUNAWAY_FALL > f0 and (dt1 >= SETTLE_RUNAWAY_GROWTH * dt0 or dt1 >= SETTLE_DT_MAX)


def push_off_saddle(problem: Problem, u: np.ndarray, lam: float, negative: int) -> np.ndarray | None:
    """``u`` (an equilibrium whose tangent has ``negative`` negative eigenvalues) moved along the
    eigenvector of the most negative eigenvalue (SciPy's shift-invert Lanczos about 0) by
    SETTLE_PUSH × the model's size (largest translation), to the side on which the out-of-balance
    force pushes on along it; None where the tangent is not symmetric or no negative eigenvalue
    is found."""
    op = problem.op
    modes = modes_near_zero(problem, u, negative + 2)
    if modes is None or modes[0].min() >= 0.0:
        return None
    vals, vecs = modes
    phi = op.expand(vecs[:, int(np.argmin(vals))])
    phi *= SETTLE_PUSH * problem.model.mesh.size() / max(float(np.abs(phi[problem.dm.translations()]).max()), 1e-300)
    Fext = problem.external(lam)

    def outward(v: np.ndarray) -> float:  # the out-of-balance force along the push at u + v
        f, _ = problem.assembler.evaluate(u + v, tangent=False)
        return float(op.reduce(Fext - f) @ op.reduce(v))

    return u + phi if outward(phi) >= outward(-phi) else u - phi


def settle(problem: Problem, u: np.ndarray, lam: float, s: NewtonSettings,
           why: str = "") -> tuple[np.ndarray, NewtonResult]:
    """The static equilibrium at the fixed load factor ``lam`` that the state ``u`` settles to
    when every DOF is damped: pseudo-transient continuation (Kelley & Keyes 1998; the automatic
    stabilisation of Abaqus/Standard is the same idea). Each pseudo-time increment Δt solves
    f_int(u) + (D/Δt)(u − u_n) = F_ext(λ) by :func:`newton` (D = |diag K_r| at ``u``); Δt starts
    at SETTLE_DT0, doubles after each converged increment and is quartered after a failed one.
    With small Δt the damped tangent K_r + D/Δt is positive definite even where K_r is not (a
    layer released beyond its buckling load), and the state moves along the energy's descent -
    the snap a structure makes at a fixed load, without the inertia - instead of the jump of a
    Newton step, which on the CFRP plate on 24 × 16 cycles through the contact sets of a
    buckling sublaminate. An increment counts only where its damped tangent is positive definite
    (else Δt is cut and capped): beyond 1/|μ| of an unstable mode μ implicit Euler damps that
    mode instead of letting it grow and converges onto the saddle (the imperfect column at
    1.5 P_E would end on its straight state). Once the damping force is below SETTLE_STATIC of the
    load and the undamped tangent is positive definite (or its inertia unknown: a friction
    tangent that is not symmetric), the damping is removed and a static Newton solve from there
    (with an increment's budget, then tried again after Δt has grown fourfold) must converge to
    a state with a positive definite tangent: the result is an equilibrium of the undamped
    problem (its residual within ``tol_residual``), not a damped approximation. Where the static
    solves fail, the damped increments go on: their damping force is the static residual of
    their state, and once it is within ``tol_residual`` a static solve is tried at once (on the
    completely debonded CFRP plate on 24 × 16 static solves from damping forces below 1 % of
    the load fail, 125 iterations each, while the damped increments converge in 6-7). A
    saddle is left by :func:`push_off_saddle`. The work of the out-of-balance force along the
    path (the energy the snap released: the fall of the potential energy where the structure is
    conservative) and the largest displacement change are recorded in
    ``problem.interfaces.settlements`` (runner: a warning and summary.json 'settlements'; not in
    the cohesive energy ledger, whose balance error then shows it). A result that is not
    converged: the damped states did not settle (SETTLE_MAX_INCREMENTS, Δt below SETTLE_DT_MIN,
    or back on a saddle after SETTLE_PUSHES pushes), or they move without stiffness
    (:func:`moves_without_stiffness`) and have left the model's size behind: no equilibrium."""
    if not hasattr(problem, "pseudo"):
        return u, NewtonResult(False, 0, message="pseudo-transient settling is not available in the distributed "
                                                 "(PETSc) solver")
    op = problem.op
    u = problem.impose(u, lam)
    u_start = u.copy()
    _, Kr = problem.assembler.evaluate_reduced(u, op, forces=False)
    D = np.abs(Kr.diagonal())
    D = np.where(D > 0.0, D, D.max() if D.size and D.max() > 0 else 1.0)
    Fext = problem.external(lam)
    scale = max(float(np.linalg.norm(op.reduce(Fext))), 1e-3 * getattr(problem, "force_scale", 0.0), 1e-300)
    s_in = replace(s, max_iterations=min(s.max_iterations, SETTLE_ITERATIONS),
                   max_contact_iterations=min(s.max_contact_iterations, 4 * SETTLE_ITERATIONS))
    total = NewtonResult(False, 0)
    dt, cap, work, static_at, pushes = SETTLE_DT0, SETTLE_DT_MAX, 0.0, 0.0, 0
    gauss = (0.5 - 0.5 / np.sqrt(3.0), 0.5 + 0.5 / np.sqrt(3.0))

    def released(a: np.ndarray, b: np.ndarray) -> float:
        """The work of the out-of-balance force F_ext − f_int along the segment from ``a`` to ``b``
        (two-point Gauss: exact where f_int is cubic in u, Green-Lagrange strains with a linear
        material); summed over the path, the energy the structure released (for a conservative
        one, the fall of its potential energy)."""
        d = b - a
        return 0.5 * sum(float((Fext - problem.assembler.evaluate(a + x * d, tangent=False)[0]) @ d) for x in gauss)
    message = f"the damped states did not settle in {SETTLE_MAX_INCREMENTS} pseudo-time increments"
    size, translations, history = problem.model.mesh.size(), problem.dm.translations(), []
    for k in range(1, SETTLE_MAX_INCREMENTS + 1):
        problem.pseudo = PseudoViscosity(D, u, 1.0 / dt)
        try:
            u_new, res = newton(problem, u, lam, s_in)
            # a descent step only where the damped tangent there is positive definite: with Δt
            # beyond 1/|μ| of an unstable mode μ, implicit Euler damps that mode instead of letting
            # it grow, and the steps converge onto the saddle (unknown inertia: accepted)
            descent = res.converged and (problem.inertia_at(u_new, s.backend) or 0) == 0
        finally:
            problem.pseudo = None
        total = _joined(total, res)
        if not descent:
            if res.converged:
                cap = 0.5 * dt  # Δt stays below an unstable mode's time scale from here
            dt *= 0.25
            if dt < SETTLE_DT_MIN:
                message = f"no damped equilibrium even for a pseudo-time step of {dt:.1e} ({res.message})"
                break
            continue
        damping = float(np.linalg.norm(D * (u_new - u)[op.independent] / dt))  # = the static residual there
        work += released(u, u_new)
        u = u_new
        history.append((dt, damping))
        moved = float(np.abs((u - u_start)[translations]).max())
        if moved > size and moves_without_stiffness(history):
            dt0, f0 = history[-SETTLE_RUNAWAY - 1]
            message = (f"no equilibrium: the state moves without stiffness (over the last {SETTLE_RUNAWAY} pseudo-time "
                       f"increments the step grew from {dt0:.1e} to {dt:.1e} while the out-of-balance force stayed at "
                       f"{f0 / scale:.1e} -> {damping / scale:.1e} of the load), and it has moved {moved:.3g} from "
                       f"where it started, more than the model's size {size:.3g}: a part of the model that nothing "
                       f"holds (a mechanism, or a layer that has debonded completely) runs away under the load")
            break
        push: int | None = None  # the negative eigenvalues of a saddle to push off
        if (damping <= SETTLE_STATIC * scale and dt >= 4.0 * static_at) or damping <= s.tol_residual * scale:
            static_at = dt  # the next static try after Δt has grown fourfold
            here = problem.inertia_at(u, s.backend)
            if here:  # still near a saddle: flow on, pushed off where the flow has stopped there
                if damping <= 1e-6 * scale:
                    push = here
            else:
                u_s, rs = newton(problem, u, lam, s_in)
                total = _joined(total, rs)
                negative = problem.inertia_at(u_s, s.backend) if rs.converged else None
                if rs.converged:
                    work += released(u, u_s)
                    u = u_s
                if negative:
                    push = negative
                elif rs.converged:
                    total.converged, total.message = True, "settled"
                    ctl = problem.interfaces
                    if ctl is not None and hasattr(ctl, "settlements"):
                        fraction = getattr(ctl, "debonded_fraction", None)
                        ctl.settlements.append({
                            "load_factor": float(lam), "increments": k, "iterations": total.iterations,
                            "energy_released": work, "largest_displacement_change": float(np.abs(u_s - u_start).max()),
                            "debonded_fraction": float(fraction()) if fraction is not None else None,
                            "pushes": pushes, "reason": why})
                    return u_s, total
        if push is not None:
            if pushes >= SETTLE_PUSHES:
                message = f"it came back to an unstable equilibrium after {pushes} pushes off it"
                break
            pushed = push_off_saddle(problem, u, lam, push)
            if pushed is None:
                message = "it stopped at an unstable equilibrium whose unstable mode was not found"
                break
            work += released(u, pushed)
            u, dt, static_at, pushes = pushed, SETTLE_DT0, 0.0, pushes + 1
            history.clear()
            continue
        cap *= 1.25
        dt = min(2.0 * dt, cap, SETTLE_DT_MAX)
    total.converged, total.message = False, f"pseudo-transient settling failed: {message}"
    return u, total


def contact_hint(problem: Problem) -> str:
    """The end of the message of a failed solve on a model whose thesis-law contact between
    debonded layers acts at the face Gauss points (the default, the thesis's): there the stiff
    penalty's tractions oscillate from point to point, and on refined meshes the contact set can
    cycle (the §5.1 plate with slip-softening friction on 12 × 12 stops at λ = 0.375 with a load
    step's budget for its re-solutions; at the nodes it reaches λ = 1 with it, and at the Gauss
    points with :data:`REEQUILIBRATION_BUDGET` in 1884 iterations, against 377 at the
    nodes; tests/test_delamination.py, docs/user-guide.md). Where the contact has moved to the
    nodes (:func:`contact_to_nodes`, the rule left open) it says where instead. '' otherwise."""
    from ..delamination import InterfaceLaw

    moved = getattr(problem.interfaces, "contact_moved_at", None)
    if moved is not None:
        return (f"; the contact between debonded layers had moved from the face Gauss points to the nodes at load "
                f"factor {moved:.6g}, where its contact set cycled")
    if not any(isinstance(getattr(r, "law", None), InterfaceLaw) and r.law.rule == "gauss"
               for r in getattr(problem.interfaces, "runs", ())):
        return ""
    return ("; the contact between debonded layers acts at the face Gauss points (the thesis's), whose contact set can "
            "cycle on refined meshes: [[interfaces]] rule = \"lobatto\" puts it at the nodes (the stress criterion stays "
            "at the Gauss points)")


def dissipation_so_far(problem: Problem) -> tuple[float, float] | None:
    """(fracture, viscous) energy dissipated by the cohesive interfaces (None: no interface
    laws), at the start of a step for :func:`check_stabilised_step`."""
    return problem.interfaces.dissipation() if hasattr(problem.interfaces, "dissipation") else None


def stabilise(problem: Problem, s: NewtonSettings, increment: float, lam: float) -> bool:
    """A step that failed through all its cuts: switch on the viscous stabilisation of the
    cohesive interfaces from the converged state at ``lam`` with η = ``s.stabilize`` ×
    ``increment`` (the step's nominal load-factor increment). False where it is off, already on,
    or there is no cohesive interface: the run stops."""
    return (s.stabilize > 0 and hasattr(problem.interfaces, "stabilize") and problem.interfaces.stabilized is None
            and problem.interfaces.stabilize(s.stabilize * increment, lam))


def check_stabilised_step(problem: Problem, n: int, lam: float, e0: tuple[float, float] | None,
                           limit: float) -> None:
    """ConvergenceError where the viscous share of a stabilised step's dissipation exceeds
    ``limit`` (NewtonSettings.stabilize_limit): past a limit point of the load or a snap-back.
    Nothing before the stabilisation is switched on."""
    if e0 is None or not limit > 0 or getattr(problem.interfaces, "stabilized", None) is None:
        return
    f1, v1 = problem.interfaces.dissipation()
    df, dv = f1 - e0[0], v1 - e0[1]
    if dv > limit * (df + dv):
        lam_s = problem.interfaces.stabilized["load_factor"]
        raise ConvergenceError(
            f"step {n}: the viscous stabilisation switched on at load factor {lam_s:.6g} dissipated "
            f"{dv / (df + dv):.1%} of the dissipation of the step to {lam:.6g} (limit {limit:.0%}, [steps] "
            f"stabilize_limit): the regularisation, not the interface, carries the load - past load factor "
            f"{lam_s:.6g} the rate-independent path has no equilibrium nearby (a limit point of the load, or a "
            f"snap-back where the front jumps a node spacing); follow it with control = 'arc_length' (force "
            f"loads) or refine the mesh along the front", lam, float("nan"))
