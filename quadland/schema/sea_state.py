"""The WMO sea state codes a landing scenario's ``deck.sea_state`` names.

Data only: the code's band of significant wave height (WMO code 3700) and the
most probable significant wave height and peak period of Bales (1983), open
ocean, North Atlantic (docs/sea.md cites them). The schema checks a given
height against its band; the landing's values take the most probable ones
for a preset (:mod:`quadland.engine.sea` makes the waves).

References
----------
Bales, S. L. (1983). Designing ships to the natural environment. Naval
Engineers Journal 95(2), 31-40.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from types import MappingProxyType

__all__ = ["SeaState", "SEA_STATES"]


@dataclasses.dataclass(frozen=True)
class SeaState:
    """One row of the sea state table.

    Attributes
    ----------
    hs_band : tuple of float
        The WMO code's range of significant wave height, m.
    hs : float
        Most probable significant wave height, m.
    tp : float
        Most probable peak (modal) period, s.
    tp_range : tuple of float
        Bales' 5 to 95 percentile of the peak period, s (None for code 1).
    """

    hs_band: tuple[float, float]
    hs: float
    tp: float
    tp_range: tuple[float, float] | None


#: WMO sea state code -> :class:`SeaState`: Bales (1983), open ocean, North
#: Atlantic. Bales gives no period for codes 0-1; code 1's ``tp`` is that of a
#: fully developed Pierson-Moskowitz sea of its ``hs`` (``omega_p = 0.40
#: sqrt(g / Hs)``, docs/sea.md).
SEA_STATES: Mapping[int, SeaState] = MappingProxyType({
    1: SeaState((0.0, 0.1), 0.05, 1.1, None),
    2: SeaState((0.1, 0.5), 0.3, 7.5, (3.3, 12.8)),
    3: SeaState((0.5, 1.25), 0.88, 7.5, (5.0, 14.8)),
    4: SeaState((1.25, 2.5), 1.88, 8.8, (6.1, 15.2)),
    5: SeaState((2.5, 4.0), 3.25, 9.7, (8.3, 15.5)),
    6: SeaState((4.0, 6.0), 5.0, 12.4, (9.8, 16.2)),
})
