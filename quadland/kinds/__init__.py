"""The loop kinds, one object each (:class:`~quadland.kinds.base.LoopKind`), and their registry.

:func:`kind_of` gives a scenario's kind; everything above the kinds (the
public :func:`quadland.simulate`, margins, campaigns, code generation, the
command line) asks it, never a model's name.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

from quadland.kinds.base import LoopKind
from quadland.kinds.landing.kind import LANDING
from quadland.kinds.paper.kind import PAPER

__all__ = ["LoopKind", "KINDS", "kind_of"]

#: Every loop kind by its ``scenario.model`` name (one line per kind).
KINDS: Mapping[str, LoopKind] = MappingProxyType({k.name: k for k in (PAPER, LANDING)})


def kind_of(scenario) -> LoopKind:
    """The loop kind of a scenario (or of a ``scenario.model`` name)."""
    return KINDS[scenario if isinstance(scenario, str) else scenario.model]
