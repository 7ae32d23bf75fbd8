"""The static problem: model + DOF map + constraint operator + assembler + load vectors."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..assembly import Assembler
from ..constraints import ConstraintOperator, constraint_operator
from ..dofs import DofMap, number_dofs
from ..loads import external_forces
from ..model import Model


@dataclass
class Problem:
    model: Model
    dm: DofMap
    assembler: Assembler
    op: ConstraintOperator
    F_scaled: np.ndarray
    F_const: np.ndarray
    bonded: dict[int, np.ndarray] = field(default_factory=dict)
    F_friction: np.ndarray | None = None
    extra_blocks: list = field(default_factory=list)
    interfaces: object = None  # InterfaceController when the model has interface laws
    solvers: dict = field(default_factory=dict, repr=False)  # (backend, reuse) -> LinearSolver
    # PARDISO's ordering choice per sparsity pattern, kept when the solvers are started afresh
    orderings: dict = field(default_factory=dict, repr=False)
    # the largest force scale (applied loads or reactions) of a converged state so far: a floor
    # of the residual's scale, so that Newton can converge where the reactions vanish (complete
    # separation under prescribed displacements) instead of chasing round-off
    force_scale: float = 0.0
    # cohesive active sets accepted within their consistency tolerance where the loop cycled
    # (solver/newton.py ActiveSetLoop): how many, and the largest violation (fraction of the
    # strength); reported in summary.json "active_set"
    accepted_sets: int = 0
    accepted_violation: float = 0.0
    solve_counts_before: dict = field(default_factory=dict, repr=False)  # of the run before a restart
    # the negative eigenvalues of the tangent at the state the current step started from, kept by
    # the step's first solve (solve_tangent; stability.py); None: unknown. ``start_open``: that
    # first solve is still to come (begin_step)
    start_inertia: int | None = field(default=None, repr=False)
    start_open: bool = field(default=False, repr=False)
    # the bond flags the constraint operator was built from (rebuild_constraints)
    op_bonded: dict = field(default_factory=dict, repr=False)
    # the damping term of a pseudo-transient relaxation (solver/newton.py PseudoViscosity), added
    # to every residual and tangent while set; None: the static problem
    pseudo: object = field(default=None, repr=False)

    @classmethod
    def build(cls, model: Model) -> "Problem":
        dm = number_dofs(model)
        below = model.below()
        bonded = {up: dm.present[up] & dm.present[lo] for up, lo in below.items()}
        Fs, Fc = external_forces(model, dm)
        pb = cls(model, dm, Assembler(model, dm), None, Fs, Fc, bonded)
        if model.interface_laws:
            from .interface_state import InterfaceController

            pb.interfaces = InterfaceController.build(pb, model.interface_laws, model.initially_debonded,
                                                      model.initial_laws, model.delamination)
            pb.assembler.add_blocks(pb.extra_blocks)
        pb.rebuild_constraints()
        return pb

    def rebuild_constraints(self) -> None:
        """The constraint operator for the current bond flags; kept where they have not changed
        since it was built (a new one costs its reduced assembly map and a symbolic analysis:
        step cuts restored unchanged flags 23 times in 40 increments of the DCB by arc length)."""
        if (self.op is not None and self.op_bonded.keys() == self.bonded.keys()
                and all(np.array_equal(v, self.op_bonded[k]) for k, v in self.bonded.items())):
            return
        self.op = constraint_operator(self.model, self.dm, self.bonded)
        self.op_bonded = {k: v.copy() for k, v in self.bonded.items()}

    def linear_solver(self, backend: str = "auto", reuse: str = "auto"):
        """This problem's linear solver (keeps PARDISO's symbolic analysis between iterations and,
        with ``reuse``, its last factorisation as GMRES's preconditioner)."""
        from .linear import LinearSolver

        key = (backend, reuse)
        if key not in self.solvers:
            # PARDISO's symmetric mode wherever K_r is symmetric (checked per call); friction
            # tangents that are not fall back to the general mode
            self.solvers[key] = LinearSolver(backend, symmetric=True, decisions=self.orderings, reuse=reuse)
        return self.solvers[key]

    def begin_step(self) -> None:
        """A load step or path increment starts: its first :meth:`solve_tangent`, at the state
        it starts from, keeps the inertia of that state's tangent (``start_inertia``)."""
        self.start_inertia, self.start_open = None, True

    def solve_tangent(self, Kr, r: np.ndarray, backend: str = "auto", reuse: str = "auto") -> np.ndarray:
        """K_r x = r by this problem's linear solver. The first solve of a step (begin_step) keeps
        the negative eigenvalues of K_r where it factorised it (PARDISO's symmetric mode), None
        where it did not (GMRES on a kept factorisation, a failed or non-symmetric solve)."""
        sol = self.linear_solver(backend, reuse)
        before = sol.counts.factorisations
        try:
            return sol.solve(Kr, r)
        finally:
            if self.start_open:
                self.start_open = False
                self.start_inertia = sol.info.negative_pivots if sol.counts.factorisations > before else None

    def inertia_at(self, u: np.ndarray, backend: str = "auto") -> int | None:
        """The negative eigenvalues of the reduced tangent at ``u`` (one assembly and one
        factorisation, by a solver that keeps no factorisation); None where the tangent is not
        symmetric or PARDISO is missing (stability.py: the last state of a run, bisections)."""
        from .linear import SingularSystemError

        _, Kr = self.assembler.evaluate_reduced(u, self.op, forces=False)
        if self.pseudo is not None:  # the damped tangent of a pseudo-transient increment
            Kr = self.pseudo.tangent(Kr)
        sol = self.linear_solver(backend, "never")  # always factorises (kept: its symbolic analysis)
        try:
            sol.solve(Kr, np.zeros(Kr.shape[0]))
        except SingularSystemError:
            return None
        return sol.info.negative_pivots

    def solve_counts(self) -> dict:
        """Factorisations and GMRES solves of this problem's linear solvers (summary.json), with
        those of the run before a restart (``solve_counts_before``)."""
        out: dict = dict(self.solve_counts_before)
        for sol in self.solvers.values():
            for k, v in sol.counts.as_dict().items():
                out[k] = out.get(k, 0) + v
        return out

    def commit(self, u: np.ndarray, lam: float | None = None) -> None:
        """Take the material state of the inelastic layers at the converged ``u`` (load factor
        ``lam``) as committed (nothing without inelastic layers)."""
        self.assembler.commit(u, lam)

    def snapshot(self) -> dict:
        """Copy of the mutable delamination state (bond flags, per-point history, friction
        anchors) and of the inelastic layers' committed state, to undo a load increment (step
        cutting); the same state a checkpoint saves."""
        mat = self.assembler.material_state() if self.assembler.inelastic else None
        if self.interfaces is None:
            return {"bonded": {k: v.copy() for k, v in self.bonded.items()}, "materials": mat}
        return {"state": self.interfaces.state(self), "resolves": self.interfaces.resolves, "materials": mat}

    def restore(self, snap: dict) -> None:
        """Undo to a :meth:`snapshot`; rebuilds the constraint operator where the bond flags
        change."""
        if snap.get("materials") is not None:
            self.assembler.set_material_state(snap["materials"])
        if self.interfaces is None:
            for k, v in snap["bonded"].items():
                self.bonded[k] = v.copy()
            self.rebuild_constraints()
            return
        self.interfaces.restore(self, snap["state"])
        self.interfaces.resolves = snap["resolves"]  # re-solutions so far in this load step

    @property
    def prescribed(self) -> bool:
        """The model has prescribed (non-zero) support displacements."""
        return self.op is not None and self.op.prescribed is not None

    def impose(self, u: np.ndarray, lam: float) -> np.ndarray:
        """``u`` with the constraints u = T u_r + λ g_scaled + g_const imposed at load factor
        ``lam`` (u_r are the independent entries of ``u``); ``u`` itself without prescribed
        displacements."""
        op = self.op
        if op.prescribed is None:
            return u
        v = op.expand(u[op.independent])
        if op.g_scaled is not None:
            v += lam * op.g_scaled
        if op.g_const is not None:
            v += op.g_const
        return v

    def reactions(self, u: np.ndarray, lam: float) -> np.ndarray:
        """Full-space support reactions f_int(u) − F_ext(λ) (non-zero at constrained DOFs only
        at equilibrium; at a prescribed DOF the force the support applies)."""
        f, _ = self.assembler.evaluate(u, tangent=False)
        return f - self.external(lam)

    def external(self, lam: float) -> np.ndarray:
        for b in self.extra_blocks:  # rate-dependent blocks (viscous cohesive law) need λ
            if hasattr(b, "set_load_factor"):
                b.set_load_factor(lam)
        F = lam * self.F_scaled + self.F_const
        return F if self.F_friction is None else F + self.F_friction


def commit_state(problem, u: np.ndarray, lam: float | None = None) -> None:
    """Commit the material state of a converged ``u`` at load factor ``lam`` where the problem has
    one (stand-ins of a problem in the solver's tests have none)."""
    commit = getattr(problem, "commit", None)
    if commit is not None:
        commit(u, lam)

