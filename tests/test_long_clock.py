"""The sensors' sample counts of a long flight, exact (issue 20).

A sensor's samples before a horizon were counted with a tolerance of ``1e-5`` of the
horizon: past about 800 s it exceeded two control periods, and a sample two ticks
before the end of a chunk of the per-tick table was left out of that chunk (placed
later, in a row the flight had already passed). The counts are now a tolerance of the
sensor's own period (:meth:`SensorClock.count`) or integers (:meth:`SensorDraws.extend_ticks`,
what the table draws with). Checked against hand counts.
"""

from __future__ import annotations

import numpy as np

from quadland.kinds.landing.sensing import SensorDraws
from quadland.kinds.landing.sensor_settings import SENSOR_DEFAULTS

RATE = 250.0                          # the control clock, Hz


def test_a_long_flights_samples_counted_by_hand():
    """The vision at 25 Hz (a sample every 10th control tick from tick 0): before tick
    200,002 (800.008 s) lie ticks 0, 10, ..., 200,000, 20,001 samples by hand; before
    800.008 s, the same. The old count gave 20,000: it took the sample at 800.000 s,
    8 ms before the horizon, for one at it."""
    draws = SensorDraws(None, seed=5, random=False)
    clock = draws.sensors["vision"].clock
    assert clock.count(800.008) == 20_001
    assert clock.before_tick(200_002, RATE) == 20_001
    # at a sample's own instant it is not before the horizon: 800.000 s, tick 200,000
    assert clock.count(800.0) == clock.before_tick(200_000, RATE) == 20_000
    assert clock.before_tick(200_001, RATE) == 20_001


def test_every_sensor_before_a_late_tick_by_hand():
    """Each default sensor (its rate divides 250 Hz, phase 0) has ``ceil(T / stride)``
    samples before tick ``T``: hand counts at T = 250,003 (1,000.012 s), the last sample
    of the 5 Hz GNSS at tick 250,000, of the 10 Hz datalink at 250,000, of the 125 Hz
    rangefinder at 250,002."""
    hand = {"imu": 250_003, "vision": 25_001, "gnss": 5_001, "rangefinder": 125_002,
            "datalink": 10_001}
    assert {n: SENSOR_DEFAULTS[n]["rate_hz"] for n in hand} == {
        "imu": 250.0, "vision": 25.0, "gnss": 5.0, "rangefinder": 125.0, "datalink": 10.0}
    draws = SensorDraws(None, seed=5, random=False)
    assert draws.extend_ticks(250_003, RATE) == hand
    for name, n in hand.items():
        t, delivered, noise = draws.window(name, 0, n)
        ticks = np.rint(t * RATE).astype(np.int64)
        assert ticks[-1] < 250_003 and len(t) == n
        assert ticks[-1] + round(RATE / SENSOR_DEFAULTS[name]["rate_hz"]) >= 250_003


def test_a_phase_moves_the_first_sample():
    """A 25 Hz sensor starting 3 control periods late (phase 0.012 s) samples at ticks
    3, 13, 23, ...: before tick 3 none, before 4 one, before 200,004 (800.016 s) the
    ticks 3 to 199,993 and 200,003: 20,001."""
    draws = SensorDraws({"vision": {"phase": 0.012}}, seed=5, random=False)
    clock = draws.sensors["vision"].clock
    assert [clock.before_tick(t, RATE) for t in (0, 3, 4, 13, 14)] == [0, 0, 1, 1, 2]
    assert clock.before_tick(200_004, RATE) == clock.count(800.016) == 20_001


def test_a_sensors_ticks_are_its_sample_times_on_the_control_clock():
    """``SensorClock.ticks`` (the rows :class:`TickTable` writes a sensor's samples into, in
    integers) against the samples' own times rounded to the control clock, the rule the
    table placed them by before (``rint(t * rate)``): every default sensor, a phase of 3
    control periods and the IMU at 125 Hz, samples from 0 and from a late block to
    1,000 s; and hand values for the 25 Hz vision 3 periods late (ticks 3, 13, 23)."""
    settings = ({}, {"vision": {"phase": 0.012}, "rangefinder": {"phase": 0.02},
                     "imu": {"rate_hz": 125.0}})
    for s in settings:
        draws = SensorDraws(s, seed=5, random=False)
        for name, sen in draws.sensors.items():
            n = sen.clock.before_tick(250_003, RATE)
            for k0, k1 in ((0, 1), (0, min(n, 4_097)), (n - 3_000, n), (n - 1, n)):
                by_time = np.rint(sen.clock.times(k0, k1) * RATE).astype(np.int64)
                rows = np.arange(250_003)[sen.clock.ticks(k0, k1, RATE)]
                assert np.array_equal(rows, by_time), (name, s, k0, k1)
    vision = SensorDraws({"vision": {"phase": 0.012}}, seed=5, random=False).sensors["vision"]
    assert vision.clock.ticks(0, 3, RATE) == slice(3, 24, 10)
