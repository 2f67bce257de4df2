"""The sensors' draws in blocks, drawn only as far as the flight goes (issue 20).

A sensor's draws come in blocks of ``BLOCK`` samples, each block from a generator
seeded by the run's seed, the sensor and the block's index alone; the processes run
on across the blocks. So a table drawn to 12 s is the first 12 s of one drawn to
40 s, bit for bit, and a landing draws its table as its flight needs it
(``TickTable.more``, called by the compiled driver at the first tick past the rows
drawn): the same flight, bit for bit, as on the whole table.
"""

from __future__ import annotations

import contextlib

import numpy as np
import pytest
from tick_reference import placed_table

import quadland
from quadland.engine.runs import SIM_ROWS
from quadland.kinds.landing import sensing
from quadland.kinds.landing import simulate as landing_simulate
from quadland.kinds.landing.sensed import TickTable, tick_table
from quadland.kinds.landing.sensing import BLOCK, SensorDraws, draw_sensors, sensor_seed
from quadland.kinds.landing.sensor_settings import SENSOR_DEFAULTS
from quadland.kinds.landing.values import landing_values
from quadland.scenario import load_scenario
from quadland_symbolic.landing.sensed_loop import SENSED_TICK
from quadland_symbolic.landing.sensors import SENSOR_NAMES

#: Off the IMU's grid: the IMU at half the control rate, the vision 1 ms late (its
#: attitude error joins the IMU's process between its samples, as does the
#: rangefinder's at every other tick).
OFF_GRID = {"imu": {"rate_hz": 125.0}, "vision": {"phase": 0.001},
            "rangefinder": {"rate_hz": 250.0}}


def _same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    a, b = np.asarray(a), np.asarray(b)
    return a.shape == b.shape and np.array_equal(a.view(np.uint8), b.view(np.uint8))


@pytest.mark.parametrize("settings", [None, OFF_GRID])
def test_a_window_of_12_s_is_the_first_12_s_of_40_s(settings):
    """Every sensor's times, deliveries and noise drawn to 12 s are those of the draw to
    40 s, cut at 12 s, bit for bit; so are draws extended in uneven steps."""
    long, short = (draw_sensors(settings, d, seed=31) for d in (40.0, 12.0))
    steps = SensorDraws(settings, seed=31)
    for horizon in (0.3, 1.7, 1.71, 5.0, 12.0):
        steps.extend(horizon)
    for name in SENSOR_NAMES:
        k = len(short[name].times)
        assert k == int(np.sum(long[name].times < 12.0 - 1e-9)) > 0
        for field in ("times", "arrival", "delivered", "noise"):
            whole = getattr(long[name], field)[:k]
            assert _same_bits(getattr(short[name], field), whole), (name, field)
        t, delivered, noise = steps.window(name, 0, k)
        assert _same_bits(t, short[name].times) and _same_bits(noise, short[name].noise)
        assert _same_bits(delivered, short[name].delivered)
    # off the grid, the attitude error of the vision and rangefinder is drawn between
    # the IMU's samples (not read from them): the case the test is about
    if settings is OFF_GRID:
        imu_t = long["imu"].times
        assert not np.any(np.isin(long["vision"].times, imu_t))
        assert np.any(~np.isin(long["rangefinder"].times, imu_t))


def test_the_highway_table_to_12_s_is_the_first_12_s_of_the_whole_table():
    """highway's per-tick table: 3,000 ticks (12 s at 250 Hz) against the 10,000 of its
    40 s, and the table drawn as a flight draws it (chunk by chunk, at uneven ticks)."""
    sc = load_scenario("highway")
    whole, short = tick_table(sc, 10_000), tick_table(sc, 3_000)
    assert _same_bits(short, whole[:3_000])
    lazy = TickTable(sc, 10_000, chunk=500, first=1_000)
    lazy.rows[:] = np.nan                             # rows past those drawn: unwritten
    for tick, filled in ((0, 1_000), (1, 1_000), (999, 1_000), (1_000, 1_500),
                         (1_234, 1_500), (2_999, 3_000)):
        assert lazy.more(tick) == filled
    assert lazy.filled == 3_000
    assert _same_bits(lazy.rows[:3_000], whole[:3_000])
    assert np.all(np.isnan(lazy.rows[3_000:]))        # nothing written past the chunk


#: Sensors off one another's clocks: the IMU at half the control rate, the GNSS every
#: 9th tick, the rangefinder every 7th and the vision every 11th from its 3rd (odd
#: periods, so blocks of draws end and the table's chunks cut mid-period), the datalink
#: 1 tick late.
ODD_RATES = ["sensors.imu.rate_hz=125.0", "sensors.gnss.rate_hz=27.77777777777778",
             "sensors.rangefinder.rate_hz=35.714285714285715",
             "sensors.vision.rate_hz=22.727272727272727", "sensors.vision.phase=0.012",
             "sensors.datalink.phase=0.004"]


@pytest.mark.parametrize("overrides", [[], ["sensors.imu.rate_hz=125.0",
                                             "sensors.vision.phase=0.012"], ODD_RATES])
def test_each_sample_is_on_its_own_tick_s_row(overrides):
    """The table against each sensor's samples (``draw_sensors``, the same draws) placed
    one by one on the row of its tick, ``round(t rate)``: its sample flag, delivery and
    noise there, zeros on every other row of its columns; to 12.3 s drawn as a flight
    draws it (chunk by chunk, each sensor's samples written through a strided view
    where its ticks are evenly spaced), and to a tick off the chunks. With the IMU at
    125 Hz (every other row) and the vision 3 ticks late; and at periods of 7, 9 and 11
    ticks (``ODD_RATES``: the chunks of 100 ticks and the blocks of draws end
    mid-period)."""
    sc = load_scenario("highway", overrides)
    rate = sc["controller.rate_hz"]
    settings = {n: dict(sc.data[f"sensors.{n}"]) for n in SENSOR_NAMES}
    for ticks, chunk in ((3_072, None), (1_237, 100)):
        table = TickTable(sc, 10_000, chunk=chunk, first=chunk)
        tick = 0
        while tick < ticks:
            tick = table.more(tick)
        draws = draw_sensors(settings, table.filled / rate, seed=sc["simulation.seed"])
        expect = placed_table(draws, table.rows.shape, rate)
        n = table.filled                              # (the rows past it are unwritten)
        assert _same_bits(table.rows[:n], expect[:n]), (overrides, ticks)


def test_samples_off_an_even_spacing_are_written_row_by_row():
    """``TickTable._place`` given ticks that are not evenly spaced (uneven, or evenly
    spaced but for one) writes each sample on its own tick's row, as it does evenly
    spaced ones (the strided view): placed one by one against the same table."""
    sc = load_scenario("highway")
    width = SENSED_TICK.slice("vision_noise").stop - SENSED_TICK.slice("vision_noise").start
    rng = np.random.default_rng(3)
    for ticks in ([3, 5, 9, 10], [0, 4, 8, 13, 16], [7], [2, 9, 16, 23], [0, 11, 22, 33, 45]):
        ticks = np.array(ticks)
        delivered = rng.random(len(ticks)) < 0.7
        noise = rng.standard_normal((len(ticks), width))
        table = TickTable(sc, 64)
        table.rows[:] = 0.0                           # as `more` zeroes a chunk's rows
        table._place("vision", ticks, delivered, noise)
        expect = np.zeros_like(table.rows)
        for k, kept, z in zip(ticks, delivered, noise, strict=True):
            expect[k, SENSED_TICK.slice("vision_sampled")] = 1.0
            expect[k, SENSED_TICK.slice("vision_kept")] = float(kept)
            expect[k, SENSED_TICK.slice("vision_noise")] = z
        assert _same_bits(table.rows, expect), ticks


def test_a_block_is_drawn_from_its_own_seed():
    """The vision's deliveries re-derived from the documented spawn key: block ``b``'s
    generator, ``(seed, SENSOR_STREAM, stream, 3, b)``, draws the block's uniforms first;
    a sample is delivered when its uniform is at least the dropout."""
    s = draw_sensors(None, 100.0, seed=5)["vision"]
    stream, p = SENSOR_NAMES.index("vision"), SENSOR_DEFAULTS["vision"]["dropout"]
    assert len(s.times) == 2500 > 2 * BLOCK
    expect = np.concatenate([np.random.default_rng(sensor_seed(5, stream, 3, b))
                             .random(BLOCK) >= p for b in range(3)])[:2500]
    np.testing.assert_array_equal(s.delivered, expect)


def _bits(a, b) -> bool:
    cols = set(a.columns)
    return cols == set(b.columns) and all(_same_bits(a[k], b[k]) for k in cols) and \
        _same_bits(a.states, b.states)


@pytest.mark.parametrize("sizes", [{}, {"first": 1_024, "chunk": 500}])
def test_a_flight_on_the_table_drawn_as_it_goes_is_the_flight_on_the_whole_table(
        monkeypatch, sizes):
    """highway flown as the runtime flies it (the table drawn chunk by chunk as the
    driver asks) and on the whole 40 s table drawn beforehand: every column and state
    the same bits; the first drew only the chunks up to its last control tick. The
    runtime's chunks are whole blocks of the IMU's draws (at 250 Hz, 3 x 1,024 ticks the
    first time, then 1,024: the default landing, 11.4 s, needs only the first); smaller
    chunks make the flight ask more often."""
    sc = load_scenario("highway")
    tables = []

    class Recorded(TickTable):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **{**kwargs, **sizes})
            tables.append(self)

    monkeypatch.setattr(landing_simulate, "drawn_table", _drawn(Recorded))
    lazy = quadland.simulate(sc)
    monkeypatch.setattr(landing_simulate, "drawn_table", _drawn(tick_table))
    whole = quadland.simulate(sc)
    assert _bits(lazy, whole)
    (table,) = tables
    rate = sc["controller.rate_hz"]
    last_tick = int(np.floor(lazy["t"][-1] * rate + 1e-6))
    if sizes:
        assert last_tick >= table.first
    else:
        assert (table.first, table.chunk) == (3 * BLOCK, BLOCK) == (3_072, 1_024)
    ahead = 0 if last_tick < table.first else \
        ((last_tick - table.first) // table.chunk + 1) * table.chunk
    assert table.filled == table.first + ahead
    assert table.filled < table.rows.shape[0] == 10_000


def _drawn(make):
    """A stand-in for ``drawn_table``: the run's table made by ``make(scenario, n)``."""
    @contextlib.contextmanager
    def table(scenario, n_ticks):
        yield make(scenario, n_ticks)
    return table


class _Failing:
    """A drawn table whose ``more`` raises, or gives no more rows."""

    def __init__(self, rows: np.ndarray, raises: bool):
        self.rows, self.filled, self.raises, self.asked = rows, 10, raises, []

    def more(self, tick: int) -> int:
        self.asked.append(tick)
        if self.raises:
            raise KeyError("no more")
        return self.filled


@pytest.mark.parametrize("raises", [True, False])
def test_the_driver_asks_at_the_first_tick_past_the_rows_and_stops_without_them(
        monkeypatch, raises):
    """With 10 rows drawn, the driver asks ``more(10)`` at the 11th control tick; what
    ``more`` raises is raised by the simulator's call; a table that gives no more rows
    stops the run there (``SIM_ROWS``, after 10 control ticks: 40 ms at 250 Hz)."""
    sc = load_scenario("highway")
    source = _Failing(np.zeros((10_000, SENSED_TICK.size)), raises)
    runs = []
    real = landing_simulate.landing_loop_part

    def part(*args, **kwargs):
        loop = real(*args, **kwargs)

        class Spy:
            model = loop.model

            def sampled(self, *a, **k):
                k["N"] = source
                runs.append(loop.sampled(*a, **k))
                return runs[-1]

            def __getattr__(self, name):
                return getattr(loop, name)
        return Spy()

    monkeypatch.setattr(landing_simulate, "landing_loop_part", part)
    if raises:
        with pytest.raises(KeyError, match="no more"):
            quadland.simulate(sc)
        assert source.asked == [10]
        return
    with pytest.raises(quadland.SimulationError):
        quadland.simulate(sc)
    assert source.asked == [10]
    assert runs[0].status == SIM_ROWS
    assert runs[0].t_stop == pytest.approx(10 / sc["controller.rate_hz"], abs=1e-12)


def test_the_gear_columns_padded_to_a_bucket_are_the_columns_of_the_exact_map():
    """The gear's signals evaluated on a map of a multiple of 32 rows (the last row
    repeated) against the map of exactly the contact's rows: the same bits."""
    from quadland.kinds.landing import contact_report

    result = quadland.simulate(load_scenario("highway"))
    touched = result["touched"]
    rows = np.flatnonzero(touched > 0.5)
    assert rows.size % contact_report.MAP_BUCKET != 0           # padded here
    held = np.zeros((len(touched), 9))
    pp = landing_values(result.scenario).pp
    cols = contact_report.gear_columns(pp, result["t"], result.states, touched, held)
    f = contact_report.flat_gear_signals().map(rows.size)
    xp = result.states[rows, :contact_report.LANDING_PLANT_STATE.size]
    exact = np.asarray(f(xp.T, held[rows].T, result["t"][None, rows],
                         np.asarray(pp, dtype=float).ravel()), dtype=float)
    for name in contact_report.GEAR_SIGNALS.names():
        assert _same_bits(cols[name][rows], exact[contact_report.GEAR_SIGNALS.slice(name)][0])
        assert np.all(np.isnan(cols[name][touched < 0.5]))


def _poisoned(monkeypatch, fill: tuple[float, bool]) -> None:
    """Every row the draws' arrays make room for (``GrowingRows.reserve``) and no draw has
    written yet holds ``fill`` (float, bool) instead of what ``np.empty`` left there."""
    real = sensing.GrowingRows.reserve

    def reserve(self, rows):
        room = self.arrays[0].shape[0]
        real(self, rows)
        for a in self.arrays:
            a[room:] = fill[1] if a.dtype == bool else fill[0]
    monkeypatch.setattr(sensing.GrowingRows, "reserve", reserve)


@pytest.mark.parametrize("scenario, overrides", [("highway", []), ("ship_ss5", []),
                                                 ("highway", ODD_RATES)])
def test_no_row_past_those_drawn_is_read(monkeypatch, scenario, overrides):
    """The draws' arrays grow without zeroing (``np.empty``): rows past those drawn must
    never reach the table. With those rows holding NaN and True, then +inf and False,
    the 40 s table (a run without a touchdown), drawn chunk by chunk at uneven ticks, and
    every sensor's samples are the same bits, without a NaN: an unwritten row read
    anywhere would make one of the two differ (or carry the NaN)."""
    sc = load_scenario(scenario, overrides)
    n = round(40.0 * sc["controller.rate_hz"])
    out = []
    for fill in ((np.nan, True), (np.inf, False)):
        _poisoned(monkeypatch, fill)
        lazy = TickTable(sc, n, chunk=333, first=97)
        tick = 0
        while tick < n:                          # asked at, and past, the rows drawn
            tick = lazy.more(min(tick + 17 * (tick % 2), n - 1))
        draws = SensorDraws({k: dict(sc.data[f"sensors.{k}"]) for k in SENSOR_NAMES},
                            seed=sc["simulation.seed"])
        for horizon in (0.5, 4.1, 4.1, 17.3, 40.0):
            draws.extend(horizon)
        samples = draws.samples(40.0)
        out.append((lazy.rows, tick_table(sc, n), samples))
    (a, whole_a, sa), (b, whole_b, sb) = out
    assert not np.any(np.isnan(a)) and not np.any(np.isinf(b))
    assert _same_bits(a, b) and _same_bits(a, whole_a) and _same_bits(b, whole_b)
    for name in SENSOR_NAMES:
        for field in ("delivered", "noise"):
            x, y = getattr(sa[name], field), getattr(sb[name], field)
            assert _same_bits(x, y) and not np.any(np.isnan(x)), (name, field)
