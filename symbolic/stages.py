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
    rings : tuple of (str, str, str)
        Delay lines, ``(line, record, past)``: ``past`` is a slice of the first input
        (the line of ``n`` slots of ``m`` values, newest first), ``record`` an
        earlier stage's output of ``m`` values, and ``line`` the one output of an SX
        stage of the inputs ``(record, past)`` computing ``past`` shifted by a slot,
        ``record`` first (the oldest slot dropped), a piece of the first output at
        ``past``'s place. :meth:`function` computes the shift; the C
        (:mod:`quadland_symbolic.codegen.staged_c`) leaves that stage out and keeps the
        line in a ring its caller holds (:meth:`ring_places`).
    free : tuple of (str, casadi.Function)
        Stages' other functions where the gear is far from the deck, ``(stage, f)``: ``f``
        has the stage's names in and out and computes its values where the gear's contact
        is exactly zero (the loop's ``free_plant`` for its ``plant``). :meth:`function`
        uses the stages themselves; the C (:mod:`quadland_symbolic.codegen.staged_c`)
        calls ``f`` where the caller says the gear is far, as the sampled driver flies
        its free plant.
    """

    name: str
    stages: tuple
    inputs: tuple
    outputs: tuple
    slices: tuple = ()
    rings: tuple = ()
    free: tuple = ()

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
        by_name = {s.name(): s for s in self.stages}
        for stage, f in self.free:
            if stage not in by_name or (f.name_in(), f.name_out()) != (
                    by_name[stage].name_in(), by_name[stage].name_out()):
                raise ValueError(f"free {f.name()}: not a stage's names in and out")
        self.ring_places()

    def ring_places(self) -> tuple[tuple[int, int, int, int, int], ...]:
        """Each ring's line: ``(input, output, start, m, n)``, the positions of the input
        its ``past`` slices and of the output it is a piece of, its place in both, its
        slots' size and its slots.

        Raises
        ------
        ValueError
            For a ring that is not as :attr:`rings` describes (a line's stage that
            computes anything but the shift, a line elsewhere than ``past``).
        """
        slices = {n: (src, start, stop) for n, src, start, stop in self.slices}
        ins = [n for n, _ in self.inputs]
        offsets = {}
        for k, (_, pieces) in enumerate(self.outputs):
            at = 0
            for piece in pieces:
                offsets[piece] = (k, at)
                at += self._size(piece)
        places = []
        for line, record, past in self.rings:
            stage = next((f for f in self.stages if line in f.name_out()), None)
            src, start, stop = slices.get(past, (None, 0, 0))
            out, at = offsets.get(line, (None, None))
            if (stage is None or src is None or at != start
                    or stage.name_in() != [record, past] or stage.n_out() != 1
                    or not stage.is_a("SXFunction")):
                raise ValueError(f"ring {line}: not the shift of a slice {past} by {record}, "
                                 "in place in an output")
            m, n = stage.nnz_in(0), stage.nnz_in(1)
            r, q = ca.SX.sym("r", m), ca.SX.sym("q", n)
            shifted, got = ca.vertcat(r, q[:n - m]), stage(r, q)
            if (n % m or stop - start != n or got.numel() != n
                    or not all(ca.is_equal(got[i], shifted[i]) for i in range(n))):
                raise ValueError(f"ring {line}: {stage.name()} is not the shift of {past} "
                                 f"by {record}")
            # the compiled ring never writes the memory's line (``past``) nor the record
            # into an output: a stage reading the one, or an output holding the other,
            # would see what the ring does not keep
            readers = [f.name() for f in self.stages if f is not stage and past in f.name_in()]
            if readers or record in offsets:
                raise ValueError(f"ring {line}: {past} is read by {', '.join(readers)}"
                                 if readers else f"ring {line}: its record {record} is an "
                                 "output's piece")
            places.append((ins.index(src), out, start, m, n // m))
        return tuple(places)

    def _size(self, name: str) -> int:
        """The number of values of a named value (an input, a slice, a stage's output)."""
        for n, size in self.inputs:
            if n == name:
                return size
        for n, _, start, stop in self.slices:
            if n == name:
                return stop - start
        for f in self.stages:
            if name in f.name_out():
                return f.nnz_out(f.name_out().index(name))
        raise KeyError(name)

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

    def with_stages(self, stages, free=None) -> Staged:
        """The same composition of other stages (the same names in and out), and of other
        :attr:`free` functions (``free``, in the same order; unchanged when ``None``)."""
        changes = {} if free is None else {"free": tuple(zip((n for n, _ in self.free), free,
                                                             strict=True))}
        return dataclasses.replace(self, stages=tuple(stages), **changes)
