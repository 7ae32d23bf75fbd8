"""Distributed solve of the reduced system with PETSc (petsc4py) and MPI (mpi4py).

Every rank holds the model, the DOF map and the constraint operator T (replicated, built by the
same functions as :meth:`layershell.solver.problem.Problem.build`), but evaluates only its
contiguous element range with the serial kernel (:class:`.partition.LocalAssembly`). Its part of
K_r = Tᵀ K T (3.69)-(3.72) is added into one PETSc MPIAIJ matrix whose rows are split in
contiguous ranges; the matrix is preallocated exactly from the union of the ranks' reduced patterns
(exchanged once with ``Alltoallv``), so no allocation happens during assembly. The reduced residual
Tᵀ(λF - f_int) is a distributed PETSc vector. The default solver is KSP ``preonly`` + LU by MUMPS
(direct, reproduces the serial solution to round-off); ``gamg`` gives CG + algebraic multigrid.
The solution is gathered on every rank (``Scatter.toAll``) and expanded u = T u_r there.

Cohesive interfaces: the blocks and their damage state are replicated (the serial
``InterfaceController``), each rank assembles the block rows on its elements (part of the exact
preallocation), and :class:`DistributedProblem` offers the interface of
:class:`layershell.solver.problem.Problem`, so that the serial ``load_steps``/``newton``
(active-set loop, bisection, damage commit) and ``path_steps`` run on it unchanged.

Run with ``mpiexec -n 2 python -m layershell.parallel MODEL.toml`` (docs/distributed.md).
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Iterator

import numpy as np

from ..constraints import constraint_operator
from ..dofs import number_dofs
from ..loads import external_forces
from ..model import Model
from ..solver import linear
from ..solver.newton import ConvergenceError, DebondCut, NewtonResult, NewtonSettings, at_round_off_floor
from ..solver.newton import load_steps as serial_load_steps
from ..solver.problem import Problem
from .partition import LocalAssembly, element_ranges, element_weights, interface_rows

SOLVERS = ("mumps", "gamg")


class PetscUnavailableError(RuntimeError):
    """petsc4py/mpi4py cannot be imported."""


def find_petsc4py() -> None:
    """Make Debian's petsc4py importable where ``PETSC_DIR`` is unset (its ``.pth`` file needs it):
    append the newest ``/usr/lib/petscdir/*/*-real`` Python path. No-op where petsc4py imports."""
    try:
        import petsc4py  # noqa: F401
    except ImportError:
        import glob
        import sys

        found = sorted(glob.glob("/usr/lib/petscdir/petsc*/*-real/lib/python3/dist-packages"))
        if found and found[-1] not in sys.path:
            sys.path.append(found[-1])


def unavailable_message(exc: Exception) -> str:
    return (f"distributed runs need petsc4py and mpi4py built for this Python and NumPy ({exc}); on "
            "Debian/Ubuntu: `apt-get install python3-petsc4py python3-mpi4py`, then run with a venv made "
            "by `make test-mpi` or `/usr/bin/python3 -m venv --system-site-packages .venv-mpi` "
            "(see docs/distributed.md)")


def import_petsc():
    """``(PETSc, MPI)`` or a clear error telling how to install them."""
    find_petsc4py()
    try:
        from mpi4py import MPI
        from petsc4py import PETSc
    except (ImportError, ValueError) as exc:  # ValueError: petsc4py built for another NumPy
        raise PetscUnavailableError(unavailable_message(exc)) from exc
    return PETSc, MPI


class SolveError(RuntimeError):
    """The distributed linear solve failed (singular reduced tangent or no KSP convergence)."""


class UnsupportedModelError(ValueError):
    """The model uses a feature that distributed runs do not support yet."""


def check_supported(model: Model) -> None:
    """Raise :class:`UnsupportedModelError` for models the distributed solve cannot handle:
    interfaces other than ``law = "cohesive"`` (the thesis's stress criterion releases bonds and
    so changes the constraint operator and the sparsity pattern; contact-only interfaces)."""
    from ..cohesive import CohesiveLaw

    inelastic = [ly.name for ly in model.layers if ly.inelastic]
    if inelastic:
        raise UnsupportedModelError(
            f"distributed runs support elastic layers only, but layer(s) {', '.join(repr(n) for n in inelastic)} "
            "have a concrete material or reinforcement (their point states are not distributed yet); run "
            "serially with `layershell run`")
    other = sorted(model.layers[k].name for k, law in model.interface_laws.items() if not isinstance(law, CohesiveLaw))
    if other:
        names = ", ".join(f"'{n}'" for n in other)
        raise UnsupportedModelError(
            f"distributed runs support bonded models and cohesive interfaces only: the [[interfaces]] "
            f"section(s) of layer {names} use another law (the thesis's stress criterion releases "
            "bonds and changes the sparsity pattern, which is not distributed yet). Set law = \"cohesive\" "
            "there (with G_Ic, G_IIc), or run serially with `layershell run` (see docs/distributed.md)")


def row_ranges(n: int, size: int) -> np.ndarray:
    """PETSc's default contiguous split of n rows over ``size`` ranks: boundaries (size + 1,)."""
    per = np.full(size, n // size)
    per[: n % size] += 1
    return np.concatenate([[0], np.cumsum(per)]).astype(np.int64)


@dataclass
class Timings:
    """Wall seconds of the phases, the maximum over the ranks."""

    setup: float = 0.0  # local blocks, patterns, preallocation
    assemble: float = 0.0  # kernel + insertion into PETSc (all evaluations)
    solve: float = 0.0  # KSP solves (factorisation included)
    gather: float = 0.0
    setup_cpu: float = 0.0
    assemble_cpu: float = 0.0  # CPU seconds of this process (meaningful on an oversubscribed machine)
    solve_cpu: float = 0.0
    evaluations: int = 0
    extra: dict = field(default_factory=dict)


class DistributedProblem:
    """The static problem of a bonded model, or one with cohesive interfaces, distributed over the
    ranks of ``comm``."""

    def commit(self, u) -> None:
        """Nothing to commit: the layers are elastic (:func:`check_supported`)."""

    def __init__(self, model: Model, solver: str = "mumps", comm=None):
        check_supported(model)
        if solver not in SOLVERS:
            raise ValueError(f"unknown distributed solver {solver!r}; use one of {', '.join(SOLVERS)}")
        PETSc, MPI = import_petsc()
        t0, c0 = time.perf_counter(), time.process_time()
        self.PETSc, self.MPI = PETSc, MPI
        self.comm = comm if comm is not None else PETSc.COMM_WORLD
        self.mpi = self.comm.tompi4py()
        self.rank, self.size = self.comm.getRank(), self.comm.getSize()
        self.model = model
        self.dm = dm = number_dofs(model)
        below = model.below()
        self.bonded = {up: dm.present[up] & dm.present[lo] for up, lo in below.items()}
        self.F_scaled, self.F_const = external_forces(model, dm)
        # cohesive interfaces: the serial InterfaceController, replicated on every rank
        # (same blocks, same damage state; the block is small next to the shell elements); it
        # unbonds the cohesive interfaces before T is built
        self.extra_blocks: list = []
        self.F_friction = None
        self.interfaces = None
        self.monitor = None
        if model.interface_laws:
            from ..solver.interface_state import InterfaceController

            self.interfaces = InterfaceController.build(self, model.interface_laws, model.initially_debonded,
                                                        model.initial_laws, model.delamination)
        self._bonded_built = {k: v.copy() for k, v in self.bonded.items()}
        self.op = constraint_operator(model, dm, self.bonded)
        if model.mesh.elements.shape[0] < self.size:
            raise UnsupportedModelError(f"{self.size} MPI ranks for {model.mesh.elements.shape[0]} elements: "
                                        "start at most one rank per element (mpiexec -n)")
        self.bounds = element_ranges(element_weights(model), self.size)
        self.elements = np.arange(self.bounds[self.rank], self.bounds[self.rank + 1])
        # an interface block's element rows go to the rank that owns the mesh element below them
        lo_e, hi_e = self.bounds[self.rank], self.bounds[self.rank + 1]
        extra = [(b, interface_rows(b, lo_e, hi_e)) for b in self.extra_blocks]
        self.local = LocalAssembly(model, dm, self.op, self.elements, extra=extra)
        self.assembler = _Assembler(self)
        n = self.op.n_red
        self.rows = row_ranges(n, self.size)
        self.lo, self.hi = int(self.rows[self.rank]), int(self.rows[self.rank + 1])
        self.A = self._create_matrix()
        self.b = self.A.createVecLeft()
        self.x = self.A.createVecRight()
        self._gather, self._x_all = PETSc.Scatter.toAll(self.x)
        self.ksp = self._create_ksp(solver)
        self.solver = solver
        self._assembled = False
        self.timings = Timings()
        self.timings.setup = self._max(time.perf_counter() - t0)
        self.timings.setup_cpu = self._max(time.process_time() - c0)

    # --- setup -------------------------------------------------------------------------------
    def _max(self, t: float) -> float:
        return float(self.mpi.allreduce(t, op=self.MPI.MAX))

    def _create_matrix(self):
        """MPIAIJ matrix with the exact pattern: every rank sends its reduced entries (row, col)
        to the row's owner, which counts the distinct diagonal-/off-diagonal-block columns."""
        PETSc, MPI = self.PETSc, self.MPI
        n = self.op.n_red
        pat = self.local.pattern
        key = pat.rows * n + pat.cols
        owner = np.searchsorted(self.rows[1:], pat.rows, side="right")
        order = np.argsort(owner, kind="stable")
        send = np.ascontiguousarray(key[order], dtype=np.int64)
        scount = np.bincount(owner, minlength=self.size).astype(np.int64)
        rcount = np.empty(self.size, np.int64)
        self.mpi.Alltoall(scount, rcount)
        sdisp = np.concatenate([[0], np.cumsum(scount)[:-1]])
        rdisp = np.concatenate([[0], np.cumsum(rcount)[:-1]])
        recv = np.empty(int(rcount.sum()), np.int64)
        self.mpi.Alltoallv([send, (scount, sdisp), MPI.INT64_T], [recv, (rcount, rdisp), MPI.INT64_T])
        own = np.unique(recv)
        r, c = own // n - self.lo, own % n
        nloc = self.hi - self.lo
        diag = (c >= self.lo) & (c < self.hi)
        d_nnz = np.bincount(r[diag], minlength=nloc).astype(PETSc.IntType)
        o_nnz = np.bincount(r[~diag], minlength=nloc).astype(PETSc.IntType)
        self.nnz = int(self.mpi.allreduce(own.size))
        A = PETSc.Mat().create(comm=self.comm)
        A.setSizes(((nloc, n), (nloc, n)))
        A.setType(PETSc.Mat.Type.AIJ)
        A.setPreallocationNNZ((d_nnz, o_nnz))
        A.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, True)
        # the local contribution in CSR form over its distinct rows (pattern is sorted row-major)
        urows, start = np.unique(pat.rows, return_index=True)
        self._csr_rows = urows.astype(PETSc.IntType)
        self._csr_ptr = np.concatenate([start, [pat.rows.size]]).astype(PETSc.IntType)
        self._csr_cols = pat.cols.astype(PETSc.IntType)
        self._red_dofs = self.local.red_dofs.astype(PETSc.IntType)
        self._own = np.arange(self.lo, self.hi, dtype=PETSc.IntType)
        return A

    def _create_ksp(self, solver: str):
        PETSc = self.PETSc
        ksp = PETSc.KSP().create(comm=self.comm)
        ksp.setOperators(self.A)
        pc = ksp.getPC()
        if solver == "mumps":
            if not PETSc.Sys.hasExternalPackage("mumps"):
                raise RuntimeError("this PETSc has no MUMPS; use solver='gamg'")
            ksp.setType(PETSc.KSP.Type.PREONLY)
            pc.setType(PETSc.PC.Type.LU)
            pc.setFactorSolverType("mumps")
        else:
            ksp.setType(PETSc.KSP.Type.CG)
            pc.setType(PETSc.PC.Type.GAMG)
            ksp.setTolerances(rtol=1e-12, atol=0.0, max_it=5000)
        ksp.setOptionsPrefix("ls_")
        ksp.setFromOptions()  # -ls_ksp_type, -ls_pc_type, ... override from the command line
        return ksp

    # --- evaluation --------------------------------------------------------------------------
    def reduced_external(self, lam: float) -> np.ndarray:
        """Tᵀ(λ F_scaled + F_const) (replicated)."""
        return self.op.reduce(lam * self.F_scaled + self.F_const)

    def assemble(self, u_full: np.ndarray, lam: float, tangent: bool = True) -> None:
        """b = Tᵀ(λF - f_int(u)) and (with ``tangent``) A = Tᵀ K(u) T, both distributed."""
        PETSc = self.PETSc
        t0, c0 = time.perf_counter(), time.process_time()
        f_r, data = self.local.evaluate(u_full, tangent)
        b = self.b
        b.zeroEntries()
        b.setValues(self._red_dofs, -f_r, addv=PETSc.InsertMode.ADD_VALUES)
        b.setValues(self._own, self.reduced_external(lam)[self.lo:self.hi], addv=PETSc.InsertMode.ADD_VALUES)
        b.assemblyBegin()
        if tangent:
            self._insert(data)
        b.assemblyEnd()
        self.timings.assemble += time.perf_counter() - t0
        self.timings.assemble_cpu += time.process_time() - c0
        self.timings.evaluations += 1

    def solve(self) -> np.ndarray:
        """Solve A x = b (current assembly); the reduced solution on every rank."""
        PETSc = self.PETSc
        t0, c0 = time.perf_counter(), time.process_time()
        try:
            self.ksp.solve(self.b, self.x)
        except PETSc.Error as exc:
            raise SolveError(f"PETSc failed in the linear solve ({exc}); the reduced tangent may be "
                             "singular (check that the supports prevent every rigid-body motion)") from exc
        reason = self.ksp.getConvergedReason()
        self.timings.solve += time.perf_counter() - t0
        self.timings.solve_cpu += time.process_time() - c0
        if reason < 0:
            raise SolveError(f"PETSc KSP failed (reason {reason}); the reduced tangent may be singular "
                             "(check that the supports prevent every rigid-body motion)")
        t0 = time.perf_counter()
        self._gather.scatter(self.x, self._x_all, addv=PETSc.InsertMode.INSERT_VALUES,
                             mode=PETSc.ScatterMode.FORWARD)
        out = self._x_all.getArray(readonly=True).copy()
        self.timings.gather += time.perf_counter() - t0
        return out

    def residual_norm(self) -> float:
        return float(self.b.norm())

    # --- the interface of solver.problem.Problem (serial Newton/active-set loop on this problem)
    impose = Problem.impose
    external = Problem.external
    reactions = Problem.reactions
    snapshot = Problem.snapshot
    restore = Problem.restore
    prescribed = Problem.prescribed
    # the stability check (stability.py) reads the inertia of each step's first factorisation;
    # PETSc's KSP reports none, so it stays unknown on distributed runs
    start_inertia = None
    start_open = False

    def begin_step(self) -> None:
        """A load step or path increment starts (Problem.begin_step): nothing to keep here."""

    def solve_tangent(self, Kr, r: np.ndarray, backend: str = "auto", reuse: str = "auto") -> np.ndarray:
        """K_r x = r by the KSP (Problem.solve_tangent, without the inertia)."""
        return self.linear_solver(backend, reuse).solve(Kr, r)

    def rebuild_constraints(self) -> None:
        """T stays: cohesive interfaces never change the bond state (a thesis-law release would
        change T and the preallocated pattern, and is refused by :func:`check_supported`)."""
        if any(not np.array_equal(v, self._bonded_built[k]) for k, v in self.bonded.items()):
            raise UnsupportedModelError("the bond state changed during a distributed run; bond releases "
                                        "(thesis-law interfaces) are not distributed yet")

    def linear_solver(self, backend: str = "auto", reuse: str = "auto") -> "_Solver":
        """The PETSc KSP as :class:`layershell.solver.linear.LinearSolver` (``backend`` and
        ``reuse`` are ignored: the KSP set up from ``solver`` and the ``-ls_`` options)."""
        return _Solver(self)

    def internal_force(self, u_full: np.ndarray, tangent: bool) -> np.ndarray:
        """The full-space internal force f_int(u) on every rank (the ranks' parts summed on rank
        0 and broadcast, so that every rank takes the same decisions from it); with ``tangent``
        also A = Tᵀ K(u) T assembled."""
        t0, c0 = time.perf_counter(), time.process_time()
        f_loc, data = self.local.evaluate_local(u_full, tangent)
        part = np.zeros(self.dm.n_full)
        part[self.local.full_dofs] = f_loc
        f = np.empty_like(part)
        self.mpi.Reduce(part, f, op=self.MPI.SUM, root=0)
        self.mpi.Bcast(f, root=0)
        if tangent:
            self._insert(data)
        self.timings.assemble += time.perf_counter() - t0
        self.timings.assemble_cpu += time.process_time() - c0
        self.timings.evaluations += 1
        return f

    def _insert(self, data: np.ndarray) -> None:
        """A = the ranks' K_r entries ``data`` on their patterns (ADD_VALUES)."""
        PETSc = self.PETSc
        A = self.A
        A.zeroEntries()
        A.setValuesIJV(self._csr_ptr, self._csr_cols, data, addv=PETSc.InsertMode.ADD_VALUES,
                       rowmap=self._csr_rows)
        A.assemblyBegin()
        A.assemblyEnd()
        if not self._assembled:  # later assemblies send to the same ranks: cheaper exchange
            A.setOption(PETSc.Mat.Option.SUBSET_OFF_PROC_ENTRIES, True)
            self._assembled = True

    def solve_replicated(self, r: np.ndarray) -> np.ndarray:
        """Solve A x = r for a replicated reduced right-hand side (every rank sets its rows)."""
        self.b.setArray(np.ascontiguousarray(r[self.lo:self.hi]))
        return self.solve()

    # --- solves ------------------------------------------------------------------------------
    def solve_linear(self, lam: float = 1.0, u_full: np.ndarray | None = None) -> np.ndarray:
        """One linear solve K_r x = Tᵀ(λF - f_int(u)) at ``u`` (default 0): the linear solution for
        ``nonlinear = false`` models, the first Newton correction otherwise."""
        u = np.zeros(self.dm.n_full) if u_full is None else u_full
        self.assemble(u, lam)
        return self.solve()

    def newton(self, u: np.ndarray, lam: float, s: NewtonSettings) -> tuple[np.ndarray, NewtonResult]:
        """Equilibrium at ``lam`` from ``u`` (full space, replicated); the convergence test of
        :func:`layershell.solver.newton.newton_fixed_set` (residual, or round-off floor with
        negligible energy or correction), without line search (no contact here)."""
        ref = float(np.linalg.norm(self.reduced_external(lam)))
        res = NewtonResult(False, 0)
        e0 = None
        for it in range(s.max_iterations + 1):
            self.assemble(u, lam)
            rn = self.residual_norm()
            res.residuals.append(rn)
            if not np.isfinite(rn):
                res.message = "residual is not finite"
                return u, res
            scale = ref if ref > 0 else 1e-300
            if it > 0 and rn <= s.tol_residual * scale:
                res.converged, res.iterations = True, it
                return u, res
            if it == s.max_iterations:
                break
            du = self.solve()
            en = abs(float(self.x.dot(self.b)))
            e0 = en if e0 is None else e0
            dU = self.op.expand(du)
            work = lambda: abs(float((lam * self.F_scaled + self.F_const) @ u))  # noqa: E731  λF·u, the work scale
            if it > 0 and at_round_off_floor(res.residuals, scale, en, e0, dU, u, s, work):
                res.converged, res.iterations = True, it
                res.message = "converged at the round-off floor"
                return u + dU, res
            u = u + dU
        res.iterations = s.max_iterations
        res.message = f"no convergence in {s.max_iterations} iterations (last residual {res.residuals[-1]:.3e})"
        return u, res

    def steps(self, load_factors, s: NewtonSettings | None = None,
              path=None) -> Iterator[tuple[float, np.ndarray, int]]:
        """Newton over the load factors, yielding ``(λ, u_full, iterations)`` per converged step.
        Bonded models with fixed steps: :meth:`newton`, no bisection. Models with cohesive
        interfaces: the serial :func:`layershell.solver.newton.load_steps` on this problem - the
        same active-set loop (``newton``: frozen tension/loading sets, ``set_changed``),
        bisection, and the damage commit ``InterfaceController.update`` after every converged
        step, as ``runner.run`` calls them; every rank runs them on the replicated state and so
        takes the same decisions. ``path`` (``spec.path_following``: arc length or adaptive
        steps): the serial :func:`layershell.solver.arclength.path_steps` on this problem
        (``load_factors`` unused)."""
        s = s or NewtonSettings()
        if self.interfaces is not None or path is not None:
            ctl = self.interfaces
            on_end = ctl.update if ctl is not None else None
            if path is not None:  # as runner._path_steps (without checkpoints and probe watch)
                from ..solver.arclength import path_steps

                measure = (lambda pb: pb.interfaces.debonded_fraction()) if ctl is not None else None
                it = path_steps(self, s, path, on_step_end=on_end, measure=measure)
            else:
                cut = None
                if ctl.settings.max_debond_fraction is not None:
                    cut = DebondCut(ctl.settings.max_debond_fraction, ctl.settings.max_debond_cuts,
                                    lambda pb: pb.interfaces.debonded_fraction())
                it = serial_load_steps(self, load_factors, s, on_step_end=on_end, cut=cut)
            for st in it:
                yield st.load_factor, st.u, st.iterations
            return
        u = np.zeros(self.dm.n_full)
        for lam in load_factors:
            u, res = self.newton(u, float(lam), s)
            if not res.converged:
                raise ConvergenceError(f"distributed Newton: no convergence at load factor {lam:.6g} "
                                       f"({res.message}); bisection is not implemented for MPI runs "
                                       "of bonded models", float(lam), res.residuals[-1])
            yield float(lam), u.copy(), res.iterations

    def load_steps(self, load_factors, s: NewtonSettings | None = None, path=None) -> list[tuple[float, np.ndarray, int]]:
        """:meth:`steps` as a list ``[(λ, u_full, iterations), ...]``."""
        return list(self.steps(load_factors, s, path))

    def damage(self) -> np.ndarray:
        """The committed damage of every cohesive interface point, concatenated (empty without)."""
        from ..cohesive import CohesiveBlock

        d = [b.d_old.ravel() for b in self.extra_blocks if isinstance(b, CohesiveBlock)]
        return np.concatenate(d) if d else np.zeros(0)

    def finish_timings(self) -> Timings:
        """Timings with every phase reduced to its maximum over the ranks."""
        t = self.timings
        return Timings(t.setup, self._max(t.assemble), self._max(t.solve), self._max(t.gather),
                       t.setup_cpu, self._max(t.assemble_cpu), self._max(t.solve_cpu), t.evaluations, dict(t.extra))

    def destroy(self) -> None:
        for obj in (self.ksp, self.A, self.b, self.x, self._x_all, self._gather):
            obj.destroy()


class _Assembler:
    """What the serial Newton loop reads from ``problem.assembler``, on the distributed problem:
    the interface blocks (``extra``), the replicated internal force and the distributed K_r."""

    def __init__(self, pb: DistributedProblem):
        self.pb = pb

    @property
    def extra(self) -> list:
        return self.pb.extra_blocks

    @property
    def symmetric(self) -> bool:
        return all(getattr(b, "symmetric", False) for b in self.extra)

    def evaluate(self, u_full: np.ndarray, tangent: bool = True):
        """``(f_int, None)``: the full-space tangent is never formed here (use
        :meth:`evaluate_reduced`)."""
        if tangent:
            raise NotImplementedError("the distributed problem forms the reduced tangent only (evaluate_reduced)")
        return self.pb.internal_force(u_full, False), None

    def evaluate_reduced(self, u_full: np.ndarray, op, forces: bool = True):
        """``(f_int, A)``: A = Tᵀ K T assembled in the PETSc matrix (the handle for ``_Solver``).
        ``forces``: as the serial :meth:`layershell.assembly.Assembler.evaluate_reduced`'s (the
        serial solvers pass False where they do not read f_int); the ranks compute the force with
        the tangent in one pass anyway, so it is always returned."""
        if op is not self.pb.op:
            raise UnsupportedModelError("the constraint operator changed during a distributed run")
        return self.pb.internal_force(u_full, True), self.pb.A


class _Solver:
    """``solve(K_r, r)`` of :class:`layershell.solver.linear.LinearSolver` by the problem's KSP:
    K_r must be the matrix the last ``evaluate_reduced`` assembled; ``r`` replicated (n_red,) or
    (n_red, k); the solution replicated. A failed solve raises ``SingularSystemError`` (the
    serial Newton turns it into a failed iteration)."""

    def __init__(self, pb: DistributedProblem):
        self.pb = pb

    def solve(self, Kr, r: np.ndarray) -> np.ndarray:
        if Kr is not self.pb.A:
            raise ValueError("the distributed solver solves with the matrix of the last evaluate_reduced")
        try:
            if r.ndim == 1:
                return self.pb.solve_replicated(r)
            return np.column_stack([self.pb.solve_replicated(r[:, j]) for j in range(r.shape[1])])
        except SolveError as exc:
            raise linear.SingularSystemError(str(exc)) from exc
