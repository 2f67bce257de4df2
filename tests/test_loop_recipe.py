"""A compiled simulator keyed by its loop's recipe: nothing built to find it in the cache."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import casadi as ca
import pytest

from quadland.engine.build import have_compiler

needs_cc = pytest.mark.skipif(not have_compiler(), reason="needs a C compiler")


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """A private build cache for the test."""
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    return tmp_path / "xdg" / "quadland"


def _key(model, part="continuous", flight=None, sources=(), opt="-O2", strict=False,
         name=None):
    from quadland.engine.recall import recall_key

    return recall_key(model, part, flight, sources, name or f"qlsim_{model.name}_{part}", opt,
                      strict)


@pytest.mark.parametrize("l", [2, 3])
def test_the_recipe_describes_the_model_it_builds(l):
    """Every layout, flag and absent function the paper's recipe gives without building
    is the built model's (the model built by ``paper_loop`` itself)."""
    from quadland.engine.compiled import built_model
    from quadland.engine.recall import model_digest
    from quadland_symbolic.paper_loop import paper_loop, paper_loop_recipe

    recipe = paper_loop_recipe.__wrapped__(l)
    model = paper_loop.__wrapped__(l)
    for name, value in recipe.known().items():
        assert getattr(model, name) == value, name
    assert recipe.name == model.name == "paper"
    assert {"state", "controller_params", "recorded", "envelope_layout"} <= set(recipe.known())
    built = built_model(recipe)               # built, and checked against the description
    assert built is recipe.model and model_digest(built) == model_digest(model)


def test_a_recipe_that_describes_its_model_wrongly_is_refused():
    from quadland.engine.compiled import built_model
    from quadland_symbolic.loop_recipe import LoopRecipe
    from quadland_symbolic.paper_loop import paper_loop, paper_loop_recipe

    good = paper_loop_recipe.__wrapped__(2)
    wrong = LoopRecipe(paper_loop, (2,), "paper",
                       {**{k: v for k, v in good.known().items() if k != "flight"},
                        "state": paper_loop_recipe(3).state}, frozenset())
    with pytest.raises(ValueError, match="describes its model wrongly: state"):
        built_model(wrong)


def test_a_recipe_of_code_the_key_does_not_cover_is_refused():
    """The key hashes quadland_symbolic's code and the arguments' repr: a builder from
    elsewhere (its code unhashed, so a change to it could be served a stale build) or an
    argument whose repr is not its value is refused."""
    from quadland_symbolic.loop_recipe import LoopRecipe
    from quadland_symbolic.paper_loop import paper_loop, paper_loop_recipe

    known = paper_loop_recipe.__wrapped__(2).known()
    layouts = {k: v for k, v in known.items() if k != "flight"}

    def elsewhere(l):
        return paper_loop(l)

    with pytest.raises(ValueError, match="is not quadland_symbolic's"):
        LoopRecipe(elsewhere, (2,), "paper", layouts, frozenset())
    with pytest.raises(ValueError, match="only numbers and strings"):
        LoopRecipe(paper_loop, (object(),), "paper", layouts, frozenset())


def test_the_key_of_a_recipe_builds_nothing_and_changes_with_each_input(monkeypatch):
    """The key of the paper's recipe differs for another ``l``, part, name, level,
    strictness, flag, budget, flight code, compiler, generator, CasADi, NumPy or
    Jinja2 version; equal recipes (built anew) give equal keys; no model is built."""
    from quadland.engine import build, recall
    from quadland_symbolic.paper_loop import paper_loop_recipe

    two = paper_loop_recipe.__wrapped__(2)
    base = _key(two)
    assert "model" not in vars(two)              # nothing built for the key
    assert base == _key(paper_loop_recipe.__wrapped__(2))
    others = [_key(paper_loop_recipe.__wrapped__(3)), _key(two, "sampled"),
              _key(two, name="qlsim_other"), _key(two, opt="-Os"), _key(two, strict=True),
              _key(two, "sampled_flight", "one flight"),
              _key(two, "sampled_flight", "one flight", ("a.c",))]
    patches = [(build, "RUNTIME_CFLAGS", (*build.RUNTIME_CFLAGS, "-ffast-math")),
               (build, "SHARED_CFLAGS", (*build.SHARED_CFLAGS, "-g")),
               (build, "COMPILE_MEMORY_BUDGET", build.COMPILE_MEMORY_BUDGET + 1),
               (build, "COMPILE_TIME_BUDGET", build.COMPILE_TIME_BUDGET + 1),
               (build, "COMPILE_FIT", {}),
               (build, "compiler_identity", lambda cc: "another compiler"),
               (recall, "generator_digest", lambda: "another generator"),
               (ca, "__version__", ca.__version__ + ".post1")]
    for module, name, value in patches:
        with monkeypatch.context() as m:
            m.setattr(module, name, value)
            recall.library_versions.cache_clear()
            others.append(_key(two))
        recall.library_versions.cache_clear()
    for dist in ("numpy", "jinja2"):
        with monkeypatch.context() as m:
            real = recall.library_versions.__wrapped__
            m.setattr(recall, "library_versions",
                      lambda d=dist, r=real: r().replace(f"{d}=", f"{d}=9"))
            others.append(_key(two))
    assert len(set(others)) == len(others) and base not in others
    assert _key(two) == base and "model" not in vars(two)


def test_the_library_versions_name_numpy_and_the_installed_jinja2():
    """NumPy's version, and Jinja2's ``__init__.py`` (which holds its version) by its
    SHA-256, found without importing Jinja2."""
    import hashlib
    import importlib.metadata

    import jinja2
    import numpy as np

    from quadland.engine import recall

    recall.library_versions.cache_clear()
    text = recall.library_versions()
    source = open(jinja2.__file__, "rb").read()
    assert f'__version__ = "{importlib.metadata.version("jinja2")}"'.encode() in source
    assert f"numpy={np.__version__} " in text and f"casadi={ca.__version__} " in text
    assert text.endswith(f"jinja2={hashlib.sha256(source).hexdigest()}")


def test_the_generator_digest_follows_each_source_and_template(tmp_path, monkeypatch):
    """A changed byte in one module or one template of a copy of ``quadland_symbolic``
    changes its digest; the same files give the same digest."""
    import quadland_symbolic
    from quadland.engine import recall

    root = tmp_path / "quadland_symbolic"
    src = quadland_symbolic.__file__.rsplit("/", 1)[0]
    shutil.copytree(src, root, ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr(quadland_symbolic, "__file__", str(root / "__init__.py"))

    def digest():
        recall.generator_digest.cache_clear()
        return recall.generator_digest()

    try:
        first = digest()
        assert digest() == first
        seen = {first}
        for rel in ("paper_loop.py", "codegen/simulator.py",
                    next(p.relative_to(root).as_posix() for p in root.rglob("*.jinja"))):
            path = root / rel
            path.write_bytes(path.read_bytes() + b"\n")
            seen.add(digest())
        assert len(seen) == 4
    finally:
        monkeypatch.undo()
        recall.generator_digest.cache_clear()


_KEY = """
from quadland.engine.recall import recall_key
from quadland_symbolic.paper_loop import paper_loop_recipe
print(recall_key(paper_loop_recipe(2), "continuous", None, (), "qlsim_paper_continuous",
                 "-O2", False))
"""


@needs_cc
def test_the_key_is_the_same_in_every_process():
    keys = {subprocess.run([sys.executable, "-c", _KEY], check=True, capture_output=True,
                           text=True).stdout.strip() for _ in range(2)}
    from quadland_symbolic.paper_loop import paper_loop_recipe

    assert keys == {_key(paper_loop_recipe(2), name="qlsim_paper_continuous")}


_COLD = """
import casadi as ca
built = []
init = ca.Function.__init__
def counted(self, *args):
    built.append(args[0] if args else None)
    init(self, *args)
ca.Function.__init__ = counted
import quadland
from quadland_symbolic.paper_loop import paper_loop
res = quadland.simulate(quadland.load_scenario("paper", ["rbf.nodes=2",
                        "simulation.duration=0.2"{extra}]))
print(len(built), paper_loop.cache_info().misses, len(res["t"]))
"""


def _cold(extra: str, env) -> list[int]:
    out = subprocess.run([sys.executable, "-c", _COLD.format(extra=extra)], check=True,
                         capture_output=True, text=True, env=env)
    return [int(v) for v in out.stdout.split()]


@pytest.mark.slow
@needs_cc
@pytest.mark.parametrize("extra", ["", ', "controller.rate_hz=100"'])
def test_a_run_with_its_simulator_cached_builds_no_casadi_function(cache, extra):
    """A fresh process whose simulator is cached builds no CasADi function (every
    ``casadi.Function`` made is counted); the first process, with an empty cache,
    built the loop."""
    import os

    env = dict(os.environ)
    first = _cold(extra, env)
    assert first[0] > 0 and first[1] == 1 and first[2] == 21
    assert _cold(extra, env) == [0, 0, 21]


@pytest.mark.slow
@needs_cc
def test_a_changed_generator_rebuilds_the_model_and_its_c(cache, monkeypatch):
    """A recipe's library is recalled without building the model; after the generator's
    code changes (its digest) the model is built and its C generated again."""
    from quadland.engine import compiled, recall
    from quadland_symbolic.paper_loop import paper_loop_recipe

    generate, calls = compiled.simulator_sources, []
    monkeypatch.setattr(compiled, "simulator_sources",
                        lambda *a: calls.append(a) or generate(*a))
    first = compiled.CompiledLoop(paper_loop_recipe.__wrapped__(2), "continuous").library
    assert len(calls) == 1
    again = paper_loop_recipe.__wrapped__(2)
    assert compiled.CompiledLoop(again, "continuous").library == first
    assert len(calls) == 1 and "model" not in vars(again)
    monkeypatch.setattr(recall, "generator_digest", lambda: "a changed generator")
    changed = paper_loop_recipe.__wrapped__(2)
    assert compiled.CompiledLoop(changed, "continuous").library == first   # the same C
    assert len(calls) == 2 and "model" in vars(changed)


def _package_copy(tmp_path, monkeypatch):
    """A copy of ``quadland_symbolic`` (its files' times kept) that the process imported
    1 ns after its newest source was written, a cache in ``tmp_path`` with one library:
    the copy's root, the import's time, the cache and the library."""
    import quadland
    import quadland_symbolic
    from quadland.engine import build

    root = tmp_path / "quadland_symbolic"
    src = quadland_symbolic.__file__.rsplit("/", 1)[0]
    shutil.copytree(src, root, ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setattr(quadland_symbolic, "__file__", str(root / "__init__.py"))
    since = max(p.stat().st_mtime_ns for tree in (root, Path(quadland.__file__).parent)
                for p in tree.rglob("*") if p.suffix in (".py", ".jinja", ".toml")) + 1
    monkeypatch.setattr(quadland_symbolic, "IMPORTED_NS", since)
    monkeypatch.setattr(quadland, "IMPORTED_NS", since)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    cache = build.cache_dir()
    library = cache / ("ab" * 12) / "qlsim_x.so"
    library.parent.mkdir(parents=True)
    library.write_bytes(b"")
    return root, since, cache, library


def test_no_recipe_is_remembered_once_a_source_changed_under_the_process(tmp_path,
                                                                         monkeypatch):
    """A copy of ``quadland_symbolic`` whose one module is written after the process
    imported the packages: that module is named, and :func:`remember` records no recipe
    (the code the process runs may be the module of before, its key the text of after);
    with every file older than the import the recipe is recorded and recalled."""
    import os

    from quadland.engine import recall

    root, since, cache, library = _package_copy(tmp_path, monkeypatch)
    assert recall.sources_edited_since_import() == []

    edited = root / "paper_loop.py"
    os.utime(edited, ns=(since + 1, since + 1))
    assert recall.sources_edited_since_import() == ["quadland_symbolic/paper_loop.py"]
    recall.remember("cd" * 32, library)
    assert not (cache / recall.RECIPES).exists()

    os.utime(edited, ns=(since - 1, since - 1))
    recall.remember("cd" * 32, library)
    assert (cache / recall.RECIPES / ("cd" * 16)).read_text() == f"{'ab' * 12}/qlsim_x.so\n"


def test_a_source_dated_in_the_future_is_no_edit_until_it_is_written(tmp_path, monkeypatch):
    """A source unpacked with a date an hour ahead of this machine's clock was not written
    after the import (a write dates a file with the clock's time): the recipe is
    recorded, as by every later process (refusing would hold for that hour, each
    process generating its C again). Written now, the file is an edit and nothing is
    recorded."""
    import os
    import time

    from quadland.engine import recall

    root, since, cache, library = _package_copy(tmp_path, monkeypatch)
    edited = root / "paper_loop.py"
    ahead = time.time_ns() + 3600 * 10**9
    os.utime(edited, ns=(ahead, ahead))
    assert recall.sources_edited_since_import() == []
    recall.remember("cd" * 32, library)
    assert (cache / recall.RECIPES / ("cd" * 16)).read_text() == f"{'ab' * 12}/qlsim_x.so\n"

    edited.write_text(edited.read_text() + "# edited\n")
    assert since < edited.stat().st_mtime_ns <= time.time_ns()
    assert recall.sources_edited_since_import() == ["quadland_symbolic/paper_loop.py"]
    recall.remember("ef" * 32, library)
    assert not (cache / recall.RECIPES / ("ef" * 16)).exists()


def test_no_recipe_is_recalled_once_a_source_changed_under_the_process(tmp_path,
                                                                       monkeypatch):
    """A recipe recorded by a process of the code before is not recalled by a process
    during which a source was written (its key may hash the new text, its library
    another code's): with the copy's module written after the import, ``recalled`` gives
    None; with every file older than the import, the library (its checks passed)."""
    import ctypes
    import os

    from quadland.engine import build, recall

    root, since, cache, library = _package_copy(tmp_path, monkeypatch)
    monkeypatch.setattr(build, "verified_library", lambda path: path == library)
    monkeypatch.setattr(ctypes, "CDLL", lambda path: None)
    recall.remember("cd" * 32, library)
    assert recall.recalled("cd" * 32) == library

    edited = root / "paper_loop.py"
    os.utime(edited, ns=(since + 1, since + 1))
    assert recall.recalled("cd" * 32) is None
    os.utime(edited, ns=(since - 1, since - 1))
    assert recall.recalled("cd" * 32) == library
