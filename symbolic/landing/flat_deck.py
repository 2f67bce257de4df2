"""The landing loop on a flat deck: the deck's sinusoid sums left out.

The deck's heave, roll and pitch are sums of :data:`~quadland_symbolic.landing.deck.N_DECK`
sinusoids each (:mod:`quadland_symbolic.landing.deck`): the plant, the event, the
sensors and the outputs evaluate them, with their time derivatives, wherever the
deck's pose is needed, some 680 sines and cosines per RK4 step. A car's deck and any
scenario without sea or sinusoids has every amplitude zero, and then each term is
``0 * sin(...)``, exactly zero.

:func:`flat_deck_loop` rebuilds the functions of a landing loop that the
integration evaluates (:data:`FLATTENED`) with the amplitudes of its plant
parameters (``pp``, ``p``, and the controller's model ``pc.pp``) replaced by the
constant zero. CasADi folds the products away, and with them every sine and
cosine of the deck, the rotations by the zero roll and pitch and the additions of
zero. What remains computes the same numbers as the full loop
on a deck of zero amplitudes: the folded operations are exact (``x * 0 = 0``,
``x + 0 = x``, ``x * 1 = x``, ``cos(0) = 1``) for finite ``x``, and a deck's
frequencies and phases, the time and the state are finite (a non-finite state stops
a run). The one difference IEEE arithmetic allows is the sign of a zero (``0 *
sin(x)`` is ``-0.0`` where ``sin(x) < 0``), and CasADi's simplifications can meet
operands the folding made equal and round differently; the functions where either
shows are kept whole (:data:`FLATTENED`). ``tests/test_flat_deck.py`` compares each
rebuilt function with the original at random inputs, and whole landings, bit for
bit. The runtime flies this loop when every amplitude is zero
(``quadland.kinds.landing.simulate.flat_deck``).
"""

from __future__ import annotations

import dataclasses
import functools

import casadi as ca

from quadland_symbolic.landing.plant import LANDING_PLANT_PARAMS
from quadland_symbolic.layout import Layout
from quadland_symbolic.loop import LoopModel

__all__ = ["AMPLITUDES", "FLATTENED", "amplitude_indices", "flat_function", "flat_deck_loop"]

#: The fields of :data:`~quadland_symbolic.landing.deck.DECK_PARAMS` that scale the
#: deck's sinusoids.
AMPLITUDES = ("heave_amp", "roll_amp", "pitch_amp")

#: The functions of a :class:`LoopModel` rebuilt on the flat deck, by field name: those
#: that compute the same bits at every input (``tests/test_flat_deck.py``). Kept whole:
#: ``ride_row`` (the welded ride's rows: its ``x_e`` rounds differently at some inputs)
#: and ``step_args`` (the flight code's inputs carry the deck's motion itself, whose
#: zero sums are ``-0.0`` at some inputs); both are evaluated once a row or a
#: control period, not in every RK4 stage.
FLATTENED = ("rhs", "output_fn", "plant", "controller", "event", "ride_rhs", "free_plant")


def amplitude_indices(layout: Layout, prefix: str = "") -> tuple[int, ...]:
    """Positions of the deck's amplitudes in a vector laid out as ``layout``.

    ``layout`` is :data:`LANDING_PLANT_PARAMS` (``prefix`` empty) or a layout with
    it nested under ``prefix`` (``"pp."``, a controller's parameters).

    Examples
    --------
    >>> len(amplitude_indices(LANDING_PLANT_PARAMS))      # 27 sinusoids a motion
    81
    """
    out: list[int] = []
    for name in AMPLITUDES:
        s = layout.slice(f"{prefix}p_deck.{name}")
        out.extend(range(s.start, s.stop))
    return tuple(out)


def flat_function(f: ca.Function, zeros: dict[str, tuple[int, ...]]) -> ca.Function:
    """``f`` with the entries ``zeros[name]`` of its input ``name`` the constant zero.

    ``f`` is an SX Function (an MX Function composed of stages,
    :attr:`~quadland_symbolic.loop.LoopModel.controller_stages`, is flattened stage by
    stage).

    The other inputs, the names and the outputs are ``f``'s; the inputs zeroed
    remain (unused where they were only amplitudes). Common subexpressions are
    merged, as in the loops' own functions. ``f`` itself when it has none of
    those inputs.
    """
    if not any(zeros.get(name) for name in f.name_in()):
        return f
    if not f.is_a("SXFunction"):
        raise ValueError(f"{f.name()} is not an SX Function: flatten its stages")
    ins = [f.sx_in(i) for i in range(f.n_in())]
    args = []
    for i, x in enumerate(ins):
        idx = zeros.get(f.name_in(i), ())
        if idx:
            x = ca.SX(x)
            for k in idx:
                x[k] = 0
        args.append(x)
    return ca.Function(f.name(), ins, f.call(args), f.name_in(), f.name_out(), {"cse": True})


@functools.cache
def flat_deck_loop(model: LoopModel) -> LoopModel:
    """The landing loop ``model`` on a deck whose every amplitude is zero.

    Named ``model.name + "_flat"`` (its own compiled simulator). Its inputs and
    layouts are ``model``'s; the deck's amplitudes given at run time are ignored
    (the runtime passes zeros there).

    Raises
    ------
    ValueError
        For a model whose plant parameters are not the landing plant's.
    """
    if model.plant_params is not LANDING_PLANT_PARAMS:
        raise ValueError(f"{model.name} is not a landing loop: its plant parameters are "
                         f"{model.plant_params.name}")
    pp = amplitude_indices(LANDING_PLANT_PARAMS)
    zeros = {"pp": pp, "pc": amplitude_indices(model.controller_params, "pp.")}
    if model.params is LANDING_PLANT_PARAMS:
        zeros["p"] = pp
    staged = model.controller_stages is not None
    changes = {name: flat_function(getattr(model, name), zeros) for name in FLATTENED
               if getattr(model, name) is not None and not (staged and name == "controller")}
    if staged:          # each SX stage flattened, composed again
        stages = model.controller_stages.with_stages(
            (flat_function(f, zeros) for f in model.controller_stages.stages),
            [flat_function(f, zeros) for _, f in model.controller_stages.free])
        changes.update(controller=stages.function(), controller_stages=stages)
    return dataclasses.replace(model, name=f"{model.name}_flat", **changes)

