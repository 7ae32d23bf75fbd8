"""layershell — surface-oriented multi-director multi-layer shells that delaminate.

Implements the shell model of J. Matheas, *Entwicklung von finiten Schalenelementen zur
Berechnung von Verstärkungen aus Textilbeton bei Flächentragwerken*, TU Dresden 2006, as
specified in ``MODEL.md``. Equation numbers in docstrings refer to that thesis.
"""

__version__ = "0.1.0"
