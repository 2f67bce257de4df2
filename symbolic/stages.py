"""A Function as stages: each one a Function called on named values.

A loop's function whose work branches (the navigation filter's updates, evaluated only
when due: :mod:`quadland_symbolic.landing.estimator_switch`) cannot be one SX Function,
whose generated C computes every expression on every call. :class:`Staged` joins SX
Functions and such branching MX Functions into one MX Function by their inputs' and
outputs' names; a transformation of its SX stages (the flat deck's,
:mod:`quadland_symbolic.landing.flat_deck`) composes them again the same way, and
:mod:`quadland_symbolic.codegen.staged_c` writes its C one stage a file, the values
passed in place (a slice of an input read where it is, a piece of an output written
where it goes).
"""

from __future__ import annotations

import dataclasses

import casadi as ca

__all__ = ["Staged"]


@dataclasses.dataclass(frozen=True, eq=False)
class Staged:
    """A Function ``name(<inputs>) -> <outputs>`` computed by ``stages`` in turn.

    Attributes
    ----------
    name : str
    stages : tuple of casadi.Function
        Called in order. Each input of a stage is a named value: an input, a slice
        or an output of an earlier stage. No two stages output the same name.
    inputs : tuple of (str, int)
        The Function's inputs in order, each a dense column of that size.
    outputs : tuple of (str, tuple of str)
        The Function's outputs in order, each the named values stacked.
    slices : tuple of (str, str, int, int)
        Named values that are the entries ``start:stop`` of an input:
        ``(name, input, start, stop)``.
    """

    name: str
    stages: tuple
    inputs: tuple
    outputs: tuple
    slices: tuple = ()

    def __post_init__(self):
        known = {n for n, _ in self.inputs} | {s[0] for s in self.slices}
        for stage in self.stages:
            missing = [n for n in stage.name_in() if n not in known]
            if missing:
                raise ValueError(f"stage {stage.name()} reads {', '.join(missing)}: not an "
                                 "input, a slice nor an earlier stage's output")
            twice = [n for n in stage.name_out() if n in known]
            if twice:
                raise ValueError(f"stage {stage.name()} outputs {', '.join(twice)} again")
            known.update(stage.name_out())
        absent = [n for _, pieces in self.outputs for n in pieces if n not in known]
        if absent:
            raise ValueError(f"no stage outputs {', '.join(absent)}")

    def function(self) -> ca.Function:
        """The stages as one MX Function."""
        values = {n: ca.MX.sym(n, size) for n, size in self.inputs}
        for n, src, start, stop in self.slices:
            values[n] = values[src][start:stop]
        for stage in self.stages:
            values.update(stage.call({n: values[n] for n in stage.name_in()}))
        return ca.Function(self.name, [values[n] for n, _ in self.inputs],
                           [ca.vertcat(*[values[p] for p in pieces])
                            for _, pieces in self.outputs],
                           [n for n, _ in self.inputs], [n for n, _ in self.outputs])

    def with_stages(self, stages) -> Staged:
        """The same composition of other stages (the same names in and out)."""
        return dataclasses.replace(self, stages=tuple(stages))
