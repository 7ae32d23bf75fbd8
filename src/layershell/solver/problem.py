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

    @classmethod
    def build(cls, model: Model) -> "Problem":
        dm = number_dofs(model)
        below = model.below()
        bonded = {up: dm.present[up] & dm.present[lo] for up, lo in below.items()}
        op = constraint_operator(model, dm, bonded)
        Fs, Fc = external_forces(model, dm)
        return cls(model, dm, Assembler(model, dm), op, Fs, Fc, bonded)

    def rebuild_constraints(self) -> None:
        self.op = constraint_operator(self.model, self.dm, self.bonded)

    def external(self, lam: float) -> np.ndarray:
        return lam * self.F_scaled + self.F_const
