"""The replay and the hand integral the graze tests share (issue 19, docs/landing.md,
"highway_100: the graze the switch did not feel" and "highway: the graze switch"): a
campaign row flown again at 1 kHz, and the gear's logged load impulse over a first contact."""

import numpy as np
import pytest
from reference import HANDOVER_COLD

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
    overrides = [*overrides, *HANDOVER_COLD]
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


def assert_graze_open(before):
    """The graze flown with the old 2 ms switch: its logged load stays under a tenth of the
    weight, its impulse lies between the shipped threshold (0.5 ms of the weight) and the old
    one (2 ms), and through it the switch stays open and the phase the descent. Returns the
    graze's rows ``(k0, k1)``."""
    k0, k1, impulse = graze(before)
    weight = before.scenario.data["quadrotor"]["mass"] * G
    assert np.nanmax(before["F_gear"][k0:k1 + 1]) < 0.1 * weight
    assert 0.5e-3 < impulse[-1] < 2e-3
    assert np.all(before["t_contact"][k0:k1 + 1] == 0.0)
    assert np.all(before["phase"][k0:k1 + 1] == 2)
    return k0, k1


def assert_graze_closes(res, rep, rep_before):
    """The graze flown with the 0.5 ms switch: its logged impulse passes 0.5 ms of the weight
    (the lower bound of the switch's own integral, :func:`graze`), the switch closes within
    the graze no later than that, the guidance is in touchdown three rows on, the run lands
    and is secured, and the contact the judge scores is ``rep_before``'s (the same figures to
    1 mm)."""
    k0, k1, impulse = graze(res)
    passed = k0 + int(np.argmax(impulse > 0.5e-3))
    closed = int(np.argmax(res["t_contact"] > 0))
    assert impulse[-1] > 0.5e-3 and k0 <= closed <= passed <= k1
    assert res["phase"][closed + 3] == 3
    assert rep.success and rep.secured and not rep.bounced
    assert rep.time == pytest.approx(rep_before.time, abs=1e-3)
    assert rep.offset == pytest.approx(rep_before.offset, abs=1e-3)
