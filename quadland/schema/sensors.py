"""The sensors' settings as scenario keys: every key's unit, meaning and physical range.

``[sensors.<name>]`` of a landing scenario (:data:`SETTINGS`); the defaults and the
checks over them are the runtime's (:mod:`quadland.kinds.landing.sensor_settings`),
each default's source is in docs/sensors.md. :func:`sensor_fields` gives the schema's
fields of one sensor.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from types import MappingProxyType
from typing import NamedTuple

from quadland.exceptions import ScenarioError
from quadland.schema.fields import Field
from quadland_symbolic.landing.estimator import FLIGHT_DEPTH, N_HIST
from quadland_symbolic.landing.navigation import SENSORS
from quadland_symbolic.landing.sensed_loop import DELIVERY_SLOTS
from quadland_symbolic.landing.sensors import SENSOR_NAMES

__all__ = ["Setting", "SETTINGS", "sensor_fields", "check_ranges", "check_sensor_timing"]


class Setting(NamedTuple):
    """One key of a ``[sensors.<name>]`` table.

    Attributes
    ----------
    unit, doc : str
    lo, hi : float
        Physical range of every value, ``lo <= v <= hi``.
    length : int or None
        None for a scalar, 3 for a list of three (x, y, z or roll, pitch, yaw).
    default : optional
        The value a scenario that leaves the key out takes (None: the key is required):
        a key added after the shipped scenarios, its default the behaviour of before.
    """

    unit: str
    doc: str
    lo: float
    hi: float
    length: int | None = None
    default: object = None


def _common(rate_hi: float) -> dict[str, Setting]:
    return {
        "rate_hz": Setting("Hz", "samples per second", 1e-3, rate_hi),
        "latency": Setting("s", "from sample to arrival at the flight computer", 0.0, 10.0),
        "phase": Setting("s", "time of the first sample", 0.0, 10.0),
        "dropout": Setting("-", "probability that a sample is lost", 0.0, 1.0),
    }


_OUTLIERS = {
    "outlier_rate": Setting("-", "probability that a sample is an outlier", 0.0, 1.0),
    "outlier_sigma": Setting("m", "standard deviation of an outlier's offset per axis", 0.0,
                             1e3),
}


#: Every key of every sensor's table: unit, meaning, physical range (and length).
SETTINGS: Mapping[str, Mapping[str, Setting]] = MappingProxyType({
    "imu": MappingProxyType({
        **_common(1e5),
        "gyro_noise_density": Setting("rad/s/sqrt(Hz)", "gyro white-noise density", 0.0, 1.0),
        "gyro_bias_sigma": Setting("rad/s", "std of the gyro's turn-on bias per axis", 0.0,
                                   1.0),
        "gyro_bias_random_walk": Setting("rad/s/sqrt(s)", "gyro bias random-walk density",
                                         0.0, 1.0),
        "accel_noise_density": Setting("m/s^2/sqrt(Hz)", "accelerometer white-noise density",
                                       0.0, 10.0),
        "accel_bias_sigma": Setting("m/s^2", "std of the accelerometer's turn-on bias per "
                                    "axis", 0.0, 10.0),
        "accel_bias_random_walk": Setting("m/s^2/sqrt(s)", "accelerometer bias random-walk "
                                          "density", 0.0, 10.0),
        "attitude_sigma": Setting("rad", "std of the attitude estimator's Gauss-Markov error "
                                  "(roll, pitch, yaw)", 0.0, 1.0, 3),
        "attitude_tau": Setting("s", "its time constants (roll, pitch, yaw)", 1e-3, 1e9, 3),
        "attitude_white_sigma": Setting("rad", "std of its white part per axis", 0.0, 1.0),
        "attitude_gnss_aided": Setting("bool", "true: a GNSS-aided estimator's attitude, its "
                                       "roll and pitch levelling the biased accelerometer "
                                       "(b_a_y / g, -b_a_x / g) plus the Gauss-Markov "
                                       "residual of attitude_sigma; false: an AHRS's, the "
                                       "Gauss-Markov error alone", 0.0, 1.0,
                                       default=False),
    }),
    "vision": MappingProxyType({
        **_common(1e3), **_OUTLIERS,
        "sigma0": Setting("m", "noise per axis at zero range", 0.0, 100.0),
        "sigma_per_m": Setting("m/m", "growth of the noise per metre of range", 0.0, 10.0),
        "half_angle": Setting("rad", "half-angle of the field-of-view cone", 0.0, math.pi / 2),
        "range_min": Setting("m", "nearest range at which the marker is detected", 0.0, 1e4),
        "range_max": Setting("m", "farthest range at which the marker is detected", 0.0, 1e4),
        "small_range_min": Setting("m", "nearest range of the second, smaller marker", 0.0,
                                   1e4),
        "small_range_max": Setting("m", "farthest range of the second marker (0: none)", 0.0,
                                   1e4),
    }),
    "gnss": MappingProxyType({
        **_common(1e3),
        "position_sigma": Setting("m", "std of each receiver's position error (x, y, z)",
                                  0.0, 1e3, 3),
        "position_tau": Setting("s", "time constant of each receiver's position error", 1e-3,
                                1e9),
        "velocity_sigma": Setting("m/s", "std of each velocity's white noise per axis", 0.0,
                                  100.0),
        "rtk": Setting("bool", "true: both receivers are RTK (position_sigma gives way to the "
                       "RTK fix's)", 0.0, 1.0),
        "relative_rtk": Setting("bool", "true: the relative position is a moving-baseline RTK "
                                "pair's, white noise of relative_sigma per fix in place of "
                                "the receivers' Gauss-Markov errors; false: the receivers' "
                                "difference. Optional: a scenario that leaves it out takes "
                                "false", 0.0, 1.0, default=False),
        "relative_sigma": Setting("m", "std of the RTK relative position's white noise per "
                                  "fix (x, y, z), with relative_rtk. Optional: 0.0085, "
                                  "0.0085, 0.016", 0.0, 1e3, 3,
                                  default=(0.01 / 1.1774, 0.01 / 1.1774, 1.9 * 0.01 / 1.1774)),
    }),
    "rangefinder": MappingProxyType({
        **_common(1e5), **_OUTLIERS,
        "sigma0": Setting("m", "noise at zero distance", 0.0, 100.0),
        "sigma_per_m": Setting("m/m", "growth of the noise per metre", 0.0, 10.0),
        "range_min": Setting("m", "shortest distance reported", 0.0, 1e4),
        "range_max": Setting("m", "longest distance reported", 0.0, 1e4),
        "deck_half_length": Setting("m", "deck extent along its x axis from the pad centre",
                                    0.0, 1e4),
        "deck_half_width": Setting("m", "deck extent along its y axis from the pad centre", 0.0,
                                   1e4),
    }),
    "datalink": MappingProxyType({
        **_common(1e3),
        "eta2_sigma": Setting("rad", "std of the broadcast deck attitude (roll, pitch, yaw)",
                              0.0, 1.0, 3),
        "v2E_sigma": Setting("m/s", "std of the broadcast velocity per axis", 0.0, 100.0),
        "a2E_sigma": Setting("m/s^2", "std of the broadcast acceleration per axis", 0.0, 100.0),
        "w2E_sigma": Setting("rad/s", "std of the broadcast angular rate per axis", 0.0, 10.0),
        "w2E_dot_sigma": Setting("rad/s^2", "std of the broadcast angular acceleration per "
                                 "axis", 0.0, 100.0),
    }),
})


def sensor_fields(name: str) -> dict[str, Field]:
    """The schema's fields of ``[sensors.<name>]``, from :data:`SETTINGS`."""
    return {key: (Field(bool, "-", s.doc, default=s.default) if s.unit == "bool"
                  else Field(float, s.unit, s.doc, s.length, lo=s.lo, hi=s.hi,
                             default=None if s.default is None else list(s.default)))
            for key, s in SETTINGS[name].items()}


def check_ranges(name: str, values: Mapping) -> None:
    """Refuse a ``[sensors.<name>]`` table whose nearest range exceeds its farthest."""
    where = f"sensors.{name}"
    for lo, hi in (("range_min", "range_max"), ("small_range_min", "small_range_max")):
        if lo in values and values[hi] > 0 and values[lo] > values[hi]:
            raise ScenarioError(f"{where}.{lo}: must not exceed {where}.{hi} "
                                f"({values[hi]:g} m)")


def check_sensor_timing(data: dict) -> None:
    """A sensor samples on the control clock, and its latency fits the delivery line."""
    rate = data["controller"]["rate_hz"]
    for name in SENSOR_NAMES:
        s, where = data[f"sensors.{name}"], f"sensors.{name}"
        ticks = rate / s["rate_hz"]
        if abs(ticks - round(ticks)) > 1e-9 * ticks or round(ticks) < 1:
            raise ScenarioError(f"{where}.rate_hz: {s['rate_hz']:g} Hz must divide "
                                f"controller.rate_hz ({rate:g} Hz): a sensor samples on the "
                                "control clock")
        phase = s["phase"] * rate
        if abs(phase - round(phase)) > 1e-6:
            raise ScenarioError(f"{where}.phase: {s['phase']:g} s must be a whole number of "
                                f"control periods (1/{rate:g} s)")
        if s["latency"] * rate > DELIVERY_SLOTS - 1 + 1e-9:
            raise ScenarioError(f"{where}.latency: {s['latency']:g} s is more than the "
                                f"{DELIVERY_SLOTS - 1} control periods a packet can be held "
                                f"({(DELIVERY_SLOTS - 1) / rate:g} s at {rate:g} Hz)")
        check_ranges(name, s)
    _check_fusion(data)


def _check_fusion(data: dict) -> None:
    """What a sensor sends the filter can be fused: its packets, read at the first control
    tick at or after their latency, reach the filter's horizon (``N_HIST`` periods behind)
    less than ``max_age`` past it (at exactly ``max_age`` the discard is decided by
    rounding), and a FIFO of the depth flown holds those in flight (``rate x (D -
    latency) + 1``, docs/estimator.md)."""
    rate = data["controller"]["rate_hz"]
    horizon = N_HIST / rate
    for sensor, depth in zip(SENSORS, FLIGHT_DEPTH, strict=True):
        name = "rangefinder" if sensor == "range" else sensor
        s = data[f"sensors.{name}"]
        arrival = math.ceil(s["latency"] * rate - 1e-9)        # control periods
        late = N_HIST + data["estimator"][f"max_age_{sensor}"] * rate
        if arrival >= late - 1e-9:
            raise ScenarioError(f"sensors.{name}.latency: {s['latency']:g} s is read "
                                f"{arrival} control periods after the sample, not within the "
                                f"navigation filter's horizon ({N_HIST}) plus "
                                f"estimator.max_age_{sensor} ({late - N_HIST:g}): its packets "
                                "would be discarded")
        need = math.ceil(s["rate_hz"] * max(horizon - s["latency"], 0.0) + 1 - 1e-9)
        if need > depth:
            raise ScenarioError(f"sensors.{name}.rate_hz: {s['rate_hz']:g} Hz with "
                                f"{s['latency']:g} s of latency keeps {need} packets waiting "
                                f"for the filter's horizon ({horizon:g} s); its queue holds "
                                f"{depth}: packets would be dropped")
