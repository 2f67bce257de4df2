"""The flare's tilt cone about the deck's normal: ``[touchdown] flare_axis`` (issue 19;
docs/landing.md, "The ships' handover above the deck, and the flare about the deck's
normal").

The flare limits the thrust axis's tilt to ``flare_tilt_deg`` so that the gear meets the
deck inside the contact's tilt limit; that limit is judged from the deck's normal, the
flare's cone (``"vertical"``, the default) is about E's z. ``"deck"`` puts the cone about
the deck's normal. Checked here: the default leaves the commands and the thrust's
attitude as before (the identity's axes give the same bits as none); the cone about a
rolled deck's normal against the geometry by hand; the command only in the flare of a
flying-on policy.
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
        "ship_ss5", ["touchdown.flare_axis=\"deck\""]))["flare_axis"] == 1.0


def _thrust_attitude(t_E, tilt, axes=None):
    """``thrust_attitude`` at yaw 0.3 rad, ``T_max`` 40 N, numerically."""
    t, psi, lim, T_max = ca.SX.sym("t", 3), ca.SX.sym("psi"), ca.SX.sym("lim"), ca.SX.sym("T")
    A = ca.SX.sym("A", 3, 3)
    out = thrust_attitude(t, psi, lim, T_max, None if axes is None else A)
    names = ["T", "b3", "phi", "theta", "tilt_limited"]
    f = ca.Function("f", [t, psi, lim, T_max, A], [out[n] for n in names])
    res = f(t_E, 0.3, tilt, 40.0, np.eye(3) if axes is None else axes)
    return {n: np.asarray(v, dtype=float).ravel() for n, v in zip(names, res, strict=True)}


@pytest.mark.parametrize("t_E", [[1.0, -2.0, 19.0], [6.0, 3.0, 15.0], [-0.0, 0.0, 20.0],
                                 [8.0, -7.5, 12.0]])
def test_the_identity_axes_are_the_vertical_to_the_bit(t_E):
    """Axes of the identity (what the default passes at run time) give the same thrust,
    axis and angles as no axes, bit for bit, limited or not (15 deg)."""
    a, b = _thrust_attitude(t_E, math.radians(15.0)), _thrust_attitude(
        t_E, math.radians(15.0), np.eye(3))
    for n in a:
        assert np.array_equal(a[n], b[n]), n


def test_the_cone_about_a_rolled_decks_normal_by_hand():
    """A deck rolled 5 deg about x (normal ``n2 = (0, -sin 5, cos 5)``) and a thrust demand
    25 deg from it towards -y: about the normal the 15 deg cone clips it to 15 deg from
    ``n2`` in the same plane, ``b3 = (0, -sin 20, cos 20)`` (by hand), the thrust ``t_z /
    cos 20`` (vertical priority); about the vertical it is 25 + 5 = 30 deg from it and
    clips to 15 deg from E's z, 10 deg from the deck's normal. A demand 14 deg from E's z
    the other way (+y), 19 deg from the normal, passes the vertical cone and is clipped to
    15 deg from the normal, 10 deg from E's z: the contact's tilt failures on a rolled
    deck (docs/landing.md)."""
    d = math.radians(5.0)
    R_deck = np.array([[1, 0, 0], [0, math.cos(d), -math.sin(d)], [0, math.sin(d), math.cos(d)]])
    a = math.radians(30.0)                         # 25 deg from n2 + the deck's 5
    t_E = 18.0 * np.array([0.0, -math.sin(a), math.cos(a)])
    deck = _thrust_attitude(t_E, math.radians(15.0), R_deck)
    b = math.radians(20.0)
    assert deck["b3"] == pytest.approx([0.0, -math.sin(b), math.cos(b)], abs=1e-12)
    assert deck["T"][0] == pytest.approx(t_E[2] / math.cos(b), rel=1e-12)
    assert deck["tilt_limited"][0] == 1.0
    n2 = R_deck[:, 2]
    assert math.degrees(math.acos(deck["b3"] @ n2)) == pytest.approx(15.0, abs=1e-9)
    vertical = _thrust_attitude(t_E, math.radians(15.0))
    assert math.degrees(math.acos(vertical["b3"][2])) == pytest.approx(15.0, abs=1e-9)
    assert math.degrees(math.acos(vertical["b3"] @ n2)) == pytest.approx(10.0, abs=1e-9)
    e = math.radians(14.0)
    t_away = 18.0 * np.array([0.0, math.sin(e), math.cos(e)])
    assert _thrust_attitude(t_away, math.radians(15.0))["tilt_limited"][0] == 0.0
    away = _thrust_attitude(t_away, math.radians(15.0), R_deck)
    f = math.radians(10.0)
    assert away["b3"] == pytest.approx([0.0, math.sin(f), math.cos(f)], abs=1e-12)
    # inside the cone about the normal (10 deg from it): as demanded
    t_in = 18.0 * np.array([0.0, -math.sin(math.radians(15.0)), math.cos(math.radians(15.0))])
    inside = _thrust_attitude(t_in, math.radians(15.0), R_deck)
    assert inside["tilt_limited"][0] == 0.0
    assert inside["b3"] == pytest.approx(t_in / np.linalg.norm(t_in), abs=1e-12)


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
