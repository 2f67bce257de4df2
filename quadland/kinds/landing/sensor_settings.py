"""The sensors' settings: every key's unit and range, the defaults, the checks.

Settings are plain dicts like a scenario's ``[sensors.<name>]`` table;
:data:`SENSOR_DEFAULTS` holds the defaults (docs/sensors.md cites each) and
:data:`SETTINGS` every key's unit, meaning and physical range.
:func:`validate_settings` lays a table over the defaults and checks it;
:func:`sensor_params` forms the truth models' ``p_sens`` from the settings.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from types import MappingProxyType

import numpy as np

from quadland.exceptions import ScenarioError
from quadland.schema.sensors import SETTINGS, Setting, check_ranges
from quadland_symbolic.landing.sensors import SENSOR_NAMES, SENSOR_PARAMS

__all__ = ["Setting", "SETTINGS", "SENSOR_DEFAULTS", "GNSS_RTK", "STANDARD_GRAVITY",
           "gnss_errors",
           "validate_settings", "sensor_params"]

_DEG = math.pi / 180.0
_G0 = 9.80665                       # m/s^2, standard gravity: datasheets' "g"
#: m/s^2, standard gravity: the data sheets' "g", and the specific force a GNSS-aided
#: attitude levels the accelerometer against (``attitude_gnss_aided``, docs/sensors.md).
STANDARD_GRAVITY = _G0


#: Default settings of each sensor; docs/sensors.md gives every value's source.
SENSOR_DEFAULTS: Mapping[str, Mapping] = MappingProxyType({
    # TDK ICM-42688-P (DS-000347), PX4's attitude_estimator_q, VectorNav VN-100:
    # docs/sensors.md, "IMU and attitude estimate".
    "imu": MappingProxyType({
        "rate_hz": 250.0, "latency": 0.0, "phase": 0.0, "dropout": 0.0,
        "gyro_noise_density": 2.8e-3 * _DEG,              # 2.8 mdps/sqrt(Hz)
        "gyro_bias_sigma": 0.005 * 20.0 * _DEG,           # 0.005 dps/degC over 20 degC
        "gyro_bias_random_walk": 0.005 * 10.0 * _DEG / math.sqrt(300.0),
        "accel_noise_density": 70e-6 * _G0,               # 70 ug/sqrt(Hz)
        "accel_bias_sigma": 0.15e-3 * 20.0 * _G0,         # 0.15 mg/degC over 20 degC
        "accel_bias_random_walk": 0.15e-3 * 10.0 * _G0 / math.sqrt(300.0),
        "attitude_sigma": (0.5 * _DEG, 0.5 * _DEG, 2.0 * _DEG),
        "attitude_tau": (5.0, 5.0, 10.0),                 # 1 / ATT_W_ACC, 1 / ATT_W_MAG
        "attitude_white_sigma": 0.01 * _DEG,
        "attitude_gnss_aided": False,                     # the AHRS's error, not the bias'
    }),
    # docs/sensors.md, "Vision": issue 17's minimums, a pinhole model of a
    # Raspberry Pi Camera Module 3 Wide and a 0.6 m marker.
    "vision": MappingProxyType({
        "rate_hz": 25.0, "latency": 0.06, "phase": 0.0, "dropout": 0.05,
        "outlier_rate": 0.01, "outlier_sigma": 0.5,
        "sigma0": 0.02, "sigma_per_m": 0.01, "half_angle": 33.5 * _DEG,
        "range_min": 0.45, "range_max": 12.0, "small_range_min": 0.08, "small_range_max": 0.0,
    }),
    # u-blox NEO-M9N, Beard & McLain's GNSS error model, PX4's EKF2_GPS_DELAY:
    # docs/sensors.md, "GNSS".
    "gnss": MappingProxyType({
        "rate_hz": 5.0, "latency": 0.11, "phase": 0.0, "dropout": 0.01,
        "position_sigma": (1.5 / 1.1774, 1.5 / 1.1774, 1.9 * 1.5 / 1.1774),
        "position_tau": 1100.0, "velocity_sigma": 0.05, "rtk": False,
        # u-blox ZED-F9P moving base (NAV-RELPOSNED): the data sheet's RTK 0.01 m CEP per
        # fix as white noise, the same vertical ratio (docs/sensors.md, "RTK moving baseline")
        "relative_rtk": False,
        "relative_sigma": (0.01 / 1.1774, 0.01 / 1.1774, 1.9 * 0.01 / 1.1774),
    }),
    # Benewake TFmini-S, PX4's EKF2_RNG_DELAY: docs/sensors.md, "Rangefinder".
    "rangefinder": MappingProxyType({
        "rate_hz": 125.0, "latency": 0.005, "phase": 0.0, "dropout": 0.01,
        "outlier_rate": 0.0, "outlier_sigma": 1.0,
        "sigma0": 0.03, "sigma_per_m": 0.005, "range_min": 0.1, "range_max": 7.0,
        "deck_half_length": 1.0, "deck_half_width": 0.7,
    }),
    # A GNSS-aided MEMS INS on the vehicle and issue 17's minimums:
    # docs/sensors.md, "Datalink".
    "datalink": MappingProxyType({
        "rate_hz": 10.0, "latency": 0.1, "phase": 0.0, "dropout": 0.02,
        "eta2_sigma": (0.1 * _DEG, 0.1 * _DEG, 0.2 * _DEG),
        "v2E_sigma": 0.05, "a2E_sigma": 0.05, "w2E_sigma": 0.002, "w2E_dot_sigma": 0.03,
    }),
})


#: Overrides of ``[sensors.gnss]`` for RTK (u-blox ZED-F9P, docs/sensors.md).
GNSS_RTK: Mapping = MappingProxyType({
    "position_sigma": (0.01 / 1.1774, 0.01 / 1.1774, 1.9 * 0.01 / 1.1774),
})


def gnss_errors(s: Mapping) -> tuple[np.ndarray, float]:
    """The receivers' position errors ``e_q``, ``e_t``: their six sigmas and time constant.

    Standard or RTK receivers: both Gauss-Markov, ``position_sigma`` (or :data:`GNSS_RTK`'s)
    over ``position_tau``. A moving-baseline RTK pair (``relative_rtk``, docs/sensors.md):
    the relative position's error alone, ``e_q = 0`` and ``e_t`` white (``tau = 0``) of
    ``relative_sigma`` per axis.
    """
    if s["relative_rtk"]:
        return np.concatenate([np.zeros(3), np.asarray(s["relative_sigma"], dtype=float)]), 0.0
    sigma = GNSS_RTK["position_sigma"] if s["rtk"] else s["position_sigma"]
    return np.tile(np.asarray(sigma, dtype=float), 2), float(s["position_tau"])


def validate_settings(name: str, values: Mapping | None = None) -> dict:
    """A sensor's settings over its defaults, checked.

    ``values`` (a ``[sensors.<name>]`` table) over :data:`SENSOR_DEFAULTS`.

    Raises
    ------
    ScenarioError
        One line naming ``sensors.<name>.<key>``: an unknown sensor or key,
        a value of the wrong kind or length, or out of its physical range.
    """
    if name not in SETTINGS:
        raise ScenarioError(f"sensors.{name}: unknown sensor; sensors are "
                            f"{', '.join(SENSOR_NAMES)}")
    schema, out = SETTINGS[name], dict(SENSOR_DEFAULTS[name])
    for key, v in (values or {}).items():
        where = f"sensors.{name}.{key}"
        if key not in schema:
            raise ScenarioError(f"{where}: unknown key; keys are {', '.join(schema)}")
        s = schema[key]
        if s.unit == "bool":
            if not isinstance(v, bool):
                raise ScenarioError(f"{where}: must be true or false, got {v!r}")
            out[key] = v
            continue
        items = v if s.length is not None else [v]
        if s.length is not None and (not isinstance(v, list | tuple) or len(v) != s.length):
            raise ScenarioError(f"{where}: must be a list of {s.length} numbers ({s.unit})")
        for x in items:
            if isinstance(x, bool) or not isinstance(x, int | float) or not math.isfinite(x):
                raise ScenarioError(f"{where}: must be a finite number ({s.unit}), got {x!r}")
            if not s.lo <= x <= s.hi:
                raise ScenarioError(f"{where}: must be in [{s.lo:g}, {s.hi:g}] {s.unit}, "
                                    f"got {x!r}")
        out[key] = tuple(float(x) for x in v) if s.length is not None else float(v)
    check_ranges(name, out)
    return out


def sensor_params(settings: Mapping[str, Mapping] | None = None) -> np.ndarray:
    """The Functions' ``p_sens`` from the sensors' settings.

    :data:`SENSOR_PARAMS` from the vision and rangefinder settings
    (defaults for whatever is missing).
    """
    settings = settings or {}
    v = validate_settings("vision", settings.get("vision"))
    r = validate_settings("rangefinder", settings.get("rangefinder"))
    values = {f"vision_{k}": v[k] for k in ("sigma0", "sigma_per_m", "half_angle", "range_min",
                                           "range_max", "small_range_min", "small_range_max")}
    values.update({f"rangefinder_{k}": r[k] for k in ("sigma0", "sigma_per_m", "range_min",
                                                      "range_max")})
    values.update(deck_half_length=r["deck_half_length"], deck_half_width=r["deck_half_width"])
    return SENSOR_PARAMS.pack(values)
