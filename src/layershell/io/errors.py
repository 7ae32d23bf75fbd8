"""Bad-input error and small helpers shared by the model-file builder (:mod:`.build`) and the
probes (:mod:`.probes`), in a module of their own so that neither imports the other's module
for them (no import circle)."""
from __future__ import annotations

from ..formula import FormulaError, compile_formula

XYZ = ("x", "y", "z")


class InputError(ValueError):
    """Bad input, with a message for the user (exit code 2 in the CLI)."""


def formula(text, variables, field: str):
    """Compile a model-file formula; InputError naming ``field`` if it is not valid."""
    try:
        return compile_formula(str(text), variables)
    except FormulaError as exc:
        raise InputError(f"'{field}': {exc}") from None
