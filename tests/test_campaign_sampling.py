"""Per-run seeds and draws: keyed by the run index, whatever the order or subset."""

import numpy as np
import pytest

from quadland.campaign.sampling import draws, run_seed, unit_samples
from quadland.campaign.spec import campaign_spec_of
from quadland.scenario import load_scenario


def _spec(sampling="random", runs=64):
    sc = load_scenario("highway", [f"campaign.sampling=\"{sampling}\"", f"campaign.runs={runs}"])
    return sc, campaign_spec_of(sc)


def test_run_seed_is_the_spawned_child():
    children = np.random.SeedSequence(2024).spawn(50)
    for i in (0, 1, 17, 49):
        expected = int(children[i].generate_state(1, np.uint64)[0]) >> 1
        assert run_seed(2024, i) == expected
    seeds = {run_seed(7, i) for i in range(1000)}
    assert len(seeds) == 1000 and all(0 <= s < 2 ** 63 for s in seeds)


@pytest.mark.parametrize("sampling", ["random", "sobol", "lhs"])
def test_run_i_does_not_depend_on_order_or_subset(sampling):
    _, spec = _spec(sampling)
    whole = {d.index: d for d in draws(spec, range(64))}
    order = np.random.default_rng(1).permutation(64)
    for d in draws(spec, order[:20]):
        assert d.columns == whole[d.index].columns and d.seed == whole[d.index].seed
    assert draws(spec, [63])[0].values == whole[63].values


def test_sobol_prefix_and_lhs_strata():
    _, spec = _spec("sobol")
    u16 = unit_samples(spec, range(16))
    u64 = unit_samples(spec, range(64))
    assert np.array_equal(u16, u64[:16])                 # more runs extend, not change
    for j in range(u16.shape[1]):                        # a (0, m, d)-net: one per stratum
        assert sorted(np.floor(u16[:, j] * 16).astype(int)) == list(range(16))
    _, spec = _spec("lhs", runs=50)
    u = unit_samples(spec, range(50))
    for j in range(u.shape[1]):
        assert sorted(np.floor(u[:, j] * 50).astype(int)) == list(range(50))


@pytest.mark.slow
def test_values_follow_their_distributions():
    sc, spec = _spec("random", runs=2000)
    ds = draws(spec, range(2000))
    mass = np.array([d.values["quadrotor.mass"] for d in ds])
    nominal = sc["quadrotor.mass"]
    assert mass.min() >= 0.9 * nominal and mass.max() <= 1.1 * nominal        # relative +-10 %
    assert np.mean(mass) == pytest.approx(nominal, rel=0.005)
    # truncnorm std 1 cut at +-2 m around the nominal
    x = np.array([d.values["initial.position1"][0] for d in ds]) - sc["initial.position1"][0]
    assert x.min() >= -2.0 and x.max() <= 2.0
    from scipy.stats import truncnorm

    assert np.std(x) == pytest.approx(truncnorm.std(-2, 2), rel=0.05)
    # normal std 0.1 N on each force bias, independent per element
    b = np.array([d.values["disturbance.force_bias"] for d in ds]) - np.array(
        sc["disturbance.force_bias"])
    assert np.std(b, axis=0) == pytest.approx([0.1] * 3, rel=0.08)
    assert abs(np.corrcoef(b[:, 0], b[:, 1])[0, 1]) < 0.1
    # common: one factor for the speed and the drive force that holds it
    for d in ds[:50]:
        f_speed = d.values["initial.velocity2"][0] / sc["initial.velocity2"][0]
        f_tau = d.values["vehicle.tau"][0] / sc["vehicle.tau"][0]
        assert f_speed == pytest.approx(f_tau, rel=1e-14) and 0.8 <= f_speed <= 1.2
        assert d.values["initial.velocity2"][1] == 0.0
    # the seed dispersion is the run's seed
    assert all(d.values["simulation.seed"] == d.seed == run_seed(spec.seed, d.index)
               for d in ds[:20])


def test_choice_and_weights(tmp_path):
    text = (load_scenario("paper").to_toml().split("[campaign]")[0] +
            "[campaign]\nruns = 4000\nseed = 3\n[campaign.dispersions]\n"
            "\"controller.nominal_model\" = {distribution = \"choice\", values = [true, false],"
            " weights = [3, 1]}\n\"rbf.nodes\" = {distribution = \"choice\", values = [5, 10, 20]}"
            "\n")
    path = tmp_path / "c.toml"
    path.write_text(text)
    spec = campaign_spec_of(load_scenario(path))
    ds = draws(spec, range(4000))
    share = np.mean([d.values["controller.nominal_model"] for d in ds])
    assert share == pytest.approx(0.75, abs=0.03)
    nodes = [d.values["rbf.nodes"] for d in ds]
    assert set(nodes) == {5, 10, 20}
    assert ds[0].columns["controller.nominal_model"] in ("true", "false")


def test_overrides_replay_the_values_exactly():
    sc, spec = _spec("random")
    d = draws(spec, [5])[0]
    replayed = load_scenario("highway", d.overrides())
    direct = sc.replace(**d.values)
    assert replayed.data == direct.data


def _spec_of(table: str, model: str = "paper"):
    """The validated campaign of the shipped scenario ``model`` with ``table`` as its table."""
    import tomllib

    from quadland.campaign.spec import campaign_spec

    sc = load_scenario(model)
    return sc, campaign_spec(tomllib.loads(table)["campaign"], sc.data, sc.model)


@pytest.mark.parametrize("std", [1e-300, 1e-30, 1e-8, 1.0, 1e8, 1e300])
@pytest.mark.parametrize("mean", [-1e6, -0.2, 0.75, 0.9, 3.0, 1e300])
def test_truncnorm_draws_stay_within_their_bounds(std, mean):
    # V7: std = 1e-300 with the mean outside [low, high] drew inf. Whatever the spread,
    # every draw lies in [low, high]; where the spread vanishes against the distance to
    # the interval, all the mass is at the nearest bound (the limit std -> 0).
    low, high = 0.5, 1.0
    sc, spec = _spec_of(f"[campaign]\nruns = 256\nseed = 5\n[campaign.dispersions]\n"
                        f"\"quadrotor.mass\" = {{distribution = \"truncnorm\", mode = \"absolute\""
                        f", mean = {mean!r}, std = {std!r}, low = {low}, high = {high}}}\n")
    x = np.array([d.values["quadrotor.mass"] for d in draws(spec, range(256))])
    assert np.all(np.isfinite(x)) and x.min() >= low and x.max() <= high
    from scipy.special import ndtr

    a, b = (low - mean) / std, (high - mean) / std
    if std <= 1e-8 and not a <= 0 <= b:
        # near a bound at distance d the law is exponential of scale std^2 / d (in X);
        # u >= 2^-53 keeps every draw within 37 such scales (-log(2^-53))
        bound = low if mean < low else high
        d = abs(bound - mean)
        assert np.all(np.abs(x - bound) <= 37 * std * (std / d) + 2 * np.spacing(bound))
    elif std == 1.0 and a <= 0 <= b:
        # the truncated law's CDF, from the normal CDF, gives back each run's u
        u = np.array([np.random.default_rng(d.seed).random(1)[0] for d in draws(spec, range(256))])
        cdf = (ndtr((x - mean) / std) - ndtr(a)) / (ndtr(b) - ndtr(a))
        assert np.allclose(cdf, u, atol=1e-9)


@pytest.mark.parametrize("weights, expected", [
    ([1e308, 1e308], [0.5, 0.5]),          # V20: the sum overflowed; the last value every time
    ([1.7e308, 0.0, 1.7e308], [0.5, 0.0, 0.5]),
    ([5e-324, 5e-324], [0.5, 0.5]),         # the smallest subnormal weights
    ([1e308, 1e307], [10 / 11, 1 / 11]),
])
def test_choice_weights_of_any_size_pick_in_proportion(weights, expected):
    n = 4000
    sc, spec = _spec_of(f"[campaign]\nruns = {n}\nseed = 9\n[campaign.dispersions]\n"
                        f"\"rbf.nodes\" = {{distribution = \"choice\", values = "
                        f"{list(range(5, 5 + len(weights)))}, weights = {weights!r}}}\n")
    picks = np.array([d.values["rbf.nodes"] - 5 for d in draws(spec, range(n))])
    for k, p in enumerate(expected):
        share = np.mean(picks == k)
        if p == 0.0:
            assert share == 0.0
        else:                                # within 5 binomial standard deviations
            assert abs(share - p) < 5 * np.sqrt(p * (1 - p) / n), (k, share, p)
