"""The sensors' draws as far as the samples go, and the table's chunks (issue 20, fifteenth).

A sensor's block of draws is begun from its generator (its spawn key, the block's
index) and continued, as far as the samples asked for, from the same generator: the
values are those of the whole block, in their order. The IMU's bias walk restarts its
sums at each block (the block's start: the last value of the block before). The table
draws its first chunk, two more, then its rest at once. Checked against the documented
scheme re-derived by hand and against ``draw_sensors`` placed sample by sample.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from tick_reference import placed_table

from quadland.kinds.landing.sensed import TickTable
from quadland.kinds.landing.sensing import (
    BLOCK,
    SENSOR_STREAM,
    SensorDraws,
    draw_sensors,
)
from quadland.kinds.landing.sensor_settings import SENSOR_DEFAULTS
from quadland.scenario import load_scenario
from quadland_symbolic.landing.sensors import NOISES, SENSOR_NAMES

#: Off the IMU's grid (the vision's and rangefinder's blocks draw the attitude error's
#: normals after the whole block's noise normals).
OFF_GRID = {"imu": {"rate_hz": 125.0}, "vision": {"phase": 0.001},
            "rangefinder": {"rate_hz": 250.0}}


def _same_bits(a, b) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and np.array_equal(a.view(np.uint8), b.view(np.uint8))


def test_the_imu_s_walk_and_white_noise_re_derived_from_each_block_s_generator():
    """The IMU's biases and white noise at 2,600 samples (two blocks and part of a third),
    re-derived in Python floats from the spawn key ``(seed, SENSOR_STREAM, 0, 3, b)``:
    the block's dropout uniforms, the turn-on biases (block 0), then 18 normals a sample;
    ``b_k = start + sum of the block's steps w sqrt(dt) n`` (the first sample's step
    none), ``n_k = d sqrt(rate) n``; drawn at once and extended in uneven steps."""
    s, seed, n = SENSOR_DEFAULTS["imu"], 11, 2_600
    h, lay = 1.0 / s["rate_hz"], NOISES["imu"]
    walk = [s["accel_bias_random_walk"]] * 3 + [s["gyro_bias_random_walk"]] * 3
    dens = [s["accel_noise_density"] * math.sqrt(s["rate_hz"])] * 3 + \
        [s["gyro_noise_density"] * math.sqrt(s["rate_hz"])] * 3
    bias, white, start = [], [], None
    for b in range(-(-n // BLOCK)):
        rng = np.random.default_rng(np.random.SeedSequence(
            seed, spawn_key=(SENSOR_STREAM, 0, 3, b)))
        rng.random(BLOCK)                                   # the deliveries' uniforms
        if b == 0:
            start = [s["accel_bias_sigma"] * v for v in rng.standard_normal(3)] + \
                [s["gyro_bias_sigma"] * v for v in rng.standard_normal(3)]
        z = rng.standard_normal((BLOCK, 18)).tolist()
        sums = [0.0] * 6
        for i in range(BLOCK):
            k = b * BLOCK + i
            dt = (s["phase"] + h * k) - (s["phase"] + h * (k - 1))
            for j in range(6):
                step = 0.0 if k == 0 else walk[j] * math.sqrt(dt) * z[i][j]
                sums[j] = sums[j] + step
            bias.append([start[j] + sums[j] for j in range(6)])
            white.append([dens[j] * z[i][6 + j] for j in range(6)])
        start = bias[-1]
    bias, white = np.array(bias[:n]), np.array(white[:n])
    whole = draw_sensors(None, n * h, seed)["imu"].noise
    steps = SensorDraws(None, seed)
    for horizon in (0.5, 4.092, 4.096, 4.1, 7.0, 8.2, n * h):
        steps.extend(horizon)
    for noise in (whole, steps.sensors["imu"].noise[:n]):
        assert len(noise) == n
        for name, cols in (("b_a", bias[:, :3]), ("b_g", bias[:, 3:]),
                           ("n_a", white[:, :3]), ("n_g", white[:, 3:])):
            assert _same_bits(noise[:, lay.slice(name)], cols), name


@pytest.mark.parametrize("settings", [None, OFF_GRID])
def test_draws_extended_sample_by_sample_across_a_block_are_the_whole_draw(settings):
    """Every sensor's deliveries and noise (the attitude error's too), drawn to 20 s
    at once and extended one IMU sample at a time across the end of its first block,
    then in uneven steps that end mid-block: the same bits; off the IMU's grid the
    vision's and rangefinder's blocks draw their attitude normals after the block's."""
    whole = draw_sensors(settings, 20.0, seed=23)
    rate = (settings or {}).get("imu", {}).get("rate_hz", SENSOR_DEFAULTS["imu"]["rate_hz"])
    steps = SensorDraws(settings, seed=23)
    for k in range(BLOCK - 3, BLOCK + 4):
        steps.extend((k + 0.5) / rate)
    for horizon in (9.37, 9.371, 13.0, 16.5, 20.0):
        steps.extend(horizon)
    for name in SENSOR_NAMES:
        k = len(whole[name].times)
        assert k > 0
        t, delivered, noise = steps.window(name, 0, k)
        assert _same_bits(noise, whole[name].noise), name
        assert _same_bits(delivered, whole[name].delivered), name


@pytest.mark.parametrize(("overrides", "chunks"), [
    ([], [3_072, 4_096, 5_120, 10_000]),
    (["sensors.imu.rate_hz=125.0", "sensors.vision.phase=0.012"],   # blocks of 2,048 ticks
     [4_096, 6_144, 8_192, 10_000])])
def test_the_default_table_to_40_s_places_each_sample_on_its_tick(overrides, chunks):
    """The table with its default chunks, drawn as a flight without a touchdown draws
    it (at 250 Hz 12.3 s, two chunks of 4.1 s, then the rest at once), against each sensor's
    samples of ``draw_sensors`` placed one by one on the row of its tick, zeros on every
    other row of its columns; rows past those drawn left as they were (NaN here)."""
    sc = load_scenario("highway", overrides)
    rate = sc["controller.rate_hz"]
    table = TickTable(sc, 10_000)
    table.rows[:] = np.nan
    ends, tick = [], 0
    while tick < 10_000:
        tick = table.more(tick)
        ends.append(tick)
        if tick < 10_000:
            assert np.all(np.isnan(table.rows[tick:]))
    assert ends == chunks
    settings = {n: dict(sc.data[f"sensors.{n}"]) for n in SENSOR_NAMES}
    draws = draw_sensors(settings, 40.0, seed=sc["simulation.seed"])
    assert _same_bits(table.rows, placed_table(draws, table.rows.shape, rate))


def test_off_the_imu_s_grid_a_vision_block_draws_its_attitude_normals_after_its_noise():
    """The vision 1 ms off the IMU's 125 Hz grid, 1,324 samples (a block and part of a
    second), re-derived from the spawn key ``(seed, SENSOR_STREAM, vision, 3, b)``: the
    deliveries' and outliers' uniforms, the block's 6 noise normals a sample (3 white,
    3 outliers'), then its 6 attitude normals a sample (the attitude error's bridge
    between the IMU's samples); drawn at once and extended in steps ending mid-block."""
    settings, seed, n = {"imu": {"rate_hz": 125.0}, "vision": {"phase": 0.001}}, 11, BLOCK + 300
    s, lay = SENSOR_DEFAULTS["vision"], NOISES["vision"]
    stream = SENSOR_NAMES.index("vision")
    delivered, white, outlier, att = [], [], [], []
    for b in range(2):
        rng = np.random.default_rng(np.random.SeedSequence(
            seed, spawn_key=(SENSOR_STREAM, stream, 3, b)))
        kept = (rng.random(BLOCK) >= s["dropout"]).tolist()
        hit = (rng.random(BLOCK) < s["outlier_rate"]).tolist()
        z = rng.standard_normal((BLOCK, 6)).tolist()
        a = rng.standard_normal((BLOCK, 6)).tolist()
        delivered += kept
        white += [row[:3] for row in z]
        outlier += [[s["outlier_sigma"] * v if h else 0.0 for v in row[3:]]
                    for h, row in zip(hit, z, strict=True)]
        att += a
    horizon = (n - 0.5) / s["rate_hz"]
    whole = SensorDraws(settings, seed)
    whole.extend(horizon)
    steps = SensorDraws(settings, seed)
    for t in (0.3, 20.01, 40.93, 40.97, 41.0, horizon):
        steps.extend(t)
    for draws in (whole, steps):
        v = draws.sensors["vision"]
        assert v.n >= n
        assert _same_bits(v.delivered[:n], np.array(delivered[:n]))
        assert _same_bits(v.att_normals[:n], np.array(att[:n]))
        assert _same_bits(v.noise[:n, lay.slice("n_r")], np.array(white[:n]))
        assert _same_bits(v.noise[:n, lay.slice("o_r")], np.array(outlier[:n]))


def test_past_its_chunks_a_long_table_draws_twice_its_rows_not_its_whole_rest():
    """ship_ss5's 180 s table (45,000 ticks at 250 Hz), asked at the first tick past its
    rows as a flight asks: the first chunk and two more (to 20.5 s), then twice the rows
    drawn each time, at most the table (a flight touching down at 25 s draws 41 s of it,
    not 180 s); each end's rows against the table drawn whole, rows past it untouched
    (NaN)."""
    sc = load_scenario("ship_ss5")
    n = round(sc["simulation.duration"] * sc["controller.rate_hz"])
    assert n == 45_000
    table = TickTable(sc, n)
    table.rows[:] = np.nan
    whole = TickTable(sc, n, first=n)
    whole.more(0)
    ends, tick = [], 0
    while tick < n:
        tick = table.more(tick)
        ends.append(tick)
        assert _same_bits(table.rows[:tick], whole.rows[:tick])
        assert np.all(np.isnan(table.rows[tick:]))
    assert ends == [3_072, 4_096, 5_120, 10_240, 20_480, 40_960, 45_000]


def test_the_rows_reserved_for_the_chunks_are_the_rows_each_sensor_reads():
    """A first chunk of 100 ticks (0.4 s) with the GNSS's first fix at 8 s: the first
    ``more`` reserves each sensor's rows up to the chunks' end (100 + 2 x 1,024 = 2,148
    ticks, 8.592 s) before drawing; by hand the IMU's 2,148 samples, the vision's 215
    (every 10th tick), the rangefinder's 1,074 (every 2nd), the datalink's 86 (every 25th)
    and the GNSS's 3 (ticks 2,000, 2,050, 2,100), none of which it draws yet. Each sensor's
    rows seen (its ``noise`` and ``delivered``) are those reserved rows, the GNSS's too, and
    the table's ``nbytes`` counts them; the table then drawn to 40 s against each sample
    of ``draw_sensors`` placed on its tick, rows past those drawn untouched (NaN)."""
    sc = load_scenario("highway", ["sensors.gnss.phase=8.0"])
    rate = sc["controller.rate_hz"]
    table = TickTable(sc, 10_000, first=100)
    table.rows[:] = np.nan
    assert table.more(0) == 100
    room = {"imu": 2_148, "vision": 215, "gnss": 3, "rangefinder": 1_074, "datalink": 86}
    drawn = {"imu": 100, "vision": 10, "gnss": 0, "rangefinder": 50, "datalink": 4}
    for name, sen in table.draws.sensors.items():
        assert len(sen.noise) == len(sen.delivered) == drawn[name], name
        assert sen.noise.base.shape == (room[name], NOISES[name].size), name
        assert sen.delivered.base.shape == (room[name],), name
    rows = sum(room[n] * (1 + 8 * NOISES[n].size + 8 * 6) for n in SENSOR_NAMES)
    assert table.nbytes >= table.rows.nbytes + rows
    tick = 100
    while tick < 10_000:
        assert np.all(np.isnan(table.rows[tick:]))
        tick = table.more(tick)
    settings = {n: dict(sc.data[f"sensors.{n}"]) for n in SENSOR_NAMES}
    draws = draw_sensors(settings, 40.0, seed=sc["simulation.seed"])
    assert _same_bits(table.rows, placed_table(draws, table.rows.shape, rate))
