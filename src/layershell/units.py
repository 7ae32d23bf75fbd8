"""Physical units of the quantities on figure axes, derived from ``[model] units``.

``units`` names a force and a length unit, in either order, apart by a comma, semicolon or space
(e.g. ``"kN, m"``, ``"N, mm"``). Stresses and tractions are then force/length², line loads and
energy per area force/length, moments force·length, areas length².
"""
from __future__ import annotations

import re
from dataclasses import dataclass

#: the length and force units that ``[model] units`` may name
LENGTH_UNITS = ("m", "dm", "cm", "mm", "µm", "um", "km", "in", "ft")
FORCE_UNITS = ("N", "mN", "daN", "kN", "MN", "GN", "lbf", "kip")


@dataclass(frozen=True)
class Units:
    """Force and length unit of a model; empty strings where ``units`` does not name them."""

    force: str = ""
    length: str = ""

    @classmethod
    def parse(cls, text: str | None) -> Units:
        parts = re.split(r"[,;\s]+", (text or "").strip()) if (text or "").strip() else []
        if len(parts) != 2:
            return cls()
        force, length = parts
        if force in LENGTH_UNITS and length in FORCE_UNITS:
            force, length = length, force
        if force not in FORCE_UNITS or length not in LENGTH_UNITS:
            return cls()
        return cls(force, length)

    @property
    def known(self) -> bool:
        return bool(self.force and self.length)

    def _combine(self, text: str) -> str:
        return text if self.known else ""

    @property
    def stress(self) -> str:
        """Stress and interface traction: force/length²."""
        return self._combine(f"{self.force}/{self.length}²")

    @property
    def per_length(self) -> str:
        """Line load, stress resultant per unit width, energy per area: force/length."""
        return self._combine(f"{self.force}/{self.length}")

    @property
    def moment(self) -> str:
        return self._combine(f"{self.force}·{self.length}")

    @property
    def moment_per_width(self) -> str:
        return self._combine(f"{self.force}·{self.length}/{self.length}")

    @property
    def area(self) -> str:
        return self._combine(f"{self.length}²")

    def of_probe(self, quantity: str, component: str | None = None) -> str:
        """Unit of a probe's value (before its ``scale``); "" for the load factor and unknown units."""
        component = component or ""
        if quantity in ("displacement", "crack_width"):
            return self.length
        if quantity in ("stress", "traction", "rebar_stress"):
            return self.stress
        if quantity == "debonded_area":
            return self.area
        if quantity == "reaction":
            return self.moment if component.startswith("m") else self.force
        if quantity == "resultant":
            return self.moment_per_width if component.startswith("m") else self.per_length
        return ""


def check_units(text: str) -> str:
    """``text`` if it is empty or names a force and a length unit; else ValueError with the fix."""
    if text.strip() and not Units.parse(text).known:
        raise ValueError(
            f"'{text}' does not name a force and a length unit: give 'force, length' with a force unit of "
            f"{', '.join(FORCE_UNITS)} and a length unit of {', '.join(LENGTH_UNITS)} (e.g. 'kN, m' or 'N, mm'); "
            "stresses are then labelled force/length²")
    return text


def axis_label(name: str, unit: str | None) -> str:
    """``name [unit]``, or ``name`` alone without a unit."""
    return f"{name} [{unit}]" if unit else name


#: metres per length unit and newtons per force unit
_METRES = {"m": 1.0, "dm": 0.1, "cm": 0.01, "mm": 1e-3, "µm": 1e-6, "um": 1e-6, "km": 1e3, "in": 0.0254, "ft": 0.3048}
_NEWTONS = {"N": 1.0, "mN": 1e-3, "daN": 10.0, "kN": 1e3, "MN": 1e6, "GN": 1e9, "lbf": 4.4482216152605,
            "kip": 4448.2216152605}


def si_factors(units: Units) -> tuple[float, float]:
    """(MPa per model stress unit, metres per model length unit) of known ``units``: for the
    material defaults that codes give in MPa and metres (concrete strength classes, steel grades)."""
    if not units.known:
        raise ValueError("the model's units are not known")
    m, n = _METRES[units.length], _NEWTONS[units.force]
    return n / m ** 2 / 1e6, m

