"""The runtime's import graph: layered, one way, without circles.

Read from the source with ``ast`` (every ``import``, those inside functions
included; an import under ``if TYPE_CHECKING:`` is not made at run time and
does not count), independently of what Python happens to have imported. The
layers are those of docs/overview.md, bottom first.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent

#: The runtime's layers, bottom first: a module may import its own layer or lower.
#: The package ``quadland`` itself is a lazy face (its names load on first use)
#: holding the version: any module may read it.
LAYERS = (
    ("quadland", "quadland.exceptions", "quadland.constants"),
    ("quadland.schema", "quadland.scenario", "quadland.output"),
    ("quadland.engine", "quadland.linear", "quadland.metrics", "quadland.analysis"),
    ("quadland.plots",),
    ("quadland.kinds",),
    ("quadland.simulation", "quadland.linearization", "quadland.margins", "quadland.run",
     "quadland.codegen", "quadland.campaign"),
    ("quadland.cli", "quadland.__main__"),
)


def _modules(folder: str, package: str) -> dict[str, Path]:
    """``{dotted name: path}`` of the modules under ``folder``, installed as ``package``."""
    mods = {}
    for path in sorted((ROOT / folder).rglob("*.py")):
        parts = list(path.relative_to(ROOT / folder).with_suffix("").parts)
        parts = parts[:-1] if parts[-1] == "__init__" else parts
        mods[".".join([package, *parts])] = path
    return mods


def _runtime_imports(tree: ast.AST):
    typing_only = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            typing_only.update(id(n) for stmt in node.body for n in ast.walk(stmt))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import | ast.ImportFrom) and id(node) not in typing_only:
            yield node


def import_graph(folder: str = "quadland", package: str = "quadland") -> dict[str, set[str]]:
    """``{module: {modules of the package it imports}}``, lazy imports included.

    ``from a.b import c`` counts as an import of ``a.b.c`` when that is a module,
    else of ``a.b``; relative imports resolve against the importing module.
    """
    mods = _modules(folder, package)

    def resolve(name: str) -> str | None:
        while name and name not in mods:
            name = name.rpartition(".")[0]
        return name or None

    graph = {}
    for name, path in mods.items():
        out = set()
        for node in _runtime_imports(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            else:
                base = node.module or ""
                if node.level:
                    pkg = name.split(".") if path.name == "__init__.py" else \
                        name.split(".")[:-1]
                    pkg = pkg[:len(pkg) - (node.level - 1)]
                    base = ".".join([*pkg, base] if base else pkg)
                targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in mods else base
                           for a in node.names]
            out.update(r for t in targets if t.split(".")[0] == package
                       and (r := resolve(t)) is not None)
        out.discard(name)
        graph[name] = out
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index, low, stack, on, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def layer(module: str) -> int:
    """The layer of ``module``: that of its longest prefix in :data:`LAYERS`."""
    best = max(((i, len(p)) for i, names in enumerate(LAYERS) for p in names
                if module == p or module.startswith(p + ".")), key=lambda b: b[1])
    return best[0]


def test_the_graph_reader_sees_lazy_relative_and_typing_imports():
    """A hand-made package: a cycle through a function-level import is found, one under
    TYPE_CHECKING is not an edge, a relative import resolves."""
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        pkg = Path(tmp) / "pkgx"
        pkg.mkdir()
        (pkg / "__init__.py").write_text("")
        (pkg / "a.py").write_text("def f():\n    from pkgx import b\n")
        (pkg / "b.py").write_text("from . import a\n")
        (pkg / "c.py").write_text("from typing import TYPE_CHECKING\n"
                                  "if TYPE_CHECKING:\n    from pkgx.a import f\n")
        global ROOT
        saved, ROOT = ROOT, Path(tmp)
        try:
            graph = import_graph("pkgx", "pkgx")
        finally:
            ROOT = saved
    assert graph["pkgx.a"] == {"pkgx.b"} and graph["pkgx.b"] == {"pkgx.a"}
    assert graph["pkgx.c"] == set()
    assert cycles(graph) == [["pkgx.a", "pkgx.b"]]


@pytest.mark.parametrize("folder, package", [("quadland", "quadland"),
                                             ("symbolic", "quadland_symbolic")])
def test_no_import_circle(folder, package):
    graph = import_graph(folder, package)
    assert len(graph) > 20 and sum(map(len, graph.values())) > 50    # the reader reads
    assert cycles(graph) == []


def test_every_module_has_a_layer_and_imports_only_down():
    graph = import_graph()
    upward = [f"{m} (layer {layer(m)}) imports {t} (layer {layer(t)})"
              for m, deps in sorted(graph.items()) for t in sorted(deps) if layer(t) > layer(m)]
    assert upward == []


def test_the_runtime_does_not_import_upward_into_quadland_from_symbolic():
    """Data flows one way: the symbolic layer never imports the runtime."""
    for path in sorted((ROOT / "symbolic").rglob("*.py")):
        for node in _runtime_imports(ast.parse(path.read_text())):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
                [node.module or ""]
            assert not any(n == "quadland" or n.startswith("quadland.") for n in names), path


def test_no_private_name_crosses_a_module():
    """``from quadland.x import _y`` would tie a module to another's internals."""
    found = []
    for name, path in _modules("quadland", "quadland").items():
        for node in _runtime_imports(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("quadland"):
                found += [f"{name}: {node.module}.{a.name}" for a in node.names
                          if a.name.startswith("_") and not a.name.startswith("__")]
    assert found == []


def test_no_runtime_module_branches_on_the_model_name():
    """The loop kind is an object: outside the kinds and the schemas (which name the
    kinds they register), no module compares ``model`` with a kind's name."""
    found = []
    for name, path in _modules("quadland", "quadland").items():
        if name.startswith(("quadland.kinds", "quadland.schema")):
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Compare):
                text = ast.unparse(node)
                if "model" in text and any(f"'{k}'" in text or f'"{k}"' in text
                                           for k in ("paper", "landing")):
                    found.append(f"{name}:{node.lineno}: {text}")
    assert found == []


def test_module_level_layouts_have_distinct_names():
    """Every layout a symbolic module defines at its top level names its vector
    uniquely, so that a name read in a message, a struct or a table is one vector."""
    import importlib
    import pkgutil

    import quadland_symbolic
    from quadland_symbolic.layout import Layout

    owners: dict[str, str] = {}
    seen: set[int] = set()
    for info in pkgutil.walk_packages(quadland_symbolic.__path__, "quadland_symbolic."):
        module = importlib.import_module(info.name)
        for attr, value in vars(module).items():
            if not isinstance(value, Layout) or id(value) in seen:
                continue
            seen.add(id(value))
            where = f"{info.name}.{attr}"
            assert value.name not in owners, (
                f"layout name {value.name!r} of {where} is also {owners[value.name]}")
            owners[value.name] = where
    assert len(owners) > 40    # the walk saw the landing's and the paper's layouts
