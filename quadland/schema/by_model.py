"""A registry by model name whose entries are loaded on first use (:class:`ByModel`).

The landing's schema and loop kind import the landing's symbolic modules
(CasADi expressions of the controller, the filter, the gear): about half of the
Python a process loads. A paper scenario needs none of it; the registries
(:data:`quadland.schema.SCHEMAS`, :data:`quadland.kinds.KINDS`) hold each model's
entry as the module and name it lives under and import it when it is first read.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterator, Mapping

__all__ = ["ByModel"]


class ByModel(Mapping):
    """A read-only mapping of model names to values loaded on first use.

    Parameters
    ----------
    where : mapping of str to (str, str)
        Each model's value as ``(module, attribute)``: the value is
        ``getattr(importlib.import_module(module), attribute)``, imported the
        first time the model's value is read. Keys and their order are
        known without loading anything (``in``, ``len``, iterating the keys);
        reading values (``[name]``, ``.values()``, ``.items()``) loads them.
    """

    def __init__(self, where: Mapping[str, tuple[str, str]]):
        self._where = dict(where)
        self._loaded: dict[str, object] = {}

    def __getitem__(self, name: str):
        try:
            return self._loaded[name]
        except KeyError:
            module, attribute = self._where[name]      # KeyError for an unknown model
            value = self._loaded[name] = getattr(importlib.import_module(module), attribute)
            return value

    def __iter__(self) -> Iterator[str]:
        return iter(self._where)

    def __len__(self) -> int:
        return len(self._where)

    def __contains__(self, name) -> bool:
        return name in self._where

    def loaded(self) -> tuple[str, ...]:
        """The models whose values are loaded so far."""
        return tuple(name for name in self._where if name in self._loaded)

    def __repr__(self) -> str:
        return f"ByModel({', '.join(self._where)})"
