"""The replay and the hand integral the graze tests share (issue 19, docs/landing.md,
"highway_100: the graze the switch did not feel" and "highway: the graze switch"): a
campaign row flown again at 1 kHz, and the gear's logged load impulse over a first contact."""

import numpy as np

import quadland
from quadland.campaign.sampling import draws
from quadland.campaign.spec import campaign_spec_of
from quadland.kinds.landing.report import touchdown_report
from quadland.scenario import load_scenario

G = 9.8
FINE = "simulation.output_rate_hz=1000.0"   # a row per ms: a graze lasts ~25 ms


def flown(scenario, index, *extra):
    """Row ``index`` of ``scenario``'s campaign (its own campaign seed) flown at 1 kHz with
    ``extra`` overrides on top of the row's draws: the result and its touchdown report."""
    overrides = draws(campaign_spec_of(load_scenario(scenario)), [index])[0].overrides()
    res = quadland.simulate(load_scenario(scenario, [*overrides, FINE, *extra]))
    return res, touchdown_report(res)


def graze(res):
    """The rows of the first contact up to the first row with every foot off the roof, and
    the gear's load impulse over the weight logged over them, s (trapezoid rule). It leaves
    out the load inside the contact's onset smoothing before the located contact, so it is a
    lower bound of the switch's own integral."""
    t, F = res["t"], np.nan_to_num(res["F_gear"])
    k0 = int(np.argmax(res["touched"] > 0.5))
    off = np.flatnonzero((np.arange(len(t)) > k0) & (res["feet_down"] < 0.5))
    k1 = int(off[0]) if off.size else len(t) - 1
    weight = res.scenario.data["quadrotor"]["mass"] * G
    rows = slice(k0, k1 + 1)
    impulse = np.concatenate([[0.0], np.cumsum(0.5 * (F[rows][1:] + F[rows][:-1])
                                               * np.diff(t[rows]))]) / weight
    return k0, k1, impulse
