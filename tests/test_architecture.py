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
    ("quadland", "quadland.exceptions", "quadland.constants", "quadland.interrupt"),
    ("quadland.schema", "quadland.scenario", "quadland.extends", "quadland.output",
     "quadland.png"),
    ("quadland.engine", "quadland.linear", "quadland.metrics", "quadland.analysis"),
    ("quadland.plots",),
    ("quadland.kinds",),
    ("quadland.simulation", "quadland.linearization", "quadland.margins", "quadland.run",
     "quadland.codegen", "quadland.campaign", "quadland.nonlinear"),
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


def _is_type_checking(test: ast.expr) -> bool:
    """``TYPE_CHECKING`` or ``typing.TYPE_CHECKING`` itself (not ``not TYPE_CHECKING``)."""
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
        and isinstance(test.value, ast.Name) and test.value.id == "typing")


def _runtime_imports(tree: ast.AST):
    """The import statements that run: all but those in the body of ``if TYPE_CHECKING:``."""
    typing_only = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and _is_type_checking(node.test):
            typing_only.update(id(n) for stmt in node.body for n in ast.walk(stmt))
    for node in ast.walk(tree):
        if isinstance(node, ast.Import | ast.ImportFrom) and id(node) not in typing_only:
            yield node


def _dynamic_imports(tree: ast.AST, name: str, is_package: bool) -> list[str]:
    """Modules named by string: ``import_module("a.b")`` (or ``(".b", __name__)``) and
    the values of a module-level ``_LAZY`` map, a package's names loaded on first use
    (``{"name": "a.b"}``, or a submodule's bare name)."""
    here = name if is_package else name.rpartition(".")[0]
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and (
                (isinstance(node.func, ast.Attribute) and node.func.attr == "import_module")
                or (isinstance(node.func, ast.Name) and node.func.id == "import_module")) \
                and node.args and isinstance(node.args[0], ast.Constant):
            target = node.args[0].value
            found.append(f"{here}{target}" if target.startswith(".") else target)
    for node in getattr(tree, "body", []):
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "_LAZY"
                                                for t in node.targets) \
                and isinstance(node.value, ast.Dict):
            for v in node.value.values:
                if isinstance(v, ast.Constant) and isinstance(v.value, str):
                    found.append(v.value if "." in v.value else f"{here}.{v.value}")
    return found


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
        if name != package:      # the package's own face: see LAYERS
            out.update(r for t in _dynamic_imports(ast.parse(path.read_text()), name,
                                                   path.name == "__init__.py")
                       if t.split(".")[0] == package and (r := resolve(t)) is not None)
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
    TYPE_CHECKING is not an edge (one under ``not TYPE_CHECKING`` is), a relative
    import resolves, an ``import_module`` string and a ``_LAZY`` map are edges."""
    import tempfile

    with tempfile.TemporaryDirectory() as tmp:
        pkg = Path(tmp) / "pkgx"
        pkg.mkdir()
        (pkg / "__init__.py").write_text("")
        (pkg / "a.py").write_text("def f():\n    from pkgx import b\n")
        (pkg / "b.py").write_text("from . import a\n")
        (pkg / "c.py").write_text("from typing import TYPE_CHECKING\n"
                                  "if TYPE_CHECKING:\n    from pkgx.a import f\n")
        # the same, made at run time: an import_module string, `if not TYPE_CHECKING`
        (pkg / "d.py").write_text("import importlib\n"
                                  "def g():\n    return importlib.import_module('pkgx.e')\n")
        (pkg / "e.py").write_text("from typing import TYPE_CHECKING\n"
                                  "if not TYPE_CHECKING:\n    from pkgx import d\n")
        # a subpackage's names loaded on first use, and a submodule importing its face
        (pkg / "sub").mkdir()
        (pkg / "sub" / "__init__.py").write_text("_LAZY = {'h': 'h'}\n")
        (pkg / "sub" / "h.py").write_text("from pkgx.sub import x\n")
        global ROOT
        saved, ROOT = ROOT, Path(tmp)
        try:
            graph = import_graph("pkgx", "pkgx")
        finally:
            ROOT = saved
    assert graph["pkgx.a"] == {"pkgx.b"} and graph["pkgx.b"] == {"pkgx.a"}
    assert graph["pkgx.c"] == set()
    assert graph["pkgx.d"] == {"pkgx.e"} and graph["pkgx.e"] == {"pkgx.d"}
    assert graph["pkgx.sub"] == {"pkgx.sub.h"} and graph["pkgx.sub.h"] == {"pkgx.sub"}
    assert cycles(graph) == [["pkgx.a", "pkgx.b"], ["pkgx.d", "pkgx.e"],
                             ["pkgx.sub", "pkgx.sub.h"]]


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


@pytest.mark.parametrize("folder, package", [("quadland", "quadland"),
                                             ("symbolic", "quadland_symbolic")])
def test_no_private_name_crosses_a_module(folder, package):
    """``from quadland.<module> import _y`` (or ``from .x import _y``, typing imports
    included) would tie a module to another's internals."""
    found = []
    for name, path in _modules(folder, package).items():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and (
                    node.level or (node.module or "").startswith(("quadland", package))):
                found += [f"{name}: {'.' * node.level}{node.module or ''}.{a.name}"
                          for a in node.names
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


#: Modules over 500 lines and functions over 80 that docs/overview.md ("Size")
#: would have to explain, by path (``path:function``): none today.
SIZE_EXCEPTIONS: frozenset[str] = frozenset()


@pytest.mark.parametrize("folder", ["quadland", "symbolic"])
def test_modules_and_functions_stay_small(folder):
    """No module over 500 lines and no function over 80, but those the docs explain."""
    over = []
    for path in sorted((ROOT / folder).rglob("*.py")):
        rel = path.relative_to(ROOT).as_posix()
        text = path.read_text()
        if text.count("\n") > 500 and rel not in SIZE_EXCEPTIONS:
            over.append(f"{rel}: {text.count(chr(10))} lines")
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                n = node.end_lineno - node.lineno + 1
                if n > 80 and f"{rel}:{node.name}" not in SIZE_EXCEPTIONS:
                    over.append(f"{rel}:{node.lineno} {node.name}: {n} lines")
    assert over == []


def test_every_kind_s_schema_holds_the_keys_the_engine_reads():
    """The engine, the plan and the margin review read SHARED_KEYS of any scenario:
    each kind's schema holds each of them, so a new kind meets the contract or fails
    here, not in a run."""
    from quadland.kinds import KINDS
    from quadland.schema import SCHEMAS, SHARED_KEYS

    assert set(KINDS) == set(SCHEMAS)
    for name, schema in SCHEMAS.items():
        missing = [k for k in SHARED_KEYS
                   if k.partition(".")[2] not in schema.get(k.partition(".")[0], {})]
        assert missing == [], f"{name}'s schema lacks {missing}"
    # and the engine reads no other section directly
    read = set()
    for folder in ("engine",):
        for path in sorted((ROOT / "quadland" / folder).rglob("*.py")):
            for node in ast.walk(ast.parse(path.read_text())):
                if isinstance(node, ast.Subscript) and isinstance(node.value, ast.Attribute) \
                        and node.value.attr == "data" and isinstance(node.slice, ast.Constant):
                    read.add(node.slice.value)
    assert read and read <= {k.partition(".")[0] for k in SHARED_KEYS}
