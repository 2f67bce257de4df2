"""A lock-down device in each foot (``[touchdown] lock = "foot_magnets"``, issue 19).

The project's magnet pulls the gear's centre point, whose gap while the body leans on its
front feet is centimetres: it holds nothing until the body is level. A magnet in each foot
(the same total holding force, a quarter in each) pulls each foot by its own gap, so the
feet that meet the deck first are held from the contact on (docs/landing.md, "highway_100:
a magnet in each foot"). Checked here against hand results:

* level over the deck every foot has the centre's gap: the feet's pulls add up to the
  centre's pull, with no moment;
* pitched onto its front feet, the front pair pulls ``F_hold s / 4`` each and the rear
  pair ``F_hold s / 4 / (1 + 2 fx sin th / g0)^2``, vertical in the earth frame, with the
  moment of each about the centre its pull times the foot's horizontal distance from the
  centre (``fx cos th - h sin th`` ahead for the front feet, ``fx cos th + h sin th``
  behind for the rear ones), where the centre magnet pulls nearly nothing;
* ``lock = "magnet"`` (every other shipped scenario's) packs ``at_feet = 0``: the law of
  before, which ``tests/test_contact.py`` checks; ``highway_100`` ships
  ``"foot_magnets"`` on swivelling feet; these checks take its faces flush at any lean
  (``lock_swivel_deg = 90``, an idealization; the sourced swivel's law is
  ``tests/test_swivel_feet.py``'s);
* flown, highway_100's campaign run 3 (contact 0.10 m behind the centre at 43.6 deg, off
  the pad with the tenth session's touchdown): with a magnet in each foot and a 1 s
  level-out its centre goes back by the geometric pivot about the front feet and no
  more, and it lands.
"""

import math

import casadi as ca
import numpy as np
import pytest
from lock_rig import F_HOLD, FX, FY, G0, H, lock_function, lock_packs
from reference import HANDOVER_COLD, HIGHWAY_100_TWELFTH

import quadland
from quadland.campaign.sampling import draws
from quadland.campaign.spec import campaign_spec_of
from quadland.kinds.landing.gear import lock_params
from quadland.kinds.landing.report import touchdown_report
from quadland.scenario import load_scenario
from quadland_symbolic.kinematics import rotation
from quadland_symbolic.landing.contact import (
    HOLD,
    LOCK,
    lock_defaults,
)
from quadland_symbolic.landing.quadrotor import QUAD6_STATE
from quadland_symbolic.vehicle import VEHICLE_STATE


def _params(at_feet):
    return lock_packs(at_feet, swivel=math.pi / 2)                 # flush: the ideal


def _pull(eta, z, t=0.5, at_feet=1):
    x1q = np.zeros(QUAD6_STATE.size)
    x1q[2], x1q[3:6] = z, eta
    out = lock_function()(x1q, np.zeros(VEHICLE_STATE.size), t, 0.0, *_params(at_feet))
    R = np.array(rotation(ca.DM(eta)))
    return R @ np.array(out[0]).ravel(), np.array(out[1]).ravel(), \
        HOLD.unpack(np.array(out[2]).ravel())


def test_the_devices_pack_where_they_pull():
    assert lock_defaults("magnet")["at_feet"] == 0.0
    assert lock_defaults("foot_magnets")["at_feet"] == 1.0
    for name in ("highway", "turning", "ship", "ship_ss5"):
        sc = load_scenario(name)
        assert sc.data["touchdown"]["lock"] == "magnet"
        assert LOCK.unpack(lock_params(sc))["at_feet"] == 0.0
    # highway_100 ships them on swivelling feet since the twelfth session
    feet = load_scenario("highway_100")
    lk = LOCK.unpack(lock_params(feet))
    assert lk["at_feet"] == 1.0 and lk["F_hold"] == 200.0
    assert lk["swivel"] == pytest.approx(math.radians(18.0))


@pytest.mark.parametrize("gap", [0.0, 0.002, 0.02])
def test_level_the_feet_pull_as_the_centre_does(gap):
    """Level, every foot and the centre have the same gap: the four quarter-pulls add up
    to the centre's ``F_hold s / (1 + gap / g0)^2``, straight down, with no moment."""
    s = 1 - math.exp(-0.5 / lock_defaults()["lock_rise_time"])
    want = F_HOLD * s / (1 + gap / G0) ** 2
    for at_feet in (0, 1):
        F_E, M, hold = _pull(np.zeros(3), H + gap, at_feet=at_feet)
        assert hold["F_lock"].item() == pytest.approx(want, rel=1e-12)
        np.testing.assert_allclose(F_E, [0.0, 0.0, -want], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(M, 0.0, atol=1e-12)


@pytest.mark.parametrize("deg", [20.0, 43.0, 58.0])
def test_on_its_front_feet_only_the_front_magnets_pull(deg):
    """Pitched ``th`` with its front feet on the deck (the contact at highway_100's
    leans): the front pair pulls ``F_hold s / 4`` each, the rear pair, ``2 fx sin th`` up,
    ``F_hold s / 4 / (1 + 2 fx sin th / g0)^2`` each; the moment about the centre is each
    vertical pull times its foot's horizontal distance from the centre, ``fx cos th - h
    sin th`` (front) and ``fx cos th + h sin th`` (rear, on the other side). The centre
    magnet, ``fx sin th`` up, pulls ``F_hold s / (1 + fx sin th / g0)^2``: under 0.3 N."""
    th = math.radians(deg)
    s = 1 - math.exp(-0.5 / lock_defaults()["lock_rise_time"])
    for sign in (1.0, -1.0):              # the sign of the pitch that lowers the nose
        eta = np.array([0.0, sign * th, 0.0])
        R = np.array(rotation(ca.DM(eta)))
        if (R @ np.array([FX, 0.0, -H]))[2] < (R @ np.array([-FX, 0.0, -H]))[2]:
            break
    z = -(R @ np.array([FX, FY, -H]))[2]                      # front feet on the plane
    F_E, M, hold = _pull(eta, z)
    front = F_HOLD * s / 4
    rear = front / (1 + 2 * FX * math.sin(th) / G0) ** 2
    assert hold["F_lock"].item() == pytest.approx(2 * front + 2 * rear, rel=1e-9)
    np.testing.assert_allclose(F_E, [0.0, 0.0, -(2 * front + 2 * rear)], rtol=1e-9,
                               atol=1e-9)
    lever = 2 * front * (FX * math.cos(th) - H * math.sin(th)) \
        - 2 * rear * (FX * math.cos(th) + H * math.sin(th))
    # the front pulls, ahead of the centre, pitch the nose further down: the moment about
    # body y has the sign of the pitch that lowered the nose (roll and yaw 0: the pitch
    # rate is the body's y rate), so a reversed cross product fails here
    assert lever > 0
    assert M[1] == pytest.approx(np.sign(eta[1]) * lever, rel=1e-9)
    assert abs(M[0]) < 1e-9 and abs(M[2]) < 1e-9
    centre = _pull(eta, z, at_feet=0)[2]["F_lock"].item()
    assert centre == pytest.approx(F_HOLD * s / (1 + FX * math.sin(th) / G0) ** 2, rel=1e-9)
    assert centre < 0.3


def _run(index, *overrides):
    sc = load_scenario("highway_100")
    d = draws(campaign_spec_of(sc), [index])[0]
    res = quadland.simulate(load_scenario("highway_100", [*d.overrides(), *HANDOVER_COLD,
                                                          *HIGHWAY_100_TWELFTH,
                                                          *overrides]))
    k0 = int(np.argmax(res["touched"] > 0.5))
    k4 = k0 + int(np.argmax(res["feet_down"][k0:] > 3.5))
    return dict(x0=float(res["x_e"][k0]), th=math.degrees(abs(float(res["theta1"][k0]))),
                down=float(res["x_e"][k4] - res["x_e"][k0]),
                rest=float(res["x_e"][-1] - res["x_e"][k0]),
                foot=float(res["foot_offset"][-1]), report=touchdown_report(res))


#: The tenth session's touchdown (two magnets under the gear, the 0.1 s level-out, the aim
#: 0.3 of the pivot ahead), and the same aim with a magnet in each foot and the 1 s level-out.
TENTH = ["touchdown.lock=magnet", "touchdown.level_time=0.1", "touchdown.cut_time=0.1",
         "touchdown.pivot_aim=0.3"]
FEET = ["touchdown.lock=foot_magnets", "touchdown.level_time=1.0", "touchdown.cut_time=1.0",
        "touchdown.pivot_aim=0.3", "touchdown.lock_swivel_deg=90"]   # the flush idealization


def test_campaign_run_3_held_on_its_front_feet_lands():
    """Run 3 of the campaign (default campaign seed, sensors on) meets the roof 0.10 m
    behind the centre at 43.6 deg. With the tenth session's touchdown the centre goes
    back 0.317 m (the pivot about the front feet, 0.3 (1 - cos th) + 0.15 sin th = 0.186
    m, and the drag's slide) and its farthest foot ends past the 0.7 m pad. With a magnet
    in each foot and the 1 s level-out (the aim kept) the flight up to the contact is the
    same; the front feet are held and the centre goes back by the geometric pivot to
    within a centimetre by every foot down (the gear's spring and the body's roll) and 2
    cm at rest, and the run lands and is secured."""
    before = _run(3, *TENTH)
    assert before["report"].failures == ["off the pad"] and before["foot"] > 0.7
    now = _run(3, *FEET)
    assert now["x0"] == before["x0"] and now["th"] == before["th"]
    th = math.radians(now["th"])
    pivot = FX * (1 - math.cos(th)) + H * math.sin(th)
    assert pivot == pytest.approx(0.186, abs=0.001)
    assert -before["rest"] > pivot + 0.1
    assert abs(-now["down"] - pivot) < 0.01
    assert abs(-now["rest"] - pivot) < 0.02
    assert now["foot"] < 0.7
    assert now["report"].success and now["report"].secured
