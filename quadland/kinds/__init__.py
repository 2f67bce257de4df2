"""The loop kinds, one object each (:class:`~quadland.kinds.base.LoopKind`), and their registry.

:func:`kind_of` gives a scenario's kind; everything above the kinds (the
public :func:`quadland.simulate`, margins, campaigns, code generation, the
command line) asks it, never a model's name.
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping

from quadland.kinds.base import LoopKind
from quadland.schema.by_model import ByModel

__all__ = ["LoopKind", "KINDS", "kind_of"]

#: The kinds' objects, loaded on first use (a paper run does not import the landing's).
_LAZY = {"PAPER": "quadland.kinds.paper.kind", "LANDING": "quadland.kinds.landing.kind"}

#: Every loop kind by its ``scenario.model`` name (one line per kind), each imported
#: when first read (:class:`~quadland.schema.by_model.ByModel`).
KINDS: Mapping[str, LoopKind] = ByModel({"paper": (_LAZY["PAPER"], "PAPER"),
                                         "landing": (_LAZY["LANDING"], "LANDING")})


def __getattr__(name):
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'quadland.kinds' has no attribute {name!r}")


def kind_of(scenario) -> LoopKind:
    """The loop kind of a scenario (or of a ``scenario.model`` name)."""
    return KINDS[scenario if isinstance(scenario, str) else scenario.model]
