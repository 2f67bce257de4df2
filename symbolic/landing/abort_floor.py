"""The crawl's out-of-limits abort, and its floor: no abort is started once the gear is within
``abort_floor`` of the deck (:mod:`quadland_symbolic.landing.guidance`, docs/landing.md,
"ship_ss5: an abort the gear cannot fly").

In the committed crawl an offset past ``max_offset`` or a horizontal relative speed past
``max_relative_speed`` aborts the descent: the reference climbs back to the hover height. A
quadrotor whose gear is a few centimetres over the deck cannot climb away before it touches:
the crawl closes at 0.3-0.5 m/s, a leaning body meets the deck on its lowest foot (4.4 cm
below the level gear at 15 deg, along the gear's diagonal) and the climb needs the vertical
loop's response. Such an abort turns a contact into a touch and a climb away, which the judge
reads as a bounce off the pad. With ``abort_floor`` the abort is not started once the gear's
height above the deck, as the flight code knows it (the filter's relative height less the
height of the contact, :func:`~quadland_symbolic.landing.guidance.contact_height`), is at or
below it: the crawl goes on to the contact, which is judged on its own figures. The default,
-1000 m, never holds: the abort fires down to the contact. With ``crawl_pause`` on as well, an
offset or a speed past the limits is also out of the align band, so within the floor the
crawl does not go on but pauses, the reference held a few centimetres over the deck until
the estimate is back in the band (:func:`~quadland_symbolic.landing.crawl_gate.fall_band`);
no shipped scenario sets both, and that combination was not flown.

Branch-free CasADi, generated into C with the guidance step.
"""

from __future__ import annotations

import casadi as ca

__all__ = ["out_of_limits"]


def out_of_limits(offset, speed, gap, p, aborts=0):
    """1 (CasADi) when the crawl's abort is started: the horizontal ``offset`` (m) past
    ``max_offset`` or past ``crawl_abort_offset`` (1000, the default: no tighter bound than the
    judge's) while the descent's abort count ``aborts`` is below ``crawl_abort_budget`` (a
    retry budget: a run whose crawls drift past the tighter bound window after window falls
    back to ``max_offset`` instead of running out of time), or the horizontal relative
    ``speed`` (m/s) past ``max_relative_speed``, with the gear's estimated height above the
    deck ``gap`` (m) above ``abort_floor``. ``p`` the unpacked guidance parameters; the caller
    adds that the step is in the committed crawl."""
    tight = ca.if_else(aborts < p["crawl_abort_budget"], p["crawl_abort_offset"],
                       p["max_offset"])
    limit = ca.fmin(p["max_offset"], tight)
    past = ca.logic_or(offset > limit, speed > p["max_relative_speed"])
    return ca.logic_and(past, gap > p["abort_floor"])
