"""The land detector on hand-built cue sequences, against hand-counted windows and
the run statistics of independent Gaussian noise."""

import math

import casadi as ca
import numpy as np
import pytest

from quadland_symbolic.landing.land_detector import (
    LAND_DETECTOR_CUES,
    LAND_DETECTOR_DEFAULTS,
    LAND_DETECTOR_FLAGS,
    LAND_DETECTOR_PARAMS,
    LAND_DETECTOR_SOURCES,
    LAND_DETECTOR_STATE,
    land_detector_function,
)

DETECTOR = land_detector_function()
DT = 0.004                                     # the 250 Hz control period
FLAG = {n: i for i, n in enumerate(LAND_DETECTOR_FLAGS.element_names())}
STATE = {n: i for i, n in enumerate(LAND_DETECTOR_STATE.element_names())}
#: On the deck: every cue says landed (a fresh range each step, the weight on the deck).
ON_DECK = dict(range_gap=0.0, range_valid=1.0, est_gap=0.0, est_vz=0.0, thrust_ratio=0.5,
               f_z=9.81, in_descend=1.0)
#: Hovering 1 m above the deck, descending.
FLYING = dict(ON_DECK, range_gap=1.0, est_gap=1.0, thrust_ratio=1.0)


def _params(**changes):
    return LAND_DETECTOR_PARAMS.pack({**LAND_DETECTOR_DEFAULTS, **changes})


def _run(rows, p=None, dt=DT, x0=None):
    """Step through ``rows`` (dicts of cues); returns the states after each step
    (n x 11) and the flags (n x 10)."""
    cues = np.column_stack([LAND_DETECTOR_CUES.pack(r) for r in rows])
    x0 = LAND_DETECTOR_STATE.zeros() if x0 is None else x0
    xs, fl = DETECTOR.mapaccum(len(rows))(x0, cues, _params() if p is None else p, dt)
    return np.asarray(xs).T, np.asarray(fl).T


def _first(flags, name):
    """1-based step at which flag ``name`` is first set (0: never)."""
    hits = np.flatnonzero(flags[:, FLAG[name]] > 0.5)
    return int(hits[0]) + 1 if hits.size else 0


def test_defaults_cover_every_parameter_with_a_source():
    names = set(LAND_DETECTOR_PARAMS.names())
    assert set(LAND_DETECTOR_DEFAULTS) == names == set(LAND_DETECTOR_SOURCES)
    assert all(LAND_DETECTOR_SOURCES[n].startswith(("PX4", "assumption")) for n in names)


def test_a_one_sample_false_gap_does_not_trigger():
    rows = [FLYING] * 50 + [ON_DECK] + [FLYING] * 400
    xs, flags = _run(rows)
    assert flags[:, :3].max() == 0
    # the contact's time was one step, then reset
    assert xs[50, STATE["t_contact"]] == pytest.approx(DT)
    assert xs[51:, STATE["t_contact"]].max() == 0


def test_a_burst_one_step_short_of_the_window_does_not_trigger():
    # W = 1/3 s at dt = 4 ms: the window is k steps with k dt >= W - dt/2, k >= 82.83: 83
    rows = ([ON_DECK] * 82 + [FLYING]) * 5
    _, flags = _run(rows)
    assert flags[:, :3].max() == 0
    _, flags = _run([ON_DECK] * 83)
    assert _first(flags, "ground_contact") == 83


# the first step of each stage, counted by hand: the smallest k with k dt >= W - dt/2;
# stage 2 starts on the step stage 1 sets, stage 3 on the step stage 2 sets, so
# maybe landed = n1 + n2 - 1, landed = n1 + n2 + n3 - 2
@pytest.mark.parametrize("dt, n", [
    (0.004, 83),       # W/dt = 83.33: k >= 82.83
    (0.02, 17),        # PX4's 50 Hz: 16.67, k >= 16.17
    (0.01, 33),        # 33.33, k >= 32.83
    (0.002, 167),      # 166.67, k >= 166.17
])
def test_the_stages_set_at_the_hand_counted_steps(dt, n):
    _, flags = _run([ON_DECK] * (3 * n + 5), dt=dt)
    assert _first(flags, "ground_contact") == n
    assert _first(flags, "maybe_landed") == 2 * n - 1
    assert _first(flags, "landed") == 3 * n - 2
    assert flags[-1, FLAG["slow_windows"]] == 0


def test_without_range_or_spike_the_windows_are_three_times_longer():
    # W = 1 s at 4 ms: k >= 250 - 0.5: 250 steps per stage
    rows = [dict(ON_DECK, range_valid=0.0)] * 800
    _, flags = _run(rows)
    assert (_first(flags, "ground_contact"), _first(flags, "maybe_landed"),
            _first(flags, "landed")) == (250, 499, 748)
    assert flags[:, FLAG["slow_windows"]].min() == 1


def test_a_touchdown_spike_stands_in_for_the_range():
    # no range at all; the specific force jumps by 5 m/s^2 (over spike_min 3) on step 2
    # (step 1 seeds the mean); the spike then counts for 1 s: through step 2 + 249
    rows = [dict(ON_DECK, range_valid=0.0)] + \
        [dict(ON_DECK, range_valid=0.0, f_z=9.81 + 5.0)] + \
        [dict(ON_DECK, range_valid=0.0)] * 400
    _, flags = _run(rows)
    assert (_first(flags, "ground_contact"), _first(flags, "maybe_landed"),
            _first(flags, "landed")) == (83, 165, 247)
    spike = flags[:, FLAG["spike_cue"]]
    assert spike[0] == 0 and spike[1:251].min() == 1 and spike[251:].max() == 0


def test_a_range_at_half_the_control_rate_stays_fresh():
    # a 125 Hz range finder: a fresh sample every other step, the rest marked invalid
    rows = [dict(ON_DECK, range_valid=float(k % 2 == 0), range_gap=0.0 if k % 2 == 0 else 9.0)
            for k in range(300)]
    _, flags = _run(rows)
    assert _first(flags, "landed") == 247
    assert flags[:, FLAG["range_fresh"]].min() == 1


def test_a_fresh_range_vetoes_the_estimate():
    rows = [dict(ON_DECK, range_gap=0.5)] * 800          # the filter says contact, the range not
    _, flags = _run(rows)
    assert flags[:, :3].max() == 0
    assert flags[:, FLAG["gap_cue"]].min() == 1 and flags[:, FLAG["range_cue"]].max() == 0


def test_a_stale_range_stops_vetoing_after_its_timeout():
    # one range of 0.5 m at step 1, then none: fresh while 0.1 - k dt > dt/2, k <= 24,
    # i.e. through step 25; from step 26 the estimate alone counts, with tripled windows:
    # contact from step 26 needs 250 steps, set on step 275
    rows = [dict(ON_DECK, range_gap=0.5)] + [dict(ON_DECK, range_valid=0.0)] * 400
    _, flags = _run(rows)
    fresh = flags[:, FLAG["range_fresh"]]
    assert fresh[:25].min() == 1 and fresh[25:].max() == 0
    assert _first(flags, "ground_contact") == 275


def test_hysteresis_widens_the_thresholds_while_set():
    base = [ON_DECK] * 83                                   # ground contact on step 83
    # within 2.5 x the thresholds (gap 0.2 < 0.25 m, speed 0.5 < 0.625 m/s): held
    held = [dict(ON_DECK, est_gap=0.2, range_gap=0.2, est_vz=-0.5)] * 100
    _, flags = _run(base + held)
    assert flags[82:, FLAG["ground_contact"]].min() == 1
    # the same cues could not have set it
    _, flags = _run(held * 5)
    assert flags[:, :3].max() == 0


def test_a_stage_drops_at_once_beyond_the_widened_thresholds_then_starts_over():
    rows = [ON_DECK] * 170 + [dict(ON_DECK, est_gap=0.3)] + [ON_DECK] * 300
    xs, flags = _run(rows)
    assert flags[168, FLAG["maybe_landed"]] == 1                # maybe landed on step 165
    assert flags[170, :3].tolist() == [0, 0, 0]                # step 171: both dropped
    assert xs[170, STATE["t_contact"]] == 0
    # a full window again from step 172: contact on 171 + 83, maybe on 171 + 165
    assert np.flatnonzero(flags[171:, FLAG["ground_contact"]])[0] + 172 == 171 + 83
    assert np.flatnonzero(flags[171:, FLAG["maybe_landed"]])[0] + 172 == 171 + 165
    assert np.flatnonzero(flags[171:, FLAG["landed"]])[0] + 172 == 171 + 247


def test_landed_latches():
    rows = [ON_DECK] * 247 + [FLYING] * 300
    _, flags = _run(rows)
    assert flags[246:, :3].min() == 1


def test_a_descent_is_needed_until_maybe_landed():
    rows = [ON_DECK] * 100 + [dict(ON_DECK, in_descend=0.0, thrust_ratio=1.0)]
    _, flags = _run(rows)
    assert flags[99, FLAG["ground_contact"]] == 1 and flags[100, FLAG["ground_contact"]] == 0
    rows = [ON_DECK] * 170 + [dict(ON_DECK, in_descend=0.0)] * 200
    _, flags = _run(rows)
    assert flags[169:, FLAG["maybe_landed"]].min() == 1 and _first(flags, "landed") == 247
    _, flags = _run([dict(ON_DECK, in_descend=0.0)] * 500)
    assert flags[:, :3].max() == 0


def test_the_running_mean_is_the_exact_first_order_lag():
    # a step of 1 m/s^2 (under spike_min): mean = 10.81 - exp(-k dt / tau) after k steps
    rows = [ON_DECK] + [dict(ON_DECK, f_z=10.81)] * 500
    xs, flags = _run(rows)
    k = np.arange(1, 501)
    np.testing.assert_allclose(xs[1:, STATE["f_z_mean"]], 10.81 - np.exp(-k * DT / 0.5),
                               rtol=0, atol=1e-13)
    assert flags[:, FLAG["spike_cue"]].max() == 0


def _hover(rng, n, h, sigma_est, sigma_range):
    """Cue rows of a still hover with the gear h above the deck and Gaussian gap noise."""
    est = h + sigma_est * rng.standard_normal(n)
    rng_gap = h + sigma_range * rng.standard_normal(n)
    return [dict(FLYING, est_gap=e, range_gap=r, est_vz=0.0, thrust_ratio=0.5)
            for e, r in zip(est, rng_gap, strict=True)]


def _phi(x):
    return 0.5 * math.erfc(-x / math.sqrt(2))


def test_a_noisy_hover_at_the_defaults_never_triggers():
    """The worst case: hovering still 0.15 m above the deck, descending, at low thrust, a
    fresh range each step. Per step, the contact test passes with p = P(est <= 0.1)
    P(range <= 0.1) = Phi(-1) Phi(-1.61) = 8.5e-3 (sigmas 0.05 m and 0.031 m, the range
    finder's on the deck); a contact needs 83 passes in a row, so over N steps the expected
    number of false contacts is under N p^83 < 1e-160. A run of m passes anywhere has
    probability under N p^m: for N = 150,000 (10 min) and m = 4 that is 8e-4, so the
    longest run is at most 3 steps (with a fixed seed, deterministic)."""
    p = _phi(-0.05 / 0.05) * _phi(-0.05 / 0.031)
    n_steps = 150_000
    assert n_steps * p ** 83 < 1e-160 and n_steps * p ** 4 < 1e-3
    rows = _hover(np.random.default_rng(17), n_steps, 0.15, 0.05, 0.031)
    xs, flags = _run(rows)
    assert flags[:, :3].max() == 0
    assert xs[:, STATE["t_contact"]].max() <= 3 * DT + 1e-12


def test_false_contacts_with_short_windows_match_the_run_count():
    """With 3-step windows, no hysteresis and no range (so the estimate alone decides),
    a contact is set where a run of passes reaches 3. With per-step probability p, the
    expected number over N steps is p^3 + (N - 3)(1 - p) p^3 (a run starting at step 1,
    or after a failure), here 336; the count of a fixed seed lies within 4 standard
    deviations (Poisson) of it."""
    p_pass = _phi(-1.0)                                      # h = 0.15 m, sigma 0.05 m
    n_steps = 100_000
    expected = p_pass ** 3 + (n_steps - 3) * (1 - p_pass) * p_pass ** 3
    assert expected == pytest.approx(336.0, abs=0.1)
    rows = [dict(r, range_valid=0.0) for r in _hover(np.random.default_rng(5), n_steps, 0.15,
                                                     0.05, 0.0)]
    p = _params(contact_time=3 * DT, maybe_time=3 * DT, landed_time=1e3, hold_factor=1.0,
                no_range_factor=1.0)
    _, flags = _run(rows, p=p)
    gc = flags[:, FLAG["ground_contact"]]
    sets = int(gc[0] + np.sum((gc[1:] > 0.5) & (gc[:-1] < 0.5)))
    assert abs(sets - expected) <= 4 * math.sqrt(expected)
    # and by the runs themselves: every set is a run of passes reaching 3
    passes = np.array([r["est_gap"] <= 0.1 for r in rows])
    runs = sum(1 for k in range(2, n_steps) if passes[k - 2:k + 1].all()
               and (k == 2 or not passes[k - 3]))
    assert sets == runs


def _random_inputs(rng, n):
    """Columns of finite states, cues, parameters and steps over many decades and signs."""
    def draw(size):
        scale = 10.0 ** rng.uniform(-300, 300, (size, n))
        pick = rng.integers(0, 4, (size, n))
        v = np.where(pick == 0, 0.0, np.where(pick == 1, rng.standard_normal((size, n)),
                                              rng.choice([-1, 1], (size, n)) * scale))
        return np.where(rng.random((size, n)) < 0.1, np.finfo(float).max
                        * rng.choice([-1, 1], (size, n)), v)
    return (draw(LAND_DETECTOR_STATE.size), draw(LAND_DETECTOR_CUES.size),
            draw(LAND_DETECTOR_PARAMS.size), draw(1))


def test_every_flag_is_0_or_1_and_every_output_finite_for_finite_inputs():
    rng = np.random.default_rng(3)
    n = 20_000
    xs, fl = (np.asarray(v) for v in DETECTOR.map(n)(*_random_inputs(rng, n)))
    assert np.isfinite(xs).all() and np.isfinite(fl).all()
    assert set(np.unique(fl)) <= {0.0, 1.0}
    for name in ("ground_contact", "maybe_landed", "landed"):
        assert set(np.unique(xs[LAND_DETECTOR_STATE.index(name)])) <= {0.0, 1.0}


def test_non_finite_cues_fail_their_tests_and_stay_out_of_the_memory():
    bad = dict(range_gap=np.nan, range_valid=1.0, est_gap=np.nan, est_vz=np.inf,
               thrust_ratio=np.nan, f_z=np.nan, in_descend=np.nan)
    xs, flags = _run([ON_DECK] * 10 + [bad] * 10 + [ON_DECK] * 10)
    assert np.isfinite(xs).all() and flags[:, :3].max() == 0
    # the NaN ranges were not taken: the last finite one (0 m, step 10) ages out
    assert xs[19, STATE["range_gap"]] == 0
    assert xs[19, STATE["range_hold"]] == pytest.approx(0.1 - 10 * DT, abs=1e-15)
    assert xs[19, STATE["f_z_mean"]] == pytest.approx(9.81, abs=1e-14)
    assert flags[10:20, [FLAG["gap_cue"], FLAG["still_cue"], FLAG["thrust_cue"],
                         FLAG["spike_cue"]]].max() == 0


def test_derivative_free_the_flags_are_decisions():
    """The flags are piecewise constant in every input: their Jacobian is zero wherever it
    is defined (no slope of a noisy signal enters a decision)."""
    syms = [LAND_DETECTOR_STATE.sym(), LAND_DETECTOR_CUES.sym(), LAND_DETECTOR_PARAMS.sym(),
            ca.SX.sym("dt")]
    flags = DETECTOR(*syms)[1]
    jac = ca.Function("flag_jacobian", syms, [ca.jacobian(flags, ca.vertcat(*syms))])
    rng = np.random.default_rng(11)
    for _ in range(200):
        x = np.abs(rng.standard_normal(LAND_DETECTOR_STATE.size))
        c = rng.standard_normal(LAND_DETECTOR_CUES.size) * 0.2
        p = _params() * rng.uniform(0.5, 2.0, LAND_DETECTOR_PARAMS.size)
        assert np.all(np.asarray(jac(x, c, p, DT)) == 0)
