"""The navigation filter's step with each sensor's updates evaluated only when due.

:func:`~quadland_symbolic.landing.estimator.estimator_step_function` computes every
block's update at every step and selects it by the sensor's ``due`` flag: a block
that is not due runs the same instructions with a zero gain. A sensor's FIFO head is
due at a few steps in ten at most (the range finder at 125 Hz, the camera at 25 Hz,
the datalink at 10 Hz and the GNSS at 5 Hz, on a 250 Hz control clock), so most of
those instructions give back the state and covariance they were given.

:func:`conditional_step_function` is the same step as an MX Function of the same
pieces (:mod:`quadland_symbolic.landing.estimator`'s :func:`step_queues`,
:func:`fuse_sensor`, :func:`finish_step`), one SX Function each:

1. ``estimator_queues``: the latest broadcast and every sensor's FIFO's head, count,
   ``due`` flag and its ``push`` and ``pop`` flags (steps 1 and 2's queueing); then for
   each sensor ``estimator_fifo_<sensor>`` (:func:`fifo_switch`): a ``Switch`` on
   ``push`` or ``pop`` between the FIFO's slots pushed and popped by selection, as in
   the branch-free step, and the slots held (plus ``+0.0``, what the selections give
   when neither flag is set). A FIFO is pushed or popped in a few periods in ten, the
   range finder's in about half; by selection alone its slots cost two selections a
   value every period (docs/performance.md);
2. for each sensor in fusion order, ``estimator_<sensor>``: a CasADi ``Switch``
   (``Function.conditional``) on the sensor's ``due`` flag between ``fuse_<sensor>``
   (the deck's normal at the head's time and the sensor's gated updates, as in the
   branch-free step) and ``skip_<sensor>`` (the state and covariance passed through,
   every outcome zero). CasADi's generated C evaluates only the chosen case (an
   ``if`` on the flag around the case's call);
3. ``estimator_finish``: the output predictor, the prediction, the memory and the
   diagnostics (steps 3 and 4).

The sensed loop's compiled simulator flies it (:mod:`quadland_symbolic.landing.sensed_loop`)
as two of its controller's stages (:func:`conditional_step_stages`), the finish its own:
there it writes the memory, the measurements and the diagnostics where they go, not
into a work vector they are copied out of.
The flight code's C (``generated/estimator_step.c``) stays the branch-free step: there
the stages' copies (the memory, state and covariance passed between CasADi's
functions) cost more than the updates skipped save in a period where every sensor is
due, over the filter's budget of 30,000 instructions (docs/performance.md).

The bits are those of the branch-free step. Where a sensor is due, ``fuse_<sensor>``
computes the same expressions with the same ``due`` (its value 1 passed in, not
folded). Where it is not, the branch-free step's outcomes are the zeros of its
selections and its state is ``x + k nu`` with ``k`` and ``nu`` exactly zero, ``x``
itself for every ``x`` but ``-0.0`` (which a zero of the other sign turns to
``+0.0``); its covariance likewise. The filter's state and covariance are never
``-0.0`` in a flight (tests/test_estimator_switch.py compares the two steps bit for
bit on filters running through sensed landings, and at random inputs).
"""

from __future__ import annotations

import functools

import casadi as ca

from quadland_symbolic.kalman import fifo_push_pop
from quadland_symbolic.landing.estimator import (
    block_streaks,
    estimator_memory,
    finish_step,
    fuse_sensor,
    sensor_blocks,
    step_queues,
)
from quadland_symbolic.landing.navigation import (
    IMU,
    NAV,
    NAV_PACKETS,
    SENSORS,
    covariance_pattern,
    estimator_params,
)

__all__ = ["OUTCOME", "fusion_switch", "fifo_switch", "conditional_step_function",
           "conditional_step_stages"]

#: The outcome of a block after its measurement's ``dim`` innovations, in order.
OUTCOME = ("nis", "fused", "held", "rejected")

_DECK = 10          # eta2, w2E, w2E_dot, tau of the latest broadcast


def _deck(v) -> dict:
    return dict(eta2=v[0:3], w2E=v[3:6], w2E_dot=v[6:9], tau=v[9])


def _record_size(sensor: str) -> int:
    """Reals of a FIFO record of ``sensor``: its packet without ``fresh``."""
    return next(p for p in NAV_PACKETS if p.name == sensor).size - 1


def _outcome_size(sensor: str) -> int:
    return sum(b.dim + len(OUTCOME) for b in sensor_blocks(sensor))


@functools.cache
def fusion_switch(sensor: str, coupling: str = "full") -> ca.Function:
    """``estimator_<sensor>(due, x, P, head, due, deck, streak, p_est) -> (x, P, outcome)``.

    A ``Switch`` on its first input: ``fuse_<sensor>`` where it is not 0,
    ``skip_<sensor>`` where it is. ``P`` the stored entries of the covariance
    (:func:`~quadland_symbolic.landing.navigation.covariance_pattern`), ``head`` the FIFO's
    head record, ``deck`` the latest broadcast (``eta2``, ``w2E``, ``w2E_dot``, ``tau``),
    ``streak`` each block's gate refusals; ``outcome`` per block of the sensor, in
    fusion order: its innovation and :data:`OUTCOME`.
    """
    pattern, blocks = covariance_pattern(coupling), sensor_blocks(sensor)
    x, P = NAV.sym("x"), ca.SX.sym("P", pattern.size)
    head, due = ca.SX.sym("head", _record_size(sensor)), ca.SX.sym("due")
    deck, streak = ca.SX.sym("deck", _DECK), ca.SX.sym("streak", len(blocks))
    p_est = estimator_params().sym("p_est")
    ins, names = [x, P, head, due, deck, streak, p_est], \
        ["x", "P", "head", "due", "deck", "streak", "p_est"]
    x1, P1, blk = fuse_sensor(sensor, x, pattern.unpack(P), head, due, _deck(deck),
                              ca.vertsplit(streak), p_est, pattern)
    outcome = ca.vertcat(*[ca.vertcat(blk[b.name]["nu"], *[blk[b.name][k] for k in OUTCOME])
                           for b in blocks])
    outs = ["x_next", "P_next", "outcome"]
    fuse = ca.Function(f"fuse_{sensor}", ins,
                       [ca.densify(x1), ca.densify(pattern.pack(P1)), ca.densify(outcome)],
                       names, outs, {"cse": True})
    skip = ca.Function(f"skip_{sensor}", ins, [x, P, ca.DM.zeros(_outcome_size(sensor))],
                       names, outs)
    return ca.Function.conditional(f"estimator_{sensor}", [skip], fuse)


@functools.cache
def fifo_switch(sensor: str, n_hist: int, depth, coupling: str = "full") -> ca.Function:
    """``estimator_fifo_<sensor>(active, mem, packet, push, pop, active) -> fifo_next``.

    ``mem`` the filter's memory before the step
    (:func:`~quadland_symbolic.landing.estimator.estimator_memory` at these sizes), of
    which the FIFO and its count are read. A ``Switch`` on its first input (``push`` or
    ``pop``): ``move_<sensor>``, the FIFO's slots pushed and popped by selection as in
    the branch-free step (:func:`~quadland_symbolic.kalman.fifo_push_pop`, the same
    expressions of the same flags), where it is not 0; ``hold_<sensor>`` where it is:
    the slots plus ``active``, ``+0.0`` there. That is what the selections give when
    neither flag is set (``0 + x``: every slot itself, ``-0.0`` turned to ``+0.0``),
    without computing them.
    """
    lay = estimator_memory(n_hist, depth, coupling)
    mem, pkt = lay.sym("mem"), ca.SX.sym("packet", _record_size(sensor) + 1)
    push, pop, active = (ca.SX.sym(n) for n in ("push", "pop", "active"))
    m = lay.unpack(mem)
    ins, names = [mem, pkt, push, pop, active], ["mem", "packet", "push", "pop", "active"]
    moved = fifo_push_pop(m[f"fifo_{sensor}"], m[f"count_{sensor}"], pkt[1:], push,
                          lambda head, nonempty: pop)["slots"]
    move = ca.Function(f"move_{sensor}", ins, [ca.densify(ca.vec(moved))], names,
                       ["fifo_next"], {"cse": True})
    hold = ca.Function(f"hold_{sensor}", ins, [mem[lay.slice(f"fifo_{sensor}")] + active],
                       names, ["fifo_next"])
    return ca.Function.conditional(f"estimator_fifo_{sensor}", [hold], move)


def _queues_function(lay, held: bool):
    """``estimator_queues(mem, <packets>, p_est, dt, t) -> (x_h, P_h, deck, <per sensor>)``.

    Per sensor: ``head``, ``due``, ``streak``, ``push``, ``pop``, ``active`` (either),
    ``count``, ``discarded``, ``dropped``
    (:func:`~quadland_symbolic.landing.estimator.step_queues`); the FIFO's slots
    ``fifo`` too where not ``held`` (else :func:`fifo_switch`'s).
    """
    mem, p_est = lay.sym("mem"), estimator_params().sym("p_est")
    pkts = [layout.sym(layout.name) for layout in NAV_PACKETS]
    dt, t = ca.SX.sym("dt"), ca.SX.sym("t")
    m = lay.unpack(mem)
    deck, sen = step_queues(m, pkts, estimator_params().unpack(p_est), dt, t)
    outs, names = [m["x_h"], m["P_h"], ca.vertcat(*_deck_values(deck))], ["x_h", "P_h", "deck"]
    for s in SENSORS:
        q = sen[s]
        fifo = (("push", q["push"]), ("pop", q["pop"]),
                ("active", ca.logic_or(q["push"], q["pop"]))) if held else (("fifo", q["fifo"]),)
        for k, v in (("head", q["head"]), ("due", q["due"]),
                     ("streak", ca.vertcat(*block_streaks(m, s))), *fifo,
                     ("count", q["count"]), ("discarded", q["discarded"]),
                     ("dropped", q["dropped"])):
            outs.append(ca.densify(v))
            names.append(f"{k}_{s}")
    return ca.Function("estimator_queues", [mem, *pkts, p_est, dt, t], outs,
                       ["mem", *SENSORS, "p_est", "dt", "t"], names, {"cse": True})


def _deck_values(deck: dict) -> list:
    return [deck["eta2"], deck["w2E"], deck["w2E_dot"], deck["tau"]]


def _finish_function(lay, pattern, name="estimator_finish", rename=lambda n: n):
    """``estimator_finish(mem, imu, p_est, dt, t, deck, <queues>, x, P, <outcomes>)
    -> (mem_next, y, diag)`` (:func:`~quadland_symbolic.landing.estimator.finish_step`);
    ``name`` and its inputs and outputs named ``rename(<those names>)``."""
    mem, imu, p_est = lay.sym("mem"), IMU.sym("imu"), estimator_params().sym("p_est")
    dt, t, deck = ca.SX.sym("dt"), ca.SX.sym("t"), ca.SX.sym("deck", _DECK)
    x, P = NAV.sym("x"), ca.SX.sym("P", pattern.size)
    ins, names, sen, blk = [mem, imu, p_est, dt, t, deck], \
        ["mem", "imu", "p_est", "dt", "t", "deck"], {}, {}
    m = lay.unpack(mem)
    for s in SENSORS:
        q = {k: ca.SX.sym(f"{k}_{s}", lay[f"fifo_{s}"].size if k == "fifo" else 1)
             for k in ("fifo", "count", "discarded", "dropped")}
        sen[s] = q
        ins += list(q.values())
        names += [f"{k}_{s}" for k in q]
    ins += [x, P]
    names += ["x", "P"]
    for s in SENSORS:
        v = ca.SX.sym(f"outcome_{s}", _outcome_size(s))
        ins.append(v)
        names.append(f"outcome_{s}")
        k = 0
        for b in sensor_blocks(s):
            blk[b.name] = dict(nu=v[k:k + b.dim],
                               **{o: v[k + b.dim + i] for i, o in enumerate(OUTCOME)})
            k += b.dim + len(OUTCOME)
    mem_next, y, diag = finish_step(lay, pattern, m, IMU.unpack(imu), imu, p_est, dt, t,
                                    _deck(deck), sen, x, pattern.unpack(P), blk)
    return ca.Function(name, ins, [mem_next, y, diag], [rename(n) for n in names],
                       [rename(n) for n in ("mem_next", "y", "diag")], {"cse": True})


def _fused_args(lay, n_hist, depth, coupling, held):
    """The MX inputs of the step and the finish's arguments (queues, FIFOs, fusions)."""
    queues = _queues_function(lay, held)
    mem, imu, p_est = ca.MX.sym("mem", lay.size), ca.MX.sym("imu", IMU.size), \
        ca.MX.sym("p_est", estimator_params().size)
    pkts = [ca.MX.sym(p.name, p.size) for p in NAV_PACKETS]
    dt, t = ca.MX.sym("dt"), ca.MX.sym("t")
    q = queues.call(dict(mem=mem, **dict(zip(SENSORS, pkts, strict=True)), p_est=p_est,
                         dt=dt, t=t))
    x, P, done = q["x_h"], q["P_h"], {}
    fifo = {s: fifo_switch(s, n_hist, depth, coupling)(
        q[f"active_{s}"], mem, pkt, q[f"push_{s}"], q[f"pop_{s}"], q[f"active_{s}"])
        if held else q[f"fifo_{s}"] for s, pkt in zip(SENSORS, pkts, strict=True)}
    for s in SENSORS:
        due = q[f"due_{s}"]
        x, P, done[f"outcome_{s}"] = fusion_switch(s, coupling)(
            due, x, P, q[f"head_{s}"], due, q["deck"], q[f"streak_{s}"], p_est)
    args = dict(mem=mem, imu=imu, p_est=p_est, dt=dt, t=t, deck=q["deck"])
    for s in SENSORS:
        args[f"fifo_{s}"] = fifo[s]
        args.update({f"{k}_{s}": q[f"{k}_{s}"] for k in ("count", "discarded", "dropped")})
    args.update(x=x, P=P, **done)
    return [mem, imu, *pkts, p_est, dt, t], args


@functools.cache
def conditional_step_function(n_hist: int, depth, coupling: str = "full",
                              held: bool = True) -> ca.Function:
    """The navigation filter's step, each sensor's updates evaluated only when due.

    ``estimator_step(mem, imu, vision, gnss, range, datalink, p_est, dt, t)
    -> (mem_next, y, diag)``: the inputs, outputs and bits of
    :func:`~quadland_symbolic.landing.estimator.estimator_step_function` at the same
    sizes, as an MX Function (the module docstring). ``held``: each FIFO's slots by
    :func:`fifo_switch`, computed only where pushed or popped (the default); else by
    selection in ``estimator_queues`` every step (before; the same bits).
    """
    lay = estimator_memory(n_hist, depth, coupling)
    finish = _finish_function(lay, covariance_pattern(coupling))
    ins, args = _fused_args(lay, n_hist, depth, coupling, held)
    out = finish.call(args)
    return ca.Function("estimator_step", ins,
                       [out["mem_next"], out["y"], out["diag"]],
                       ["mem", "imu", *SENSORS, "p_est", "dt", "t"],
                       ["mem_next", "y", "diag"])


def conditional_step_stages(n_hist: int, depth, coupling: str = "full", held: bool = True,
                            names=("estimator_fused", "estimator_finish"),
                            rename=lambda n: n) -> tuple[ca.Function, ca.Function]:
    """:func:`conditional_step_function` as two Functions called in turn, the same bits.

    ``estimator_fused(mem, imu, vision, gnss, range, datalink, p_est, dt, t) -> (deck,
    <per sensor: fifo, count, discarded, dropped>, x, P, <outcome per sensor>)``, an MX
    Function (the queues, the FIFOs' and the fusions' ``Switch`` Functions), and
    ``estimator_finish(mem, imu, p_est, dt, t, <those>) -> (mem_next, y, diag)``, the SX
    Function of step 3 and 4. Composed as stages
    (:class:`quadland_symbolic.stages.Staged`), the finish writes the memory, the
    measurements and the diagnostics where they are read: an MX Function copies each
    output out of its work vector (938 reals a step here, against the 440 the first
    Function outputs). ``names`` the two Functions' names, ``rename(n)`` the name of
    each of their inputs and outputs ``n``.
    """
    lay = estimator_memory(n_hist, depth, coupling)
    finish = _finish_function(lay, covariance_pattern(coupling))
    ins, args = _fused_args(lay, n_hist, depth, coupling, held)
    between = finish.name_in()[5:]
    fused = ca.Function(names[0], ins, [args[n] for n in between],
                        [rename(n) for n in ("mem", "imu", *SENSORS, "p_est", "dt", "t")],
                        [rename(n) for n in between])
    return fused, _finish_function(lay, covariance_pattern(coupling), names[1], rename)
