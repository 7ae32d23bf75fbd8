"""Closed-form and semi-analytic reference solutions used to validate the finite elements."""
