"""The sea state's keys of a landing scenario's ``[deck]`` and their check (docs/sea.md).

The waves' spectrum and the vessel's response; :data:`~quadland.schema.sea_state.SEA_STATES`
gives each WMO code's band of significant wave height, which :func:`check_sea` holds a
given height to.
"""

from __future__ import annotations

from quadland.exceptions import ScenarioError
from quadland.schema.fields import Field
from quadland.schema.sea_state import SEA_STATES

__all__ = ["sea_fields", "check_sea"]

_POS = dict(lo=0.0, lo_open=True)


def sea_fields() -> dict[str, Field]:
    """The sea state's keys of [deck] (docs/sea.md): the waves and the vessel's response."""
    return {
        "sea_state": Field(int, "-", "WMO sea state code: 1 to 6 add that sea's wave components "
                           "to the sinusoids; 0: the sinusoids alone", lo=0, hi=max(SEA_STATES)),
        "significant_wave_height": Field(float, "m", "Hs (0: the sea state's most probable); "
                                         "within the sea state's WMO band", lo=0.0, hi=20.0),
        "peak_period": Field(float, "s", "Tp, the spectrum's peak period (0: the sea state's most "
                             "probable)", lo=1.0, hi=30.0, zero_ok=True),
        "peak_enhancement": Field(float, "-", "JONSWAP's gamma: 1 is Pierson-Moskowitz, 3.3 "
                                  "JONSWAP's mean", lo=1.0, hi=10.0),
        "wave_heading_deg": Field(float, "deg", "the waves' direction of travel from the bow "
                                  "toward port: 180 head seas, 0 following, 90 from starboard",
                                  lo=-360.0, hi=360.0),
        "vessel_length": Field(float, "m", "waterline length: the hull averages the waves over it",
                               hi=1e3, **_POS),
        "vessel_beam": Field(float, "m", "waterline breadth", hi=1e3, **_POS),
        "roll_period": Field(float, "s", "natural roll period", hi=100.0, **_POS),
        "roll_damping": Field(float, "-", "roll damping ratio (linearized)", hi=2.0, **_POS),
    }


def check_sea(deck: dict) -> None:
    """A significant wave height given lies in its sea state's WMO band."""
    hs, code = deck["significant_wave_height"], deck["sea_state"]
    if code == 0 or hs == 0:
        return
    lo, hi = SEA_STATES[code].hs_band
    if not lo <= hs <= hi:
        raise ScenarioError(f"deck.significant_wave_height: {hs:g} m is outside sea state "
                            f"{code}'s band, {lo:g} to {hi:g} m (WMO; 0 takes its most probable "
                            f"{SEA_STATES[code].hs:g} m)")
