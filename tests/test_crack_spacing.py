"""Crack spacing after EN 1992-1-1 §7.3.4 and the note on elements shorter than it."""
import math
from pathlib import Path

import pytest

from layershell.analytic.crack_spacing import max_crack_spacing, mean_crack_spacing
from layershell.io.build import load
from layershell.material import MaterialError

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "rc_strip.toml"


def test_max_crack_spacing_by_hand():
    """The RC strip's 5 Ø10/m at 30 mm from the soffit of a 160 mm slab, worked by hand: c = 25 mm,
    h_c,ef = min(2.5 · 30, 80) = 75 mm, ρ = (π 25/200)/75 = 0.0052360, s_r,max = 3.4 · 25 +
    0.8 · 0.5 · 0.425 · 10/0.0052360 = 85 + 324.68 = 409.68 mm; s_rm = 409.68/1.7 = 240.99 mm."""
    a = math.pi * 25.0 / 200.0
    assert max_crack_spacing(25.0, 10.0, a, 160.0) == pytest.approx(409.68, abs=0.01)
    assert mean_crack_spacing(25.0, 10.0, a, 160.0) == pytest.approx(240.99, abs=0.01)
    # a thin slab: h/2 limits the effective depth (2.5 · 30 = 75 > 60/2 = 30), pure tension k2 = 1
    assert max_crack_spacing(25.0, 10.0, a, 60.0, k2=1.0) == pytest.approx(85 + 0.8 * 0.425 * 10 / (a / 30), rel=1e-12)
    with pytest.raises(MaterialError, match="'cover'"):
        max_crack_spacing(0.0, 10.0, a, 160.0)


@pytest.mark.parametrize("nx, noted", [(6, False), (12, False), (15, True)])
def test_note_on_elements_shorter_than_the_crack_spacing(tmp_path, nx, noted):
    """Bands of 181 and 128 mm pass, 114 mm (< s_rm/2 = 120.5 mm) gets the note with s_rm."""
    model = tmp_path / "strip.toml"
    model.write_text(EXAMPLE.read_text(encoding="utf-8").replace("nx = 6\n", f"nx = {nx}\n"), encoding="utf-8")
    notes = [w for w in load(model).warnings if "mean crack spacing" in w]
    assert bool(notes) == noted
    if noted:
        assert "241" in notes[0] and "layer 'slab'" in notes[0]
