"""A loop model not built yet: its layouts now, its CasADi functions when asked for.

Building a :class:`quadland_symbolic.loop.LoopModel` builds every CasADi
function of the loop (the paper's at ``l = 10``: about 30 ms). A compiled
simulator found in the cache needs none of them, only the layouts of its
arguments; a :class:`LoopRecipe` holds those, the builder and the builder's
inputs, and builds the model the first time a function is asked for
(:attr:`LoopRecipe.model`, or any attribute of the model that is not a layout).

What the generated C of the model depends on is then the builder (its
module and name) and its inputs (:attr:`LoopRecipe.inputs`), with the code of
``quadland_symbolic`` it runs and the library versions it runs on: the
runtime's cache key (``quadland.engine.recall``) hashes those instead of the
functions.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable

from quadland_symbolic.layout import Layout
from quadland_symbolic.loop import LoopModel

__all__ = ["LoopRecipe"]

#: The fields of a model that are CasADi functions (or None).
_FUNCTIONS = frozenset(f.name for f in dataclasses.fields(LoopModel)
                       if "Function" in str(f.type) or f.name == "controller_stages")


class LoopRecipe:
    """How to build one loop model, with the layouts that need no building.

    Parameters
    ----------
    builder : callable
        A module-level function of ``quadland_symbolic`` that returns the
        :class:`LoopModel` for ``*args``; it must depend on nothing but its
        arguments and the code of ``quadland_symbolic`` (and the libraries'
        versions), as :func:`quadland_symbolic.paper_loop.paper_loop` does.
    args : tuple
        Its positional arguments (numbers, strings: their ``repr`` is part of
        the cache key).
    name : str
        The model's :attr:`LoopModel.name`.
    layouts : dict of str to Layout or None
        Every :class:`Layout` field of the model (``state``, ``disturbance``,
        ...), equal to the built model's.
    absent : frozenset of str
        The function fields the model leaves None (``event``, ``ride_rhs``,
        ...): asked for, they are None without a build.
    flags : dict, optional
        The model's other fields (``flight``, ``event_continues``).
    """

    def __init__(self, builder: Callable[..., LoopModel], args: tuple, name: str,
                 layouts: dict[str, Layout | None], absent: frozenset[str],
                 flags: dict | None = None):
        if not builder.__module__.startswith("quadland_symbolic."):
            raise ValueError(f"builder: {builder.__module__}.{builder.__qualname__} is not "
                             "quadland_symbolic's, whose code alone the cache key covers")
        if not all(isinstance(a, (bool, int, float, str)) for a in args):
            raise ValueError(f"args: only numbers and strings, whose repr is the key: {args!r}")
        unknown = set(absent) - _FUNCTIONS
        if unknown:
            raise ValueError(f"absent: not function fields of LoopModel: {sorted(unknown)}")
        self.builder, self.args, self.name = builder, tuple(args), name
        self._known = {**layouts, **dict.fromkeys(absent), **(flags or {})}

    @property
    def inputs(self) -> str:
        """What the model is built from: the builder's module and name and its arguments."""
        return f"{self.builder.__module__}.{self.builder.__qualname__}{self.args!r}"

    def known(self) -> dict:
        """The fields given without building: layouts, absent functions (None), flags."""
        return dict(self._known)

    @functools.cached_property
    def model(self) -> LoopModel:
        """The model, built on the first call."""
        return self.builder(*self.args)

    def __getattr__(self, name: str):
        if name.startswith("__") or name in ("_known", "model"):
            raise AttributeError(name)
        known = self.__dict__.get("_known", {})
        if name in known:
            return known[name]
        return getattr(self.model, name)

    def __eq__(self, other) -> bool:
        return isinstance(other, LoopRecipe) and self.inputs == other.inputs

    def __hash__(self) -> int:
        return hash(self.inputs)

    def __repr__(self) -> str:
        return f"LoopRecipe({self.inputs})"
