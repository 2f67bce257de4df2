"""A campaign run's Python around its flight, cut without changing a bit (issue 20).

CasADi's functions called on numbers through their buffers
(:class:`quadland.engine.direct_call.DirectCall`) against the ``casadi.DM`` calls they
replace; one touchdown report per result; the sampled driver's row buffers left
unzeroed (every row it returns written whole); the envelope's cells checked as far as
they change the scenario, refused as the full validation refuses them.
"""

import casadi as ca
import numpy as np
import pytest

import quadland
from quadland.campaign.dispersed import dispersed
from quadland.campaign.grid import cell_draws, plan_envelope
from quadland.cli import main
from quadland.engine import compiled, runs
from quadland.engine.direct_call import DirectCall
from quadland.kinds.landing import report
from quadland.scenario import load_scenario
from quadland_symbolic.landing.deck import DECK_PARAMS, deck_function
from quadland_symbolic.landing.estimator import (
    FLIGHT_COUPLING,
    FLIGHT_DEPTH,
    N_HIST,
    estimator_init_function,
)
from quadland_symbolic.landing.loop import landing_gear_signals_function
from quadland_symbolic.landing.relative import touchdown_figures_function

MAP = ["initial.velocity2[0]=5:35:20", "wind.mean[1]=0:20:20"]


def _dm(f, args):
    out = f(*args)
    out = out if isinstance(out, tuple | list) else [out]
    return [np.asarray(o, dtype=float) for o in out]


def _same(a, b):
    return a.shape == b.shape and np.ascontiguousarray(a).tobytes() == \
        np.ascontiguousarray(b).tobytes()


def _random_args(f, rng, scale):
    args = []
    for i in range(f.n_in()):
        shape = (f.size1_in(i), f.size2_in(i))
        a = rng.normal(0.0, scale, size=shape)
        a[rng.random(shape) < 0.1] = 0.0
        a[rng.random(shape) < 0.05] = -0.0
        args.append(a.ravel() if shape[1] == 1 else a)
    return args


@pytest.mark.parametrize("name", ["deck", "touchdown_figures", "estimator_init", "gear_map"])
def test_a_direct_call_is_the_dm_call_bit_for_bit(name):
    """Random arguments (zeros and negative zeros among them; the deck's sinusoids and the
    plant's parameters at their scale): every output the DM call's bits and shape."""
    gear = landing_gear_signals_function()
    f = {"deck": deck_function(), "touchdown_figures": touchdown_figures_function(),
         "estimator_init": estimator_init_function(N_HIST, FLIGHT_DEPTH, FLIGHT_COUPLING),
         "gear_map": gear.map(64, [n == "pp" for n in gear.name_in()],
                              [False] * gear.n_out())}[name]
    call, rng = DirectCall(f), np.random.default_rng(20)
    for trial in range(40):
        args = _random_args(f, rng, [0.1, 1.0, 10.0][trial % 3])
        if name == "deck":                      # deck params: the drive's times positive
            args[3] = np.abs(args[3]) + DECK_PARAMS.zeros()
        expected, got = _dm(f, args), call(*args)
        assert len(expected) == len(got)
        for e, g in zip(expected, got, strict=True):
            assert _same(e, g), (name, trial)


def test_a_direct_call_reads_matrices_in_column_order_and_refuses_what_it_cannot_take():
    x = ca.SX.sym("x", 2, 3)
    y = ca.SX.sym("y")
    f = ca.Function("f", [x, y], [ca.sin(x) * y, ca.sum2(x), ca.mtimes(x.T, x)])
    A = np.arange(6.0).reshape(2, 3) / 7
    for a in (A, np.asfortranarray(A)):
        got = DirectCall(f)(a, 0.3)
        for e, g in zip(_dm(f, [a, 0.3]), got, strict=True):
            assert _same(e, g)
    with pytest.raises(TypeError, match="takes 2 arguments"):
        DirectCall(f)(A)
    with pytest.raises(ValueError, match="has 2x3 entries"):
        DirectCall(f)(np.zeros(5), 0.3)
    s = ca.SX.sym("s", ca.Sparsity.diag(3))
    with pytest.raises(ValueError, match="sparse"):
        DirectCall(ca.Function("g", [s], [s * 2]))


def _envelope_scenarios(indices):
    env = plan_envelope("highway", None, MAP, 30)
    return [dispersed(env.base, d.values) for d in cell_draws(env, indices)], env


def test_a_runs_metrics_read_one_touchdown_report(monkeypatch):
    """The metrics, the false touchdown and the gear's failures of a run: one report,
    and the same as each read from a fresh report."""
    scenarios, env = _envelope_scenarios([0, 5000])
    kind = quadland.kind_of(env.base)
    real, calls = report.touchdown_report, []

    def counted(result):
        calls.append(1)
        return real(result)

    for sc in scenarios:
        result = quadland.simulate(sc)
        calls.clear()
        monkeypatch.setattr(report, "_LAST", (None, None))
        monkeypatch.setattr(report, "touchdown_report", counted)
        metrics = kind.run_metrics(result)
        missed = kind.judge(result, metrics, kind.limits(sc, env.spec.limits))
        assert len(calls) == 1
        monkeypatch.setattr(report, "_report", real)   # a fresh report at each reader
        assert kind.run_metrics(result) == metrics
        assert kind.judge(result, metrics, kind.limits(sc, env.spec.limits)) == missed
        monkeypatch.undo()


def test_rows_past_those_the_driver_returns_are_never_read(monkeypatch):
    """The sampled driver's row buffers filled with NaN, then with infinities, instead of
    zeros: landings of the map (one on the pad, one without a touchdown in its 40 s) the
    same bits in every column and state; the buffers are not zeroed."""
    scenarios, _ = _envelope_scenarios([0, 11999])
    real = runs.row_buffer
    made = []

    def filled(value):
        def buffer(rows, width, zeroed=True):
            made.append(zeroed)
            out = real(rows, width, zeroed)
            out[...] = value
            return out
        return buffer

    for sc in scenarios:
        base = quadland.simulate(sc)
        for value in (np.nan, np.inf):
            monkeypatch.setattr(compiled, "row_buffer", filled(value))
            got = quadland.simulate(sc)
            monkeypatch.undo()
            assert list(got) == list(base)
            assert all(_same(got[k], base[k]) for k in base)
            assert _same(got.states, base.states)
    assert made and not any(made)
    assert [report.touchdown_report(quadland.simulate(sc)).touchdown for sc in scenarios] \
        == [True, False]


def test_a_row_buffer_unzeroed_is_writable_doubles_of_its_shape():
    buf = runs.row_buffer(300, 40, zeroed=False)
    assert buf.shape == (300, 40) and buf.dtype == np.float64 and buf.flags.c_contiguous
    assert buf.flags.writeable


def test_a_cell_refused_by_a_cross_key_check_says_what_the_full_validation_says(tmp_path,
                                                                                  capsys):
    """rbf.center_max below rbf.center_min: the envelope names the cell and the message
    of ``Scenario.replace`` (every key validated)."""
    base = load_scenario("paper")
    with pytest.raises(quadland.ScenarioError) as exc:
        base.replace(**{"rbf.center_max": -100.0})
    status = main(["envelope", "--scenario", "paper", "--axis", "rbf.center_max=-100:-99:2",
                   "--axis", "controller.k1[0]=3:4:2", "--runs-per-cell", "2",
                   "--out", str(tmp_path / "e")])
    err = capsys.readouterr().err.strip().splitlines()
    assert status == 2 and err == [
        "quadland: error: --axis: the cell rbf.center_max = -100, controller.k1[0] = 3 is no "
        f"valid scenario: {exc.value}"]


def test_the_rotation_on_numbers_is_its_dm_evaluation_bit_for_bit():
    """4,000 random angles from a hundredth of a radian to a hundred radians, and every
    triple of signed zeros, quarter and half turns, tiny and huge angles: the same bits
    as ``rotation`` evaluated on ``casadi.DM`` (``math``'s and the C library's sines)."""
    from quadland.kinds.landing.values import rotation_values
    from quadland_symbolic.kinematics import rotation

    rng = np.random.default_rng(21)
    special = [0.0, -0.0, np.pi, -np.pi, np.pi / 2, -np.pi / 2, 1e-300, -1e-300, 1e10, 0.5]
    cases = [rng.normal(0.0, s, 3) for s in (0.01, 0.3, 3.0, 100.0) for _ in range(1000)]
    cases += [np.array([a, b, c]) for a in special for b in special for c in special]
    for eta in cases:
        assert _same(np.asarray(rotation(eta), dtype=float), rotation_values(eta)), eta


def test_the_stiffest_rate_on_numbers_is_its_dm_evaluation_bit_for_bit():
    """Each shipped landing's quadrotor and gear, every value scaled by a random factor
    (a lognormal of 0.3), 600 times each: the same bits as ``stiffest_rate`` on
    ``casadi.DM``. (Squared by ``x * x`` instead of the C library's ``pow``, 2 of 3,000
    such cases differed in the last bit, another seed.)"""
    from quadland.kinds.landing.gear import gear_params, stiffest_rate_value
    from quadland.kinds.landing.values import landing_values
    from quadland_symbolic.landing.contact import stiffest_rate
    from quadland_symbolic.landing.plant import LANDING_PLANT_PARAMS

    rng = np.random.default_rng(22)
    for name in ("highway", "ship", "ship_ss5", "turning", "highway_100"):
        sc = load_scenario(name)
        pq = np.asarray(LANDING_PLANT_PARAMS.unpack(landing_values(sc).pp)["p_quad"],
                        dtype=float).ravel()
        pg = gear_params(sc)
        for _ in range(600):
            q = pq * np.exp(rng.normal(0.0, 0.3, pq.shape))
            g = pg * np.exp(rng.normal(0.0, 0.3, pg.shape))
            assert _same(np.asarray(float(stiffest_rate(q, g))),
                         np.asarray(stiffest_rate_value(q, g))), name


def test_a_direct_call_shared_by_threads_gives_each_its_own_results():
    """A Dask worker flies runs in threads of one process: eight threads calling one
    ``DirectCall`` of the deck's pose, 200 calls each on their own arguments, each
    result the DM call's."""
    import threading

    f = deck_function()
    call, rng = DirectCall(f), np.random.default_rng(23)
    cases = [_random_args(f, rng, 1.0) for _ in range(40)]
    for args in cases:
        args[3] = np.abs(args[3]) + DECK_PARAMS.zeros()
    expected = [_dm(f, args) for args in cases]
    wrong = []

    def work(k):
        for j in range(200):
            i = (7 * j + k) % len(cases)
            got = call(*cases[i])
            if not all(_same(e, g) for e, g in zip(expected[i], got, strict=True)):
                wrong.append(i)

    threads = [threading.Thread(target=work, args=(k,)) for k in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert wrong == []


def test_the_plain_float_helpers_are_their_dm_evaluation_off_the_physical_domain_too():
    """Infinite angles (``math.sin`` raises where CasADi's sine gives NaN), and a gear or
    quadrotor with a zero, negative, infinite, NaN or overflowing value (Python's
    ``1 / 0``, ``sqrt`` of a negative and ``1e160 ** 2`` raise; ``max`` keeps a leading
    NaN where ``mmax`` drops it): each helper returns the bits of its ``casadi.DM``
    evaluation, as ``rotation`` and ``stiffest_rate`` give them, never an exception."""
    import itertools

    from quadland.kinds.landing.gear import gear_params, stiffest_rate_value
    from quadland.kinds.landing.values import landing_values, rotation_values
    from quadland_symbolic.kinematics import rotation
    from quadland_symbolic.landing.contact import stiffest_rate
    from quadland_symbolic.landing.plant import LANDING_PLANT_PARAMS

    angles = [0.0, -0.0, np.inf, -np.inf, np.nan, 5e-324, 1e300]
    for eta in itertools.product(angles, repeat=3):
        eta = np.array(eta)
        assert _same(np.asarray(rotation(eta), dtype=float), rotation_values(eta)), eta
    sc = load_scenario("highway")
    pq = np.asarray(LANDING_PLANT_PARAMS.unpack(landing_values(sc).pp)["p_quad"],
                    dtype=float).ravel()
    pg = gear_params(sc)
    for which, i, v in itertools.product((0, 1), range(max(pq.size, pg.size)),
                                         (0.0, -0.0, -1.0, np.inf, -np.inf, np.nan, 1e160)):
        q, g = pq.copy(), pg.copy()
        if i >= (q, g)[which].size:
            continue
        (q, g)[which][i] = v
        assert _same(np.asarray(float(stiffest_rate(q, g))),
                     np.asarray(stiffest_rate_value(q, g))), (which, i, v)
