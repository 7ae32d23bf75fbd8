"""Physical units of the quantities on figure axes, derived from ``[model] units``.

``units`` names a force and a length unit (e.g. ``"kN, m"``, ``"N, mm"``; the order is free
when both are recognised, else force first). Stresses and tractions are then force/length²,
line loads and energy per area force/length, moments force·length, areas length².
"""
from __future__ import annotations

from dataclasses import dataclass

#: length units recognised in either position of ``units`` (anything else: force first, length second)
LENGTH_UNITS = frozenset({"m", "dm", "cm", "mm", "µm", "um", "km", "in", "ft"})


@dataclass(frozen=True)
class Units:
    """Force and length unit of a model; empty strings where ``units`` does not name them."""

    force: str = ""
    length: str = ""

    @classmethod
    def parse(cls, text: str | None) -> Units:
        parts = [p.strip() for p in (text or "").replace(";", ",").split(",") if p.strip()]
        if len(parts) != 2:
            return cls()
        force, length = parts
        if force in LENGTH_UNITS and length not in LENGTH_UNITS:
            force, length = length, force
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
        if quantity == "displacement":
            return self.length
        if quantity in ("stress", "traction"):
            return self.stress
        if quantity == "debonded_area":
            return self.area
        if quantity == "reaction":
            return self.moment if component.startswith("m") else self.force
        if quantity == "resultant":
            return self.moment_per_width if component.startswith("m") else self.per_length
        return ""


def axis_label(name: str, unit: str | None) -> str:
    """``name [unit]``, or ``name`` alone without a unit."""
    return f"{name} [{unit}]" if unit else name
