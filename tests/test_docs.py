"""The user documentation against the code: scenario keys, links, the README example.

``python tests/test_docs.py`` prints the key tables of ``docs/scenario.md`` as
:func:`schema_rows` renders them from ``quadland.scenario.SCHEMAS`` (with each
key's ``doc`` as a placeholder meaning), for pasting after a schema change:
the paper's schema first, then, under the page's ``# Landing scenarios``
heading, the landing schema.
"""

import importlib
import re
from pathlib import Path

import pytest

from quadland.schema import SCHEMAS, Field

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
PAGES = (*sorted(DOCS.glob("*.md")), ROOT / "README.md")

_KIND = {float: "number", int: "integer", bool: "boolean", str: "string"}
_LINK_RE = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")
#: The heading of docs/scenario.md above which the paper's schema is
#: documented, and below which the landing schema.
LANDING_HEADING = "# Landing scenarios"
#: Pages linked before they are written (by another change): a missing one is
#: reported as an expected failure, not hidden; drop it here once it exists.
PENDING: set = set()
_FENCE_RE = re.compile(r"^(```|~~~)")


def type_text(field: Field) -> str:
    """The table's "type" cell: ``number``, ``3 numbers``, ``1 to 3 numbers``, ``integer``, ..."""
    if field.length is None:
        return _KIND[field.kind]
    if field.min_length is not None and field.min_length != field.length:
        return f"{field.min_length} to {field.length} {_KIND[field.kind]}s"
    return f"{field.length} {_KIND[field.kind]}s"


def range_cell(field: Field) -> str:
    """The table's "range" cell: ``Field.range_text()``, or ``-`` without a range."""
    return field.range_text() or "-"


def schema_rows(section: str, model: str = "paper") -> dict[str, str]:
    """Expected start of each key's row in docs/scenario.md: key, type, unit, range.

    The rest of the row (the meaning) is written by hand.
    """
    return {key: f"| `{key}` | {type_text(f)} | {f.unit} | {range_cell(f)} |"
            for key, f in SCHEMAS[model][section].items()}


def schema_tables(model: str = "paper") -> str:
    """Every section's table of a model's schema, with each key's ``doc`` as its meaning."""
    out = []
    for section, fields in SCHEMAS[model].items():
        out += [f"## [{section}]", "| key | type | unit | range | meaning |",
                "| --- | --- | --- | --- | --- |"]
        out += [f"{row} {fields[key].doc} |" for key, row in schema_rows(section, model).items()]
        out.append("")
    return "\n".join(out)


def _sections(text: str) -> dict[str, str]:
    """The text under each ``## [section]`` heading of docs/scenario.md."""
    parts = re.split(r"^## \[([\w.]+)\].*$", text, flags=re.M)
    return dict(zip(parts[1::2], parts[2::2], strict=True))


def _prose(text: str) -> list[tuple[int, str]]:
    """Numbered lines outside fenced code blocks."""
    out, fenced = [], False
    for n, line in enumerate(text.splitlines(), 1):
        if _FENCE_RE.match(line.strip()):
            fenced = not fenced
        elif not fenced:
            out.append((n, line))
    return out


def _slug(heading: str) -> str:
    """GitHub's anchor of a heading."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def _anchors(page: Path) -> set[str]:
    return {_slug(line.lstrip("#")) for _, line in _prose(page.read_text())
            if line.startswith("#")}


def _model_parts() -> dict[str, str]:
    """docs/scenario.md's text about each model's schema."""
    text = (DOCS / "scenario.md").read_text()
    head, sep, tail = text.partition(f"\n{LANDING_HEADING}")
    assert sep, f"docs/scenario.md: no '{LANDING_HEADING}' heading"
    return {"paper": head, "landing": tail}


@pytest.mark.parametrize("model", sorted(SCHEMAS))
def test_scenario_md_lists_every_key_with_its_unit_and_range(model):
    schema = SCHEMAS[model]
    sections = _sections(_model_parts()[model])
    assert set(sections) == set(schema), (
        f"docs/scenario.md ({model}): one '## [section]' per section")
    for section in schema:
        rows = [ln.strip() for ln in sections[section].splitlines() if ln.startswith("| `")]
        for expected in schema_rows(section, model).values():
            assert any(r.startswith(expected) for r in rows), (
                f"docs/scenario.md ({model}) [{section}]: no row starting {expected!r} "
                "(python tests/test_docs.py prints the tables)")
        documented = {r.split("`")[1] for r in rows}
        assert documented <= set(schema[section]), (
            f"docs/scenario.md ({model}) [{section}]: "
            f"{sorted(documented - set(schema[section]))} are not keys of "
            f"quadland.scenario.SCHEMAS[{model!r}]")


def trajectory_rows() -> list[str]:
    """Expected start of each row of docs/simulation.md's column table: names, unit."""
    from quadland.kinds.paper.simulate import TRAJECTORY

    rows = []
    for f in TRAJECTORY.fields:
        units = f.element_units()
        unit = units[0] if len(set(units)) == 1 else ", ".join(units)
        rows.append("| " + ", ".join(f"`{n}`" for n in f.element_names()) + f" | {unit} |")
    return rows


def test_simulation_md_lists_every_csv_column_with_its_unit():
    lines = [ln.strip() for ln in (DOCS / "simulation.md").read_text().splitlines()]
    for expected in trajectory_rows():
        assert any(ln.startswith(expected) for ln in lines), (
            f"docs/simulation.md: no row starting {expected!r} "
            "(quadland.kinds.paper.simulate.TRAJECTORY)")


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(ROOT)))
def test_relative_links_point_to_existing_files(page):
    broken, pending = [], []
    for n, line in _prose(page.read_text()):
        for target in _LINK_RE.findall(line):
            if re.match(r"[a-z][a-z0-9+.-]*:", target):      # http:, mailto:, ...
                continue
            path, _, anchor = target.partition("#")
            dest = (page.parent / path).resolve() if path else page
            if not dest.exists() and dest in PENDING:
                pending.append(f"line {n}: {target}")
            elif not dest.exists():
                broken.append(f"line {n}: {target} (no such file)")
            elif anchor and dest.suffix == ".md" and anchor not in _anchors(dest):
                broken.append(f"line {n}: {target} (no such heading)")
    assert not broken, f"{page.relative_to(ROOT)}: " + "; ".join(broken)
    if pending:
        pytest.xfail(f"{page.relative_to(ROOT)}: not written yet: " + "; ".join(pending))


def _readme_python() -> str:
    blocks = re.findall(r"^```python\n(.*?)^```", (ROOT / "README.md").read_text(),
                        flags=re.M | re.S)
    assert len(blocks) == 1, "README.md: expected one ```python block"
    return blocks[0]


def test_readme_python_example_runs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)                         # it writes trajectory.csv
    namespace = {}
    exec(compile(_readme_python(), "README.md", "exec"), namespace)
    res = namespace["res"]
    assert (tmp_path / "trajectory.csv").read_text().startswith("t,z_e,")
    assert res.states.shape[0] == len(res["t"])


def _model_md_names() -> list[str]:
    """Dotted names the "function" column of docs/model.md's equation table cites.

    A cell lists ``symbolic.<module>.<name>`` or ``symbolic.<module>`` followed
    by bare names of that module.
    """
    names = []
    text = (DOCS / "model.md").read_text()
    table = text.split("## Equations", 1)[1].split("\n## ", 1)[0]
    for row in table.splitlines():
        if not row.startswith("|") or row.startswith("| ---"):
            continue
        module = None
        for token in re.findall(r"`([^`]+)`", row.rstrip(" |").rsplit("|", 1)[-1]):
            if token.startswith("quadland_symbolic."):
                parts = token.split(".")
                module = _module_of(parts)
                if len(parts) > len(module.split(".")):
                    names.append(token)
            elif module and token.isidentifier():
                names.append(f"{module}.{token}")
    return names


def _module_of(parts: list[str]) -> str:
    """The longest importable module path that begins ``parts``."""
    for n in range(len(parts), 0, -1):
        try:
            importlib.import_module(".".join(parts[:n]))
        except ImportError:
            continue
        return ".".join(parts[:n])
    raise AssertionError(f"no module in {'.'.join(parts)}")


def test_model_md_cites_functions_that_exist():
    names = _model_md_names()
    assert len(names) > 20
    missing = []
    for dotted in names:
        module, _, attr = dotted.rpartition(".")
        if not hasattr(importlib.import_module(module), attr):
            missing.append(dotted)
    assert not missing, f"docs/model.md cites {missing}, which do not exist"


#: A dotted name of the runtime or the symbolic layer, as the pages write it in code
#: spans; ``quadland.h``/``quadland.c`` (files of the generated tree) are not names.
_DOTTED = re.compile(r"`((?:quadland|quadland_symbolic)(?:\.[A-Za-z_][A-Za-z0-9_]*)+)")
_FILES = re.compile(r"^quadland(?:_landing)?\.(?:h|c)$|\.jinja$")


def _resolves(dotted: str) -> bool:
    """Whether ``dotted`` is an importable module followed by attributes (a class's
    annotated attribute, such as a ``ClassVar`` a subclass sets, counts)."""
    parts = dotted.split(".")
    for n in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:n]))
        except ImportError:
            continue
        for attr in parts[n:]:
            if not hasattr(obj, attr):
                return attr in getattr(obj, "__annotations__", {}) and attr == parts[-1]
            obj = getattr(obj, attr)
        return True
    return False


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.name)
def test_every_dotted_name_in_the_pages_exists(page):
    """Each ``quadland.<module>.<name>`` or ``quadland_symbolic.<module>.<name>`` a page
    names in code is a module, or a module's attribute, of the installed package: a
    page cannot keep citing a module or function that moved."""
    missing = [f"line {n}: {m.group(1)}"
               for n, line in enumerate(page.read_text().splitlines(), 1)
               for m in _DOTTED.finditer(line)
               if not _FILES.search(m.group(1)) and not _resolves(m.group(1))]
    assert not missing, f"{page.relative_to(ROOT)} names what does not exist: {missing}"



#: The code whose docstrings, comments and messages name the package's objects.
CODE = [p for folder in ("quadland", "symbolic", "tests", "benchmarks")
        for p in sorted((ROOT / folder).rglob("*")) if p.suffix in (".py", ".jinja")]
_NAMED = re.compile(r"\b((?:quadland|quadland_symbolic)(?:\.[A-Za-z_][A-Za-z0-9_]*)+)")
_FILE_NAME = re.compile(r"\.(?:py|h|c|toml|json|md|jinja|so|csv|png)$")


def test_every_dotted_name_in_the_code_exists():
    """What the docs test asks of the pages, for the code's own words: a docstring, a
    comment, a template or a message that names ``quadland.<module>.<name>`` names
    something that exists (the names of moved modules do not linger)."""
    missing = [f"{p.relative_to(ROOT)}:{n}: {m.group(1)}"
               for p in CODE for n, line in enumerate(p.read_text().splitlines(), 1)
               for m in _NAMED.finditer(line)
               if not _FILE_NAME.search(m.group(1)) and not _resolves(m.group(1))]
    assert len(CODE) > 150 and missing == []


if __name__ == "__main__":
    print(schema_tables())
    print(LANDING_HEADING, "\n")
    print(schema_tables("landing"))
