"""Landing scenarios flown end to end, against checks independent of the loop's code.

The shipped scenarios must land within their limits at their default seed,
at every seed 0-19 and, for ``highway``, at 80 km/h (its tilt limits raised by the
steady tilt's closed form, docs/landing.md "Real drag and thrust"). The trajectory is
checked from its CSV columns alone: Newton's law by finite differences of
the logged positions (the thrust, attitude and external force as logged, a
rotation multiplied out by hand); the touchdown figures by hand at the
touchdown row; the ride on the deck as a rigid pose in the deck frame with
the rotors winding down by the motor lag; the wind as the drag of the air
velocity. The compiled simulator and CasADi's virtual machine fly the same
landing. Each landing takes about 0.1 s compiled.
"""

import csv
import io
import json
import warnings

import numpy as np
import pytest
from highway_before import BEFORE as HIGHWAY_BEFORE
from reference import rotation
from scipy.optimize import brentq
from turning_before import BEFORE

import quadland
from quadland.cli import main
from quadland.engine import compiled
from quadland.exceptions import ScenarioError
from quadland.kinds.landing.report import touchdown_report
from quadland.scenario import load_scenario
from quadland.schema import LANDING_SCHEMA
from quadland_symbolic.landing.guidance import ALIGN, APPROACH, DESCEND, TOUCHDOWN

SCENARIOS = ("highway", "turning", "ship", "ship_ss5", "highway_100")
#: Descents aborted at the default seed, on the sensors and on the true state: the
#: scenarios' measured ones (docs/landing.md, docs/sea.md). Since the quiescent-period
#: prediction (issue 19 item 4, docs/landing.md "Quiescent periods") the ships wait at the
#: wait height for a calm window and commit once, aborting none: ship lands at 20.59 s
#: (sensors) and 20.44 s (true state), ship_ss5 at 21.11 s and 21.07 s (with the descent
#: that pauses out of the align band; 20.59, 20.43, 21.10, 21.06 s without it). (Before,
#: aborting every descent the deck rose through, they aborted 14 and 3, 28 and 4 times and
#: landed at 73.36 s and 132.46 s on their sensors; with the old drag and gains 16 and 42,
#: 1 and 6.) highway_100 on its sensors aborted once, above the crawl, until the descent
#: paused out of the align band instead (touchdown 23.37 s). With the ships' faster vertical
#: loop (docs/landing.md "The ships' vertical loop"), their flare ("The ships' flare") and
#: the sensors' draws in blocks (issue 20): ship on its sensors lands at 13.08 s, none
#: aborted (20.52 s on the true state); ship_ss5 on its sensors commits to four descents
#: the deck's rise withdraws (past max_deck_rise) and lands at 71.62 s (21.14 s on the true
#: state, none aborted). (On the draws of before, with the flare, ship withdrew once and
#: landed at 25.99 s; ship_ss5 aborted none.) Since ship_ss5's crawl goes on over a rising
#: deck and its commit waits for the deck's tilt too (docs/landing.md, "ship_ss5: the deck's
#: roll at the contact and the withdrawals in the crawl") it lands at 22.29 s on its sensors
#: with none aborted (21.14 s on the true state); with the pad's heave in its filter within
#: the crawl (docs/landing.md, "ship_ss5: the heave oscillator in the crawl only") at 22.21 s.
ABORTS = {("highway", "sensors"): 0, ("turning", "sensors"): 0, ("ship", "sensors"): 0,
          ("ship_ss5", "sensors"): 0, ("highway_100", "sensors"): 0,
          ("highway", "perfect"): 0, ("turning", "perfect"): 0, ("ship", "perfect"): 0,
          ("ship_ss5", "perfect"): 0, ("highway_100", "perfect"): 0}
#: trajectory.csv's columns, as the issue names them.
COLUMNS = ["t", "phase", "x1", "y1", "z1", "phi1", "theta1", "psi1",
           "x2", "y2", "z2", "phi2", "theta2", "psi2", "x_e", "y_e", "z_e",
           "F_total", "M_x", "M_y", "M_z", "F_1", "F_2", "F_3", "F_4", "d_Fx", "d_Fy", "d_Fz"]
#: The columns a landing on its sensors adds: the true relative velocity, the filter's
#: estimate beside it and its standard deviations.
SENSED_COLUMNS = [*COLUMNS, "dx_e", "dy_e", "dz_e", "x_e_hat", "y_e_hat", "z_e_hat",
                  "vx_e_hat", "vy_e_hat", "vz_e_hat", "sigma_p_x", "sigma_p_y", "sigma_p_z"]
#: The loop on the true state, at once: what the sensors' absence leaves.
PERFECT = "sensors.enabled=false"
E_Z = np.array([0.0, 0.0, 1.0])


def _fly(name, *overrides):
    return quadland.simulate(load_scenario(name, list(overrides)))


def _csv(result) -> dict:
    """The trajectory as trajectory.csv holds it: each column by name, from its text."""
    rows = list(csv.reader(io.StringIO(result.to_csv())))
    data = np.array(rows[1:], dtype=float)
    return {name: data[:, i] for i, name in enumerate(rows[0])}


def _steady_tilt_deg(V, m=2.0, g=9.8, Kt=0.3, Kq=0.01225):
    """The tilt that holds V m/s through still air at the shipped drag: the root of
    m g sin(theta) = Kt V cos(theta) + Kq (V cos(theta))^2 (docs/landing.md)."""
    th = brentq(lambda th: m * g * np.sin(th) - Kt * V * np.cos(th) - Kq * (V * np.cos(th)) ** 2,
                0.0, np.pi / 2)
    return float(np.degrees(th))


def _speed(kmh):
    """highway at kmh: the car's speed and the drive force that holds it, the tilt limit at
    contact 10 deg beyond the steady tilt (as the shipped scenarios'), and above 25 deg of
    steady tilt the controller's tilt limit at PX4's 45 deg (30 deg tops out at 21.4 m/s)."""
    u2 = kmh / 3.6
    tilt = _steady_tilt_deg(u2)
    return [f"initial.velocity2=[{u2!r}, 0.0]", f"vehicle.tau=[{150.0 * u2!r}, 0.0, 0.0]",
            f"landing.max_tilt_deg={tilt + 10.0!r}",
            *(["controller.tilt_max_deg=45.0"] if tilt > 25 else [])]


def _first_rows(phase):
    """Each phase's number in the order the phases are first entered."""
    _, first = np.unique(phase, return_index=True)
    return [int(phase[k]) for k in sorted(first)]


# ---------------------------------------------------------------- the scenarios land

@pytest.mark.parametrize("sensing", ["sensors", "perfect"])
@pytest.mark.parametrize("name", SCENARIOS)
def test_lands_within_the_limits_at_the_default_seed(name, sensing):
    """On its sensors and on the true state, each lands at the default seed after the
    measured number of aborted descents (:data:`ABORTS`: none on a car's roof; before the
    descent waited for the marker, the ship aborted once on its sensors; ship_ss5 aborted
    four times on its sensors until its crawl went on over a rising deck, the comment of
    :data:`ABORTS` says why). highway_100
    lands with the touchdown policy that flies on until the magnet holds (``[touchdown]
    policy = "secure"``, issue 18): with the rotors cut at the contact switch it tipped
    over on the true state (a 39 deg lean past the gear's 36.9 deg) and bounced 2.2 cm on
    its sensors; judged by its feet (issue 18's review) its rear feet left the 0.5 m pad
    (0.559 m) until its aim point anticipated the level-out's pivot about its front feet
    (``pivot_aim``, docs/landing.md, "The pivot at the level-out": 0.377 m)."""
    res = _fly(name, *([PERFECT] if sensing == "perfect" else []))
    rep = touchdown_report(res)
    assert rep.touchdown and rep.success, rep
    assert rep.secured and not rep.bounced and not rep.tipped and rep.on_pad
    assert rep.aborts == ABORTS[name, sensing]
    flying = res["t"] < rep.time
    assert _first_rows(res["phase"][flying]) == [APPROACH, ALIGN, DESCEND]
    # before the contact the phases only go forward, but for each abort's one step back
    # to align (a descent aborted within one output period, 10 ms, shows no step back)
    phase = res["phase"][flying]
    back = np.flatnonzero(np.diff(phase) < 0)
    assert len(back) <= rep.aborts and res["aborts"][flying][-1] == rep.aborts
    assert np.all(np.diff(res["aborts"]) >= 0)
    assert all(phase[k] == DESCEND and phase[k + 1] == ALIGN for k in back)
    # descending at the contact, the flight code hears the gear's contact switch (closed
    # at 2 ms of the weight's impulse) and enters touchdown within a few control periods
    k = int(np.argmax(~flying))
    if res["phase"][k - 1] == DESCEND:
        assert res["phase"][res["t"] >= rep.time + 0.05][0] == TOUCHDOWN
    # the run ends at the first grid point settle_time after the first contact: its last
    # row is within an output period (10 ms) of that instant
    settle = res.scenario["landing.settle_time"]
    assert abs(res["t"][-1] - (rep.time + settle)) <= 0.01 + 1e-9
    # the lock holds the gear down: engaged, every foot on the deck
    assert res["engaged"][-1] > 0.99 and res["feet_down"][-1] == 4
    q = res.scenario.data["quadrotor"]
    F_max = q["thrust_to_weight"] * q["mass"] * q["gravity"] / 4
    rotors = np.vstack([res[f"F_{i}"] for i in range(1, 5)])
    assert rotors.min() >= 0 and rotors.max() <= F_max * (1 + 1e-12)


#: highway_100 is left out of the sweep: with its touchdown policy (docs/landing.md,
#: "Touchdown policy") 13 of seeds 0-19 land on the true state (4 with the rotor cut at
#: the contact switch), the others touch down past the gear's tip-over angle or drift off
#: the pad before the magnet holds.
@pytest.mark.parametrize("name,seed", [(n, s) for n in SCENARIOS if n != "highway_100"
                                       for s in range(20)])
def test_lands_within_the_limits_at_every_seed(name, seed):
    """With perfect sensing, every seed of the disturbance lands (the sensors' share of
    the failures is the campaigns', docs/landing.md)."""
    rep = touchdown_report(_fly(name, f"simulation.seed={seed}", PERFECT))
    assert rep.touchdown and rep.success, rep


#: highway at 80 km/h judged by its feet (issue 18's review): with the rotors cut at the
#: contact switch after a 30 deg lean the body drops onto its rear feet and slides back.
#: With the magnet's pull counted from 0.25 s after the switch, seeds 2, 5, 11, 13, 14, 15
#: and 19 left the 0.5 m pad by a rear foot (0.508 to 0.606 m); with the magnet switched
#: on before the contact (highway's lock_delay 0, docs/landing.md, "The feet on the pad")
#: only seed 11 did, and with the disturbance observer as well none does (farthest feet
#: 0.238 to 0.362 m; 80 km/h is past highway's 40-60 km/h table).
FEET_OFF_AT_80 = ()
#: With the observer on z and no outer bias estimates on x, y (docs/landing.md, "The bias
#: estimates' slow tail") seed 15 touches down 2.7 s sooner (8.99 s against 11.66 s),
#: in another moment of its turbulence, leaning 37.2 deg (35.0 before): past the gear's
#: static tip-over angle, 36.87 deg, and it tips. 80 km/h is past highway's table, whose
#: campaign the change was measured on. With highway's flare (30 deg of the thrust axis from
#: 0.15 m, docs/landing.md, "highway: the flare and the leash") it lands, leaning 31.6 deg
#: and 6.9 cm off: the flare is under the gear's tip-over angle, and under the 31.1 deg
#: steady lean at 80 km/h, so it drifts back in the last half second rather than tips.
TIPPED_AT_80 = ()


@pytest.mark.parametrize("seed", [pytest.param(
    s, marks=pytest.mark.xfail(strict=True, reason="a rear foot leaves the 0.5 m pad"))
    if s in FEET_OFF_AT_80 else pytest.param(
    s, marks=pytest.mark.xfail(strict=True, reason="leans past the gear's tip-over angle"))
    if s in TIPPED_AT_80 else s for s in range(20)])
def test_highway_lands_at_80_kmh(seed):
    rep = touchdown_report(_fly("highway", f"simulation.seed={seed}", *_speed(80), PERFECT))
    assert rep.touchdown and rep.success, rep


@pytest.mark.parametrize("kmh", [30, 60, 70])
def test_highway_lands_at_other_speeds(kmh):
    rep = touchdown_report(_fly("highway", *_speed(kmh)))
    assert rep.touchdown and rep.success, rep


def test_a_heaving_deck_holds_the_descent_until_a_calm_window():
    """The ship's deck before sea states, heave alone (0.68 m at w = 0.349 rad/s, phase
    180 deg: the pad's vertical speed 0.237 cos(w t + pi) m/s in closed form), on the true
    state with calm_speed = 0.15 m/s: the descent waits at the wait height
    (touchdown_height + commit_height) until the speed predicted 2.5 s ahead stays within
    0.15 m/s, near a crest or a trough. Over the 2.5 s after the commit the deck's true
    speed stays within 0.15 m/s plus the prediction's error, V (|w - w_hat| 2.5 +
    |w / w_hat - 1|) with |w_hat / w - 1| <= 2 r / (1 - 2 r), r = 1 / (2 sqrt(1 +
    (2 w 20)^2)) (tests/test_quiescence.py): 0.19 m/s. It lands within the limits with no
    abort. Logged at the control rate."""
    res = _fly("ship", PERFECT, "deck.sea_state=0", "deck.heave_amplitude=[0.68]",
               "deck.heave_frequency=[0.349]", "deck.heave_phase_deg=[180.0]",
               "landing.calm_speed=0.15", "simulation.duration=120.0",
               "simulation.output_rate_hz=250.0")
    rep = touchdown_report(res)
    assert rep.success and rep.aborts == 0
    lg = res.scenario.data["landing"]
    wait = res.scenario.data["quadrotor"]["gear_height"] + lg["commit_height"]
    t, z_ref, phase = res["t"], res["z_ref"], res["phase"]
    held = (phase == DESCEND) & (np.abs(z_ref - wait) < 1e-9)
    k = int(np.flatnonzero(held)[-1])                     # the last step at the wait height
    assert held.sum() * 0.004 > 1.0                       # it waited (over a second)
    assert z_ref[k + 1] < wait and t[k + 1] < rep.time    # then committed, before contact
    w, V = 0.349, 0.68 * 0.349
    window = np.linspace(t[k], t[k] + 2.5, 251)
    speed = np.abs(V * np.cos(w * window + np.pi))
    r = 1 / (2 * np.sqrt(1 + (2 * w * 20.0) ** 2))
    rel = 2 * r / (1 - 2 * r)
    assert speed.max() <= 0.15 + V * (w * rel * 2.5 + rel / (1 - rel)) + 1e-9
    assert speed.max() <= 0.19


@pytest.mark.parametrize("name", ["highway", "ship"])
def test_on_the_true_state_the_sensed_world_changes_nothing(name):
    """Issue 17's "sensors.enabled = false with controller.delay_periods = 0 flies the
    loop of before, bit for bit": with the sensors off, nothing of the sensors', the
    filter's or the land detector's tables, their random draws or the controller's backend
    reaches the flight (review of issue 17: the promise stood only on a one-time check).
    Each variant would change a sensed flight."""
    base = [PERFECT, "controller.delay_periods=0", "simulation.duration=20"]
    ref = _fly(name, *base).to_csv()
    for extra in (["sensors.vision.rate_hz=5.0", "sensors.gnss.latency=0.2"],
                  ["sensors.random=false"], ["estimator.q_acc=[0.3, 0.4, 0.05]"],
                  ["land_detector.gap_max=0.5"], ['controller.backend="c"']):
        assert _fly(name, *base, *extra).to_csv() == ref, extra


# ---------------------------------------------------------------- landed and secured

#: The turning car on the true state, with no lock-down: what the gear alone holds (the
#: rotors cut at the contact switch: turning's touchdown and gains of before its flare,
#: whose flights these tests pin; docs/landing.md, "turning: the flare, and the observer alone").
LOOSE = ["sensors.enabled=false", 'touchdown.lock="none"', *BEFORE]


def test_a_too_hard_landing_bounces_and_tips_and_the_report_says_why(tmp_path, capsys):
    """A crawl forced to 3.5 m/s hits the deck at 4.15 m/s, past 14 CFR 27.725's 2.55 m/s
    drop, tilted past the limit (25.3 deg): the gear rebounds 12.4 cm (restitution 0.45,
    no lock to hold it), its load (463 N) passes the default gear's 27.725 limit load
    (424 N) and the quadrotor rolls over (a 2.5 m/s crawl meets the deck at 3.13 m/s
    with 314 N and a 0.75 cm rebound: it tips but neither bounces nor overloads). The
    run stops there at the singular attitude: a landing that failed, judged and reported
    (exit 0, summary.json written), not a failed flight; the verdict says why."""
    out = tmp_path / "hard"
    # the law without the disturbance observer, whose flight these numbers are (with it the
    # forced crawl aborts twice and meets the deck at 1.82 m/s, upright: a judge's test)
    sets = [*LOOSE, "landing.touchdown_speed=3.5", "landing.descent_speed=3.5",
            "controller.observer_frequency=[0.0, 0.0, 0.0]"]
    assert main(["simulate", "--scenario", "turning", "--no-plots", "--out", str(out),
                 *(a for s in sets for a in ("--set", s))]) == 0
    lines = capsys.readouterr().out.splitlines()
    land = json.loads((out / "summary.json").read_text())["landing"]
    assert land["touchdown"] and not land["success"]
    assert land["bounced"] and land["tipped"] and not land["secured"]
    assert land["bounce"] > 0.02 and land["peak_gear_force"] > 424
    assert land["sink_rate"] > 2.55
    assert land["failures"] == ["sink_rate", "tilt_deg", "bounced", "tipped", "gear load",
                                "off the pad", "not secured"]
    assert lines[1].startswith(f"landing: FAILED: sink rate {land['sink_rate']:.3g} > 0.5 m/s; "
                               f"tilt {land['tilt_deg']:.3g} > 23.3 deg; bounced "
                               f"{100 * land['bounce']:.1f} cm > 2 cm; tipped over on the deck; "
                               "gear load ")
    assert "  secured NO, tipped YES, on the pad NO" in lines


def test_a_gear_narrower_than_the_tilt_at_contact_tips_over():
    """The static tip-over angle atan(half_track / h_cg) (docs/contact.md): skids 2 cm apart
    under a 0.2 m high centre tip at 2.9 deg; the turning car's landing meets its roof
    tilted by more (5.3 deg: the lateral acceleration), so without a lock it rolls over;
    on the default 0.25 m track (32 deg) the same landing rests."""
    narrow = touchdown_report(_fly("turning", *LOOSE, "gear.feet_y=0.01"))
    assert narrow.tilt_deg > np.degrees(np.arctan(0.01 / 0.2))
    assert narrow.tipped and not narrow.secured and not narrow.success
    wide = touchdown_report(_fly("turning", *LOOSE))
    assert not wide.tipped and wide.secured and wide.success      # friction holds it


def test_without_a_lock_highway_100_s_drag_leaves_it_not_secured():
    """No device on the 100 km/h roof: the still air's drag (Kt V + Kq V^2 = 17.8 N) is
    more than friction holds (mu m g = 9.8 N), so the body does not rest secured. Before
    the report's margin carried the drag and a missing device engaged nothing, this
    landing read "secured yes" (the lock's clock at 1, the margin 0) beside "off the
    pad"."""
    res = _fly("highway_100", 'touchdown.lock="none"')
    rep = touchdown_report(res)
    assert res["engaged"][-1] == 0.0 and res["F_lock"][-1] == 0.0
    assert res["friction_margin"][-1] > 1
    assert not rep.secured and not rep.success and "not secured" in rep.failures


def test_the_welded_idealization_stays_a_switch():
    """gear.welded = true is the old touchdown: the gear point's crossing ends the flight,
    the ride pins the pose; the gear's figures are undefined, and the campaign's gear
    limits do not apply to it."""
    from quadland.kinds.landing.kind import LandingKind

    res = _fly("highway", PERFECT, "gear.welded=true")
    rep = touchdown_report(res)
    assert rep.touchdown and rep.success and rep.secured is None and rep.peak_gear_force is None
    assert "touched" not in res
    metrics = LandingKind().run_metrics(res)
    assert metrics["secured"] is None
    assert LandingKind().judge(res, metrics, LandingKind().limits(res.scenario)) == []
    # the pure-C example flies the contact only: its generation refuses the weld
    with pytest.raises(ScenarioError, match="^gear.welded: the pure-C example flies"):
        LandingKind().codegen_defaults(res.scenario)


@pytest.mark.parametrize("setting,message", [
    ("gear.stiffness=-5.0", "gear.stiffness"),
    ("gear.friction=3.0", "gear.friction"),
    ('touchdown.lock="harpoon"', "touchdown.lock"),
    ('touchdown.policy="brake"', "touchdown.policy"),
    ("touchdown.switch_impulse=0.0", "touchdown.switch_impulse"),
    ("landing.max_friction_margin=1.5", "landing.max_friction_margin"),
    ("quadrotor.gear_height=0.0", "quadrotor.gear_height: must be positive for the gear's"),
    # F_max = 2 x 2 kg x 9.8 / 4 = 9.8 N by hand: the plant clips a command above it, and
    # 100 N "idle" flew the cut body 8.3 m off the roof (reported bounced and tipped)
    ("touchdown.idle_thrust=9.81", "touchdown.idle_thrust: 9.81 N is more than a rotor's "
     "F_max (quadrotor.thrust_to_weight x mass x gravity / 4 = 9.8 N)"),
    # highway's feet at (0.15, 0.125) m: the corner 0.1953 m from the centre by hand, so a
    # contact 0.2 m off (the limit) can put a foot at 0.3953 m, outside a 0.35 m pad
    ("landing.pad_radius=0.35", "landing.pad_radius: 0.35 m is smaller than landing.max_offset "
     "plus the gear's corner (hypot(gear.feet_x, gear.feet_y) = 0.195256 m)"),
])
def test_a_bad_gear_or_touchdown_value_is_one_line(tmp_path, capsys, setting, message):
    out = tmp_path / "run"
    assert main(["simulate", "--scenario", "highway", "--no-plots", "--out", str(out),
                 "--set", setting]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("quadland: error: ") and message in err[0]
    assert not out.exists()


# ---------------------------------------------------------------- physics from the log

@pytest.fixture(scope="module")
def fine_result():
    """highway logged at 1 kHz."""
    return _fly("highway", "simulation.output_rate_hz=1000")


@pytest.fixture(scope="module")
def welded_result():
    """highway logged at 1 kHz, the welded idealization (gear.welded)."""
    return _fly("highway", "simulation.output_rate_hz=1000", "gear.welded=true")


@pytest.fixture(scope="module")
def fine(fine_result):
    """highway logged at 1 kHz: its CSV columns and the scenario."""
    return _csv(fine_result), fine_result.scenario


def _newton_residual(c, sc, k):
    """m a - (R (F_total e_z + d_F) - m g e_z - R Kt (R^T v)) at rows k, N, by central
    differences of the logged positions."""
    q = sc.data["quadrotor"]
    m, g, Kt = q["mass"], q["gravity"], np.asarray(q["drag_translational"])
    t = c["t"]
    p = np.column_stack([c["x1"], c["y1"], c["z1"]])
    h = (t[k + 1] - t[k])[:, None]
    a = (p[k + 1] - 2 * p[k] + p[k - 1]) / h**2
    v = (p[k + 1] - p[k - 1]) / (2 * h)
    out = []
    for j, kk in enumerate(k):
        R = rotation((c["phi1"][kk], c["theta1"][kk], c["psi1"][kk]))
        d_F = np.array([c["d_Fx"][kk], c["d_Fy"][kk], c["d_Fz"][kk]])
        force = (R @ (c["F_total"][kk] * E_Z + d_F) - m * g * E_Z
                 - R @ (Kt * (R.T @ v[j])))
        out.append(m * a[j] - force)
    return np.array(out)


def _smooth_rows(c, t_td, rate_hz):
    """Rows whose neighbours are 1 ms away on either side, away from the touchdown's
    impact, and with no switch at the row: of the held disturbance (every 10 ms; the
    acceleration jumps) or of the held rotor commands (at the control rate; the
    motors' lag makes the thrust's rate jump there, which a central second
    difference across it turns into an error of about m h |jump| / 4)."""
    t = c["t"]
    k = np.arange(1, len(t) - 1)
    even = np.isclose(t[k + 1] - t[k], 1e-3) & np.isclose(t[k] - t[k - 1], 1e-3)
    switch = np.zeros(len(k), bool)
    for period in (0.01, 1.0 / rate_hz):
        switch |= np.isclose(np.round(t[k] / period) * period, t[k], atol=1e-9)
    away = (t[k + 1] < t_td - 1e-9) | (t[k - 1] > t_td + 1e-9)
    return k[even & ~switch & away]


def test_plant_obeys_newton_from_the_logged_thrust_attitude_and_forces(fine, fine_result,
                                                                       welded_result):
    c, sc = fine
    t_td = touchdown_report(fine_result).time
    k = _smooth_rows(c, t_td, sc["controller.rate_hz"])
    # in flight up to 5 ms before the contact (the contact's onset, smoothed over 0.1 mm,
    # passes in 0.3 ms at the sink rate: a 1 ms difference cannot follow it), and resting
    # on the deck a second after it: the rotors cut, the lock pulled in
    before, after = k[c["t"][k] < t_td - 5e-3], k[c["t"][k] > t_td + 1.0]
    assert len(before) > 5000 and len(after) > 500
    r = _newton_residual(c, sc, before)
    assert np.max(np.abs(r)) < 5e-3                       # N, of forces up to 20 N
    # on the deck, d_F holds the gear's contact and the lock's pull too: Newton's law
    # still holds (the load, 120 N, is 6 times the flight's forces)
    assert np.max(np.abs(_newton_residual(c, sc, after))) < 3e-2
    # and on the welded idealization's ride, whose d_F is what holds the pose
    cw = _csv(welded_result)
    t_w = cw["t"][np.argmax(cw["phase"] == TOUCHDOWN)]
    kw = _smooth_rows(cw, t_w, sc["controller.rate_hz"])
    assert np.max(np.abs(_newton_residual(cw, sc, kw[cw["t"][kw] > t_w]))) < 5e-3


def test_touchdown_figures_by_hand_at_the_touchdown_row(fine, fine_result):
    c, sc = fine
    k = int(np.argmax(fine_result["touched"] > 0.5))
    rep = touchdown_report(fine_result)
    assert rep.time == pytest.approx(c["t"][k], abs=1e-9)
    assert c["t"][k] - c["t"][k - 1] <= 1e-3 + 1e-12     # the touchdown row is its own
    p_e = np.array([c["x_e"], c["y_e"], c["z_e"]])
    v_e = (p_e[:, k] - p_e[:, k - 1]) / (c["t"][k] - c["t"][k - 1])
    assert rep.offset == pytest.approx(np.hypot(*p_e[:2, k]), abs=1e-9)
    assert rep.sink_rate == pytest.approx(-v_e[2], abs=5e-3)
    assert rep.relative_speed == pytest.approx(np.hypot(*v_e[:2]), abs=5e-3)
    R1 = rotation((c["phi1"][k], c["theta1"][k], c["psi1"][k]))
    R2 = rotation((c["phi2"][k], c["theta2"][k], c["psi2"][k]))
    tilt = np.degrees(np.arccos(R1[:, 2] @ R2[:, 2]))
    assert rep.tilt_deg == pytest.approx(tilt, abs=1e-6)
    limits = sc.data["landing"]
    assert rep.success == (rep.sink_rate <= limits["max_sink_rate"]
                           and rep.offset <= limits["max_offset"]
                           and rep.tilt_deg <= limits["max_tilt_deg"]
                           and rep.relative_speed <= limits["max_relative_speed"]
                           and rep.peak_gear_force <= limits["max_gear_load"]
                           and not rep.bounced and not rep.tipped and rep.on_pad
                           and rep.secured)
    # the first contact is located within the step: the lowest foot is on the deck
    # plane, every other above it
    p1 = np.array([c["x1"][k], c["y1"][k], c["z1"][k]])
    p2 = np.array([c["x2"][k], c["y2"][k], c["z2"][k]])
    g = sc.data["gear"]
    feet = [p1 + R1 @ [sx * g["feet_x"], sy * g["feet_y"], -sc["quadrotor.gear_height"]]
            for sx in (1, -1) for sy in (1, -1)]
    heights = sorted(R2[:, 2] @ (foot - p2) for foot in feet)
    assert heights[0] == pytest.approx(0, abs=1e-9) and heights[1] > 1e-6


def test_on_the_deck_the_pose_is_rigid_and_the_rotors_wind_down(welded_result):
    """The welded idealization (gear.welded = true): pinned at the touchdown pose."""
    fine_result = welded_result
    c, sc = _csv(welded_result), welded_result.scenario
    k = int(np.argmax(c["phase"] == TOUCHDOWN))
    t = c["t"]
    p_e = np.array([c["x_e"], c["y_e"], c["z_e"]])
    np.testing.assert_allclose(p_e[:, k:], np.broadcast_to(p_e[:, [k]], p_e[:, k:].shape),
                               atol=1e-9)
    R_rel = [rotation((c["phi2"][j], c["theta2"][j], c["psi2"][j])).T
             @ rotation((c["phi1"][j], c["theta1"][j], c["psi1"][j])) for j in range(k, len(t))]
    np.testing.assert_allclose(R_rel, np.broadcast_to(R_rel[0], np.shape(R_rel)), atol=1e-9)
    # the decay from the result's own doubles: the CSV's 12 digits of t alone
    # leave exp(-(t - t_k) / tau) uncertain by 2 x 5e-11 s / tau = 5e-9
    tau, t = sc["quadrotor.motor_time_constant"], fine_result["t"]
    for i in range(1, 5):
        F = fine_result[f"F_{i}"]
        np.testing.assert_allclose(F[k:], F[k] * np.exp(-(t[k:] - t[k]) / tau),
                                   rtol=1e-12, atol=1e-300)


def test_wind_acts_as_the_drag_of_the_air_velocity():
    """With a steady wind alone and eq. (2)'s linear drag alone (the quadratic drag and
    the ground effect off: tests/test_drive_aero.py checks those), the logged external
    force is ``Kt R^T v_wind``."""
    wind = np.array([3.0, -4.0, 1.0])
    res = _fly("highway", "quadrotor.drag_quadratic=[0.0, 0.0, 0.0]",
               "controller_model.drag_quadratic=[0.0, 0.0, 0.0]", "quadrotor.rotor_radius=0.0",
               "wind.turbulence_w20=0.0", "wind.gust_amplitude=0.0",
               f"wind.mean={wind.tolist()}", "disturbance.force_bias=[0.0, 0.0, 0.0]",
               "disturbance.force_amplitude=0.0", "disturbance.noise=false")
    c, Kt = _csv(res), np.asarray(res.scenario["quadrotor.drag_translational"])
    # the first contact's row, logged at the instant the gear meets the deck (off the
    # output grid), and the rows after it hold the contact's force too (the touchdown
    # phase comes with the flight code's contact switch, a row later at this seed since
    # the sensors' draws come in blocks, issue 20): the rows before it, the drag alone
    first = int(np.argmax(res["touched"] > 0.5))
    assert first > 0 and np.all(c["phase"][:first] < TOUCHDOWN)
    off_grid = abs(100 * c["t"][first] - round(100 * c["t"][first])) > 1e-6
    assert off_grid and abs(c["d_Fz"][first]) > 1.0
    for j in range(0, first, 50):
        R = rotation((c["phi1"][j], c["theta1"][j], c["psi1"][j]))
        d_F = [c["d_Fx"][j], c["d_Fy"][j], c["d_Fz"][j]]
        np.testing.assert_allclose(d_F, Kt * (R.T @ wind), atol=1e-9)


@pytest.mark.parametrize("name", ["highway", "highway_100"])
def test_compiled_and_virtual_machine_fly_the_same_landing(monkeypatch, name):
    """The same landing on both, highway_100's drive profile and lane change too."""
    ref = _fly(name)
    monkeypatch.setattr(compiled, "have_compiler", lambda: False)
    compiled.compiled_loop.cache_clear()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", compiled.QuadlandWarning)
            vm = _fly(name)
    finally:
        monkeypatch.undo()
        compiled.compiled_loop.cache_clear()
    assert len(vm["t"]) == len(ref["t"])
    for name in COLUMNS:
        np.testing.assert_allclose(vm[name], ref[name], rtol=1e-9, atol=1e-9, err_msg=name)


def test_the_ride_is_one_algorithm_compiled_and_on_the_virtual_machine():
    """The ride after touchdown, run by quadland_loop.h's qll_ride in the compiled
    simulator and by its Python mirror on the VM, from the same touchdown: the same
    rows at the same times (ride_grid's), the same states and signals to roundoff;
    a non-finite start stops it at once with SIM_NONFINITE and no row."""
    from quadland.engine.compiled import SIM_NONFINITE, SIM_OK, CompiledLoop, VMLoop
    from quadland.engine.loop import Clock, ride_grid
    from quadland.kinds.landing.values import landing_values
    from quadland_symbolic.landing.loop import (
        LANDING_RECORDED,
        landing_loop,
        landing_ride_start,
    )
    from quadland_symbolic.landing.signals import LANDING_SIGNALS

    # highway's touchdown of before its flare and leash (tests/highway_before.py), whose
    # touchdown time is pinned below
    sc = load_scenario("highway", ["simulation.duration=22", PERFECT, "gear.welded=true",
                                   *HIGHWAY_BEFORE])
    res, lv = quadland.simulate(sc), landing_values(sc)
    k = int(np.argmax(res["phase"] == TOUCHDOWN))
    x_td, t_td = res.states[k], float(res["t"][k])
    y_td = np.array([res[n][k] for n in LANDING_SIGNALS.element_names()])
    rec = np.array([res[n][k] for n in LANDING_RECORDED.element_names()])
    z0, a = (np.asarray(v, dtype=float).ravel()
             for v in landing_ride_start(lv.l)(x_td, y_td, rec, t_td, 2.0))
    rows, model = Clock(100.0, 0.0, 22.0, True), landing_loop(lv.l, welded=True)
    runs = [loop.ride(z0, a, rows, t_td, t_td + 2.0, 0.004, lv.pp)
            for loop in (CompiledLoop(model, "sampled"), VMLoop(model, "sampled"))]
    times, _ = ride_grid(rows, t_td, t_td + 2.0, 0.004)
    # touchdown between 8.36 and 8.37 s (10.93 and 10.94 s before the observer on z and
    # no outer bias estimates on x, y, docs/landing.md, "The bias estimates' slow tail";
    # 17.26 and 17.27 s before the disturbance observer, 16.40 and 16.41 s before the
    # changes for issue 19's bar): the 100 Hz ticks 8.37 .. 10.36 s, then the end
    assert len(times) == 201 and times[0] == pytest.approx(8.37, abs=1e-12)
    assert times[-1] == t_td + 2.0
    for ride in runs:
        assert ride.status == SIM_OK
        np.testing.assert_array_equal(ride.times, times)
    c, v = runs
    np.testing.assert_allclose(c.X, v.X, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(c.Y, v.Y, rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(c.R, v.R)
    bad = z0.copy()
    bad[0] = np.nan
    for loop in (CompiledLoop(model, "sampled"), VMLoop(model, "sampled")):
        ride = loop.ride(bad, a, rows, t_td, t_td + 2.0, 0.004, lv.pp)
        assert ride.status == SIM_NONFINITE and len(ride.times) == 0


# ---------------------------------------------------------------- outputs and failures

def test_simulate_writes_the_landing_columns_and_summary(tmp_path):
    out = tmp_path / "run"
    assert main(["simulate", "--scenario", "highway", "--no-plots", "--out", str(out)]) == 0
    with open(out / "trajectory.csv") as fh:
        header = next(csv.reader(fh))
    assert header == SENSED_COLUMNS
    side = json.loads((out / "columns.json").read_text())["columns"]
    assert [c["name"] for c in side] == SENSED_COLUMNS and all(c["unit"] for c in side)
    perfect = tmp_path / "perfect"
    assert main(["simulate", "--scenario", "highway", "--no-plots", "--out", str(perfect),
                 "--set", PERFECT]) == 0
    with open(perfect / "trajectory.csv") as fh:
        assert next(csv.reader(fh)) == COLUMNS
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "ok"
    assert set(summary["landing"]) == {"touchdown", "time", "sink_rate", "offset",
                                       "relative_speed", "tilt_deg", "aborts", "success",
                                       "limits", "secured", "bounced", "tipped",
                                       "peak_gear_force", "impact_energy", "bounce",
                                       "tip_over_deg", "on_pad", "failures"}
    assert summary["landing"]["limits"] == {"max_sink_rate": 0.5, "max_offset": 0.2,
                                            "max_tilt_deg": 32.6, "max_relative_speed": 0.5,
                                            "max_gear_load": 424.0, "max_bounce": 0.02,
                                            "max_friction_margin": 1.0, "pad_radius": 0.5}
    assert summary["landing"]["secured"] is True and summary["landing"]["failures"] == []
    assert summary["landing"]["success"] is True
    # landed: judged landed and secured settle_time (2 s) after the first contact, on the
    # last row (the 100 Hz rows' grid), not null (the guidance's touchdown verdict, on the
    # land detector, lags the contact, so it never entered "landed" before the run ended)
    phases, land = summary["phases"], summary["landing"]
    assert abs(phases["landed"] - (land["time"] + 2.0)) <= 0.01
    assert phases["touchdown"] < phases["landed"]
    # the tilt at contact is judged against the gear's tip-over angle too: atan(0.15 / 0.2)
    # = 36.87 deg for a pure pitch, larger for a tilt with some roll (the support rectangle's
    # corner is farther than its edge)
    assert land["tip_over_deg"] >= np.degrees(np.arctan(0.15 / 0.2)) - 1e-9
    blocks = summary["navigation"]["blocks"]
    assert all(set(b) == {"fused", "rejected", "held"} for b in blocks.values())
    # only a range is ever held back before its gate, and the first ones are: at the
    # handover the horizontal position is known to 1 m per axis (p0_position), and
    # 2 sqrt(2) m > range_deck_radius 0.5 m (E12a)
    assert blocks.pop("range")["held"] > 0 and not any(b["held"] for b in blocks.values())
    again = load_scenario(out / "scenario.toml")
    assert again.model == "landing" and again.data == load_scenario("highway").data


def test_animate_writes_the_landing_as_a_gif_and_refuses_the_paper_loop(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["simulate", "--scenario", "highway", "--no-plots", "--animate", "--out",
                 str(out), "--set", "simulation.duration=1.0"]) == 0
    assert (out / "landing.gif").read_bytes()[:4] == b"GIF8"
    assert not list(out.glob("*.png"))
    capsys.readouterr()
    assert main(["simulate", "--animate", "--out", str(tmp_path / "paper")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("quadland: error: --animate:")
    assert not (tmp_path / "paper").exists()


@pytest.mark.parametrize("delay", [0, 1, 2])
def test_each_command_acts_delay_periods_later(delay):
    """The motors are a first-order lag, F' = (u - F) / tau, which RK4 steps in
    closed form: over a control period h with u held, F_next = R F + (1 - R) u with
    R = 1 + z + z^2/2 + z^3/6 + z^4/24, z = -h / tau. Solving for u from the logged
    forces gives the command that acted; it is the one the step computed delay
    periods before (hover thrust before the first)."""
    sc = load_scenario("highway", ["simulation.output_rate_hz=250",
                                   "disturbance.sample_rate_hz=250", "simulation.duration=2",
                                   f"controller.delay_periods={delay}"])
    res = quadland.simulate(sc)
    t, tau = res["t"], sc["quadrotor.motor_time_constant"]
    z = -np.diff(t) / tau
    R = 1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24
    hover = sc["quadrotor.mass"] * sc["quadrotor.gravity"] / 4
    for i in range(1, 5):
        F, computed = res[f"F_{i}"], res[f"F_{i}_cmd"]
        acted = (F[1:] - R * F[:-1]) / (1 - R)
        expected = np.r_[np.full(delay, hover), computed[:len(acted) - delay]]
        np.testing.assert_allclose(acted, expected, rtol=0, atol=1e-12 * hover)


def test_failed_landing_exits_3_with_the_partial_trajectory(tmp_path, capsys):
    out = tmp_path / "run"
    status = main(["simulate", "--scenario", "highway", "--no-plots", "--out", str(out),
                   "--set", "initial.omega1_deg_s=[0.0, 3000.0, 0.0]"])
    err = capsys.readouterr().err.strip().splitlines()
    # the tumble passes 90 degrees of tilt (the envelope, checked at every grid
    # point) before the guard's |cos(theta) cos(phi)| falls below its minimum
    assert status == 3 and len(err) == 1 and "flight failed at t = 0.032 s: the tilt" in err[0]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and summary["landing"]["touchdown"] is False
    with open(out / "trajectory.csv") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == SENSED_COLUMNS and len(rows) > 1


def test_a_motor_lag_too_fast_for_the_step_is_refused_before_any_work(tmp_path):
    with pytest.raises(ScenarioError, match="rk_steps_per_interval to 3"):
        _fly("highway", "quadrotor.motor_time_constant=0.001")
    out = tmp_path / "run"
    assert main(["simulate", "--scenario", "highway", "--out", str(out), "--set",
                 "quadrotor.motor_time_constant=0.001"]) == 2
    assert not out.exists()


# ---------------------------------------------------------------- the landing schema

def test_the_landing_schema_has_the_keys_the_issue_names():
    for dotted in ("vehicle.tau", "initial.position1", "initial.z1", "initial.velocity2",
                   "deck.heave_amplitude", "deck.heave_frequency", "deck.roll_amplitude_deg",
                   "deck.roll_frequency", "deck.pitch_amplitude_deg", "deck.pitch_frequency",
                   "landing.max_sink_rate", "landing.max_offset", "landing.max_tilt_deg",
                   "landing.max_relative_speed", "landing.hover_height", "landing.dwell_time",
                   "landing.touchdown_speed", "landing.settle_time", "simulation.seed",
                   "disturbance.noise", "quadrotor.thrust_to_weight",
                   "quadrotor.motor_time_constant", "quadrotor.gear_height",
                   "controller.rate_hz"):
        section, key = dotted.split(".")
        assert key in LANDING_SCHEMA[section], dotted
    defaults = {"max_sink_rate": 0.5, "max_offset": 0.2, "max_relative_speed": 0.5}
    for name in SCENARIOS:
        sc = load_scenario(name)
        assert sc.model == "landing"
        assert {k: sc.data["landing"][k] for k in defaults} == defaults
        # the tilt at contact: 10 deg beyond the steady tilt that holds the pad, into the
        # scenario's airflow (the vehicle's speed through its mean wind) and, in a turn,
        # against its acceleration u2 r2 as well (the two forces at right angles),
        # docs/landing.md; highway's at its campaign's fastest car, 20 % over the 50 km/h
        v2, wind = sc["initial.velocity2"], sc["wind.mean"]
        air = np.hypot(v2[0] - wind[0], v2[1] - wind[1]) * (1.2 if name == "highway" else 1.0)
        turn = v2[0] * np.radians(sc["initial.r2_deg_s"]) / sc["quadrotor.gravity"]
        steady = np.degrees(np.arctan(np.hypot(np.tan(np.radians(_steady_tilt_deg(air))), turn)))
        assert sc["landing.max_tilt_deg"] == pytest.approx(steady + 10, abs=0.05)


def test_ship_deck_is_sea_state_4_and_ship_ss5_the_same_ship_in_sea_state_5():
    """ship_ss5 differs from ship in its sea state, its duration and its campaign's sea
    (docs/sea.md; both fly the crawl on the leash, ship_ss5 since the nineteenth session:
    docs/landing.md, "ship_ss5: the crawl on the leash, with the heave in the filter"), and
    in ship_ss5's handover
    above the deck (docs/landing.md, "The ships' handover above the deck, and the flare
    about the deck's normal"), in ship_ss5's nested marker (docs/landing.md, "The nested
    marker on highway_100 and ship_ss5"), in ship_ss5's datalink gates (docs/landing.md,
    "ship_ss5: the datalink refused at the deck's turn"), and in ship_ss5's commit: no
    withdrawal in the crawl, the deck's tilt at the contact (docs/landing.md, "ship_ss5: the
    deck's roll at the contact and the withdrawals in the crawl"), the gust's lean, and no
    crawl abort within 6 cm of the deck (docs/landing.md, "ship_ss5: an abort the gear cannot
    fly"), and the frequency of the pad's heave its filter carries in the crawl (ship_ss5's
    sea state 5, docs/landing.md "ship_ss5: the heave oscillator in the crawl only"; ship's sea
    state 4, "ship: the heave oscillator in the crawl at sea state 4's frequency"), and the
    flare held about the deck's
    normal too (docs/landing.md, "The ships' tilt at the contact: the flare held about the
    deck's normal too"), and in ship's withdrawal budget (ship_ss5 withdraws nothing in its
    crawl already: docs/landing.md, "The ships' repeated withdrawals")."""
    ship, ss5 = load_scenario("ship"), load_scenario("ship_ss5")
    assert ship["deck.sea_state"] == 4 and ss5["deck.sea_state"] == 5
    for d in (ship.data["deck"], ss5.data["deck"]):
        assert d["heave_amplitude"] == d["roll_amplitude_deg"] == d["pitch_amplitude_deg"] \
            == (0.0,)
    differ = {f"{section}.{key}" for section, keys in ship.data.items() for key in keys
              if ship.data[section][key] != ss5.data[section][key]}
    assert differ == {"scenario.name", "scenario.description", "deck.sea_state",
                      "simulation.duration", "initial.handover_clearance",
                      "sensors.vision.small_range_max",
                      "estimator.gate_datalink_v", "estimator.gate_datalink_a",
                      "landing.withdraw_height", "landing.calm_tilt_deg",
                      "landing.calm_lean_deg", "landing.lean_withdraw", "landing.abort_floor",
                      "estimator.heave_frequency", "touchdown.flare_deck_tilt_deg",
                      "landing.withdraw_budget"}
    assert set(ship.campaign_table["dispersions"]) == set(ss5.campaign_table["dispersions"])


def test_the_paper_scenario_keeps_its_schema():
    sc = load_scenario("paper")
    assert sc.model == "paper" and "model" not in sc.data["scenario"]
    assert load_scenario("paper", ['scenario.model="paper"']).data == sc.data
    with pytest.raises(ScenarioError, match=r"controller.k1p.*scenario.model = \"landing\""):
        load_scenario("paper", ["controller.k1p=[1.0, 1.0, 1.0]"])
    with pytest.raises(ScenarioError, match="scenario.model: must be one of paper, landing"):
        load_scenario("paper", ["scenario.model=plane"])


def test_deck_motions_take_one_to_three_sinusoids_of_matching_lengths():
    sc = load_scenario("ship", ["deck.heave_amplitude=[0.5, 0.2, 0.1]",
                                "deck.heave_frequency=[0.3, 0.6, 0.9]",
                                "deck.heave_phase_deg=[0.0, 10.0, 20.0]"])
    assert sc["deck.heave_amplitude"] == (0.5, 0.2, 0.1)
    with pytest.raises(ScenarioError, match="deck.heave_frequency: must have as many"):
        load_scenario("ship", ["deck.heave_amplitude=[0.5, 0.2]"])
    with pytest.raises(ScenarioError, match="expected a list of 1 to 3 numbers"):
        load_scenario("ship", ["deck.roll_frequency=[0.1, 0.2, 0.3, 0.4]"])


# ---------------------------------------------------------------- the controller's own model

def test_the_law_reads_its_own_model_and_the_plant_is_the_quadrotor():
    """[controller_model] reaches the law (the flight step's p_quad, p_act) and nothing
    else; [quadrotor] is the plant the simulator integrates."""
    from quadland.kinds.landing.values import landing_values
    from quadland_symbolic.landing.loop import landing_loop
    from quadland_symbolic.landing.plant import LANDING_PLANT_PARAMS
    from quadland_symbolic.landing.quadrotor import ACTUATOR
    from quadland_symbolic.parameters import QUADROTOR

    sc = load_scenario("highway", ["controller_model.mass=2.4",
                                   "controller_model.motor_time_constant=0.03"])
    lv = landing_values(sc)
    args = dict(zip(landing_loop(lv.l).step_args.name_out(),
                    landing_loop(lv.l).step_args(lv.xp0, lv.xc0, lv.pc, 1.0, 0.0), strict=True))
    law_q = QUADROTOR.unpack(np.asarray(args["p_quad"], dtype=float).ravel())
    law_a = ACTUATOR.unpack(np.asarray(args["p_act"], dtype=float).ravel())
    assert law_q["m1"][0] == 2.4 and law_a["motor_time_constant"][0] == 0.03
    assert law_a["F_max"][0] == 2.0 * 2.4 * 9.8 / 4            # its own thrust_to_weight
    plant = LANDING_PLANT_PARAMS.unpack(lv.pp)
    assert QUADROTOR.unpack(plant["p_quad"])["m1"][0] == 2.0
    assert ACTUATOR.unpack(plant["p_act"])["motor_time_constant"][0] == 0.02


def test_with_a_wrong_mass_the_hover_holds_the_true_weight():
    """At the hover equilibrium on a level deck, with no wind and no disturbance, the
    quadrotor moves with the vehicle at constant velocity: the vertical force is the
    plant's weight m g, whatever mass the controller assumes. The vertical force, by
    hand: the thrust T cos(phi) cos(theta) times Cheeseman and Bennett's ground-effect
    ratio at the height z_e above the deck, plus the vertical part of the body's
    quadratic drag -Kq V1 |V1| (eq. 2's linear drag is the same on every axis:
    horizontal). Without the bias estimates (ki_p = 0, as here) and the observer on z
    (off here) the altitude settles off its reference; with either it does not
    (tests/test_landing_robust.py)."""
    from quadland.linearization import equilibrium

    calm = ["wind.mean=[0.0, 0.0, 0.0]", "disturbance.force_bias=[0.0, 0.0, 0.0]",
            "disturbance.moment_bias=[0.0, 0.0, 0.0]", "controller.ki_p=[0.0, 0.0, 0.0]",
            "controller.observer_frequency=[12.0, 12.0, 0.0]"]
    sc = load_scenario("highway", calm)
    q, Kq, R_rotor = sc.data["quadrotor"], np.asarray(sc["quadrotor.drag_quadratic"]), 0.127
    assert list(q["drag_translational"]) == [0.3, 0.3, 0.3]
    assert sc["quadrotor.rotor_radius"] == R_rotor
    nominal = equilibrium(sc)
    wrong = equilibrium(load_scenario("highway", [*calm, "controller_model.mass=2.4"]))
    for point in (nominal, wrong):
        z = {n: point.xr[i] for i, n in enumerate(point.state_names)}
        T = point.u[0]
        R = rotation((z["phi1"], z["theta1"], 0.0))
        V1 = np.array([z["u1"], z["v1"], z["w1"]])
        v_E = R @ V1
        assert abs(v_E[2]) < 1e-9                             # level flight with the car
        v_i2 = T / 4 / (2 * 1.225 * np.pi * R_rotor ** 2)
        k = 1 / (1 - (R_rotor / (4 * z["z_e"])) ** 2 / (1 + (v_E[0] ** 2 + v_E[1] ** 2) / v_i2))
        up = T * k * np.cos(z["phi1"]) * np.cos(z["theta1"]) + (R @ (-Kq * V1 * np.abs(V1)))[2]
        assert up == pytest.approx(2.0 * 9.8, rel=1e-9)
    assert abs(wrong.xr[2] - nominal.xr[2]) > 1e-3      # z_e off its reference


def test_a_campaign_disperses_the_plant_and_keeps_the_controller_s_model():
    """A run's dispersed quadrotor.mass reaches the plant; the law keeps the nominal."""
    from quadland.campaign.sampling import draws
    from quadland.campaign.spec import campaign_spec_of
    from quadland.kinds.landing.values import landing_values
    from quadland_symbolic.landing.loop import landing_loop_params
    from quadland_symbolic.landing.plant import LANDING_PLANT_PARAMS
    from quadland_symbolic.parameters import QUADROTOR

    base = load_scenario("highway")
    draw = next(iter(draws(campaign_spec_of(base), [0])))
    lv = landing_values(base.replace(**draw.values))
    mass = QUADROTOR.unpack(LANDING_PLANT_PARAMS.unpack(lv.pp)["p_quad"])["m1"][0]
    model = LANDING_PLANT_PARAMS.unpack(landing_loop_params(lv.l).unpack(lv.pc)["pp"])
    assert mass == draw.values["quadrotor.mass"] != 2.0
    assert QUADROTOR.unpack(model["p_quad"])["m1"][0] == 2.0
