"""Which of the hover loop's measured outputs each landing sensor feeds.

The margin review breaks the landing loop at a sensor's outputs
(:func:`quadland.analysis.sensitivity.group_delay_margin`) to find the
latency it tolerates. The hover loop is linearized with perfect sensing: the
law reads ``y = [p_e, v_e, eta1, Omega1]``
(:data:`quadland_symbolic.landing.linearization.HOVER_OUTPUT`). Each sensor's
packet (docs/sensors.md) measures some of these:

* ``vision``: the marker's offset ``r_E``, the relative position ``p_e``;
* ``gnss``: the relative position ``rel`` and the velocities ``v1``, ``vt``,
  so ``p_e`` and ``v_e``;
* ``rangefinder``: the range along ``-b3``, at hover the height ``z_e``;
* ``imu``: the attitude estimate ``eta_hat`` and the gyro ``omega``, so
  ``eta1`` and ``Omega1`` (its specific force drives the filter's
  prediction, not the law);
* ``datalink``: the deck's broadcast. At the hover point the vehicle is
  exogenous (its motion is frozen), so the datalink feeds no loop: a delay
  of it moves no closed-loop pole.

Vision and GNSS both measure ``p_e``: breaking at one of them delays the
position the law reads, as if the filter passed that sensor through alone.
"""

from __future__ import annotations

from types import MappingProxyType

from quadland.kinds.landing.sensor_settings import validate_settings
from quadland.scenario import Scenario
from quadland_symbolic.landing.linearization import HOVER_OUTPUT

__all__ = ["SENSOR_OUTPUTS", "sensor_channels"]

_P, _V = HOVER_OUTPUT.element_names()[0:3], HOVER_OUTPUT.element_names()[3:6]
_ETA, _OMEGA = HOVER_OUTPUT.element_names()[6:9], HOVER_OUTPUT.element_names()[9:12]

#: Sensor -> the hover loop's measured outputs it feeds (names of HOVER_OUTPUT).
SENSOR_OUTPUTS = MappingProxyType({
    "vision": _P,
    "gnss": _P + _V,
    "rangefinder": (_P[2],),
    "imu": _ETA + _OMEGA,
    "datalink": (),
})


def sensor_channels(scenario: Scenario) -> dict[str, tuple[tuple[str, ...], float]]:
    """Each sensor's outputs (:data:`SENSOR_OUTPUTS`) and its flown latency, s."""
    tables = scenario.data.get("sensors", {})
    return {name: (outputs, float(validate_settings(name, tables.get(name))["latency"]))
            for name, outputs in SENSOR_OUTPUTS.items()}
