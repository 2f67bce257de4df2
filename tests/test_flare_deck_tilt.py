"""The flare's second cone, about the deck's normal (``touchdown.flare_deck_tilt_deg``;
docs/landing.md, "The ships' tilt at the contact: the flare held about the deck's normal too").

The contact's tilt is judged from the deck's normal (17.9 deg on the ships); the flare holds
the thrust axis within ``flare_tilt_deg`` of the vertical. A body leaning into the airflow
over a deck rolled or pitched the other way meets it tilted by the sum. With the key below
90 deg the landing step also holds the thrust axis within it of the deck's normal, from the
flare on, after the vertical's cone. Checked here: the clipped axis against the angles worked
by hand, the axis unchanged to the bit within the cone and at the default, the clip staying
in the vertical's cone, the policy's command by phase, the key's default on every shipped
scenario, and seed 11's run 293 of ``ship_ss5`` replayed both ways.
"""

import ctypes

import casadi as ca
import numpy as np
import pytest
from reference import GUIDANCE_P, HANDOVER_COLD, have_compiler
from test_landing_flight_code import STATUS, Harness, L, _measurement

import quadland
from quadland.campaign.sampling import draws
from quadland.campaign.spec import campaign_spec_of
from quadland.kinds.landing.gear import touchdown_guidance
from quadland.kinds.landing.report import touchdown_report
from quadland.scenario import load_scenario
from quadland_symbolic.codegen.structs import landing_output_layout
from quadland_symbolic.kinematics import rotation
from quadland_symbolic.landing.attitude import thrust_attitude
from quadland_symbolic.landing.controller import (
    LANDING_MEASUREMENT,
    landing_guidance_function,
    landing_memory,
    landing_step_function,
    landing_step_outputs,
)
from quadland_symbolic.landing.guidance import (
    DESCEND,
    GUIDANCE_PARAMS,
    GUIDANCE_STATE,
    POSITION_REFERENCE,
    TOUCHDOWN,
)
from quadland_symbolic.landing.touchdown_policy import (
    INERT_COMMANDS,
    NO_TILT_LIMIT,
    TOUCHDOWN_COMMANDS,
    bounded_commands,
    touchdown_commands,
)

DEG = np.pi / 180


def _b3(t_E, tilt_max, deck=None):
    out = thrust_attitude(ca.DM(t_E), 0.0, tilt_max, 100.0,
                          None if deck is None else (deck[0], ca.DM(deck[1])))
    return np.asarray(ca.evalf(out["b3"])).ravel(), float(ca.evalf(out["tilt_limited"]))


def _roll(phi):
    return np.asarray(rotation(ca.DM([phi, 0.0, 0.0]))).reshape(3, 3)


def test_a_lean_against_a_rolled_deck_is_cut_back_to_the_deck_cone_by_hand():
    """A thrust vector 14 deg from the vertical toward +y (``phi = -14`` deg about x) over a
    deck rolled +5 deg (its normal 5 deg toward -y): 19 deg apart. With the deck's cone at
    16 deg the axis lies on it in the same plane, 16 - 5 = 11 deg from the vertical toward
    +y: ``(0, sin 11, cos 11)``; the vertical's 15 deg cone alone leaves it at 14 deg."""
    t = 20.0 * np.array([0.0, np.sin(14 * DEG), np.cos(14 * DEG)])
    alone, limited = _b3(t, 15 * DEG)
    np.testing.assert_allclose(alone, t / 20.0, rtol=0, atol=1e-15)
    assert limited == 0.0
    R = _roll(5 * DEG)
    np.testing.assert_allclose(R[:, 2], [0.0, -np.sin(5 * DEG), np.cos(5 * DEG)], atol=1e-15)
    b3, limited = _b3(t, 15 * DEG, (16 * DEG, R))
    np.testing.assert_allclose(b3, [0.0, np.sin(11 * DEG), np.cos(11 * DEG)], rtol=0,
                               atol=1e-14)
    assert limited == 1.0


def test_a_lean_the_deck_shares_is_left_alone_and_the_default_never_clips():
    """The same lean over a deck rolled toward it (9 deg apart) passes the 16 deg cone to the
    bit, and so does every axis within the vertical's cone at the default ``pi / 2``."""
    t = 20.0 * np.array([0.0, np.sin(14 * DEG), np.cos(14 * DEG)])
    alone, _ = _b3(t, 15 * DEG)
    b3, limited = _b3(t, 15 * DEG, (16 * DEG, _roll(-5 * DEG)))
    assert limited == 0.0
    np.testing.assert_array_equal(b3.view(np.uint64), alone.view(np.uint64))
    rng = np.random.default_rng(3)
    for _ in range(50):
        t = rng.normal(size=3) + [0.0, 0.0, 4.0]
        R = np.asarray(rotation(ca.DM(rng.uniform(-0.2, 0.2, 3)))).reshape(3, 3)
        a, la = _b3(t, 30 * DEG)
        b, lb = _b3(t, 30 * DEG, (float(NO_TILT_LIMIT), R))
        np.testing.assert_array_equal(a.view(np.uint64), b.view(np.uint64))
        assert la == lb


def test_the_clip_stays_within_both_cones():
    """Random thrust vectors and decks tilted up to 10 deg: the axis ends within 15 deg of
    the vertical and within 16 deg of the normal (the arc toward the normal stays in the
    vertical's cone, which holds the normal), and on the deck's cone where it was clipped, moved
    along the great circle toward the normal (in the plane of the two, between them)."""
    rng, clipped = np.random.default_rng(7), 0
    for _ in range(100):
        t = rng.normal(size=3) + [0.0, 0.0, 2.0]
        R = np.asarray(rotation(ca.DM([*rng.uniform(-10, 10, 2) * DEG, rng.uniform(-3, 3)])))
        R = R.reshape(3, 3)
        b3, _ = _b3(t, 15 * DEG, (16 * DEG, R))
        alone, _ = _b3(t, 15 * DEG)
        assert np.linalg.norm(b3) == pytest.approx(1.0, abs=1e-12)
        assert b3[2] >= np.cos(15 * DEG) - 1e-12
        assert R[:, 2] @ b3 >= np.cos(16 * DEG) - 1e-12
        if R[:, 2] @ alone < np.cos(16 * DEG):
            assert R[:, 2] @ b3 == pytest.approx(np.cos(16 * DEG), abs=1e-12)
            # on the great circle through the vertical's axis and the normal, between them:
            # in their plane, and the two arcs to it add up to the whole
            n = R[:, 2]
            assert np.linalg.det(np.array([n, alone, b3])) == pytest.approx(0.0, abs=1e-12)
            arcs = np.arccos(np.clip([alone @ b3, b3 @ n, alone @ n], -1, 1))
            assert arcs[0] + arcs[1] == pytest.approx(arcs[2], abs=1e-9)
            clipped += 1
    assert clipped >= 10


def _deck_limit(down, descending, z_next, fly_on=1.0, key=16 * DEG, height=1e3):
    p = dict(GUIDANCE_P, fly_on=fly_on, flare_deck_tilt=key, flare_height=0.3,
             touchdown_height=0.2, contact_drop=0.0, flare_deck_height=height)
    out = np.asarray(touchdown_commands(float(down), float(descending), 0.1, z_next, p)).ravel()
    return TOUCHDOWN_COMMANDS.unpack(out)["deck_tilt_limit"][0]


def test_the_policy_commands_the_deck_cone_from_the_flare_on_only():
    """The key's angle in the flare (the reference 0.3 m or less above touchdown) and on the
    deck; above the flare, with the policy inert, and in the inert commands ``pi / 2``; the
    landing step bounds it to ``[0, pi / 2]``."""
    assert _deck_limit(down=0, descending=1, z_next=0.45) == 16 * DEG
    assert _deck_limit(down=1, descending=0, z_next=0.1) == 16 * DEG
    assert _deck_limit(down=0, descending=1, z_next=0.6) == float(NO_TILT_LIMIT)
    assert _deck_limit(down=1, descending=0, z_next=0.1, fly_on=0.0) == float(NO_TILT_LIMIT)
    assert INERT_COMMANDS["deck_tilt_limit"] == float(NO_TILT_LIMIT)
    for asked, got in ((3.0, float(NO_TILT_LIMIT)), (-0.1, 0.0), (0.2, 0.2)):
        b = bounded_commands(dict(INERT_COMMANDS, deck_tilt_limit=asked), 0.5)
        assert float(ca.evalf(b["deck_tilt_limit"])) == got


def test_below_flare_deck_height_only_and_on_the_deck():
    """With ``flare_deck_height`` 0.125 m (binary heights): the flare's reference 0.25 m above
    touchdown (z_next 0.45) has no deck cone, 0.125 m exactly and below have it, and so has
    the deck whatever the height; the vertical's cone is the flare's throughout."""
    assert _deck_limit(0, 1, 0.45, height=0.125) == float(NO_TILT_LIMIT)
    assert _deck_limit(0, 1, 0.325, height=0.125) == 16 * DEG
    assert _deck_limit(0, 1, 0.25, height=0.125) == 16 * DEG
    assert _deck_limit(1, 0, 0.45, height=0.125) == 16 * DEG
    p = dict(GUIDANCE_P, fly_on=1.0, flare_deck_tilt=16 * DEG, flare_height=0.3,
             touchdown_height=0.2, contact_drop=0.0, flare_deck_height=0.125)
    out = TOUCHDOWN_COMMANDS.unpack(np.asarray(touchdown_commands(0.0, 1.0, 0.1, 0.45, p)).ravel())
    assert out["tilt_limit"][0] == p["flare_tilt"]


def test_the_key_is_optional_and_off_by_default():
    """No shipped landing scenario but the ships sets it; the default packs ``pi / 2``."""
    for name in ("highway", "turning", "highway_100"):
        g = touchdown_guidance(load_scenario(name))
        assert g["flare_deck_tilt"] == np.pi / 2 and g["flare_deck_height"] == 1e3
    sc = load_scenario("highway", ["touchdown.flare_deck_tilt_deg=16.0"])
    assert touchdown_guidance(sc)["flare_deck_tilt"] == pytest.approx(16 * DEG, abs=1e-15)


@pytest.mark.slow
def test_seed_11_run_293_of_ship_ss5_meets_the_deck_within_the_tilt_limit():
    """``ship_ss5``'s seed 11 run 293 leans 15.7 deg toward +x (the flare's 15 and the
    attitude's overshoot) over a deck pitched 4.5 deg the other way, and meets it at 19.4
    deg. With the deck's cone at 16 deg it meets it within 17.9 deg, the contact within
    0.05 s of the other, and lands."""
    sc = load_scenario("ship_ss5", {"campaign.seed": 11})
    overrides = draws(campaign_spec_of(sc), [293])[0].overrides() + HANDOVER_COLD

    def flown(*extra):
        return touchdown_report(quadland.simulate(load_scenario("ship_ss5",
                                                                [*overrides, *extra])))

    before = flown("touchdown.flare_deck_tilt_deg=90.0")
    assert before.touchdown and before.tilt_deg > 17.9
    after = flown("touchdown.flare_deck_tilt_deg=16.0")
    assert after.success and after.tilt_deg < 17.9
    assert abs(after.time - before.time) < 0.05


@pytest.mark.skipif(not have_compiler(), reason="no C compiler")
@pytest.mark.parametrize("precision", ["double", "float"])
def test_the_c_step_clips_to_the_deck_cone_as_casadi(precision):
    """The generated landing step (double and float) against the CasADi function with the
    deck's cone commanded in the reference: random measurements over decks rolled and pitched
    up to 0.3 rad, cones of 0.05 rad to ``pi / 2``. Every output and the next memory agree
    (1e-12 relative in double, 2e-3 in float, as ``test_landing_flight_code``), and the cone
    binds in part of the calls (they differ from the same call at ``pi / 2``)."""
    h = Harness(precision)
    step, names = landing_step_function(L), landing_step_outputs(L).names()
    rtol = 1e-12 if h.dtype == np.float64 else 2e-3
    at = POSITION_REFERENCE.size - TOUCHDOWN_COMMANDS.size + TOUCHDOWN_COMMANDS.index(
        "deck_tilt_limit")
    rng, bound = np.random.default_rng(19), 0
    for _ in range(60):
        y = LANDING_MEASUREMENT.unpack(_measurement(rng))
        y["eta2"][:2] = rng.uniform(-0.3, 0.3, 2)
        h.v_y[:] = LANDING_MEASUREMENT.pack(y)
        ref = np.concatenate([rng.normal(size=3) * 0.5 + [0, 0, 1.0], rng.normal(size=6) * 0.3,
                              TOUCHDOWN_COMMANDS.pack(INERT_COMMANDS)])
        ref[at] = rng.uniform(0.05, np.pi / 2)
        h.v_ref[:] = ref
        h.v_state[:] = rng.normal(size=landing_memory(L).size) * 0.2
        args = [h.v_y.astype(float), h.v_ref.astype(float), h.v_state.astype(float),
                h.pc["p_ctrl"], h.pp["p_quad"], h.pp["p_act"], 0.004]
        res = dict(zip(names, (np.asarray(v, dtype=float).ravel(order="F")
                               for v in step(*args)), strict=True))
        args[1] = args[1].copy()
        args[1][at] = np.pi / 2
        free = dict(zip(names, (np.asarray(v, dtype=float).ravel(order="F")
                                for v in step(*args)), strict=True))
        bound += int(any(np.any(res[n] != free[n]) for n in names))
        assert h.step(0.004) == STATUS["QL_OK"]
        out = landing_output_layout(L).unpack(h.v_out.astype(float))
        for name, value in out.items():
            scale = max(1.0, float(np.max(np.abs(res[name]))))
            np.testing.assert_allclose(value, res[name], rtol=0, atol=rtol * scale * 10,
                                       err_msg=name)
        np.testing.assert_array_equal((h.out.thrust_limited, h.out.tilt_limited,
                                       h.out.n_clipped), res["limits"])
        scale = max(1.0, float(np.max(np.abs(res["mem_next"]))))
        np.testing.assert_allclose(h.v_state, res["mem_next"], rtol=0, atol=rtol * scale * 10)
    assert bound >= 10


@pytest.mark.skipif(not have_compiler(), reason="no C compiler")
@pytest.mark.parametrize("precision", ["double", "float"])
def test_the_c_guidance_commands_the_deck_cone_as_casadi(precision):
    """The generated guidance (double and float) with the policy on, the key at 16 deg and
    ``flare_deck_height`` 0.125 m, against the CasADi function: in the descent at reference
    heights across the flare and at the touchdown, the reference (its ``deck_tilt_limit``
    among it) agrees, and the cone is commanded in some calls and not in others."""
    h = Harness(precision)
    guide = landing_guidance_function()
    p_guid = h.pc["p_guid"].copy()
    for name, value in (("fly_on", 1.0), ("flare_deck_tilt", 16 * DEG),
                        ("flare_deck_height", 0.125)):
        p_guid[GUIDANCE_PARAMS.index(name)] = value
    p_guid = p_guid.astype(h.dtype).astype(float)
    h.v_gp[:] = p_guid
    at = POSITION_REFERENCE.size - TOUCHDOWN_COMMANDS.size + TOUCHDOWN_COMMANDS.index(
        "deck_tilt_limit")
    rtol = 1e-12 if h.dtype == np.float64 else 2e-3
    rng, seen = np.random.default_rng(23), set()
    for k in range(80):
        h.v_y[:] = _measurement(rng)
        h.api.lib.ql_guidance_state_init(ctypes.byref(h.gs), ctypes.byref(h.gp))
        phase = TOUCHDOWN if k % 4 == 0 else DESCEND
        h.gs.phase, h.gs.z_ref, h.gs.committed = phase, rng.uniform(0.0, 1.0), 1.0
        h.cues.touchdown, h.cues.marker_age, h.cues.contact_switch = 0.0, 0.0, 0.0
        xg = GUIDANCE_STATE.pack(dict(
            phase=h.gs.phase, timer=h.gs.timer, z_ref=h.gs.z_ref, aborts=h.gs.aborts,
            committed=h.gs.committed, armed=h.gs.armed, ms_rise=h.gs.ms_rise,
            ms_rise_rate=h.gs.ms_rise_rate, ms_tilt_rate=h.gs.ms_tilt_rate,
            ms_tilt_acc=h.gs.ms_tilt_acc, lean_x=h.gs.lean_x, lean_y=h.gs.lean_y,
            lean_gust=h.gs.lean_gust))
        assert h.guide(0.004) == STATUS["QL_OK"]
        _, ref = (np.asarray(v, dtype=float).ravel() for v in guide(
            xg, h.v_y.astype(float), [0.0, 0.0, 0.0], 0.004, p_guid))
        np.testing.assert_allclose(h.v_ref, ref, rtol=rtol, atol=1e-6)
        seen.add(round(float(ref[at]), 6))
    assert seen == {round(16 * DEG, 6), round(np.pi / 2, 6)}
