"""The sensors' delivery: each sensor's delay line of records and its reading.

A sensor's packet of a control tick, with its ``fresh`` flag and capture time, is a
record (:func:`delivery_record`, :func:`sensor_record`); it enters the sensor's line of
:data:`DELIVERY_SLOTS` records, newest first (:func:`push`), and is read ``delay``
ticks later (:func:`read_function`: the one slot; :func:`read_slot`: every slot
selected, branch-free). The sensed loop (:mod:`quadland_symbolic.landing.sensed_loop`)
composes them as stages: the shift (:func:`push_stage`) is a ring in its compiled
simulator (:attr:`quadland_symbolic.stages.Staged.rings`), no copy of the line a
tick.
"""

from __future__ import annotations

import functools
import math

import casadi as ca

from quadland_symbolic.landing.navigation import DATALINK, GNSS, IMU, RANGE, VISION
from quadland_symbolic.landing.sensors import SENSOR_PACKETS, sensor_function
from quadland_symbolic.layout import Field, Layout

__all__ = ["DELIVERY_SLOTS", "NAV_PACKET_OF", "READ_NAME", "delivery_record", "delivery_delay",
           "sensor_record", "push", "line_next", "read_slot", "deliver", "read_function",
           "push_stage", "read_stage"]

#: The longest delivery delay a sensor's line holds, in control periods (0.256 s at
#: 250 Hz: past the filter's 0.2 s horizon and its largest packet age).
DELIVERY_SLOTS = 64

#: The filter's packet layout each sensor delivers (the IMU's has no flag: it is held).
NAV_PACKET_OF = {"imu": IMU, "vision": VISION, "gnss": GNSS, "rangefinder": RANGE,
                 "datalink": DATALINK}

def delivery_record(name: str) -> Layout:
    """A packet in ``name``'s delay line: ``fresh``, ``tau``, the filter's packet values."""
    nav = NAV_PACKET_OF[name]
    values = nav.fields if name == "imu" else nav.fields[2:]
    return Layout(f"line_{name}", (
        Field("fresh", 1, "0/1", "1: a packet taken at tau, kept and valid"),
        Field("tau", 1, "s", "capture time"), *values), f"a {name} packet in delivery")


def delivery_delay(latency: float, period: float) -> int:
    """Control ticks from a packet's capture to its reading: ``ceil(latency / period)``.

    A packet arriving within ``1e-9`` of a tick is read at that tick (the ratio
    of two decimals, such as 0.06 s over 0.004 s, is not exact in binary).
    """
    return max(0, math.ceil(latency / period - 1e-9))


def sensor_record(name, xp, uh, w, t, pp, p_sens, tick, contact: bool = True):
    """This tick's record of ``name`` (:func:`delivery_record`): ``fresh``, ``tau = t``, the
    packet's values (``contact``: :func:`~quadland_symbolic.landing.sensors.sensor_function`'s)."""
    packet = SENSOR_PACKETS[name]
    y = packet.unpack(sensor_function(name, contact)(xp, uh, w, t, pp, p_sens,
                                                     tick[f"{name}_noise"]))
    fresh = tick[f"{name}_sampled"] * tick[f"{name}_kept"]
    if "valid" in packet.names():
        fresh = fresh * y["valid"]
    values = [y[f.name] for f in delivery_record(name).fields[2:]]
    return ca.vertcat(fresh, t, *values)


def push(record, line, size):
    """The line after ``record`` enters it: the record first, the oldest slot dropped."""
    return ca.vertcat(record, line[:(DELIVERY_SLOTS - 1) * size])


def line_next(name, xp, uh, w, t, pp, p_sens, tick, line):
    """This tick's packet into ``name``'s line: the line after."""
    return push(sensor_record(name, xp, uh, w, t, pp, p_sens, tick), line,
                delivery_record(name).size)


def read_slot(line, size, delay):
    """The packet read now: slot ``delay`` of the line, every slot computed and selected
    (``+0.0`` for a ``-0.0``, the sum of the other slots' zeros)."""
    read = ca.SX.zeros(size)
    for i in range(DELIVERY_SLOTS):
        read += ca.if_else(delay == i, line[i * size:(i + 1) * size], ca.SX.zeros(size))
    return read


def deliver(name, xp, uh, w, t, pp, p_sens, tick, line, delay):
    """This tick's packet into ``name``'s line; the packet read now, and the line after."""
    after = line_next(name, xp, uh, w, t, pp, p_sens, tick, line)
    return read_slot(after, delivery_record(name).size, delay), after


@functools.cache
def read_function(name: str) -> ca.Function:
    """``read_<name>(delay, line, zero) -> packet``: slot ``delay`` of ``name``'s line, plus
    ``zero``.

    A CasADi ``Switch`` on ``delay`` (one case a slot, zeros beyond the line): its C reads
    the one slot, where the branch-free read (:func:`read_slot`) selects from every slot
    and adds the others' zeros. Given ``zero = +0.0`` it gives the same bits: the slot's
    values, a ``-0.0`` turned to ``+0.0``.
    """
    size = delivery_record(name).size
    line, zero = ca.SX.sym("line", DELIVERY_SLOTS * size), ca.SX.sym("zero")
    cases = [ca.Function(f"slot_{name}_{i}", [line, zero],
                         [line[i * size:(i + 1) * size] + zero], ["line", "zero"], ["packet"])
             for i in range(DELIVERY_SLOTS)]
    beyond = ca.Function(f"beyond_{name}", [line, zero], [ca.DM.zeros(size)], ["line", "zero"],
                         ["packet"])
    return ca.Function.conditional(f"read_{name}", cases, beyond)


#: The name of each sensor's packet read now, as the sensed loop's stages name it.
READ_NAME = {"imu": "read_imu", "vision": "vision", "gnss": "gnss", "rangefinder": "range",
             "datalink": "datalink"}


def push_stage(name) -> ca.Function:
    """``sensed_push_<name>``: step 2's delay line, ``name``'s record of this tick into its
    line (:func:`push`): a ring in the compiled simulator
    (:attr:`quadland_symbolic.stages.Staged.rings`)."""
    size = delivery_record(name).size
    record, past = ca.SX.sym("record", size), ca.SX.sym("past", DELIVERY_SLOTS * size)
    return ca.Function(f"sensed_push_{name}", [record, past], [push(record, past, size)],
                       [f"record_{name}", f"past_{name}"], [f"line_{name}"])


def read_stage(name) -> ca.Function:
    """``sensed_read_<name>``: step 2's reading, the one slot of the delay
    (:func:`read_function`)."""
    line, delay = ca.MX.sym("line", DELIVERY_SLOTS * delivery_record(name).size), \
        ca.MX.sym("delay")
    return ca.Function(f"sensed_read_{name}", [line, delay],
                       [read_function(name)(delay, line, ca.MX(0.0))],
                       [f"line_{name}", f"delay_{name}"], [READ_NAME[name]])
