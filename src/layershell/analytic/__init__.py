"""Closed-form and semi-analytic reference solutions (independent of the finite elements)."""
