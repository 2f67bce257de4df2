"""A Function as stages: each one a Function called on named values.

A loop's function whose work branches (the navigation filter's updates, evaluated only
when due: :mod:`quadland_symbolic.landing.estimator_switch`) cannot be one SX Function,
whose generated C computes every expression on every call. :func:`compose_stages`
joins SX Functions and such branching MX Functions into one MX Function by their
inputs' and outputs' names; a transformation of its SX stages (the flat deck's,
:mod:`quadland_symbolic.landing.flat_deck`) composes them again the same way.
"""

from __future__ import annotations

import casadi as ca

__all__ = ["compose_stages", "recompose"]


def compose_stages(name: str, stages, inputs: dict, names_out) -> ca.Function:
    """One MX Function ``name(<inputs>) -> <names_out>`` from ``stages``.

    Parameters
    ----------
    name : str
    stages : sequence of casadi.Function
        Called in order. Each input of a stage is the input of that name or an
        output of that name of an earlier stage; its outputs are named values
        of the later ones. No two stages output the same name.
    inputs : dict of str to casadi.Sparsity or int
        The composed Function's inputs in order, each one's sparsity (an int: a
        dense column).
    names_out : sequence of str
        The named values it returns, in order.

    Raises
    ------
    ValueError
        A stage's input that is neither an input nor an earlier output; an output
        named twice or not made; an output not dense where its stage's is.
    """
    values = {n: ca.MX.sym(n, s if isinstance(s, ca.Sparsity) else ca.Sparsity.dense(s, 1))
              for n, s in inputs.items()}
    for stage in stages:
        missing = [n for n in stage.name_in() if n not in values]
        if missing:
            raise ValueError(f"stage {stage.name()} reads {', '.join(missing)}: not an input "
                             "nor an earlier stage's output")
        twice = [n for n in stage.name_out() if n in values]
        if twice:
            raise ValueError(f"stage {stage.name()} outputs {', '.join(twice)} again")
        values.update(stage.call({n: values[n] for n in stage.name_in()}))
    absent = [n for n in names_out if n not in values]
    if absent:
        raise ValueError(f"no stage outputs {', '.join(absent)}")
    return ca.Function(name, list(values[n] for n in inputs), [values[n] for n in names_out],
                       list(inputs), list(names_out))


def recompose(like: ca.Function, stages) -> ca.Function:
    """:func:`compose_stages` with the name, inputs and outputs of ``like``."""
    return compose_stages(like.name(), stages,
                          {n: like.sparsity_in(i) for i, n in enumerate(like.name_in())},
                          like.name_out())
