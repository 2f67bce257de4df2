"""A magnet in each foot on a ball joint of a sourced swivel (issue 19, twelfth session).

``[touchdown] lock = "foot_magnets"`` puts an electro-permanent magnet in each foot. Its
face swivels on a ball joint: flush with the deck while the deck's normal is within
``lock_swivel_deg`` of the joint's neutral axis (a DIN 71802 angled ball joint turns 18
deg; docs/contact.md), and past that by ``e`` it meets the deck on its edge, its centre
``w / 2 sin e`` off (``w = lock_face_width``), where the gap law of every magnet here
applies. The neutral axis may be pitched nose down (``lock_swivel_pitch_deg``). A foot
magnet's pull closes through its sole, so the legs are judged on ``F_n - pull``.

Checked against hand results:

* pitched ``th`` on its front feet, the front pair pulls ``F s / 4 / (1 + (w / 2) sin(e)
  / g0)^2`` with ``e = max(|th - b| - a, 0)``: flush inside the swivel, on its edge past it,
  and the old flush law (``lock_swivel_deg = 90``) bit for bit up to 90 deg;
* rolled ``phi`` (the neutral axis upright) the same with ``e = phi - a``;
* resting level and pressed ``delta`` into the deck, the peak-load follower's rate is
  ``4 (k delta - F s / 4)`` with the magnets in the feet and ``4 k delta`` with the magnet
  under the gear's centre, whose pull the legs carry;
* the statics of the held front feet at the contact: friction on the front pair alone,
  ``mu (F_n)``, against the drag at the table's corner.
"""

import math

import casadi as ca
import numpy as np
import pytest
from lock_rig import F_HOLD, FX, FY, G0, H, lock_function, lock_packs
from reference import HANDOVER_COLD, HIGHWAY_100_TWELFTH

from quadland.kinds.landing.gear import lock_params
from quadland.scenario import load_scenario
from quadland_symbolic.kinematics import rotation
from quadland_symbolic.landing.contact import (
    GEAR,
    HOLD,
    LOCK,
    gear_defaults,
)
from quadland_symbolic.landing.deck import DECK_PARAMS
from quadland_symbolic.landing.gear import GEAR_STATE, PEAK_RATE, TOUCHDOWN_POLICY, gear_terms
from quadland_symbolic.landing.quadrotor import QUAD6_STATE
from quadland_symbolic.parameters import QUADROTOR, VEHICLE
from quadland_symbolic.vehicle import VEHICLE_STATE

W = 0.03                                          # m: the magnet's face width
S = 1 - math.exp(-0.5 / 0.17)                     # the rise at t = 0.5 s


def _packs(at_feet=1, **lock):
    return lock_packs(at_feet, lock_rise_time=0.17, face_width=W, **lock)


def _hold(eta, z, **lock):
    x = np.zeros(QUAD6_STATE.size)
    x[2], x[3:6] = z, eta
    out = lock_function()(x, np.zeros(VEHICLE_STATE.size), 0.5, 0.0, *_packs(**lock))
    return HOLD.unpack(np.array(out[2]).ravel())


def _nose_down(th):
    for sign in (1.0, -1.0):
        eta = np.array([0.0, sign * th, 0.0])
        R = np.array(rotation(ca.DM(eta)))
        if (R @ np.array([FX, 0.0, -H]))[2] < (R @ np.array([-FX, 0.0, -H]))[2]:
            return eta, -(R @ np.array([FX, FY, -H]))[2]      # front feet on the plane
    raise AssertionError("no pitch lowers the nose")


def _edge_pull(e_deg):
    e = math.radians(max(min(e_deg, 90.0), 0.0))
    return F_HOLD * S / 4 / (1 + W / 2 * math.sin(e) / G0) ** 2


def test_the_keys_pack_and_default_to_the_sourced_swivel():
    lk = LOCK.unpack(lock_params(load_scenario("highway", ["touchdown.lock=foot_magnets"])))
    assert lk["at_feet"] == 1.0 and lk["swivel"] == pytest.approx(math.radians(18.0))
    assert lk["swivel_pitch"] == 0.0 and lk["face_width"] == 0.03
    lk = LOCK.unpack(lock_params(load_scenario("highway_100")))           # as shipped
    assert lk["at_feet"] == 1.0 and lk["swivel"] == pytest.approx(math.radians(18.0))
    assert lk["swivel_pitch"] == pytest.approx(math.radians(15.0))
    lk = LOCK.unpack(lock_params(load_scenario("highway_100", [
        "touchdown.lock=foot_magnets", "touchdown.lock_swivel_pitch_deg=18",
        "touchdown.lock_swivel_deg=10", "touchdown.lock_face_width=0.05"])))
    assert lk["swivel"] == pytest.approx(math.radians(10.0))
    assert lk["swivel_pitch"] == pytest.approx(math.radians(18.0))
    assert lk["face_width"] == 0.05


@pytest.mark.parametrize("deg", [10.0, 20.0, 36.0, 43.0, 58.0])
@pytest.mark.parametrize("pitch", [0.0, 18.0])
def test_on_its_front_feet_the_face_is_flush_within_the_swivel(deg, pitch):
    """The front pair, on the deck, pulls ``F s / 4`` each while ``|th - b| <= 18 deg`` and
    ``F s / 4 / (1 + (w / 2) sin(|th - b| - 18 deg) / g0)^2`` past it; the rear pair's gap
    is ``2 fx sin th`` on top of the same edge."""
    eta, z = _nose_down(math.radians(deg))
    hold = _hold(eta, z, swivel=math.radians(18.0), swivel_pitch=math.radians(pitch))
    e = abs(deg - pitch) - 18.0
    front = _edge_pull(e)
    pulls = hold["foot_pull"].ravel()
    rear_gap = 2 * FX * math.sin(math.radians(deg)) + W / 2 * math.sin(math.radians(max(e, 0)))
    rear = F_HOLD * S / 4 / (1 + rear_gap / G0) ** 2
    np.testing.assert_allclose(pulls, [front, rear, rear, front], rtol=1e-9)
    assert hold["F_lock"].item() == pytest.approx(pulls.sum(), rel=1e-12)
    if e <= 0:
        assert front == pytest.approx(F_HOLD * S / 4, rel=1e-12)
    else:
        assert front < 0.5 * F_HOLD * S / 4


@pytest.mark.parametrize("deg", [20.0, 43.0, 58.0])
def test_the_idealization_is_the_flush_law(deg):
    """``lock_swivel_deg = 90``: the pull of the eleventh session's flush faces, by its gap
    alone, to the last bit."""
    eta, z = _nose_down(math.radians(deg))
    flush = _hold(eta, z, swivel=math.pi / 2)["foot_pull"].ravel()
    front = F_HOLD * S / 4
    rear = front / (1 + 2 * FX * math.sin(math.radians(deg)) / G0) ** 2
    np.testing.assert_allclose(flush, [front, rear, rear, front], rtol=1e-12)


@pytest.mark.parametrize("deg", [10.0, 25.0])
def test_rolled_the_excess_is_the_roll_past_the_swivel(deg):
    """Rolled ``phi`` on its right or left feet (the neutral axis upright) the lower pair
    pulls ``F s / 4 / (1 + (w / 2) sin(phi - 18 deg)+ / g0)^2``."""
    phi = math.radians(deg)
    eta = np.array([phi, 0.0, 0.0])
    R = np.array(rotation(ca.DM(eta)))
    feet = np.array([[FX, FY, -H], [-FX, FY, -H], [-FX, -FY, -H], [FX, -FY, -H]])
    heights = feet @ R.T[:, 2]
    z = -heights.min()
    low = np.isclose(heights, heights.min())
    pulls = _hold(eta, z, swivel=math.radians(18.0))["foot_pull"].ravel()
    np.testing.assert_allclose(pulls[low], _edge_pull(deg - 18.0), rtol=1e-9)


def _peak_rate(at_feet, delta):
    """``F_peak``'s rate over ``PEAK_RATE`` resting level, ``delta`` into the deck, the
    follower at 0 and the lock on 0.5 s."""
    x1q, xv, xg, t = QUAD6_STATE.sym(), VEHICLE_STATE.sym(), GEAR_STATE.sym(), ca.SX.sym("t")
    F = ca.SX.sym("F", 4)
    args = [QUADROTOR.sym(), VEHICLE.sym(), DECK_PARAMS.sym(), GEAR.sym(), LOCK.sym(),
            TOUCHDOWN_POLICY.sym()]
    _, _, xg_dot, _ = gear_terms(x1q, xv, xg, F, t, *args)
    f = ca.Function("g", [x1q, xv, xg, F, t, *args], [xg_dot])
    pv, pd, pg, pl = _packs(at_feet=at_feet)
    pq = QUADROTOR.pack(dict(QUADROTOR.unpack(np.zeros(QUADROTOR.size)), m1=2.0, g=9.81))
    x = np.zeros(QUAD6_STATE.size)
    x[2] = H - delta
    xg0 = GEAR_STATE.pack(dict(impulse=1.0, t_contact=0.5, F_peak=0.0))
    pt = TOUCHDOWN_POLICY.pack(dict(cut=0.0, cut_delay=0.0, F_idle=0.0, s_switch=0.002))
    out = f(x, np.zeros(VEHICLE_STATE.size), xg0, np.zeros(4), 0.5, pq, pv, pd, pg, pl, pt)
    return GEAR_STATE.unpack(np.array(out).ravel())["F_peak"].item() / PEAK_RATE


def test_the_legs_carry_the_contact_load_without_the_feet_pulls():
    """Level and still, each foot ``delta`` in: the deck pushes ``k delta`` on each (the
    spring alone, no rate, ``delta`` far past the onset's smoothing). A magnet in the foot
    pulls ``F s / 4`` through the sole, so its leg carries ``k delta - F s / 4``; the
    centre's magnet pulls through the legs, which carry all of ``k delta``."""
    k = gear_defaults("car_roof")["k"]
    delta = 0.02                                   # m: 100 N a foot, past the pull's 49 N
    spring = k * (delta + 1e-4 * math.log1p(math.exp(-delta / 1e-4)))
    assert _peak_rate(1, delta) == pytest.approx(4 * (spring - F_HOLD * S / 4), rel=1e-9)
    assert _peak_rate(0, delta) == pytest.approx(4 * spring, rel=1e-9)


def test_held_front_feet_hold_the_corner_drag():
    """Statics of the front pair at the contact, flush, the rotors' thrust left out: the
    deck's normal force on the pair is at least the pulls, ``2 F s / 4``, so friction
    holds at least ``mu F s / 2`` along the roof, which beats the drag at the table's
    corner (110 km/h, drag +30 %: 26.8 N) once ``s >= 2 D / (mu F)`` = 0.536, 0.131 s into
    the rise. Edged 7 deg past the swivel (a 43 deg contact on an upright 18 deg joint,
    ``w`` = 3 cm) the same pulls reach only 12.6 % of that: the pair slides with the
    drag."""
    V = 110 / 3.6
    D = 1.3 * (0.3 * V + 0.01225 * V ** 2)
    assert D == pytest.approx(26.8, abs=0.05)
    mu = gear_defaults("car_roof")["mu"]
    s_min = 2 * D / (mu * F_HOLD)
    assert s_min == pytest.approx(0.536, abs=0.001)
    assert -0.17 * math.log(1 - s_min) == pytest.approx(0.131, abs=0.001)
    edge = 1 / (1 + W / 2 * math.sin(math.radians(7.0)) / G0) ** 2
    assert edge == pytest.approx(0.126, abs=0.001)
    assert mu * F_HOLD / 2 * edge < D


def _replay(index, *overrides):
    import quadland
    from quadland.campaign.sampling import draws
    from quadland.campaign.spec import campaign_spec_of
    from quadland.kinds.landing.report import touchdown_report
    d = draws(campaign_spec_of(load_scenario("highway_100")), [index])[0]
    res = quadland.simulate(load_scenario("highway_100", [*d.overrides(), *HANDOVER_COLD,
                                                          *HIGHWAY_100_TWELFTH,
                                                          *overrides]))
    k0 = int(np.argmax(res["touched"] > 0.5))
    th = np.abs(res["theta1"])
    front = res["x_e"] + FX * np.cos(th) - H * np.sin(th)
    k4 = k0 + int(np.argmax(res["feet_down"][k0:] > 3.5))
    return dict(th=float(th[k0]), slide=float(front[k4] - front[k0]),
                back=float(res["x_e"][-1] - res["x_e"][k0]),
                foot=float(res["foot_offset"][-1]), report=touchdown_report(res))


def test_campaign_run_54_held_by_its_front_feet_lands():
    """Run 54 (default campaign seed, sensors on) meets the roof 0.115 m behind the centre
    at 46.8 deg. With the two magnets under the gear and the 0.1 s level-out (the tenth
    session's touchdown) it leaves the 0.7 m pad. As shipped its front faces, edged 10.8
    deg past the swivel at the contact, slide about a centimetre before the lean falls
    under 36 deg and they lie flush; the centre then goes back by the geometric pivot
    ``fx (1 - cos th) + h sin th`` (0.204 m) and a few centimetres, and it lands, its legs
    under their 424 N limit."""
    before = _replay(54, "touchdown.lock=magnet", "touchdown.level_time=0.1",
                     "touchdown.cut_time=0.1", "touchdown.pivot_aim=0.3")
    assert before["report"].failures == ["off the pad"] and before["foot"] > 0.7
    now = _replay(54)
    th = now["th"]
    assert math.degrees(th) == pytest.approx(46.8, abs=0.1)
    pivot = FX * (1 - math.cos(th)) + H * math.sin(th)
    assert pivot == pytest.approx(0.204, abs=0.001)
    assert abs(now["slide"]) < 0.02
    assert pivot < -now["back"] < pivot + 0.04
    assert now["foot"] < 0.7
    assert now["report"].success and now["report"].secured
    assert now["report"].peak_gear_force < 424.0


def _resting(eta, **lock):
    """The foot pulls with the body at ``eta`` (roll, pitch, yaw), its lowest feet on the
    deck."""
    R = np.array(rotation(ca.DM(np.asarray(eta, dtype=float))))
    feet = np.array([[FX, FY, -H], [-FX, FY, -H], [-FX, -FY, -H], [FX, -FY, -H]])
    return _hold(np.asarray(eta, dtype=float), -(feet @ R.T[:, 2]).min(),
                 **lock)["foot_pull"].ravel()


@pytest.mark.parametrize(("nose_up", "roll", "share"), [
    (0.0, 0.0, 1.0),           # level: flush, but on the cone's very edge
    (1.0, 0.0, 0.628),         # nose up 1 deg: e = 1 deg, (w/2) sin e = 0.26 mm
    (5.0, 0.0, 0.188),         # nose up 5 deg: 1.31 mm, under a fifth of the pull
    (0.0, 5.0, 0.727),         # level, rolled 5 deg: acos(cos 18 cos 5) = 18.68 deg
    (0.0, 10.0, 0.364),        # level, rolled 10 deg: 20.49 deg
])
def test_with_the_axis_pitched_by_the_swivel_level_is_the_edge_of_flush(nose_up, roll, share):
    """18 deg of swivel about an axis pitched 18 deg nose down (highway_100's first
    merge; it ships 15 deg) puts level exactly on the edge of the swivel's cone: any
    nose-up pitch or any roll of the body against the deck edges every face at once
    (review of the twelfth session). By hand, the deck's normal in body axes
    ``(sin th cos phi, -sin phi, cos th cos phi)`` (nose up ``th``, roll ``phi``) against
    the axis ``(-sin b, 0, cos b)``: ``cos A = cos(b + th) cos phi``, ``e = A - 18 deg``."""
    th = math.radians(nose_up)
    sign = _nose_down(math.radians(5.0))[0][1] > 0                 # which pitch is nose down
    eta = [math.radians(roll), (-th if sign else th), 0.0]
    pulls = _resting(eta, swivel=math.radians(18.0), swivel_pitch=math.radians(18.0))
    b = math.radians(18.0)
    e = math.degrees(math.acos(math.cos(b + th) * math.cos(math.radians(roll)))) - 18.0
    assert pulls.max() == pytest.approx(_edge_pull(e), rel=1e-6)
    assert pulls.max() / (F_HOLD * S / 4) == pytest.approx(share, abs=0.001)


def test_a_swivel_past_90_deg_is_outside_the_law():
    """``swivel_edge`` caps the excess at 90 deg by ``cos e < 0``, which also holds for
    ``e < -90 deg``: a swivel past 90 deg (LOCK's ``pi`` was once documented as "flush at
    any attitude") edges every face by the full ``w / 2`` instead. The schema stops at 90
    deg, and 90 deg is the flush idealization."""
    eta, z = _nose_down(math.radians(10.0))
    flush = F_HOLD * S / 4
    assert _hold(eta, z, swivel=math.pi / 2)["foot_pull"].ravel()[0] == pytest.approx(flush)
    assert _hold(eta, z, swivel=math.pi)["foot_pull"].ravel()[0] < 0.01 * flush
    from quadland.schema.lock import LOCK_FIELDS
    assert LOCK_FIELDS["lock_swivel_deg"].hi == 90.0


@pytest.mark.parametrize("nose_up, roll", [(0.0, 0.0), (2.9, 0.0), (0.0, 9.5), (-32.9, 0.0)])
def test_the_shipped_15_deg_pitch_keeps_level_inside_the_swivel(nose_up, roll):
    """highway_100 ships the axis pitched 15 deg nose down: at rest level, up to 3 deg nose
    up, up to 10 deg of roll (``acos(cos 15 cos phi) <= 18``) and up to 33 deg nose down,
    every face lies flush and pulls its full share, by the same hand geometry as above."""
    lk = LOCK.unpack(lock_params(load_scenario("highway_100")))
    th = math.radians(nose_up)
    sign = _nose_down(math.radians(5.0))[0][1] > 0
    eta = [math.radians(roll), (-th if sign else th), 0.0]
    b = float(np.ravel(lk["swivel_pitch"])[0])
    assert math.degrees(math.acos(math.cos(b + th) * math.cos(math.radians(roll)))) < 18.0
    pulls = _resting(eta, swivel=float(np.ravel(lk["swivel"])[0]), swivel_pitch=b)
    assert pulls.max() == pytest.approx(F_HOLD * S / 4, rel=1e-9)
