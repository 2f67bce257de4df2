"""Landed and secured: what the gear's contact says of a landing.

A landing on the gear's contact (``gear.welded = false``) is judged on its
rows after the first contact (docs/landing.md, "Landed and secured"; each
limit's source there):

* **tilted**: the tilt at the first contact, relative to the deck, past the
  gear's static tip-over angle in its direction (``tip_margin > 1`` there: the
  centre's projection along the deck normal outside the feet's rectangle; the
  angle is ``atan(tan(tilt_rel) / tip_margin)``, exact in every direction):
  the gear meets the deck with the centre of mass outside its support, which
  only the rotors can hold. ``landing.max_tilt_deg`` stays the old figure's
  limit; the tilt is judged against the smaller of the two;
* **peak gear load**: the plant's peak follower ``F_peak`` (every RK4
  substep), against ``landing.max_gear_load``; the impact energy
  ``m1 v_n^2 / 2`` of the sink rate at first contact is reported beside it;
* **bounced**: after the first contact, every foot off the deck with the
  lowest foot above ``landing.max_bounce`` (the gear's rebound, not the
  tilt's: a body that meets the deck tilted lifts its centre by the tilt);
* **tipped**: tipped over on the gear: at a row after the contact, a foot
  off the deck with the relative roll or pitch past the static tip-over
  angle (``tip_margin > 1``) while the rotors are cut (their thrust below
  :data:`CUT_THRUST` of the weight: nothing but the gear holds the body, so
  its centre of mass is outside the support polygon with no thrust); or the
  run stopped on the deck (its lowest foot within :func:`gear_span` of it) at
  the singular attitude or outside its envelope; a run that stops farther from
  the deck has flown off it (bounced), not tipped over on it.
  A body the rotors still fly past that angle (the flare onto a windy roof)
  has not tipped;
* **on the pad**: every foot within ``landing.pad_radius`` of the pad centre
  (deck frame, ``foot_offset``) from the first contact to ``settle_time``
  after it, the run reaching that instant;
* **secured**: at the last row (``settle_time`` after the first contact, the
  instant summary.json's ``phases.landed`` gives for a secured landing),
  resting on the deck (every foot down) with the friction margin (thrust, the
  drag of the airspeed through the wind at that row, the lock's pull) below
  ``landing.max_friction_margin``. The lock-down's pull acts along the deck
  normal, so it holds through friction alone: an engaged lock on a slippery
  deck the body slides on is not secured (issue 18's second review; before,
  the lock engaged at 95 % counted as secured on its own).
"""

from __future__ import annotations

import functools

import numpy as np

from quadland.engine.direct_call import DirectCall
from quadland.kinds.landing.gear import gear_span
from quadland_symbolic.landing.contact import N_FEET
from quadland_symbolic.landing.flat_deck import amplitude_indices, flat_function
from quadland_symbolic.landing.gear import CUT_THRUST, FAILURES, GEAR_SIGNALS, GEAR_STATE
from quadland_symbolic.landing.loop import landing_gear_signals_function
from quadland_symbolic.landing.plant import LANDING_PLANT_PARAMS, LANDING_PLANT_STATE

__all__ = ["MAP_BUCKET", "gear_columns", "flat_gear_signals", "contact_figures", "ENGAGED",
           "FAILURES", "CUT_THRUST"]

#: The lock counts as engaged at this engagement.
ENGAGED = 0.95


def gear_columns(pp, times, X, touched, W) -> dict[str, np.ndarray]:
    """The gear's signals at each row from the first contact on (:data:`GEAR_SIGNALS` by
    name, plus ``F_peak`` and ``t_contact`` of the plant's gear memory), from the rows'
    loop states ``X`` and held disturbances ``W`` (one row each, :data:`~quadland_symbolic.
    landing.plant.LANDING_DISTURBANCE`: the wind in the friction margin); NaN before the
    contact (``touched`` 0), where the gear is off."""
    names = (*GEAR_SIGNALS.names(), "F_peak", "t_contact")
    cols = {name: np.full(len(times), np.nan) for name in names}
    rows = np.flatnonzero(np.asarray(touched) > 0.5)
    if rows.size == 0:
        return cols
    xp = np.asarray(X, dtype=float)[rows, :LANDING_PLANT_STATE.size]
    w = np.asarray(W, dtype=float)[rows, :]
    pp = np.asarray(pp, dtype=float).ravel()
    flat = not np.any(pp[list(amplitude_indices(LANDING_PLANT_PARAMS))])
    t = np.asarray(times, dtype=float)[rows]
    n = -(-rows.size // MAP_BUCKET) * MAP_BUCKET     # a map of few sizes (each column its own)
    pad = n - rows.size
    xp, w, t = (np.concatenate([a, np.repeat(a[-1:], pad, axis=0)]) for a in (xp, w, t))
    s = _mapped(n, flat)(xp.T, w.T, t[None, :], pp)[0][:, :rows.size]
    xp = xp[:rows.size]
    for name in GEAR_SIGNALS.names():
        cols[name][rows] = s[GEAR_SIGNALS.slice(name)][0]
    xg = xp[:, LANDING_PLANT_STATE.slice("gear")].T
    cols["F_peak"][rows] = xg[GEAR_STATE.slice("F_peak")][0]
    cols["t_contact"][rows] = xg[GEAR_STATE.slice("t_contact")][0]
    return cols


#: Rows of the gear's mapped signals are evaluated in multiples of this (the last row
#: repeated): building a map costs about 1 ms, a landing's contact rows vary.
MAP_BUCKET = 32


@functools.lru_cache(maxsize=64)
def _mapped(n: int, flat: bool):
    """The gear's signals at ``n`` rows; ``flat``: on a deck whose sinusoids' amplitudes
    are all zero, without their sums (the same bits, ``tests/test_flat_deck.py``). The
    plant's parameters ``pp`` are one column for every row (``reduce_in``): CasADi
    tiled them to ``n`` columns on each call, a third of the call's time. Called on the
    rows' arrays in place (:class:`~quadland.engine.direct_call.DirectCall`: CasADi's
    conversions were two thirds of what remained)."""
    f = flat_gear_signals() if flat else landing_gear_signals_function()
    return DirectCall(f.map(n, [name == "pp" for name in f.name_in()], [False] * f.n_out()))


@functools.cache
def flat_gear_signals():
    """``landing_gear_signals`` on a flat deck
    (:func:`quadland_symbolic.landing.flat_deck.flat_function`)."""
    return flat_function(landing_gear_signals_function(),
                         {"pp": amplitude_indices(LANDING_PLANT_PARAMS)})


def contact_figures(result, limits: dict, mass: float) -> dict:
    """The landed-and-secured figures of a landing on the gear (module docstring).

    Returns a dict: ``peak_gear_force`` (N), ``impact_energy`` (J), ``bounce`` (m, the
    lowest foot's highest rebound with every foot off the deck), ``tip_over_deg`` (the
    gear's static tip-over angle in the direction of the tilt at the contact, deg),
    ``bounced``, ``tipped``, ``on_pad``, ``settled`` (the run reached ``settle_time``
    after the contact), ``lock`` (the last engagement), ``friction_margin`` (last),
    ``secured``, ``failures`` (the reasons, from :data:`FAILURES`).
    """
    t, touched = result["t"], result["touched"] > 0.5
    k0 = int(np.argmax(touched))
    after = np.flatnonzero(touched)
    airborne = touched & (result["feet_down"] < 0.5)
    bounce = float(np.max(result["foot_gap"][airborne], initial=0.0))
    last = int(after[-1])
    d = result.scenario.data
    settle, row = d["landing"]["settle_time"], 1.0 / d["simulation"]["output_rate_hz"]
    end = min(t[k0] + settle, d["simulation"]["duration"])
    settled = bool(t[last] >= t[k0] + settle - row - 1e-9)
    stopped = bool(t[last] < end - row - 1e-9)       # stopped on the deck: tipped over
    stopped = stopped and bool(result["foot_gap"][last] <= gear_span(d))
    cut = result["F_total"][after] < CUT_THRUST * mass * d["quadrotor"]["gravity"]
    lifted = result["feet_down"][after] < N_FEET - 0.5
    tipped = bool(np.any((result["tip_margin"][after] > 1) & lifted & cut) or stopped)
    tip0 = float(result["tip_margin"][k0])
    tip_over = (float(np.degrees(np.arctan(np.tan(result["tilt_rel"][k0]) / tip0)))
                if tip0 > 0 else 90.0)
    lock = float(result["engaged"][last])
    margin = float(result["friction_margin"][last])
    resting = bool(result["feet_down"][last] >= N_FEET - 0.5)
    secured = bool(settled and resting and margin < limits["max_friction_margin"])
    peak = float(np.max(result["F_peak"][after]))
    v_n = float(result["foot_sink_rate"][k0])
    fig = {"peak_gear_force": peak, "impact_energy": 0.5 * mass * v_n ** 2,
           "bounce": bounce, "tip_over_deg": tip_over, "bounced": bounce > limits["max_bounce"],
           "tipped": tipped,
           "on_pad": bool(settled and np.all(result["foot_offset"][after]
                                             <= limits["pad_radius"])),
           "settled": settled, "lock": lock, "friction_margin": margin, "secured": secured}
    fig["failures"] = [name for name, bad in zip(FAILURES, (
        tip0 > 1, fig["bounced"], tipped, peak > limits["max_gear_load"], not fig["on_pad"],
        not secured), strict=True) if bad]
    return fig
