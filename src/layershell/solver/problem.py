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
    solvers: dict = field(default_factory=dict, repr=False)  # backend -> LinearSolver

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
        self.op = constraint_operator(self.model, self.dm, self.bonded)

    def linear_solver(self, backend: str = "auto"):
        """This problem's linear solver (keeps PARDISO's symbolic analysis between iterations)."""
        from .linear import LinearSolver

        if backend not in self.solvers:
            # contact/delamination: penalty-stiffened, ill-conditioned, partly unsymmetric tangents
            self.solvers[backend] = LinearSolver(backend, symmetric=self.interfaces is None)
        return self.solvers[backend]

    def snapshot(self) -> dict:
        """Copy of the mutable delamination state (bond flags, per-point history, friction
        anchors) to undo a load increment (step cutting)."""
        snap: dict = {"bonded": {k: v.copy() for k, v in self.bonded.items()}, "runs": []}
        if self.interfaces is not None:
            snap["resolves"] = self.interfaces.resolves
            for r in self.interfaces.runs:
                snap["runs"].append((_copy_state(r), _copy_state(r.block)))
        return snap

    def restore(self, snap: dict) -> None:
        """Undo to a :meth:`snapshot`; rebuilds the constraint operator."""
        for k, v in snap["bonded"].items():
            self.bonded[k] = v.copy()
        if self.interfaces is not None:
            self.interfaces.resolves = snap["resolves"]
            for r, (rs, bs) in zip(self.interfaces.runs, snap["runs"]):
                for obj, st in ((r, rs), (r.block, bs)):
                    for k, v in st.items():
                        setattr(obj, k, v.copy() if isinstance(v, np.ndarray) else v)
            self.interfaces.sync(self)
        self.rebuild_constraints()

    def external(self, lam: float) -> np.ndarray:
        F = lam * self.F_scaled + self.F_const
        return F if self.F_friction is None else F + self.F_friction


def _copy_state(obj) -> dict:
    """Array and scalar attributes of ``obj`` (copies), i.e. its mutable numeric state."""
    return {k: (v.copy() if isinstance(v, np.ndarray) else v) for k, v in vars(obj).items()
            if isinstance(v, (np.ndarray, float, int, bool)) or v is None}
