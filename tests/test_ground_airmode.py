"""The level-out without air mode (``touchdown.ground_airmode = false``; docs/landing.md,
"highway_100: the level-out without air mode").

With air mode (the default, as before) the rotors' collective rises to the band's lower end
``4 max(-m_i)`` whenever a moment would need a rotor below 0, so the attitude loop buys its
moments with thrust. On the roof that thrust unloads the feet the drag is sliding. With the
key false the touchdown policy tells the landing step, from the touchdown verdict on, not to
raise the collective: the rotor that would go below 0 is clipped there and the moment gives
way (PX4's mixer with ``MC_AIRMODE`` disabled never raises the thrust to unsaturate a rotor
either, but scales roll and pitch back instead of clipping: the clip here adds the clipped
rotor's deficit to the thrust made, and a yaw).
Checked here: the policy's flag by phase, the thrust rule against the rotor forces ``T / 4 +
m_i`` by hand, the landing step unchanged where the moments leave every rotor room, the key's
default on every shipped scenario, and seed 11's run 42 of highway_100 replayed both ways.
"""

import casadi as ca
import numpy as np
import pytest
from reference import GUIDANCE_P, HANDOVER_COLD, HIGHWAY_100_CREEP

import quadland
from quadland.campaign.sampling import draws
from quadland.campaign.spec import campaign_spec_of
from quadland.kinds.landing.gear import touchdown_guidance
from quadland.kinds.landing.report import touchdown_report
from quadland.scenario import load_scenario
from quadland_symbolic.landing.desaturation import clip_forces, thrust_within_moments
from quadland_symbolic.landing.touchdown_policy import (
    INERT_COMMANDS,
    TOUCHDOWN_COMMANDS,
    touchdown_commands,
)
from quadland_symbolic.parameters import QUADROTOR
from quadland_symbolic.quadrotor import rotors_from_wrench, wrench_from_rotors

#: A quadrotor for the mixer: 0.25 m arms, the rotor drag factor 0.05 m.
Q = dict(m1=2.0, I=[0.025, 0.025, 0.045], Kt=[0.3] * 3, Kr=[0.001] * 3, g=9.8, arm=0.25,
         c=0.05)
F_MAX = 14.7


def _airmode(down, descending, ground_airmode, fly_on=1.0):
    p = dict(GUIDANCE_P, fly_on=fly_on, ground_airmode=ground_airmode, hold_time=0.0,
             level_time=0.6, cut_time=0.6)
    out = np.asarray(touchdown_commands(float(down), float(descending), 0.1, 0.3, p)).ravel()
    return TOUCHDOWN_COMMANDS.unpack(out)["airmode"][0]


def test_the_policy_turns_air_mode_off_from_the_touchdown_only_with_the_key():
    """Off (0) only on the deck (touchdown or landed), with the policy flying on and the key
    false; in the descent, with the key true, or with the policy inert it stays on (1)."""
    assert _airmode(down=1, descending=0, ground_airmode=0.0) == 0.0
    assert _airmode(down=0, descending=1, ground_airmode=0.0) == 1.0
    assert _airmode(down=1, descending=0, ground_airmode=1.0) == 1.0
    assert _airmode(down=1, descending=0, ground_airmode=0.0, fly_on=0.0) == 1.0
    assert INERT_COMMANDS["airmode"] == 1.0


def _thrust(T, M, airmode):
    p_quad = QUADROTOR.pack(Q)
    return float(thrust_within_moments(T, ca.DM(M), p_quad, F_MAX, airmode))


def _shares(M):
    """Each rotor's share of the moments ``M`` alone (the mixer with no collective)."""
    return np.asarray(rotors_from_wrench(ca.vertcat(0, ca.DM(M)), QUADROTOR.pack(Q))).ravel()


@pytest.mark.parametrize("M", [[0.0, -1.2, 0.0], [0.4, 0.9, 0.02], [-1.0, 0.0, -0.05]])
def test_air_mode_raises_the_collective_for_the_moments_and_without_it_the_rotor_clips(M):
    """A collective of 4 N under moments whose shares ``m_i`` reach below ``-1 N``: in air
    mode the thrust rises until the lowest rotor, ``T / 4 + min m_i``, is exactly 0; without
    it the thrust stays at 4 N and that rotor's ``T / 4 + m_i`` is below 0 (the mixer's clip
    takes it to 0, and the moment gives way). Near the top both come down to the band's upper
    end ``4 (F_max - max m_i)``, where the highest rotor makes exactly ``F_max``."""
    m = _shares(M)
    assert 4.0 / 4 + m.min() < 0                       # the moments need a rotor below 0
    raised = _thrust(4.0, M, 1.0)
    assert raised / 4 + m.min() == pytest.approx(0.0, abs=1e-12)
    assert _thrust(4.0, M, 0.0) == 4.0
    assert _thrust(4.0, M, 1) == raised                # the Python default's expression
    top = 4 * F_MAX + 1.0
    for airmode in (0.0, 1.0):
        assert _thrust(top, M, airmode) / 4 + m.max() == pytest.approx(F_MAX, abs=1e-12)
    assert _thrust(-1.0, M, 0.0) == 0.0                 # never below 0


def _delivered(T, M, airmode):
    """The landing step's rotors (its thrust rule, the mixer, the clip to ``[0, F_max]``) and
    the wrench they make."""
    p_quad = QUADROTOR.pack(Q)
    T = thrust_within_moments(T, ca.DM(M), p_quad, F_MAX, airmode)
    F = clip_forces(rotors_from_wrench(ca.vertcat(T, ca.DM(M)), p_quad), 0, F_MAX)
    return (np.asarray(F).ravel(), np.asarray(wrench_from_rotors(F, p_quad)).ravel())


def test_without_air_mode_the_clip_gives_up_pitch_and_adds_some_thrust_and_yaw():
    """By hand, arm ``d`` 0.25 m, drag factor ``c`` 0.05 m, ``T`` 4 N, ``My`` -1.2 N m: the
    shares ``-My / 2d = 2.4`` (rotor 1) and ``My / 2d = -2.4`` N (rotor 3). In air mode ``T``
    rises to ``4 * 2.4 = 9.6`` N: rotors 4.8, 2.4, 0, 2.4 N, the pitch made whole. Without it
    rotor 3's ``1 - 2.4 = -1.4`` N clips to 0: rotors 3.4, 1, 0, 1 N, so the thrust made is
    5.4 N (the clipped 1.4 N added to the 4 N asked for, less than air mode's 9.6), the
    pitch ``d (F3 - F1) = -0.85`` N m of the -1.2 asked for, and a yaw ``c (F1 - F2 + F3 -
    F4) = 0.07`` N m nobody asked for. (PX4's mixer with ``MC_AIRMODE`` disabled would
    instead scale the pitch back to -0.5 N m, rotor 3 at 0, the thrust held at 4 N and no
    yaw: docs/landing.md, "highway_100: the level-out without air mode".)"""
    F, w = _delivered(4.0, [0.0, -1.2, 0.0], 1.0)
    np.testing.assert_allclose(F, [4.8, 2.4, 0.0, 2.4], rtol=0, atol=1e-12)
    np.testing.assert_allclose(w, [9.6, 0.0, -1.2, 0.0], rtol=0, atol=1e-12)
    F, w = _delivered(4.0, [0.0, -1.2, 0.0], 0.0)
    np.testing.assert_allclose(F, [3.4, 1.0, 0.0, 1.0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(w, [5.4, 0.0, -0.85, 0.07], rtol=0, atol=1e-12)


def test_where_the_moments_leave_every_rotor_room_the_flag_changes_nothing():
    """Shares within ``[-T / 4, F_max - T / 4]``: the thrust asked for is made either way,
    to the bit."""
    M = [0.05, -0.08, 0.01]
    m = _shares(M)
    assert 20.0 / 4 + m.min() > 0 and 20.0 / 4 + m.max() < F_MAX
    assert _thrust(20.0, M, 0.0) == _thrust(20.0, M, 1.0) == 20.0


def test_every_shipped_scenario_keeps_air_mode_on_the_deck():
    """The key is optional and true by default: no shipped landing scenario sets it, and the
    guidance packs 1 for them; false packs 0."""
    for name in ("highway", "turning", "ship", "ship_ss5", "highway_100"):
        assert touchdown_guidance(load_scenario(name))["ground_airmode"] == 1.0
    sc = load_scenario("highway_100", ["touchdown.ground_airmode=false"])
    assert touchdown_guidance(sc)["ground_airmode"] == 0.0


def test_seed_11_run_42_stays_on_the_pad_without_air_mode():
    """highway_100's seed 11 run 42 (sensors on) meets the roof 0.01 m ahead of the pad's
    centre at 44 deg, within every limit. In air mode the attitude loop, fighting the body's
    fall onto its rear feet, raises the collective past the body's weight between 0.1 s
    after the contact (the level-out's ramp under way) and the last foot down, and the drag
    slides the body off the pad. Without it the collective stays below the weight over the
    same interval and the run lands on the pad and is secured. Flown at the friction's cap it
    was measured with (``HIGHWAY_100_CREEP``): at the shipped 3000 the smaller creep keeps it
    on the pad in air mode too (docs/landing.md, "highway_100 on fresh seeds: the creep under
    the magnets")."""
    sc = load_scenario("highway_100", {"campaign.seed": 11})
    overrides = draws(campaign_spec_of(sc), [42])[0].overrides() + HANDOVER_COLD

    weight = load_scenario("highway_100", overrides).data["quadrotor"]["mass"] * 9.8

    def flown(*extra):
        res = quadland.simulate(load_scenario("highway_100",
                                              [*overrides, *HIGHWAY_100_CREEP, *extra]))
        t = res["t"]
        k0 = int(np.argmax(res["touched"] > 0.5))
        k4 = k0 + int(np.argmax(res["feet_down"][k0:] > 3.5))     # every foot down
        window = (t >= t[k0] + 0.1) & (t < t[k4])
        return touchdown_report(res), float(np.max(res["F_total"][window]))

    before, f_before = flown()
    assert before.touchdown and not before.on_pad and before.failures == ["off the pad"]
    after, f_after = flown("touchdown.ground_airmode=false")
    assert after.success and after.secured and after.on_pad
    assert after.time == before.time                    # the same contact
    assert f_before > weight > f_after


def test_the_flight_code_flies_the_key_false_as_the_casadi_functions():
    """highway on the true state with the key false: ``controller.backend = "c"`` (the
    guidance's parameter, the policy's flag and the thrust rule in the generated C) flies the
    CasADi functions' landing, every state to 1e-9 (as tests/test_landing_flight_code.py
    does for the defaults); and the key acts: the run is the default's to the bit until the
    touchdown verdict and departs from it after."""
    off = ["sensors.enabled=false", "touchdown.ground_airmode=false"]
    a = quadland.simulate(load_scenario("highway", off))
    b = quadland.simulate(load_scenario("highway", [*off, 'controller.backend="c"']))
    assert a.states.shape == b.states.shape
    assert np.max(np.abs(a.states - b.states)) <= 1e-9
    assert touchdown_report(a) == touchdown_report(b)
    d = quadland.simulate(load_scenario("highway", ["sensors.enabled=false"]))
    k0 = int(np.argmax(d["touched"] > 0.5))
    assert k0 > 0 and a.states.shape == d.states.shape
    np.testing.assert_array_equal(a.states[:k0].view(np.uint64), d.states[:k0].view(np.uint64))
    assert np.max(np.abs(a.states[k0:] - d.states[k0:])) > 1e-3
