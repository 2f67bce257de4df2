"""The compiled simulator and the arguments the runtime passes it for a scenario's flight,
caught before it flies (shared by the tests of the simulators' staged C)."""

from __future__ import annotations

import pytest

import quadland
from quadland.engine.compiled import CompiledLoop


class _Captured(Exception):
    pass


def captured(scenario: str, overrides=()):
    """The simulator and the arguments the runtime passes it for ``scenario``'s flight
    (with ``overrides``, ``key=value`` strings as ``--set`` takes them)."""
    mp, seen = pytest.MonkeyPatch(), {}

    def capture(self, *args, **kwargs):
        seen.update(loop=self, args=args, kwargs=kwargs)
        raise _Captured

    mp.setattr(CompiledLoop, "sampled", capture)
    try:
        with pytest.raises(_Captured):
            quadland.simulate(quadland.load_scenario(scenario, list(overrides)))
    finally:
        mp.undo()
    return seen["loop"], seen["args"], seen["kwargs"]
