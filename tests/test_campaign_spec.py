"""The [campaign] table: validated once at load, one line per mistake, written back exactly."""

import tomllib

import pytest

from quadland.exceptions import ScenarioError
from quadland.scenario import SCENARIO_DIR, load_scenario

PAPER = (SCENARIO_DIR / "paper.toml").read_text().split("\n[campaign]")[0]


def _load(tmp_path, table: str, base: str = PAPER):
    path = tmp_path / "c.toml"
    path.write_text(base + "\n" + table)
    return load_scenario(path)


GOOD = """[campaign]
runs = 10
seed = 1
[campaign.dispersions]
"quadrotor.mass" = {distribution = "uniform", mode = "relative", low = -0.1, high = 0.1}
"""


@pytest.mark.parametrize("name", ["paper", "highway", "ship"])
def test_shipped_campaigns_load_and_round_trip(name, tmp_path):
    sc = load_scenario(name)
    assert sc.campaign is not None and sc.campaign.runs == 300
    path = tmp_path / "again.toml"
    path.write_text(sc.to_toml())
    again = load_scenario(path)
    assert again.data == sc.data
    assert again.campaign.table == sc.campaign.table
    assert again.campaign.columns() == sc.campaign.columns()


def test_the_simulation_ignores_the_table():
    sc = load_scenario("paper")
    plain = load_scenario("turning")
    assert plain.campaign is None
    assert "[campaign]" not in plain.to_toml()
    assert tomllib.loads(sc.to_toml())["campaign"]["dispersions"]["simulation.seed"] == \
        {"distribution": "seed"}


def test_set_campaign_keys():
    sc = load_scenario("paper", ["campaign.runs=7", "campaign.sampling=\"sobol\""])
    assert sc.campaign.runs == 7 and sc.campaign.sampling == "sobol"
    with pytest.raises(ScenarioError, match="has no \\[campaign\\] table"):
        load_scenario("turning", ["campaign.runs=7"])


@pytest.mark.parametrize("table, message", [
    ("[campaign]\nruns = 10\nseed = 1\n", "missing key campaign.dispersions"),
    (GOOD.replace("runs = 10", "runs = 0"), "campaign.runs: must be in \\[1, 1000000\\]"),
    (GOOD.replace("seed = 1", "seed = -1"), "campaign.seed: must be in"),
    (GOOD + "smapling = 1\n".replace("smapling", "[campaign.x]\ny"), "unknown key campaign.x"),
    (GOOD.replace("runs = 10", "runs = 10\nsampling = \"grid\""), "must be one of random, "
     "sobol, lhs"),
    (GOOD.replace("quadrotor.mass", "quadrotor.mas"), "did you mean 'quadrotor.mass'"),
    (GOOD.replace("uniform", "gamma"), "must be one of uniform, normal, truncnorm, choice, seed"),
    (GOOD.replace("low = -0.1", "lo = -0.1"), "uniform takes low, high, mode, common, also"),
    (GOOD.replace("high = 0.1", "high = -0.2"), "low: must be below high"),
    (GOOD.replace("high = 0.1", "high = 20000.0"), "draws reach quadrotor.mass = 40002, "
     "outside its range \\[0.001, 10000\\] kg"),
    (GOOD.replace("\"quadrotor.mass\"", "\"quadrotor.inertia\"").replace(
        "low = -0.1", "low = [-0.1, -0.1]"), "expected a number or a list of 3 numbers"),
    (GOOD + "\"rbf.nodes\" = {distribution = \"normal\", std = 1.0}\n",
     "normal draws real numbers; rbf.nodes holds integers"),
    (GOOD + "\"rbf.nodes\" = {distribution = \"choice\", values = [10, 0]}\n",
     "values: rbf.nodes: must be in \\[1, 1000\\]"),
    (GOOD + "\"quadrotor.gravity\" = {distribution = \"seed\"}\n", "a seed dispersion needs"),
    (GOOD + "\"initial.velocity2\" = {distribution = \"uniform\", low = 0.0, high = 1.0, "
     "also = [\"vehicle.tau\"]}\n", "needs one draw for all"),
    (GOOD + "\"quadrotor.inertia\" = {distribution = \"uniform\", low = 0.0, high = 0.1, "
     "common = true, also = [\"quadrotor.mass\"]}\n", "quadrotor.mass is dispersed twice"),
    (GOOD + "[campaign.limits]\nsettling_time = 1.0\n", "unknown metric 'settling_time'"),
    (GOOD + "[campaign.limits]\nrotor_max = 0.0\n", "campaign.limits.rotor_max: must be > 0"),
    (GOOD + "[campaign.limits]\nrotor_max = " + "9" * 400 + "\n", "must be finite"),
    (GOOD + "\"quadrotor.mass\" = 3\n", "duplicate key"),
])
def test_mistakes_are_one_line(tmp_path, table, message):
    with pytest.raises(ScenarioError, match=message) as info:
        _load(tmp_path, table)
    assert "\n" not in str(info.value)


def test_a_landing_key_in_a_paper_campaign_is_refused(tmp_path):
    with pytest.raises(ScenarioError, match="not a key of this scenario's schema"):
        _load(tmp_path, GOOD.replace("quadrotor.mass", "deck.height"))
