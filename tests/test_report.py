"""`layershell report DIR`: a self-contained HTML report whose tables match summary.json/probes.csv.

The HTML is parsed with the standard library's html.parser (an independent reader of what the
report wrote); figures must be the folder's PNG files, byte for byte, as data URIs.
"""
from __future__ import annotations

import base64
import csv
import json
import shutil
from html.parser import HTMLParser
from pathlib import Path

import pytest
from typer.testing import CliRunner

from layershell.cli import app
from layershell.io.build import InputError, build, parse
from layershell.report import render, write_report
from layershell.runner import run

ROOT = Path(__file__).resolve().parents[1]
TITLE = 'Cantilever <script>alert("x")</script> & co'


class Tables(HTMLParser):
    """Collects tables (by id) as lists of rows of cell texts, img sources, the <title>, and
    whether any <script> element appears."""

    def __init__(self):
        super().__init__()
        self.tables: dict[str, list[list[str]]] = {}
        self.imgs: list[tuple[str, str]] = []
        self.h1 = ""
        self.scripts = 0
        self._table = None
        self._row = None
        self._cell = None
        self._in_h1 = False

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "table":
            self._table = a.get("id", "")
            self.tables[self._table] = []
        elif tag == "tr" and self._table is not None:
            self._row = []
        elif tag in ("td", "th") and self._row is not None:
            self._cell = ""
        elif tag == "img":
            self.imgs.append((a.get("alt", ""), a.get("src", "")))
        elif tag == "h1":
            self._in_h1 = True
        elif tag == "script":
            self.scripts += 1

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None:
            self._row.append(self._cell)
            self._cell = None
        elif tag == "tr" and self._row is not None:
            self.tables[self._table].append(self._row)
            self._row = None
        elif tag == "table":
            self._table = None
        elif tag == "h1":
            self._in_h1 = False

    def handle_data(self, data):
        if self._cell is not None:
            self._cell += data
        if self._in_h1:
            self.h1 += data


def _parse(text: str) -> Tables:
    p = Tables()
    p.feed(text)
    p.close()
    return p


@pytest.fixture(scope="module")
def results(tmp_path_factory) -> Path:
    """A small linear cantilever run (2 load steps, plots on) with a title that needs escaping."""
    out = tmp_path_factory.mktemp("run")
    path = ROOT / "examples" / "cantilever_thick.toml"
    text = path.read_text().replace('title = "Thick cantilever, parabolic end shear (thesis 3.5.1)"',
                                    f"title = {json.dumps(TITLE)}").replace("n = 1\n", "n = 2\n", 1)
    assert "<script>alert" in text
    spec = build(parse(text, str(path)), path.parent)
    res = run(spec, out, write_vtu=True)
    assert res.converged
    return out


def _close(cell: str, value: float) -> bool:
    return abs(float(cell) - value) <= 1e-5 * max(abs(value), 1e-12)


def test_report_tables_match_summary(results, tmp_path):
    path = write_report(results, tmp_path / "r.html", model="examples/cantilever_thick.toml")
    html = path.read_text(encoding="utf-8")
    p = _parse(html)
    s = json.loads((results / "summary.json").read_text())
    # title escaped: shown as text, no script element injected
    assert p.h1 == TITLE and p.scripts == 0 and "<script>alert" not in html
    meta = dict(p.tables["meta"])
    assert meta["model file"] == "examples/cantilever_thick.toml"
    assert meta["units"] == s["units"] and "UTC" in meta["results written"]
    run_rows = dict(p.tables["run"][1:])
    assert int(run_rows["elements"]) == s["n_elements"] and int(run_rows["DOFs (after constraints)"]) == s["n_dofs"]
    assert int(run_rows["converged steps"]) == len(s["steps"]) == 2
    probes = {k: v for k, v in p.tables["probes"][1:]}
    assert probes.keys() == s["probes"].keys()
    assert all(_close(probes[k], v) for k, v in s["probes"].items())
    conv = p.tables["convergence"]
    assert conv[0][:4] == ["step", "load factor λ", "Newton iterations", "bisections"]
    assert len(conv) - 1 == len(s["steps"])
    for row, st in zip(conv[1:], s["steps"]):
        assert int(row[0]) == st["step"] and _close(row[1], st["load_factor"])
        assert int(row[2]) == st["iterations"] and int(row[3]) == st["bisections"]
    with (results / "probes.csv").open() as f:
        rows = list(csv.reader(f))
    table = p.tables["probes-per-step"]
    assert table[0] == rows[0] and len(table) == len(rows)
    for a, b in zip(table[1:], rows[1:]):
        assert all(_close(x, float(y)) for x, y in zip(a, b))
    # every PNG of the folder embedded byte for byte; VTU/PVD listed, not embedded
    pngs = sorted(results.glob("*.png"))
    assert pngs and [alt for alt, _ in p.imgs] == [q.name for q in pngs]
    for (alt, src), q in zip(p.imgs, pngs):
        assert src.startswith("data:image/png;base64,")
        assert base64.b64decode(src.split(",", 1)[1]) == q.read_bytes()
    files = [r[0] for r in p.tables["files"][1:]]
    assert "solid.pvd" in files
    assert "src=\"http" not in html and "href=\"http" not in html  # self-contained


def test_report_without_optional_pieces(results, tmp_path):
    """Only summary.json: no figures, the per-step table from summary.json, still valid."""
    d = tmp_path / "bare"
    d.mkdir()
    shutil.copy(results / "summary.json", d)
    path = write_report(d)
    assert path == d / "report.html"
    p = _parse(path.read_text(encoding="utf-8"))
    assert p.imgs == [] and "files" not in p.tables
    s = json.loads((d / "summary.json").read_text())
    table = p.tables["probes-per-step"]
    assert table[0] == ["step", "load_factor", "iterations"] + list(s["probes"])
    assert _close(table[-1][3], s["steps"][-1]["probes"]["w_tip"])
    assert dict(p.tables["meta"])["model file"].startswith("not recorded")
    # only probes.csv (no summary.json) works as well
    e = tmp_path / "csvonly"
    e.mkdir()
    shutil.copy(results / "probes.csv", e)
    assert "probes-per-step" in _parse(render(e)).tables


def test_report_failed_run_is_flagged(results, tmp_path):
    d = tmp_path / "failed"
    d.mkdir()
    s = json.loads((results / "summary.json").read_text())
    s.update(converged=False, error="step 3: no convergence <at> λ = 0.7")
    (d / "summary.json").write_text(json.dumps(s))
    html = render(d)
    assert "no convergence &lt;at&gt; λ = 0.7" in html and 'class="bad"' in html


def test_report_bad_folder(tmp_path):
    with pytest.raises(InputError, match="holds none of"):
        render(tmp_path)
    r = CliRunner().invoke(app, ["report", str(tmp_path / "missing")])
    assert r.exit_code == 2 and "does not exist" in r.output and "Traceback" not in r.output


def test_report_cli(results, tmp_path):
    target = tmp_path / "x.html"
    r = CliRunner().invoke(app, ["report", str(results), "--out", str(target)])
    assert r.exit_code == 0, r.output
    assert target.is_file() and target.read_text(encoding="utf-8").startswith("<!DOCTYPE html>")
