"""Distributed assembly and solve over MPI ranks (PETSc via petsc4py), docs/distributed.md.

:mod:`.partition` (NumPy/SciPy only): element ranges per rank and the local assembly into the
reduced system. :mod:`.petsc`: the PETSc matrix/vector/KSP side (imports petsc4py lazily).
Command line: ``mpiexec -n 2 python -m layershell.parallel MODEL.toml --out result.npz``.
"""
from .partition import LocalAssembly, element_ranges, element_weights, interface_rows, local_blocks

__all__ = ["LocalAssembly", "element_ranges", "element_weights", "interface_rows", "local_blocks"]
