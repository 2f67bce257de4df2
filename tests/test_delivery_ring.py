"""The sensors' delay lines as rings in the compiled simulator (issue 20).

The sensed loop's controller (:func:`quadland_symbolic.landing.sensed_loop.
landing_sensed_loop`) shifts each sensor's line of :data:`DELIVERY_SLOTS` records by
one every control tick; the compiled simulator keeps the lines in rings instead
(:attr:`quadland_symbolic.stages.Staged.rings`, ``symbolic/templates/
simulator.c.jinja``). The reference is the previous generated simulator: the same
model compiled with ``rings=()``, which shifts, flown on the same inputs, compared
bit for bit (every row, recorded signal and the final memory, its lines included),
over several wrap-arounds of the rings (65 slots: 0.26 s at 250 Hz), with delays of
0 and of the most a line holds (63), from lines that are not empty, and where a line
holds a value that is not finite.
"""

from __future__ import annotations

import dataclasses

import casadi as ca
import numpy as np
import pytest
from flight_capture import captured

from quadland.engine.compiled import SIM_NONFINITE, CompiledLoop, built_model
from quadland_symbolic.landing.sensed_loop import (
    DELIVERY_SLOTS,
    delivery_record,
    landing_sensed_loop,
    sensed_loop_memory,
    sensed_loop_params,
)
from quadland_symbolic.landing.sensors import SENSOR_NAMES
from quadland_symbolic.stages import Staged

L = 10


def _captured(duration: float):
    """The simulator and the arguments the runtime passes it for a ``highway`` flight of
    ``duration`` on sensors."""
    return captured("highway", [f"simulation.duration={duration}"])


@pytest.fixture(scope="module")
def flight():
    """A 1.6 s and a 0.2 s ``highway`` flight's arguments, the runtime's simulator (with
    rings) and the same simulator shifting."""
    ring, args, kwargs = _captured(1.6)
    _, short, short_kwargs = _captured(0.2)
    model = built_model(ring.model)
    assert model.controller_stages.rings           # the runtime's simulator has rings
    stages = dataclasses.replace(model.controller_stages, rings=())
    shift = dataclasses.replace(model, name=model.name + "_shift", controller_stages=stages)
    return dict(ring=ring, shift=CompiledLoop(shift, "sampled"), long=(args, kwargs),
                short=(short, short_kwargs))


def _fly(loop, args, kwargs, delays=None, xc0=None):
    args = list(args)
    pc = args[6]
    if xc0 is not None:
        args[1] = xc0
    if delays is not None:
        pc = np.array(pc, dtype=float).ravel()
        pc[sensed_loop_params(L).slice("delay")] = delays
        args[6] = pc
    return loop.sampled(*args, **kwargs)


def _same(a, b) -> None:
    assert a.status == b.status
    for x, y in ((a.X, b.X), (a.R, b.R), (a.times, b.times), (a.x_end, b.x_end)):
        assert x.shape == y.shape
        np.testing.assert_array_equal(np.asarray(x).view(np.uint64),
                                      np.asarray(y).view(np.uint64))
    np.testing.assert_array_equal(a.w_index, b.w_index)
    assert a.t_stop == b.t_stop or (np.isnan(a.t_stop) and np.isnan(b.t_stop))


@pytest.mark.parametrize("delays", [
    None,                                   # the scenario's own
    (0, 63, 17, 1, 40),                     # imu, vision, gnss, rangefinder, datalink
    (0, 0, 0, 0, 0),
    (2, 63, 63, 63, 63),
])
def test_the_ring_flies_what_the_shift_flies_to_the_bit(flight, delays):
    """1.6 s (400 ticks: six times round the rings), delays of 0 and 63 among them."""
    ring, shift, (args, kwargs) = flight["ring"], flight["shift"], flight["long"]
    a, b = _fly(ring, args, kwargs, delays), _fly(shift, args, kwargs, delays)
    assert a.status == 0 and a.times[-1] == 1.6
    _same(a, b)


def _filled(xc0, rng, fresh: float) -> np.ndarray:
    """``xc0`` with every line's records random (``fresh`` their flag)."""
    xc0, lay = np.array(xc0, dtype=float).ravel(), sensed_loop_memory(L)
    for name in SENSOR_NAMES:
        m = delivery_record(name).size
        line = rng.normal(size=(DELIVERY_SLOTS, m))
        line[:, 0] = fresh
        xc0[lay.slice(f"line_{name}")] = line.ravel()
    return xc0


def test_lines_not_empty_at_the_start_are_read_and_returned_in_order(flight):
    """The first 63 ticks read the start's records (each slot's values differ); a flight
    stopped within them returns the lines, newest first, the same bits."""
    ring, shift, (args, kwargs) = flight["ring"], flight["shift"], flight["short"]
    xc0 = _filled(args[1], np.random.default_rng(20), fresh=0.0)
    for delays in ((0, 63, 17, 1, 40), (63, 5, 0, 62, 30)):
        a, b = _fly(ring, args, kwargs, delays, xc0), _fly(shift, args, kwargs, delays, xc0)
        assert a.status == 0 and a.times[-1] == 0.2
        _same(a, b)
        lines = [a.x_end[-sensed_loop_memory(L).size:][sensed_loop_memory(L).slice(
            f"line_{n}")].reshape(DELIVERY_SLOTS, -1) for n in SENSOR_NAMES]
        # after n ticks the start's record k is in slot n + k
        n = len(args[2][2].times())
        assert 40 < n < DELIVERY_SLOTS
        for line, start in zip(lines, _lines_of(xc0), strict=True):
            np.testing.assert_array_equal(line[n:].view(np.uint64),
                                          start[:DELIVERY_SLOTS - n].view(np.uint64))


def _lines_of(xc0) -> list[np.ndarray]:
    lay = sensed_loop_memory(L)
    return [np.asarray(xc0)[lay.slice(f"line_{n}")].reshape(DELIVERY_SLOTS, -1)
            for n in SENSOR_NAMES]


def test_a_value_not_finite_in_a_line_stops_where_the_shift_stops(flight):
    """A NaN in slot 5 of the start's vision line is in the line after the first tick:
    SIM_NONFINITE there, both ways; in slot 63 (the oldest, dropped at once) it never
    is, and both fly on."""
    ring, shift, (args, kwargs) = flight["ring"], flight["shift"], flight["long"]
    lay = sensed_loop_memory(L)
    m = delivery_record("vision").size
    for slot, stops in ((5, True), (DELIVERY_SLOTS - 1, False)):
        xc0 = np.array(args[1], dtype=float).ravel()
        xc0[lay.slice("line_vision").start + slot * m + 2] = np.nan
        a, b = _fly(ring, args, kwargs, xc0=xc0), _fly(shift, args, kwargs, xc0=xc0)
        assert (a.status == SIM_NONFINITE) is stops
        _same(a, b)


def test_a_ring_must_be_the_shift_in_place():
    """:class:`Staged` refuses a ring whose stage is not exactly the shift of its line by
    its record, or whose line is not where the line before was."""
    r, q = ca.SX.sym("r", 2), ca.SX.sym("q", 6)
    world = ca.Function("world", [r], [2 * r], ["u"], ["record"])
    cases = {
        "shift": ca.vertcat(r, q[:4]),
        "reversed": ca.vertcat(q[:4], r),
        "scaled": ca.vertcat(r, 1.5 * q[:4]),
        "kept": ca.vertcat(r, q[2:]),
    }
    for what, expr in cases.items():
        push = ca.Function("push", [r, q], [expr], ["record", "past"], ["line"])

        def staged(start, push=push):
            return Staged("f", (world, push), (("x", 8), ("u", 2)),
                          (("x_next", ("head", "line")),),
                          slices=(("past", "x", start, start + 6), ("head", "x", 0, 2)),
                          rings=(("line", "record", "past"),))
        if what == "shift":
            assert staged(2).ring_places() == ((0, 0, 2, 2, 3),)
            with pytest.raises(ValueError, match="in place"):
                staged(1)
        else:
            with pytest.raises(ValueError, match="not the shift"):
                staged(2)


def test_a_ring_line_is_read_only_through_its_ring():
    """:class:`Staged` refuses a ring whose memory line (``past``) another stage reads, or
    whose record is also an output's piece: the compiled ring writes neither, so that stage
    or output would see stale values."""
    r, q = ca.SX.sym("r", 2), ca.SX.sym("q", 6)
    world = ca.Function("world", [r], [2 * r], ["u"], ["record"])
    push = ca.Function("push", [r, q], [ca.vertcat(r, q[:4])], ["record", "past"], ["line"])
    peek = ca.Function("peek", [q], [q[:2]], ["past"], ["seen"])
    slices = (("past", "x", 2, 8), ("head", "x", 0, 2))
    with pytest.raises(ValueError, match="past is read by peek"):
        Staged("f", (world, push, peek), (("x", 8), ("u", 2)),
               (("x_next", ("head", "line")), ("y", ("seen",))), slices=slices,
               rings=(("line", "record", "past"),))
    with pytest.raises(ValueError, match="record record is an output's piece"):
        Staged("f", (world, push), (("x", 8), ("u", 2)),
               (("x_next", ("head", "line")), ("y", ("record",))), slices=slices,
               rings=(("line", "record", "past"),))


def test_the_sensed_loop_rings_its_five_lines():
    """Each sensor's line (and nothing else) is a ring, at its place in the memory."""
    stages = landing_sensed_loop(L).controller_stages
    lay = sensed_loop_memory(L)
    assert stages.ring_places() == tuple(
        (1, 0, lay.slice(f"line_{n}").start, delivery_record(n).size, DELIVERY_SLOTS)
        for n in SENSOR_NAMES)
