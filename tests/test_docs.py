"""Documentation stays true: the model-file reference is generated from the schema, and the
README's Python quick start runs."""
import os
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_model_file_reference_is_up_to_date():
    sys.path.insert(0, str(ROOT / "docs"))
    import gen_model_file_doc

    assert (ROOT / "docs" / "model-file.md").read_text(encoding="utf-8") == gen_model_file_doc.render(), \
        "run: python docs/gen_model_file_doc.py"


def _tables() -> list:
    """Every table (pydantic model) a model file can contain, reached from ModelFile's keys."""
    import typing

    from pydantic import BaseModel

    from layershell.io import schema

    def walk(tp, seen):
        if isinstance(tp, type) and issubclass(tp, BaseModel):
            if tp not in seen:
                seen.append(tp)
                for f in tp.model_fields.values():
                    walk(f.annotation, seen)
        for a in typing.get_args(tp):
            walk(a, seen)
        return seen

    return walk(schema.ModelFile, [])[1:]


def test_every_key_has_a_meaning():
    """Issue 15: the reference gives a one-line meaning for every key of every table."""
    missing = [f"{cls.__name__}.{name}" for cls in _tables() for name, f in cls.model_fields.items()
               if name != "type" and not (f.description or "").strip()]
    assert not missing, f"add description= to these fields in io/schema.py: {missing}"


def test_every_table_is_in_the_reference():
    sys.path.insert(0, str(ROOT / "docs"))
    import gen_model_file_doc

    documented = {cls for _, cls, _ in gen_model_file_doc.SECTIONS}
    missing = [cls.__name__ for cls in _tables() if cls not in documented]
    assert not missing, f"add these tables to SECTIONS in docs/gen_model_file_doc.py: {missing}"


def test_reference_types_are_readable():
    """No pydantic/typing reprs such as Optional[list[float], FieldInfo(annotation=none, ...MinLen...)]."""
    text = (ROOT / "docs" / "model-file.md").read_text(encoding="utf-8")
    for raw in ("FieldInfo", "typing", "Annotated", "Optional[", "Union[", "<class", "layershell.io", "MinLen",
                "Gt(", "NoneType"):
        assert raw not in text, raw
    for raw in (r"\bfloat\b", r"\bint\b", r"\bstr\b", r"\bNone\b", r"\bTrue\b"):
        assert not re.search(raw, text), raw
    rows = [r for r in text.splitlines() if r.startswith("| `")]
    assert len(rows) >= 150
    kinds = {r.split(" | ")[1] for r in rows}
    for expected in ("list of 3 numbers", "number > 0", 'list of "x", "y", "z"', 'one of "+z", "-z"',
                     "number or formula in x, y, z", "integer from 0 to 4", "condition in x, y, z", "true/false"):
        assert expected in kinds, (expected, sorted(kinds))


def test_readme_python_quick_start_runs(tmp_path, monkeypatch):
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    code = re.findall(r"```python\n(.*?)```", text, re.S)[0]
    monkeypatch.chdir(ROOT)
    code = code.replace('out="results/ring"', f'out=r"{tmp_path}"')
    ns: dict = {}
    exec(compile(code, "README.md", "exec"), ns)  # our own README, not user input
    p = ns["res"].summary["probes"]
    assert abs(p["sigma_phi_outer"] + 1.670) < 0.005
    assert (tmp_path / "summary.json").exists()


def test_readme_shows_the_two_commands():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert "make demo" in text and "make test" in text
    assert os.access(ROOT / ".ci" / "run", os.X_OK)


def test_quick_start_puts_layershell_on_path():
    """The quick start types `layershell` bare: it first activates the environment that `make demo`
    installs into, and `make demo` itself ends by saying how (issue 15)."""
    import shutil
    import subprocess

    text = (ROOT / "README.md").read_text(encoding="utf-8")
    block = re.search(r"## Quick start\n\n```bash\n(.*?)```", text, re.S).group(1).splitlines()
    bare = [i for i, line in enumerate(block) if line.startswith("layershell ")]
    activate = [i for i, line in enumerate(block) if line.startswith("source .venv/bin/activate")]
    assert bare and activate and activate[0] < bare[0], block
    if shutil.which("make"):
        dry = subprocess.run(["make", "-n", "demo"], cwd=ROOT, capture_output=True, text=True, timeout=60)
        assert "source .venv/bin/activate" in dry.stdout, dry.stdout + dry.stderr
    if sys.prefix != sys.base_prefix and os.name == "posix" and shutil.which("bash"):
        # in a virtual environment (make test uses .venv): its activate script puts layershell on PATH
        env = {k: v for k, v in os.environ.items() if k != "VIRTUAL_ENV"}
        env["PATH"] = "/usr/bin:/bin"
        found = subprocess.run(["bash", "-c", f'source "{sys.prefix}/bin/activate" && command -v layershell'],
                               capture_output=True, text=True, env=env, timeout=60)
        assert found.returncode == 0, found.stderr
        assert Path(found.stdout.strip()).resolve() == (Path(sys.prefix) / "bin" / "layershell").resolve()


def test_user_guide_refers_to_existing_files():
    """docs/user-guide.md is linked from the README, and every example, doc and output figure it
    names exists / is written by the code (figure names checked against plots.write_figures)."""
    guide = (ROOT / "docs" / "user-guide.md").read_text(encoding="utf-8")
    assert "docs/user-guide.md" in (ROOT / "README.md").read_text(encoding="utf-8")
    named = set(re.findall(r"examples/([\w.]+\.(?:toml|py|geo|msh))", guide))
    named |= set(re.findall(r"`([\w]+\.(?:toml|geo|msh))`", guide))
    named = {n for n in named if not n.split(".")[0].isupper()}  # placeholders: NAME.toml, MODEL.toml
    assert len(named) > 15
    for name in named:
        assert (ROOT / "examples" / name).is_file(), name
    for link in re.findall(r"\]\(([\w./-]+\.md)\)", guide):
        assert (ROOT / "docs" / link).resolve().is_file(), link
    plots = (ROOT / "src" / "layershell" / "plots.py").read_text(encoding="utf-8")
    for png in ("deformed.png", "load_displacement.png", "load_debonded_area.png", "thickness_",
                "load_displacement_", "debonded_zone_"):
        assert png in guide and png in plots, png


# ----------------------------------------------------------------------------- documents state what holds now
#: README is a front page; the details live in docs/
README_MAX_LINES = 200
_MONTH = r"(?:Jan|Feb|Mar|Apr|May|Jun|Jul|Aug|Sep|Oct|Nov|Dec)[a-z]*\.?"
#: history that belongs in git log, not in a document: dated entries (26 Nov 2026, 2026-11-30,
#: Nov 2026, 29-30 Nov, 20:32 UTC), accounts of sessions and issues, before/after logs.
#: Legitimate years need no month: citations such as "(Teng et al. 2003)" or "Williams 1989",
#: and library versions such as "MKL 2026.2", pass.
HISTORY = {
    "a dated entry": re.compile(rf"\b\d{{1,2}}(?:-\d{{1,2}})? {_MONTH}(?: (?:19|20)\d\d)?\b"),
    "an ISO date": re.compile(r"\b(?:19|20)\d\d-[01]\d-[0-3]\d\b"),
    "a month and year": re.compile(rf"\b{_MONTH} (?:19|20)\d\d\b"),
    "a time of day of a run": re.compile(r"\b\d{1,2}:\d\d UTC\b"),
    "a session": re.compile(r"\bsessions?\b", re.I),
    "an issue number": re.compile(r"\bissues? #?\d+", re.I),
    "a before/after log": re.compile(r"\bbefore:", re.I),
}


def history_in(text: str) -> list[str]:
    """The lines of ``text`` that retell history, each with what was found."""
    return [f"{i}: {what}: {line.strip()[:120]}" for i, line in enumerate(text.splitlines(), 1)
            for what, pattern in HISTORY.items() if pattern.search(line)]


def example_header(path: Path) -> str:
    """What an example says about itself: its comment lines (TOML, Gmsh .geo, Python) and a Python
    file's module docstring."""
    text = path.read_text(encoding="utf-8")
    marker = "//" if path.suffix == ".geo" else "#"
    lines = [line for line in text.splitlines() if line.lstrip().startswith(marker)]
    if path.suffix == ".py":
        import ast

        lines.append(ast.get_docstring(ast.parse(text)) or "")
    return "\n".join(lines)


def local_links(markdown: str) -> list[str]:
    """Targets of the Markdown links that point into the repository (no URL, no bare anchor)."""
    targets = re.findall(r"\]\(([^)\s]+)\)", markdown)
    return [t.split("#")[0] for t in targets if not re.match(r"[a-z]+:|#", t)]


def test_the_history_detector_flags_history_and_passes_citations():
    flagged = ["measured on 26 Nov 2026", "re-measured 2026-11-24", "in Nov 2026", "the run of 29-30 Nov",
               "at 20:32 UTC after 75 minutes", "the twelfth session", "(issue 13)", "Issue 6, benchmark 4",
               "before: 85 s"]
    for line in flagged:
        assert history_in(line), line
    for line in ["(Teng et al. 2003)", "Williams 1989; Wang & Williams 1992", "MKL 2026.2, numpy 2.4.6",
                 "fib Model Code 2010 (5.1-9)", "the 3 × 3 face Gauss points", "before the run starts"]:
        assert not history_in(line), (line, history_in(line))


def test_readme_is_a_front_page():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    n = len(text.splitlines())
    assert n <= README_MAX_LINES, f"README.md has {n} lines: move details to docs/ (at most {README_MAX_LINES})"


def test_readme_links_to_files_that_exist():
    links = local_links((ROOT / "README.md").read_text(encoding="utf-8"))
    assert "docs/limits.md" in links and "docs/user-guide.md" in links
    missing = [t for t in links if not (ROOT / t).exists()]
    assert not missing, f"README.md links to files that do not exist: {missing}"


def test_documents_and_example_headers_state_no_history():
    """README.md, docs/*.md and the examples' headers say what holds now; the history of a result
    (when it was measured, in which session, for which issue, what it was before) is in git log."""
    found = {}
    for path in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        found[path.relative_to(ROOT)] = history_in(path.read_text(encoding="utf-8"))
    for path in sorted((ROOT / "examples").iterdir()):
        if path.suffix in (".toml", ".py", ".geo"):
            found[path.relative_to(ROOT)] = history_in(example_header(path))
    found = {str(k): v for k, v in found.items() if v}
    assert not found, "state what holds now; history belongs in git log:\n" + "\n".join(
        f"{k}:{line}" for k, v in found.items() for line in v)
