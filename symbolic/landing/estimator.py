"""The navigation filter's flight step.

A delayed fusion horizon and an output predictor.

docs/estimator.md is the design; the equations (E1)-(E17) are there. The
model (state, packets, parameters, prediction, measurement blocks) is
:mod:`quadland_symbolic.landing.navigation`. One step, at the control time ``t``:

1. The deck's latest broadcast is kept (attitude and rotation, for the range
   model and the output).
2. The filter's state ``x_h`` and covariance ``P_h`` live at the horizon
   ``t_h``, ``n_hist`` periods behind ``t``. Each sensor's fresh packet goes
   into its FIFO; the FIFO's head is fused when its sample time is within half
   a period of ``t_h`` or before it (gated per block, scalar Joseph updates),
   or discarded when older than ``t_h - max_age``; at most one packet per
   sensor per step (E16).
3. The output predictor carries ``x_h`` through the ``n_hist`` buffered
   acceleration inputs to ``t`` (state only, closed form (E17)) and forms the
   controller's :data:`~quadland_symbolic.landing.controller.LANDING_MEASUREMENT` (E7), (E15).
4. ``x_h``, ``P_h`` are predicted over the oldest buffered input (E6); this
   period's input joins the buffer.

Here everything is selected, never branched: a block that is not due, held back or
rejected runs the same instructions with a zero gain.
:mod:`quadland_symbolic.landing.estimator_switch` builds the same step from the same
pieces with each sensor's updates evaluated only when its FIFO's head is due (the
compiled simulators'; the flight code's C stays branch-free, its worst period within
the budget: docs/performance.md), to the same bits.
"""

from __future__ import annotations

import functools

import casadi as ca

from quadland_symbolic.kalman import fifo_push_pop, is_finite, select
from quadland_symbolic.kinematics import rotation
from quadland_symbolic.landing.controller import LANDING_MEASUREMENT
from quadland_symbolic.landing.nav_output import (
    estimator_output,
    heave_frequency,
    output_predictor,
)
from quadland_symbolic.landing.navigation import (
    BLOCKS,
    DATALINK,
    DECK_INIT,
    IMU,
    NAV,
    NAV_PACKETS,
    SENSORS,
    acceleration_input,
    block_update,
    covariance_pattern,
    deck_at,
    estimator_params,
    nav_predict,
)
from quadland_symbolic.layout import Field, Layout

__all__ = [
    "N_HIST",
    "FIFO_DEPTH",
    "FLIGHT_DEPTH",
    "FLIGHT_COUPLING",
    "estimator_memory",
    "estimator_diagnostics",
    "output_predictor",
    "output_predictor_function",
    "estimator_output",
    "estimator_step_function",
    "estimator_init_function",
    "sensor_blocks",
    "step_queues",
    "block_streaks",
    "fuse_sensor",
    "finish_step",
]

#: Default horizon delay in periods: D = 0.2 s at 250 Hz.
N_HIST = 50
#: Default FIFO depth per sensor.
FIFO_DEPTH = 8

#: The FIFO depths flown (vision, gnss, range, datalink): each sensor's
#: ``rate x (D - latency) + 1`` at the shipped sensors' defaults (25 Hz, 60 ms;
#: 5 Hz, 110 ms; 125 Hz, 5 ms; 10 Hz, 100 ms) with room for dropped-then-late
#: bursts, the range finder's 125 Hz needing 26 (docs/estimator.md, "Open questions").
FLIGHT_DEPTH = (8, 4, 26, 4)
#: The covariance coupling flown: x, y, z decoupled (the 30,000-instruction budget).
FLIGHT_COUPLING = "axes"

#: The rows of the filter's input history, one column per period: the acceleration input
#: (E2), the period, the body's turn over it (E6a).
HIST_ROWS = ("a_in_x", "a_in_y", "a_in_z", "dt", "turn_x", "turn_y", "turn_z")
_HIST_UNITS = ("m/s^2",) * 3 + ("s",) + ("rad",) * 3


def _depths(depth) -> tuple[int, ...]:
    """One FIFO depth per sensor, from an int or a tuple of them."""
    out = (depth,) * len(SENSORS) if isinstance(depth, int) else tuple(depth)
    if len(out) != len(SENSORS) or any(not isinstance(d, int) or d < 1 for d in out):
        raise ValueError(f"depth must be a positive int or {len(SENSORS)} of them, got {depth!r}")
    return out


def _record_fields(layout: Layout) -> tuple[Field, ...]:
    """A packet's fields but ``fresh``: what a FIFO slot holds."""
    return layout.fields[1:]


def _units(fields) -> tuple[str, ...]:
    return tuple(u for f in fields for u in f.element_units())


def _counter(name: str, names, doc: str) -> Field:
    return Field(name, len(names), "-", doc, elements=tuple(f"{name}_{n}" for n in names))


_BLOCK_NAMES = tuple(b.name for b in BLOCKS)


def _counters() -> tuple[Field, ...]:
    return (
        _counter("n_fused", _BLOCK_NAMES, "blocks fused, per block"),
        _counter("n_rejected", _BLOCK_NAMES, "blocks due but rejected by the gate, per block"),
        _counter("n_held", _BLOCK_NAMES, "blocks due but held back as unusable (E12, E12a), "
                 "per block"),
        _counter("n_discarded", SENSORS, "packets older than the horizon by max_age, per sensor"),
        _counter("n_dropped", SENSORS, "packets not queued: FIFO full, not finite, future"),
        Field("n_imu_invalid", 1, "-", "periods with a non-finite IMU sample"),
        _counter("streak", _BLOCK_NAMES, "consecutive gate refusals, per block (E8a)"),
    )


@functools.cache
def estimator_memory(n_hist: int = N_HIST, depth=FIFO_DEPTH, coupling: str = "full") -> Layout:
    """What the filter carries from one step to the next.

    Parameters
    ----------
    n_hist : int
        Periods between the horizon and now (``D = n_hist dt``).
    depth : int or tuple of int
        FIFO depth, for every sensor or per sensor (:data:`SENSORS`' order).
    coupling : str
        ``full`` covariance or ``axes`` (x, y, z decoupled).
    """
    if n_hist < 0:
        raise ValueError(f"n_hist must be >= 0, got {n_hist}")
    depths, pattern = _depths(depth), covariance_pattern(coupling)
    nav_units = NAV.element_units()
    fifos = []
    for layout, d in zip(NAV_PACKETS, depths, strict=True):
        rec = _record_fields(layout)
        size = sum(f.size for f in rec)
        fifos += [Field(f"fifo_{layout.name}", size * d, _units(rec) * d,
                        f"{layout.name} packets waiting for the horizon, oldest first",
                        shape=(size, d)),
                  Field(f"count_{layout.name}", 1, "-", f"{layout.name} packets in the FIFO")]
    return Layout("mem_est", (
        Field.nested("x_h", NAV, "state at the horizon t_h"),
        Field("P_h", pattern.size, tuple(f"({nav_units[i]})({nav_units[j]})"
                                         for i, j in pattern.entries),
              "covariance at the horizon: stored upper-triangle entries, row by row",
              elements=pattern.element_names()),
        Field("t_h", 1, "s", "time of the horizon"),
        Field("hist", len(HIST_ROWS) * n_hist, _HIST_UNITS * n_hist,
              "acceleration inputs (E), their periods and the body's turns (E, E6a) from "
              "t_h to now, oldest first",
              shape=(len(HIST_ROWS), n_hist),
              elements=tuple(f"{r}_{k + 1}" for k in range(n_hist) for r in HIST_ROWS)),
        *fifos,
        Field("deck_eta2", 3, "rad", "deck attitude of the latest broadcast"),
        Field("deck_w2E", 3, "rad/s", "deck angular velocity of the latest broadcast"),
        Field("deck_w2E_dot", 3, "rad/s^2", "deck angular acceleration of the latest broadcast"),
        Field("deck_tau", 1, "s", "sample time of the latest broadcast"),
        *_counters(),
        Field("heave_ms", 2, ("m^2/s^2", "m^2/s^4"), "exponential averages of the horizon's "
              "pad vertical velocity and acceleration squared (E17a)",
              elements=("ms_v_t_z", "ms_a_t_z")),
    ), f"navigation filter memory (n_hist={n_hist}, depth={depths}, {coupling})")


@functools.cache
def estimator_diagnostics() -> Layout:
    """What the step reports besides the controller's measurements."""
    innov = []
    for b in BLOCKS:
        packet = next(p for p in NAV_PACKETS if p.name == b.sensor)
        innov.append(Field(f"nu_{b.name}", b.dim, packet[b.field].unit,
                           f"{b.name} innovation z - h(x) when due, else 0"))
    nav_units = NAV.element_units()
    return Layout("diag_est", (
        *innov,
        _counter("nis", _BLOCK_NAMES, "NIS when due (-1 if not finite), else 0"),
        _counter("fused", _BLOCK_NAMES, "1 if the block was fused this step"),
        _counter("rejected", _BLOCK_NAMES, "1 if the block was due and rejected by the gate"),
        _counter("held", _BLOCK_NAMES, "1 if the block was due and held back as unusable"),
        _counter("discarded", SENSORS, "1 if the FIFO head was too old"),
        _counter("dropped", SENSORS, "1 if a fresh packet was not queued"),
        Field("imu_invalid", 1, "-", "1 if the IMU sample was not finite"),
        *_counters(),
        Field.nested("x_h", NAV, "state at the horizon after this step's fusion"),
        Field("P_diag", NAV.size, tuple(f"({u})^2" for u in nav_units),
              "its variances", elements=tuple(f"var_{n}" for n in NAV.element_names())),
        Field("t_h", 1, "s", "time of the horizon"),
    ), "navigation filter diagnostics")


# ---------------------------------------------------------------- pieces

@functools.cache
def output_predictor_function(n_hist: int = N_HIST) -> ca.Function:
    """``nav_output_predictor(x_h, hist, omega) -> x_now`` (E17), (E17a).

    ``hist`` is ``4 x n_hist``; ``omega`` the pad's vertical oscillation's frequency
    (rad/s; 0: a constant acceleration).
    """
    x, hist, omega = NAV.sym("x_h"), ca.SX.sym("hist", 4, n_hist), ca.SX.sym("omega")
    return ca.Function("nav_output_predictor", [x, hist, omega],
                       [output_predictor(x, hist, omega)], ["x_h", "hist", "omega"], ["x_now"])


def _latest_deck(m, dl, t):
    """The latest usable broadcast.

    This step's if fresh, finite, not older and not from the future.
    """
    values = ca.vertcat(dl["eta2"], dl["w2E"], dl["w2E_dot"], dl["tau"])
    ok = ca.logic_and(dl["fresh"] > 0.5, ca.logic_and(dl["tau"] >= m["deck_tau"], dl["tau"] <= t))
    for i in range(values.shape[0]):
        ok = ca.logic_and(ok, is_finite(values[i]))
    old = ca.vertcat(m["deck_eta2"], m["deck_w2E"], m["deck_w2E_dot"], m["deck_tau"])
    new = select(ok, values, old)
    return dict(eta2=new[0:3], w2E=new[3:6], w2E_dot=new[6:9], tau=new[9])


def _queue(layout, m, pkt, p, t_h, dt, t):
    """Queue a packet; pop its FIFO's head if due or stale (E16).

    Returns the head (the record after the push), ``due`` (popped and not older than
    ``t_h - max_age``), ``push`` and ``pop`` (the FIFO's two flags) and what the memory
    and the diagnostics keep: the FIFO, its count, ``discarded`` and ``dropped``.
    """
    pk = layout.unpack(pkt)
    push_ok = pk["tau"] <= t
    for i in range(1, pkt.shape[0]):                   # tau and the values
        push_ok = ca.logic_and(push_ok, is_finite(pkt[i]))
    fresh = pk["fresh"] > 0.5

    def pop_if(head, nonempty):
        return ca.logic_and(nonempty, head[0] <= t_h + dt / 2)

    name = layout.name
    f = fifo_push_pop(m[f"fifo_{name}"], m[f"count_{name}"], pkt[1:],
                      ca.logic_and(fresh, push_ok), pop_if)
    stale = ca.logic_and(f["pop"], f["head"][0] < t_h - p[f"max_age_{name}"])
    return dict(head=f["head"], due=ca.logic_and(f["pop"], ca.logic_not(stale)),
                push=ca.logic_and(fresh, push_ok), pop=f["pop"],
                fifo=ca.vec(f["slots"]), count=f["count"], discarded=stale,
                dropped=ca.logic_or(f["dropped"], ca.logic_and(fresh, ca.logic_not(push_ok))))


def sensor_blocks(name: str) -> tuple:
    """The measurement blocks of sensor ``name``, in fusion order."""
    return tuple(b for b in BLOCKS if b.sensor == name)


def fuse_sensor(name, x, P, head, due, deck, streaks, p_est, pattern):
    """Fuse the blocks of sensor ``name``'s FIFO head where ``due`` (E8)-(E14).

    ``deck`` the latest broadcast (its normal at the head's sample time is the range's
    model), ``streaks`` each block's gate refusals so far. Returns ``(x, P, blocks)``,
    ``blocks`` by block name: ``nu``, ``nis``, ``fused``, ``held``, ``rejected``.
    """
    p = estimator_params().unpack(p_est)
    eta2_r, _ = deck_at(deck["eta2"], deck["w2E"], deck["w2E_dot"], head[0] - deck["tau"],
                        p["deck_extrapolation_max"])
    n2 = rotation(eta2_r)[:, 2]
    head_pkt = ca.vertcat(1, head)
    blocks = {}
    for b, streak in zip(sensor_blocks(name), streaks, strict=True):
        x, P, nu, nis, fused, held = block_update(b.name, x, P, head_pkt, n2, p_est, due,
                                                  pattern, streak)
        nis_ok = is_finite(nis)
        blocks[b.name] = dict(
            nu=select(ca.logic_and(due, nis_ok), nu, 0),
            nis=select(due, select(nis_ok, nis, -1), 0), fused=fused, held=held,
            rejected=ca.logic_and(due, ca.logic_not(ca.logic_or(fused, held))))
    return x, P, blocks


def _bias_turn(eta_hat, omega, dt):
    """The body's rotation over a period as a vector in E, from the gyro (E6a).

    ``theta = R(eta_hat) omega dt``. The accelerometer's bias is fixed in the body, so its
    share of the input, ``a_b = R1 b_a`` in E, turns with the body:
    ``a_b+ = a_b + theta x a_b`` to first order in ``theta``.
    """
    return rotation(eta_hat) @ omega * dt


def _finite3(v):
    return ca.logic_and(ca.logic_and(is_finite(v[0]), is_finite(v[1])), is_finite(v[2]))


def _input(ims, x_h, p, dt):
    """This period's acceleration input (E2) and the body's turn (E6a).

    A non-finite input is replaced by the input's bias ``a_b + a_tilt`` (no acceleration),
    a non-finite turn by none.
    """
    a_in = acceleration_input(ims["eta_hat"], ims["f_b"], p["g"])
    ok = _finite3(a_in)
    turn = _bias_turn(ims["eta_hat"], ims["omega"], dt)
    x = NAV.unpack(x_h)
    return select(ok, a_in, x["a_b"] + x["a_tilt"]), select(_finite3(turn), turn, 0), ok


def step_queues(m, pkts, p, dt, t):
    """The latest broadcast and every sensor's queue (:func:`_queue`), by sensor."""
    deck = _latest_deck(m, DATALINK.unpack(pkts[-1]), t)
    return deck, {layout.name: _queue(layout, m, pkt, p, m["t_h"], dt, t)
                  for layout, pkt in zip(NAV_PACKETS, pkts, strict=True)}


def block_streaks(m, name):
    """Each of sensor ``name``'s blocks' gate refusals so far, from the memory ``m``."""
    return [m["streak"][_BLOCK_NAMES.index(b.name)] for b in sensor_blocks(name)]


def finish_step(lay, pattern, m, ims, imu, p_est, dt, t, deck, sen, x, P, blk):
    """``(mem_next, y, diag)`` from the state ``x``, ``P`` after fusion (steps 3 and 4).

    ``sen`` each sensor's queue, ``blk`` each block's outcome.
    """
    p = estimator_params().unpack(p_est)
    heave_ms, omega = heave_frequency(m["heave_ms"], x, p, dt)
    y = estimator_output(x, m["hist"], deck, imu, p_est, t, omega)
    a_in, turn, imu_ok = _input(ims, x, p, dt)
    hist = ca.horzcat(m["hist"], ca.vertcat(a_in, dt, turn))          # oldest first
    x_next, P_next = nav_predict(x, P, hist[0:3, 0], hist[3, 0], p_est, pattern, hist[4:7, 0],
                                 select(p["heave_in_filter"] > 0.5, omega, 0))    # (E17b)
    flags = dict(
        fused=ca.vertcat(*[blk[b]["fused"] for b in _BLOCK_NAMES]),
        rejected=ca.vertcat(*[blk[b]["rejected"] for b in _BLOCK_NAMES]),
        held=ca.vertcat(*[blk[b]["held"] for b in _BLOCK_NAMES]),
        discarded=ca.vertcat(*[sen[s]["discarded"] for s in SENSORS]),
        dropped=ca.vertcat(*[sen[s]["dropped"] for s in SENSORS]),
        imu_invalid=ca.logic_not(imu_ok))
    counters = dict(n_fused=m["n_fused"] + flags["fused"],
                    n_rejected=m["n_rejected"] + flags["rejected"],
                    n_held=m["n_held"] + flags["held"],
                    n_discarded=m["n_discarded"] + flags["discarded"],
                    n_dropped=m["n_dropped"] + flags["dropped"],
                    n_imu_invalid=m["n_imu_invalid"] + flags["imu_invalid"],
                    streak=ca.vertcat(*[select(blk[b]["fused"], 0, select(
                        blk[b]["rejected"], m["streak"][i] + 1, m["streak"][i]))
                        for i, b in enumerate(_BLOCK_NAMES)]))
    fifos = []
    for s in SENSORS:
        fifos += [sen[s]["fifo"], sen[s]["count"]]
    mem_next = ca.vertcat(
        x_next, pattern.pack(P_next), m["t_h"] + hist[3, 0], ca.vec(hist[:, 1:]), *fifos,
        deck["eta2"], deck["w2E"], deck["w2E_dot"], deck["tau"],
        *[counters[f.name] for f in _counters()], heave_ms)
    diag = ca.vertcat(
        *[blk[b]["nu"] for b in _BLOCK_NAMES],
        ca.vertcat(*[blk[b]["nis"] for b in _BLOCK_NAMES]),
        *[flags[k] for k in ("fused", "rejected", "held", "discarded", "dropped",
                             "imu_invalid")],
        *[counters[f.name] for f in _counters()],
        x, ca.diag(P), m["t_h"])
    assert y.shape[0] == LANDING_MEASUREMENT.size and diag.shape[0] == estimator_diagnostics().size
    return mem_next, y, diag


def _step(n_hist, depth, coupling, mem, imu, pkts, p_est, dt, t):
    """The step's expressions ``(mem_next, y, diag)``, every block's update computed.

    The module docstring's 1-4.
    """
    lay, pattern = estimator_memory(n_hist, depth, coupling), covariance_pattern(coupling)
    m, p, ims = lay.unpack(mem), estimator_params().unpack(p_est), IMU.unpack(imu)
    deck, sen = step_queues(m, pkts, p, dt, t)
    x, P, blk = m["x_h"], pattern.unpack(m["P_h"]), {}
    for s in SENSORS:
        x, P, fused = fuse_sensor(s, x, P, sen[s]["head"], sen[s]["due"], deck, block_streaks(m, s),
                            p_est, pattern)
        blk.update(fused)
    return finish_step(lay, pattern, m, ims, imu, p_est, dt, t, deck, sen, x, P, blk)


_STEP_INPUTS = ["mem", "imu", *SENSORS, "p_est", "dt", "t"]


@functools.cache
def estimator_step_function(n_hist: int = N_HIST, depth=FIFO_DEPTH,
                            coupling: str = "full") -> ca.Function:
    """The navigation filter's step, every update computed and selected (one SX Function).

    ``estimator_step(mem, imu, vision, gnss, range, datalink, p_est, dt, t)
    -> (mem_next, y, diag)``

    Parameters
    ----------
    n_hist : int
        Horizon delay in periods, ``D = n_hist dt`` (:data:`N_HIST`).
    depth : int or tuple of int
        FIFO depth, every sensor or each (:data:`FIFO_DEPTH`).
    coupling : str
        ``full`` covariance or ``axes``: x, y, z decoupled, the range fused on
        z with its x, y part as noise (E9a).

    Notes
    -----
    Inputs: ``mem`` (:func:`estimator_memory`), ``imu``
    (:data:`~quadland_symbolic.landing.navigation.IMU`), one packet per sensor
    (:data:`~quadland_symbolic.landing.navigation.NAV_PACKETS`), ``p_est``
    (:func:`~quadland_symbolic.landing.navigation.estimator_params`), the period
    ``dt`` and the time ``t`` of this step (s). Outputs: ``mem_next``,
    ``y`` (:data:`~quadland_symbolic.landing.controller.LANDING_MEASUREMENT`, at ``t``) and
    ``diag`` (:func:`estimator_diagnostics`). Equations (E1)-(E17) of
    docs/estimator.md.
    """
    lay = estimator_memory(n_hist, depth, coupling)
    mem, imu, p_est = lay.sym("mem"), IMU.sym("imu"), estimator_params().sym("p_est")
    pkts = [layout.sym(layout.name) for layout in NAV_PACKETS]
    dt, t = ca.SX.sym("dt"), ca.SX.sym("t")
    mem_next, y, diag = _step(n_hist, depth, coupling, mem, imu, pkts, p_est, dt, t)
    return ca.Function("estimator_step", [mem, imu, *pkts, p_est, dt, t],
                       [mem_next, y, diag], _STEP_INPUTS, ["mem_next", "y", "diag"],
                       {"cse": True})


@functools.cache
def estimator_init_function(n_hist: int = N_HIST, depth=FIFO_DEPTH,
                            coupling: str = "full") -> ca.Function:
    """The filter at handover as a Function.

    ``estimator_init(x0, P0_diag, deck0, t0) -> mem``. The horizon starts at ``t0`` with
    ``x0`` and a diagonal covariance; the input buffer holds ``n_hist`` empty periods
    (``dt = 0``), so the horizon stays at ``t0`` until it has filled and the output is
    ``x0`` propagated through the periods so far. ``deck0``
    (:data:`~quadland_symbolic.landing.navigation.DECK_INIT`) stands for a broadcast at ``t0``
    until one arrives; zeros mean a level deck heading along E's x, not rotating. The
    FIFOs and counters are empty.
    """
    lay, pattern = estimator_memory(n_hist, depth, coupling), covariance_pattern(coupling)
    x0, P0, deck0, t0 = NAV.sym("x0"), ca.SX.sym("P0_diag", NAV.size), DECK_INIT.sym(), \
        ca.SX.sym("t0")
    d = DECK_INIT.unpack(deck0)
    values = dict(x_h=x0, P_h=pattern.pack(ca.diag(P0)), t_h=t0, deck_eta2=d["eta2"],
                  deck_w2E=d["w2E"], deck_w2E_dot=d["w2E_dot"], deck_tau=t0)
    mem = ca.vertcat(*[values[f.name] if f.name in values else ca.DM.zeros(f.size)
                       for f in lay.fields])
    return ca.Function("estimator_init", [x0, P0, deck0, t0], [ca.densify(mem)],
                       ["x0", "P0_diag", "deck0", "t0"], ["mem"])
