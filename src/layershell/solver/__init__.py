"""Nonlinear solution: linear solvers, the static problem, Newton-Raphson with load stepping."""
