"""Point states of the inelastic laws: frozen dataclasses of equally long float arrays.

A law's ``response`` reads a committed state and returns a new trial state; the caller keeps
both (trial/committed split) and writes them to checkpoints with ``to_dict``/``from_dict``.
"""
from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np


@dataclass(frozen=True)
class PointState:
    """Base of the point states: every field is a float array of length ``n``."""

    def __post_init__(self):
        lengths = set()
        for f in fields(self):
            a = np.array(getattr(self, f.name), dtype=float, copy=True).reshape(-1)
            object.__setattr__(self, f.name, a)
            lengths.add(a.size)
        if len(lengths) > 1:
            raise ValueError(f"{type(self).__name__}: the fields have different lengths {sorted(lengths)}; "
                             "every field holds one value per point")

    @property
    def n(self) -> int:
        """Number of points."""
        fs = fields(self)
        return getattr(self, fs[0].name).size if fs else 0

    def copy(self):
        return type(self)(**{f.name: getattr(self, f.name).copy() for f in fields(self)})

    def to_dict(self, prefix: str = "") -> dict[str, np.ndarray]:
        """Plain arrays keyed ``prefix + field`` (for checkpoints)."""
        return {prefix + f.name: getattr(self, f.name).copy() for f in fields(self)}

    @classmethod
    def from_dict(cls, d, prefix: str = ""):
        """The state written by :meth:`to_dict` with the same ``prefix``."""
        missing = [prefix + f.name for f in fields(cls) if prefix + f.name not in d]
        if missing:
            raise KeyError(f"{cls.__name__}.from_dict: missing {', '.join(missing)}")
        return cls(**{f.name: np.asarray(d[prefix + f.name], float) for f in fields(cls)})

    def take(self, which):
        """The points selected by a boolean mask or an index array."""
        return type(self)(**{f.name: getattr(self, f.name)[which] for f in fields(self)})
