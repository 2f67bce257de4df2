"""An envelope's draws kept between its runs (issue 20): the sensors' table and the force
and moment noise of a replicate, drawn once in a process and flown in every cell.

The claim under test: in an envelope, run ``r`` of every cell has replicate ``r``'s
seed and drawn values with the axes' values in place, so what a landing draws from its
seed and its sensor settings does not depend on the cell, unless an axis sets one of
those settings. Each check compares against draws made afresh from the cell's own
scenario (no keeping), bit for bit.
"""

import contextlib
import csv

import numpy as np
import pytest

from quadland.campaign import grid
from quadland.campaign.dispersed import dispersed
from quadland.campaign.grid import KEEP_BYTES, cell_draws, plan_envelope, run_envelope
from quadland.engine.kept import KEPT, KeptDraws, keeping, kept_bytes
from quadland.kinds import kind_of
from quadland.kinds.landing import sensed, simulate
from quadland.kinds.landing.sensed import TickTable, table_key, tick_table
from quadland.kinds.landing.values import landing_clocks, landing_disturbance, wind_samples

MAP = ["initial.velocity2[0]=5:35:20", "wind.mean[1]=0:20:20"]


def _bits(a):
    return np.ascontiguousarray(a).view(np.uint8).tobytes()


@pytest.fixture(scope="module")
def env():
    return plan_envelope("highway", None, MAP, 3)


def _scenario(env, cell, replicate):
    draw = next(cell_draws(env, [cell * env.runs_per_cell + replicate]))
    return dispersed(env.base, draw.values)


@pytest.fixture(autouse=True)
def _nothing_kept():
    KEPT.clear()
    yield
    KEPT.clear()


def test_the_map_s_axes_do_not_enter_a_replicate_s_table(env):
    """Replicate 1 in the map's corners and middle: other car speeds, crosswinds and drive
    forces, one table key; replicate 2's is another (its seed and sensor draws)."""
    cells = (0, 19, 210, 380, 399)
    keys, where = [], set()
    for c in cells:
        sc = _scenario(env, c, 1)
        keys.append(table_key(sc, landing_clocks(sc)[2].count()))
        where.add((sc.data["initial"]["velocity2"][0], sc.data["wind"]["mean"][1],
                   sc.data["vehicle"]["tau"][0]))
    assert len(set(keys)) == 1
    assert len(where) == len(cells)                 # the cells do differ
    other = _scenario(env, 0, 2)
    assert table_key(other, landing_clocks(other)[2].count()) != keys[0]


def test_a_kept_table_is_the_freshly_drawn_table_bit_for_bit(env):
    """The table a flight in one cell drew (as far as that flight went) is, row for row,
    the table drawn afresh from another cell's scenario of the same replicate, and goes
    on as that table does when a longer flight extends it."""
    a, b = _scenario(env, 399, 0), _scenario(env, 0, 0)    # 35 m/s and 20 m/s crosswind
    n = landing_clocks(b)[2].count()
    with keeping(KEEP_BYTES):
        kind_of(a).simulate(a)
    kept = KEPT.take(table_key(b, n))
    assert kept is not None and 0 < kept.filled <= n
    fresh = TickTable(b, n)
    fresh.more(kept.filled - 1)
    assert fresh.filled == kept.filled
    assert _bits(kept.rows[:kept.filled]) == _bits(fresh.rows[:fresh.filled])
    kept.more(n - 1)                               # on to the end, as a 40 s flight asks
    assert kept.filled == n
    assert _bits(kept.rows) == _bits(tick_table(b, n))


def test_a_flight_on_a_kept_table_is_the_flight_on_fresh_draws(env):
    """Every column of a landing flown on the table (and force and moment noise) kept
    from another cell's flight is the landing flown on its own draws, bit for bit."""
    a, b = _scenario(env, 5, 2), _scenario(env, 233, 2)
    kind = kind_of(b)
    alone = kind.simulate(b)
    n = landing_clocks(b)[2].count()
    with keeping(KEEP_BYTES):
        kind.simulate(a)
        table = KEPT.take(table_key(b, n))
        KEPT.give(table_key(b, n), table, table.nbytes)
        again = kind.simulate(b)
    assert KEPT.take(table_key(b, n)) is table      # flown on the kept one, given back
    assert alone.columns.keys() == again.columns.keys()
    for name, col in alone.columns.items():
        assert _bits(col) == _bits(again.columns[name]), name
    assert _bits(alone.states) == _bits(again.states)


def test_the_kept_force_and_moment_noise_is_the_drawn_one(env):
    a, b = _scenario(env, 3, 1), _scenario(env, 396, 1)
    times = landing_clocks(b)[1].times()
    fresh = landing_disturbance(b, times)
    with keeping(KEEP_BYTES):
        landing_disturbance(a, times)
        assert len(KEPT) == 3                       # the noise, the wind's normals and gust
        kept = landing_disturbance(b, times)
        assert len(KEPT) == 3                       # the same entries, read again
    assert _bits(kept) == _bits(fresh)
    assert _bits(kept[:3]) != _bits(landing_disturbance(a, times)[:3])   # the wind is not


def test_the_wind_on_kept_normals_and_gust_is_the_drawn_wind(env):
    """The wind of a run whose turbulence normals and gust were kept from other cells'
    runs of its replicate (other car speeds and crosswinds, so other airspeeds in the
    turbulence's filter) is the wind its own scenario draws afresh, bit for bit, in the
    map's corners and middle; another replicate's is not read."""
    cells = (0, 19, 210, 380, 399)
    for i, replicate in enumerate((0, 2)):
        scenarios = [_scenario(env, c, replicate) for c in cells]
        times = landing_clocks(scenarios[0])[1].times()
        fresh = [wind_samples(sc, times) for sc in scenarios]
        with keeping(KEEP_BYTES):
            kept = [wind_samples(sc, times) for sc in scenarios]
            assert len(KEPT) == 2 * (i + 1)         # a replicate's normals and its gust
            normals = KEPT.shared(("wind normals", scenarios[0].data["simulation"]["seed"],
                                   len(times)), lambda: None)
        rng = np.random.default_rng((scenarios[0].data["simulation"]["seed"], 1))
        assert _bits(normals) == _bits(rng.standard_normal((len(times), 3)))
        for k, f in zip(kept, fresh, strict=True):
            assert _bits(k) == _bits(f)
        assert len({_bits(f) for f in fresh}) == len(cells)     # the cells' winds differ


def test_an_axis_on_the_gust_gives_each_cell_its_own_gust():
    """A wind.gust_start axis: the cells of one replicate share the turbulence's normals
    but not the gust, and each cell's wind is its fresh one."""
    env = plan_envelope("highway", None, ["wind.gust_start=4:9:2", "wind.mean[1]=0:5:2"], 2)
    a, b = _scenario(env, 0, 1), _scenario(env, 2, 1)
    times = landing_clocks(a)[1].times()
    fresh = [wind_samples(a, times), wind_samples(b, times)]
    with keeping(KEEP_BYTES):
        kept = [wind_samples(a, times), wind_samples(b, times)]
        assert len(KEPT) == 3                       # one normals, two gusts
    assert [_bits(k) for k in kept] == [_bits(f) for f in fresh]
    assert _bits(fresh[0]) != _bits(fresh[1])


def test_an_axis_on_the_sensors_draws_each_cell_s_own_table():
    """A sensors.* axis changes the table: no cell is flown on another's, each table is its
    own cell's fresh draws, and the GNSS's velocity noise differs between them."""
    env = plan_envelope("highway", None, ["sensors.gnss.velocity_sigma=0.05:0.1:2",
                                          "wind.mean[1]=0:5:2"], 2)
    a, b = _scenario(env, 0, 1), _scenario(env, 2, 1)    # the same replicate, other sigma
    n = landing_clocks(a)[2].count()
    assert table_key(a, n) != table_key(b, n)
    with keeping(KEEP_BYTES):
        kind_of(a).simulate(a)
        assert KEPT.take(table_key(b, n)) is None
        kind_of(b).simulate(b)
        ta, tb = KEPT.take(table_key(a, n)), KEPT.take(table_key(b, n))
    assert ta is not None and tb is not None and ta is not tb
    m = min(ta.filled, tb.filled)
    fresh = tick_table(b, m)
    assert _bits(tb.rows[:m]) == _bits(fresh)
    gnss = sensed.SENSED_TICK.slice("gnss_noise")
    assert _bits(ta.rows[:m, gnss]) != _bits(tb.rows[:m, gnss])
    other = np.ones(sensed.SENSED_TICK.size, dtype=bool)
    other[gnss] = False
    assert _bits(ta.rows[:m, other]) == _bits(tb.rows[:m, other])


def test_the_store_keeps_within_its_bytes_and_nothing_outside_keeping():
    store = KeptDraws()
    assert kept_bytes() == 0
    store.give("a", object(), 10)
    assert len(store) == 0 and store.take("a") is None
    with keeping(100):
        one, two, three = object(), object(), object()
        store.give("a", one, 40)
        store.give("a", two, 40)                    # two copies: two threads' runs
        store.give("b", three, 40)                  # over 100: the oldest given up
        assert store.bytes == 80 and len(store) == 2
        assert store.take("a") is two and store.take("a") is None
        store.give("c", object(), 101)              # alone over the limit: not kept
        assert store.take("c") is None and store.take("b") is three
        made = store.shared("s", lambda: np.arange(4.0))
        assert not made.flags.writeable and store.shared("s", lambda: None) is made
        assert store.bytes == 32                     # "b" taken, "s" kept
        times = np.arange(3.0).tobytes()            # a key holding an array's bytes: counted
        store.shared(("t", times), lambda: np.zeros(1))
        assert store.bytes == 32 + 8 + 24 and len(store) == 2
    assert kept_bytes() == 0


def _rows(folder):
    with open(folder / "runs.csv", newline="") as fh:
        return list(csv.reader(fh))


@pytest.mark.parametrize("workers", [1, pytest.param(2, marks=pytest.mark.slow)])
def test_an_envelope_keeping_its_draws_writes_the_runs_csv_of_one_that_does_not(
        tmp_path, monkeypatch, workers):
    """The map's corners, 3 replicates a cell: the same runs.csv bytes with and without
    the kept draws; in one process, flown replicate by replicate, one table a replicate."""
    axes = ["initial.velocity2[0]=5:35:2", "wind.mean[1]=0:20:2"]
    drawn = []

    class Counted(TickTable):
        def __init__(self, *args, **kwargs):
            drawn.append(1)
            super().__init__(*args, **kwargs)

    monkeypatch.setattr(sensed, "TickTable", Counted)
    monkeypatch.setattr(grid, "KEEP_BYTES", 0)
    run_envelope("highway", None, axes, 3, tmp_path / "fresh", workers=1, plots=False)
    assert len(drawn) == 12 + 1                     # and warm_up's
    monkeypatch.setattr(grid, "KEEP_BYTES", KEEP_BYTES)
    del drawn[:]
    run_envelope("highway", None, axes, 3, tmp_path / "kept", workers=workers, plots=False)
    if workers == 1:
        assert len(drawn) == 3 + 1 and len(KEPT) == 0   # given up after the envelope
    assert (tmp_path / "kept" / "runs.csv").read_bytes() == \
        (tmp_path / "fresh" / "runs.csv").read_bytes()
    assert len(_rows(tmp_path / "kept")) == 1 + 12


def _changed(value):
    """A nearby value of a setting: a bool flipped, numbers half as large again."""
    if isinstance(value, bool):
        return not value
    if isinstance(value, (tuple, list)):
        return type(value)(_changed(v) for v in value)
    return 1.5 * value if value else 0.01


def test_every_input_that_changes_a_table_changes_its_key():
    """Each setting of every sensor, the seed, sensors.random, the control rate and the
    duration changed one at a time: whenever the table drawn afresh (its first 12 s)
    differs from the scenario's, so does the key (equal keys never hide other draws);
    the settings no table reads (the airframe, the wind) leave the key as it is."""
    from quadland.exceptions import ScenarioError
    from quadland.scenario import load_scenario

    base = load_scenario("highway")

    def drawn(sc):
        n = landing_clocks(sc)[2].count()
        return table_key(sc, n), n, tick_table(sc, min(n, 3000))

    key0, n0, rows0 = drawn(base)
    changes = {"simulation.seed": base.data["simulation"]["seed"] + 1,
               "sensors.random": False, "controller.rate_hz": 500.0,
               "simulation.duration": base.data["simulation"]["duration"] + 4.0}
    for name, settings in sensed.sensor_settings(base).items():
        changes.update({f"sensors.{name}.{k}": _changed(v) for k, v in settings.items()})
    changes.update({"sensors.imu.rate_hz": 125.0, "sensors.vision.rate_hz": 50.0,   # valid
                    "sensors.gnss.rate_hz": 10.0, "sensors.vision.phase": 0.04,     # clocks
                    "sensors.gnss.phase": 0.2})
    differ, tried = set(), 0
    for dotted, value in changes.items():
        try:
            sc = base.replace(**{dotted: value})
        except ScenarioError:                       # e.g. a rate that divides no other
            continue
        tried += 1
        key, n, rows = drawn(sc)
        if n != n0 or _bits(rows) != _bits(rows0):
            differ.add(dotted)
            assert key != key0, dotted
    assert tried > 40
    assert {"simulation.seed", "sensors.random", "controller.rate_hz", "simulation.duration",
            "sensors.gnss.velocity_sigma", "sensors.imu.gyro_noise_density",
            "sensors.imu.rate_hz", "sensors.vision.rate_hz", "sensors.gnss.rate_hz",
            "sensors.vision.phase", "sensors.gnss.phase"} <= differ
    for dotted, value in {"quadrotor.mass": 1.5 * base.data["quadrotor"]["mass"],
                          "wind.mean": [1.0, 2.0, 0.0]}.items():
        sc = base.replace(**{dotted: value})
        assert drawn(sc)[0] == key0, dotted


def test_a_run_that_raises_mid_flight_gives_its_table_up(env, monkeypatch):
    """A table whose drawing raised in the middle of a flight is not kept: the next run of
    the replicate draws its own."""
    sc = _scenario(env, 7, 0)
    n = landing_clocks(sc)[2].count()
    more = TickTable.more

    def failing(self, tick):
        if self.filled:                             # the second chunk: mid-flight
            self.rows[self.filled:] = np.nan        # (half drawn)
            raise RuntimeError("drawing failed")
        return more(self, tick)

    monkeypatch.setattr(TickTable, "more", failing)
    with keeping(KEEP_BYTES), pytest.raises(RuntimeError, match="drawing failed"):
        kind_of(sc).simulate(sc)
    assert len(KEPT) == 3                           # the force noise, the wind's normals
                                                    # and gust alone
    with keeping(KEEP_BYTES):
        assert KEPT.take(table_key(sc, n)) is None


def test_two_threads_flying_one_replicate_each_fly_a_table_of_their_own(env, monkeypatch):
    """Two threads of one process fly two cells of one replicate at once, one table kept
    from an earlier flight: each flies on a table no other flight holds, and each flight
    is the flight on its own fresh draws, bit for bit."""
    import threading

    a, b, c = (_scenario(env, cell, 1) for cell in (12, 150, 377))
    alone = {name: kind_of(sc).simulate(sc) for name, sc in (("b", b), ("c", c))}
    with keeping(KEEP_BYTES):
        kind_of(a).simulate(a)                      # one table of replicate 1 kept
    n = landing_clocks(b)[2].count()
    assert len(KEPT) == 4                           # the table, the force noise, the
                                                    # wind's normals and gust

    both, holders = threading.Barrier(2, timeout=120), {}
    drawn_table = simulate.drawn_table

    @contextlib.contextmanager
    def met(scenario, n_ticks):
        with drawn_table(scenario, n_ticks) as table:
            holders[threading.current_thread().name] = table
            both.wait()                             # both flights hold a table at once
            yield table

    monkeypatch.setattr(simulate, "drawn_table", met)
    results, errors = {}, []

    def fly(name, sc):
        try:
            with keeping(KEEP_BYTES):
                results[name] = kind_of(sc).simulate(sc)
        except BaseException as exc:                # reported below
            errors.append(exc)

    threads = [threading.Thread(target=fly, args=(name, sc), name=name)
               for name, sc in (("b", b), ("c", c))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    assert holders["b"] is not holders["c"]
    for name in ("b", "c"):
        for col, values in alone[name].columns.items():
            assert _bits(values) == _bits(results[name].columns[col]), (name, col)
    with keeping(KEEP_BYTES):
        kept = [KEPT.take(table_key(b, n)) for _ in range(3)]
    assert kept[0] is not None and kept[1] is not None and kept[2] is None
    assert {id(kept[0]), id(kept[1])} == {id(holders["b"]), id(holders["c"])}


def test_every_input_of_the_wind_changes_its_kept_key_or_is_computed_each_run():
    """Review of issue 20 (seventeenth session): every setting the wind reads (the seed,
    the duration and the disturbance's rate, so the sample count and spacing, each
    ``wind.*`` key, turbulence off, a gust off, the airspeed's velocities and heading, the
    hover point's height) changed one at a time, all flown in one keeping block after the
    scenario's own wind: each is the wind drawn afresh from its own scenario, bit for bit,
    so no kept normals or gust stand in for other draws. The store then holds one normals
    entry per (seed, sample count) and one gust per gust and times, as its keys say."""
    from quadland.exceptions import ScenarioError
    from quadland.scenario import load_scenario

    base = load_scenario("highway")
    w = base.data["wind"]
    changes = {f"wind.{k}": _changed(v) for k, v in w.items()}
    changes.update({"simulation.seed": base.data["simulation"]["seed"] + 1,
                    "simulation.duration": base.data["simulation"]["duration"] + 4.0,
                    "disturbance.sample_rate_hz": 50.0, "wind.turbulence_w20": 0.0,
                    "wind.gust_amplitude": 0.0, "wind.gust_direction": [1.0, 0.0, 0.0],
                    "initial.velocity2": [31.0, 0.5], "initial.psi2_deg": 30.0,
                    "deck.height": base.data["deck"]["height"] + 2.0,
                    "landing.hover_height": 5.0})
    scenarios = {"": base}
    for dotted, value in changes.items():
        try:
            scenarios[dotted] = base.replace(**{dotted: value})
        except ScenarioError:
            continue
    assert len(scenarios) > 14

    def times_of(sc):
        return landing_clocks(sc)[1].times()

    fresh = {k: wind_samples(sc, times_of(sc)) for k, sc in scenarios.items()}
    with keeping(KEEP_BYTES):
        kept = {k: wind_samples(sc, times_of(sc)) for k, sc in scenarios.items()}
        again = wind_samples(base, times_of(base))            # after all the others
        base_times = times_of(base)                             # the same count, other dt
        stretched = wind_samples(base, 1.5 * base_times)
        entries = len(KEPT)
    for k in scenarios:
        assert _bits(kept[k]) == _bits(fresh[k]), k
    assert _bits(again) == _bits(fresh[""])
    assert _bits(stretched) == _bits(wind_samples(base, 1.5 * base_times))
    differ = {k for k in scenarios if k and _bits(fresh[k]) != _bits(fresh[""])}
    # the drag alone reads the air's density; a heading turns the ground speed, whose
    # norm (the airspeed through a calm mean wind) it leaves as it is
    assert set(scenarios) - differ == {"", "wind.air_density", "initial.psi2_deg"}
    normals = {(sc.data["simulation"]["seed"], len(times_of(sc))) for sc in scenarios.values()}
    gusts = {(repr(sorted((g, sc.data["wind"][g]) for g in sc.data["wind"] if "gust" in g)),
              times_of(sc).tobytes()) for sc in scenarios.values()
             if sc.data["wind"]["gust_amplitude"] > 0}
    assert entries == len(normals) + len(gusts) + 1             # and the stretched gust


def test_a_campaign_keeps_no_wind_nor_any_other_draws(tmp_path, monkeypatch):
    """A campaign flown in this process leaves the store empty, and its runs draw their
    wind afresh: wind_samples is never asked inside keeping."""
    from quadland.campaign.execute import run_campaign
    from quadland.kinds.landing import values

    asked = []
    fresh_wind = values.wind_samples

    def counted(scenario, times):
        asked.append(kept_bytes())
        return fresh_wind(scenario, times)

    monkeypatch.setattr(values, "wind_samples", counted)
    run_campaign("highway", None, 3, tmp_path / "c", workers=1, plots=False)
    assert len(asked) >= 3 and set(asked) == {0}
    assert len(KEPT) == 0
