"""A plant's terms of time alone, computed once an instant in the compiled simulators.

The sampled simulators' driver (``symbolic/templates/simulator.c.jinja``) calls the
plant four times an RK4 step, two of them at the same instant (the middle stages), the
free plant likewise, and the event at the instants the bisection tries. A moving deck's
sums of sinusoids (:mod:`quadland_symbolic.landing.deck`) are terms of the time and
the parameters alone: on a ship most of the plant's sines and cosines.

:func:`time_split` cuts an SX Function ``f(..., t, ..., pp, ...)`` in two by its
algorithm (the instructions CasADi generates C from):

* ``<name>_time(t, pp) -> hoisted``: every value computed from ``t`` and ``pp``
  alone that a term of the other inputs uses (or an output is), by the same
  instructions of the same operands;
* ``<name>(..., hoisted) -> ...``: ``f`` with those values read from its last input.

Each instruction is rebuilt by CasADi's own operations (``SX.unary``, ``SX.binary``) on
the rebuilt operands, constants as they are (a call of another Function, ``OP_CALL``, and
free variables are refused: :class:`ValueError`), so the two compute the values ``f`` does,
by the same IEEE operations: the same bits, ``hoisted`` given what ``<name>_time``
returns. The driver keeps ``hoisted`` of the last instant (by its bits) and calls
``<name>_time`` only at a new one.
"""

from __future__ import annotations

import casadi as ca

__all__ = ["time_split", "HOISTED"]

#: The name of the core's extra input, the hoisted function's output.
HOISTED = "hoisted"

_LEAF = (ca.OP_INPUT, ca.OP_OUTPUT, ca.OP_CONST)


def _deps(f: ca.Function, timed: set) -> list:
    """Per instruction: ``None`` for an input, output or constant; else whether its value
    depends on the inputs ``timed`` alone."""
    alone, out = {}, []
    for k in range(f.n_instructions()):
        op, ins, res = f.instruction_id(k), f.instruction_input(k), f.instruction_output(k)
        if op == ca.OP_OUTPUT:
            out.append(None)
            continue
        if op == ca.OP_INPUT:
            alone[res[0]] = ins[0] in timed
        elif op == ca.OP_CONST:
            alone[res[0]] = True
        else:
            alone.update(dict.fromkeys(res, all(alone[j] for j in ins if j >= 0)))
        out.append(None if op in _LEAF else alone[res[0]])
    return out


def _rebuild(f: ca.Function, symbols: list, hoist: dict) -> tuple[list, list]:
    """``f``'s outputs on ``symbols`` (one per input), the instructions in ``hoist``
    (instruction -> the value to use) replaced; and each instruction's value."""
    work, value, outs = {}, [], [ca.SX.zeros(f.sparsity_out(i)) for i in range(f.n_out())]
    for k in range(f.n_instructions()):
        op, ins, res = f.instruction_id(k), f.instruction_input(k), f.instruction_output(k)
        if op == ca.OP_INPUT:
            v = symbols[ins[0]].nz[ins[1]]
        elif op == ca.OP_CONST:
            v = ca.SX(f.instruction_constant(k))
        elif op == ca.OP_OUTPUT:
            outs[res[0]].nz[res[1]] = work[ins[0]]
            value.append(None)
            continue
        elif k in hoist:
            v = hoist[k]
        elif op == ca.OP_CALL or len(ins) > 2 or len(res) != 1:
            raise ValueError(f"time_split: {f.name()}'s instruction {k} (CasADi operation "
                             f"{op}) is not one SX.unary or SX.binary rebuilds")
        elif len(ins) == 1 or ins[1] < 0:
            v = ca.SX.unary(op, work[ins[0]])
        else:
            v = ca.SX.binary(op, work[ins[0]], work[ins[1]])
        work[res[0]] = v
        value.append(v)
    return outs, value


def _frontier(f: ca.Function, alone: list) -> list:
    """The instructions of time alone whose value an instruction of the other inputs
    reads, or an output is (in order)."""
    of, needed = {}, set()
    for k in range(f.n_instructions()):
        ins, res = f.instruction_input(k), f.instruction_output(k)
        if f.instruction_id(k) == ca.OP_OUTPUT or alone[k] is False:
            needed.update(of[j] for j in ins if j >= 0 and of.get(j) is not None)
        if f.instruction_id(k) != ca.OP_OUTPUT:
            of[res[0]] = k if alone[k] else None
    return sorted(needed)


def time_split(f: ca.Function, time_inputs=("t", "pp")):
    """``(core, hoisted)`` of an SX Function ``f`` (the module docstring), or ``None``
    when ``f`` computes nothing of ``time_inputs`` alone that its other terms use.

    Parameters
    ----------
    f : casadi.Function
        An SX Function with inputs named ``time_inputs``, each a dense column.
    time_inputs : tuple of str
        The inputs constant over an instant (the time and the parameters).

    Returns
    -------
    core : casadi.Function
        ``f``'s name, inputs and outputs, and one more input :data:`HOISTED`.
    hoisted : casadi.Function
        ``<name>_time(<time_inputs>) -> hoisted``.
    """
    if f.has_free():
        raise ValueError(f"time_split: {f.name()} has free variables {f.get_free()}")
    names = f.name_in()
    timed = {names.index(n) for n in time_inputs}
    alone = _deps(f, timed)
    frontier = _frontier(f, alone)
    if not frontier:
        return None
    symbols = [ca.SX.sym(n, f.sparsity_in(i)) for i, n in enumerate(names)]
    _, value = _rebuild(f, symbols, {})
    hoisted = ca.Function(f"{f.name()}_time", [symbols[i] for i in sorted(timed)],
                          [ca.vertcat(*[value[k] for k in frontier])],
                          [names[i] for i in sorted(timed)], [HOISTED])
    h = ca.SX.sym(HOISTED, len(frontier))
    outs, _ = _rebuild(f, symbols, {k: h[i] for i, k in enumerate(frontier)})
    core = ca.Function(f.name(), [*symbols, h], outs, [*names, HOISTED], f.name_out())
    return core, hoisted
