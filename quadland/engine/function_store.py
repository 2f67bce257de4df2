"""CasADi functions that take longer to build than to read, kept on disk (:func:`stored_function`).

A margin review of a landing scenario builds the hover's residual and linearization
functions and the landing step's law and sensing Jacobians (``quadland_symbolic``'s
``hover_equilibrium_residual_function``, ``hover_linearization_function``,
``hover_law_function``, ``hover_sensing_function``): 0.4 s of CPU in every process, 0.1
s of it each for the three largest, mostly CasADi's ``jacobian``. Each is a pure function
of its builder's code and arguments (the builders are ``functools.cache``-d on their
arguments alone), and CasADi reads one back (``Function.deserialize``) in a quarter of
the time it takes to build it.

:func:`stored_function` keeps each function serialized in the cache folder
(:func:`quadland.engine.build.cache_dir`, ``functions/``), keyed by the SHA-256 of the
builder's name, its arguments' ``repr``, every module and template of
``quadland_symbolic`` (:func:`quadland.engine.recall.generator_digest`: the builder's
code and what it calls) and the versions of Python, CasADi, NumPy and Jinja2
(:func:`quadland.engine.recall.library_versions`). A function that cannot be read (none
yet, a partial, damaged or foreign file) is built and written (atomically; a folder that
cannot be written is not an error). Each file starts with a line holding the SHA-256 of the
serialized text after it, checked before CasADi reads it: CasADi's reader takes some damaged
texts without an error and fails later, inside the call (a crash), where no exception can be
caught. Builders whose functions are as slow to read as to build (the
filter's fusion: 12.6 MB serialized) are called directly.
"""

from __future__ import annotations

import functools
import hashlib

import casadi as ca

from quadland.engine.build import cache_dir
from quadland.engine.recall import generator_digest, library_versions, sources_edited_since_import
from quadland.output import write_text_atomic

__all__ = ["FUNCTIONS", "HEADER", "stored_function", "function_key"]

#: Folder of the cache that holds the serialized functions.
FUNCTIONS = "functions"


def function_key(builder, args: tuple) -> str:
    """The key of ``builder(*args)``'s function (module docstring); nothing is built."""
    text = (f"function-1\0{builder.__module__}.{builder.__qualname__}\0{args!r}\0"
            f"{generator_digest()}\0{library_versions()}")
    return hashlib.sha256(text.encode()).hexdigest()


@functools.cache
def stored_function(builder, *args) -> ca.Function:
    """``builder(*args)``, read from the cache folder when it was built before.

    Parameters
    ----------
    builder : callable
        A function of ``quadland_symbolic`` returning a ``casadi.Function`` that depends
        on its arguments and its package's code alone.
    *args
        Its arguments, hashable, with a ``repr`` that names their value.

    Returns
    -------
    casadi.Function
        The same function (its expression graph, every constant) as ``builder(*args)``;
        one object per process for the same arguments.
    """
    path = cache_dir() / FUNCTIONS / f"{function_key(builder, args)[:32]}.casadi"
    edited = sources_edited_since_import()      # the key may name other code than the
    function = None if edited else _read(path)  # process runs: neither read nor written
    if function is not None:
        return function
    function = builder(*args)
    if edited or sources_edited_since_import():     # (or edited during the build)
        return function
    text = function.serialize()
    try:
        path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
        write_text_atomic(path, f"{HEADER} {_digest(text)}\n{text}")
    except OSError:
        pass                    # a cache that cannot be written only costs the build
    return function


#: First word of a stored file's first line; its second is the SHA-256 of the rest.
HEADER = "quadland-function-1"


def _digest(text: str) -> str:
    return hashlib.sha256(text.encode("ascii")).hexdigest()


def _read(path) -> ca.Function | None:
    """The function stored at ``path``, or None when there is none or it is not intact."""
    try:
        head, _, text = path.read_text(encoding="ascii").partition("\n")
    except (OSError, UnicodeDecodeError):
        return None             # none yet, or unreadable: build it
    if head != f"{HEADER} {_digest(text)}":
        return None             # partial, damaged, or of an older format
    try:
        function = ca.Function.deserialize(text)
    except RuntimeError:
        return None
    return None if function.is_null() else function
