"""Inelastic material laws at integration points: pure, vectorised point functions.

``ConcreteLaw`` (damage with spectral split, 3D Voigt), ``SteelLaw`` and ``TextileLaw`` (uniaxial,
for bars and textile rovings); each law's ``response`` maps strains and a committed state to stresses,
the consistent tangent and a trial state, never modifying the committed one.
"""
from layershell.laws.concrete import ConcreteLaw, ConcreteState
from layershell.laws.state import PointState
from layershell.laws.uniaxial import SteelLaw, SteelState, TextileLaw, TextileState

__all__ = ["ConcreteLaw", "ConcreteState", "PointState", "SteelLaw", "SteelState", "TextileLaw", "TextileState"]
