"""The flare's tilt cone also about the deck's normal: ``[touchdown] flare_axis`` (issue
19; docs/landing.md, "The ships' handover above the deck, and the flare about the deck's
normal").

The flare limits the thrust axis's tilt to ``flare_tilt_deg`` so that the gear meets the
deck inside the contact's tilt limit; that limit is judged from the deck's normal, the
flare's cone (``"vertical"``, the default) is about E's z. ``"both"`` also holds the axis
within the same angle of the deck's normal. Checked here: the default leaves the thrust's
attitude as before, bit for bit; the two cones over a rolled deck against the geometry by
hand; the command only in the flare of a flying-on policy.
"""

import math

import casadi as ca
import numpy as np
import pytest
from reference import GUIDANCE_P

from quadland.kinds.landing.gear import touchdown_guidance
from quadland.scenario import load_scenario, scenario_names
from quadland_symbolic.landing.attitude import thrust_attitude
from quadland_symbolic.landing.guidance import GUIDANCE_PARAMS
from quadland_symbolic.landing.touchdown_policy import (
    INERT_COMMANDS,
    TOUCHDOWN_COMMANDS,
    touchdown_commands,
)


def test_the_default_cone_is_about_the_vertical():
    """No shipped scenario sets the key: each takes ``"vertical"``, the guidance's 0; the
    inert commands carry 0."""
    for name in scenario_names():
        sc = load_scenario(name)
        if sc.model != "landing":
            continue
        assert sc["touchdown.flare_axis"] == "vertical"
        assert touchdown_guidance(sc)["flare_axis"] == 0.0
    assert INERT_COMMANDS["tilt_axis"] == 0.0
    assert touchdown_guidance(load_scenario(
        "ship_ss5", ["touchdown.flare_axis=\"both\""]))["flare_axis"] == 1.0


def _thrust_attitude(t_E, tilt, deck=None):
    """``thrust_attitude`` at yaw 0.3 rad, ``T_max`` 40 N, numerically; ``deck`` ``(on,
    R_deck)`` or None."""
    t, psi, lim, T_max = ca.SX.sym("t", 3), ca.SX.sym("psi"), ca.SX.sym("lim"), ca.SX.sym("T")
    on, R = ca.SX.sym("on"), ca.SX.sym("R", 3, 3)
    out = thrust_attitude(t, psi, lim, T_max, None if deck is None else (on, R))
    names = ["T", "b3", "phi", "theta", "tilt_limited"]
    f = ca.Function("f", [t, psi, lim, T_max, on, R], [out[n] for n in names])
    on_v, R_v = (0.0, np.eye(3)) if deck is None else deck
    res = f(t_E, 0.3, tilt, 40.0, on_v, R_v)
    return {n: np.asarray(v, dtype=float).ravel() for n, v in zip(names, res, strict=True)}


def _rolled(deg):
    """``R_deck`` of a deck rolled ``deg`` about x (its normal ``(0, -sin, cos)``)."""
    d = math.radians(deg)
    return np.array([[1, 0, 0], [0, math.cos(d), -math.sin(d)], [0, math.sin(d), math.cos(d)]])


@pytest.mark.parametrize("t_E", [[1.0, -2.0, 19.0], [6.0, 3.0, 15.0], [-0.0, 0.0, 20.0],
                                 [8.0, -7.5, 12.0], [0.0, 4.5, 18.0]])
def test_off_the_decks_cone_is_the_vertical_to_the_bit(t_E):
    """With the deck's cone off (``on`` 0, what the default passes at run time) over a deck
    rolled 5 deg, the thrust, axis and angles are those of the vertical cone alone, bit for
    bit, limited or not (15 deg)."""
    a = _thrust_attitude(t_E, math.radians(15.0))
    b = _thrust_attitude(t_E, math.radians(15.0), (0.0, _rolled(5.0)))
    for n in a:
        assert np.array_equal(a[n], b[n]), n


def test_the_decks_cone_by_hand():
    """A deck rolled 5 deg about x, its normal ``n2 = (0, -sin 5, cos 5)``; 15 deg cones.
    A demand 14 deg from E's z towards +y is 19 deg from ``n2``: the vertical cone passes it,
    the deck's clips it to 15 deg from ``n2`` in the same plane, ``b3 = (0, sin 10, cos
    10)`` (by hand), the thrust ``t_z / cos 10`` (vertical priority): the contact's tilt
    failures over a rolled deck (docs/landing.md). A demand 30 deg towards -y is clipped by
    the vertical cone to ``(0, -sin 15, cos 15)``, 10 deg from ``n2``: the deck's cone
    leaves it, to the bit. A demand within both passes as it is."""
    on = (1.0, _rolled(5.0))
    n2 = _rolled(5.0)[:, 2]
    e = math.radians(14.0)
    t_away = 18.0 * np.array([0.0, math.sin(e), math.cos(e)])
    vertical = _thrust_attitude(t_away, math.radians(15.0))
    assert vertical["tilt_limited"][0] == 0.0
    assert math.degrees(math.acos(vertical["b3"] @ n2)) == pytest.approx(19.0, abs=1e-9)
    away = _thrust_attitude(t_away, math.radians(15.0), on)
    f = math.radians(10.0)
    assert away["b3"] == pytest.approx([0.0, math.sin(f), math.cos(f)], abs=1e-12)
    assert away["T"][0] == pytest.approx(t_away[2] / math.cos(f), rel=1e-12)
    assert away["tilt_limited"][0] == 1.0
    a = math.radians(30.0)
    t_into = 18.0 * np.array([0.0, -math.sin(a), math.cos(a)])
    into, into_v = (_thrust_attitude(t_into, math.radians(15.0), d) for d in (on, None))
    g = math.radians(15.0)
    assert into["b3"] == pytest.approx([0.0, -math.sin(g), math.cos(g)], abs=1e-12)
    for n in into:
        assert np.array_equal(into[n], into_v[n]), n
    t_in = 18.0 * np.array([0.0, 0.1, 1.0])
    inside, inside_v = (_thrust_attitude(t_in, math.radians(15.0), d) for d in (on, None))
    assert inside["tilt_limited"][0] == 0.0
    for n in inside:
        assert np.array_equal(inside[n], inside_v[n]), n


@pytest.mark.parametrize(("fly_on", "axis", "descending", "z_next", "expected"), [
    (1.0, 1.0, 1.0, 0.2 + 0.1, 1.0),      # in the flare (0.15 m), about the deck
    (1.0, 1.0, 1.0, 0.2 + 0.5, 0.0),      # above it
    (1.0, 0.0, 1.0, 0.2 + 0.1, 0.0),      # the default
    (0.0, 1.0, 1.0, 0.2 + 0.1, 0.0),      # no flying on: inert
])
def test_the_command_is_the_flares(fly_on, axis, descending, z_next, expected):
    """``tilt_axis`` is ``flare_axis`` where the flare's limit holds (a flying-on policy,
    the reference within ``flare_height``), else 0."""
    p = GUIDANCE_PARAMS.unpack(GUIDANCE_PARAMS.pack(dict(GUIDANCE_P, fly_on=fly_on,
                                                         flare_axis=axis)))
    cmd = TOUCHDOWN_COMMANDS.unpack(ca.evalf(touchdown_commands(0.0, descending, 0.0, z_next,
                                                                p)))
    assert float(cmd["tilt_axis"][0]) == expected
    assert float(cmd["tilt_limit"][0]) == pytest.approx(0.6 if expected or (
        fly_on and z_next < 0.4) else math.pi / 2)
