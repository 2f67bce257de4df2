"""A cheap key for a compiled simulator: what its C is generated from, not the C itself.

:func:`quadland.engine.build.build_library` keys a library by its sources'
text, so finding a cached simulator meant generating all of its C first
(CasADi's code generation of every function a part calls: 35 to 40 ms a part).
The text is a function of fewer things, each cheap to hash:

* the loop model: a :class:`quadland_symbolic.loop_recipe.LoopRecipe` by its
  builder and the builder's inputs (:func:`recipe_digest`: nothing built, the
  builder's code is in :func:`generator_digest`), with the versions of what
  the builder and the C writers run on (CasADi, NumPy, Jinja2, Python); a
  built :class:`quadland_symbolic.loop.LoopModel` by its CasADi functions
  serialized (``Function.serialize``, the expression graph with every
  constant, deterministic across processes) and its layouts;
* the part, and the flight code's recipe (:func:`code_recipe`) of a
  ``"sampled_flight"`` part;
* the code that writes the C: every module and template of
  ``quadland_symbolic`` (:func:`generator_digest`);
* CasADi's version, the compiler (path and ``--version``), the flags and
  the build's budgets (a lowered build is never remembered).

:func:`recall_key` hashes them; the cache's ``recipes/`` folder maps such a
key to the library built from the generated text (:func:`remember`), and
:func:`recalled` returns that library, checked as every cached library is,
without generating anything. A key that changes whenever the generated code
would is enough for correctness: a stale or missing entry only costs one
generation and build.
"""

from __future__ import annotations

import ctypes
import dataclasses
import functools
import hashlib
import importlib.util
import re
import sys
from pathlib import Path

import casadi as ca

from quadland.engine import build
from quadland.output import write_text_atomic
from quadland_symbolic.loop import LoopModel
from quadland_symbolic.loop_recipe import LoopRecipe

__all__ = ["generator_digest", "package_digest", "model_digest", "recipe_digest", "code_recipe",
           "recall_key", "recalled", "remember", "sources_edited_since_import"]

#: Folder of the cache that maps recipe keys to libraries.
RECIPES = "recipes"
#: What a recipe file may name: a key folder and a library in it.
_ENTRY = re.compile(r"^[0-9a-f]{24}/[A-Za-z0-9_]+\.so$")


@functools.cache
def generator_digest() -> str:
    """SHA-256 of every module and template of ``quadland_symbolic`` (the code that
    writes the C), read once per process."""
    import quadland_symbolic

    root = Path(quadland_symbolic.__file__).parent
    digest = hashlib.sha256()
    for path in sorted(root.rglob("*")):
        if path.is_file() and path.suffix in (".py", ".jinja"):
            digest.update(path.relative_to(root).as_posix().encode() + b"\0"
                          + path.read_bytes() + b"\0")
    return digest.hexdigest()


def model_digest(model: LoopModel) -> str:
    """SHA-256 of a loop model: each field, its functions serialized, its layouts as
    their ``repr`` (names, sizes, units). Not memoized: hashing the model for a
    cache costs half as much as the digest (its layouts' nested fields)."""
    digest = hashlib.sha256()
    for field in dataclasses.fields(model):
        value = getattr(model, field.name)
        text = value.serialize() if isinstance(value, ca.Function) else repr(value)
        digest.update(field.name.encode() + b"=" + text.encode() + b"\0")
    return digest.hexdigest()


@functools.cache
def library_versions() -> str:
    """The versions of what a loop's builder and the C writers run on: Python, CasADi,
    NumPy, and Jinja2 by the SHA-256 of its ``__init__.py`` (which holds its version),
    found without importing it (nor ``importlib.metadata``: 7 ms a process)."""
    import numpy as np

    spec = importlib.util.find_spec("jinja2")
    jinja = "none" if spec is None or spec.origin is None else \
        hashlib.sha256(Path(spec.origin).read_bytes()).hexdigest()
    return (f"python={sys.version_info[:3]!r} casadi={ca.__version__} numpy={np.__version__} "
            f"jinja2={jinja}")


def recipe_digest(recipe: LoopRecipe) -> str:
    """SHA-256 of a loop recipe: its builder and inputs and :func:`library_versions`;
    the builder's code is hashed with the rest of ``quadland_symbolic`` by
    :func:`generator_digest`. Nothing is built."""
    text = f"recipe-1\0{recipe.inputs}\0{library_versions()}"
    return hashlib.sha256(text.encode()).hexdigest()


@functools.cache
def package_digest() -> str:
    """SHA-256 of every module, template and shipped scenario of ``quadland`` and
    ``quadland_symbolic``, read once per process."""
    import quadland
    import quadland_symbolic

    digest = hashlib.sha256()
    for package in (quadland, quadland_symbolic):
        root = Path(package.__file__).parent
        for path in sorted(root.rglob("*")):
            if path.is_file() and path.suffix in (".py", ".jinja", ".toml"):
                digest.update(f"{package.__name__}/{path.relative_to(root).as_posix()}"
                              .encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


def code_recipe(*what: str) -> str:
    """A recipe key of C that the runtime generates from ``what`` (e.g. ``"landing",
    "l=10"``) with the defaults of its shipped scenarios: SHA-256 of ``what``, every
    source of both packages (:func:`package_digest`), NumPy's and CasADi's versions."""
    import numpy as np

    digest = hashlib.sha256()
    for part in ("code-1", package_digest(), np.__version__, ca.__version__, *what):
        digest.update(part.encode() + b"\0")
    return digest.hexdigest()


def recall_key(model: LoopModel | LoopRecipe, part: str, flight: str | None,
               flight_sources: tuple[str, ...], name: str, opt: str, strict: bool) -> str:
    """The recipe key of one simulator's library (see the module's docstring): of a
    :class:`LoopRecipe` without building its model.

    Raises
    ------
    CompileError
        When the compiler's ``--version`` cannot run.
    """
    cc = build.find_compiler()
    digest = hashlib.sha256()
    for part_ in ("recipe-1", build.compiler_identity(cc), ca.__version__, generator_digest(),
                  recipe_digest(model) if isinstance(model, LoopRecipe) else
                  "model:" + model_digest(model), part, name,
                  " ".join(build.level_flags(opt, cc)),
                  repr(build.language_flags(strict, cc)),
                  repr((build.SHARED_CFLAGS, build.COMPILE_MEMORY_BUDGET,
                        build.COMPILE_TIME_BUDGET, build.COMPILE_FIT)), *flight_sources):
        digest.update(part_.encode() + b"\0")
    digest.update(b"flight=" + (flight or "none").encode())
    return digest.hexdigest()


def _entry(key: str) -> Path:
    return build.cache_dir() / RECIPES / key[:32]


def recalled(key: str) -> Path | None:
    """The library remembered for ``key``, verified and loadable; None if there is none
    (or it was removed, damaged or does not load), or if a source was edited while this
    process ran (:func:`sources_edited_since_import`: the key may hash other text than the
    code the process runs, and name another code's library)."""
    if sources_edited_since_import():
        return None
    try:
        rel = _entry(key).read_text(encoding="ascii").strip()
    except (OSError, ValueError):
        return None
    if not _ENTRY.match(rel):
        return None
    target = build.cache_dir() / rel
    if not build.verified_library(target):
        return None
    try:
        ctypes.CDLL(str(target))
    except OSError:
        return None
    return target


def sources_edited_since_import() -> list[str]:
    """The sources a key hashes (:func:`package_digest`'s files) written after this process
    first imported ``quadland`` or ``quadland_symbolic``, whichever came first.

    Such a file may not be the code this process runs: a module imported before the edit
    generated the C, while a digest read after it hashes the new text (a digest read
    before it, and a module imported after, the other way round). A key from such a
    process could name a library of other code. A file dated after now (unpacked with a
    clock ahead of this machine's) was not written by an edit since: a write dates it now.
    """
    import time

    import quadland
    import quadland_symbolic

    since = min(quadland.IMPORTED_NS, quadland_symbolic.IMPORTED_NS)
    now = time.time_ns()
    edited = []
    for package in (quadland, quadland_symbolic):
        root = Path(package.__file__).parent
        for path in root.rglob("*"):
            if path.suffix in (".py", ".jinja", ".toml") and path.is_file() \
                    and since < path.stat().st_mtime_ns <= now:
                edited.append(f"{package.__name__}/{path.relative_to(root).as_posix()}")
    return sorted(edited)


def remember(key: str, library: Path) -> None:
    """Record that ``key``'s library is ``library`` (a file of the cache); a cache that
    cannot be written is only a missed shortcut. Nothing is recorded when a source was
    edited while this process ran (:func:`sources_edited_since_import`): the library
    itself stays in the cache under its generated text's key, correct for that text."""
    if sources_edited_since_import():
        return
    cache = build.cache_dir()
    try:
        rel = library.relative_to(cache).as_posix()
        if _ENTRY.match(rel):
            (cache / RECIPES).mkdir(mode=0o700, exist_ok=True)
            write_text_atomic(_entry(key), rel + "\n")
    except (OSError, ValueError):
        pass
