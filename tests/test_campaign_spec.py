"""The [campaign] table: validated when a campaign asks, one line per mistake, written back."""

import tomllib

import pytest

from quadland.campaign.spec import campaign_spec_of
from quadland.exceptions import CampaignError, ScenarioError
from quadland.scenario import SCENARIO_DIR, load_scenario

PAPER = (SCENARIO_DIR / "paper.toml").read_text().split("\n[campaign]")[0]


def _load(tmp_path, table: str, base: str = PAPER):
    """The validated table of a file made of ``base`` and ``table``."""
    path = tmp_path / "c.toml"
    path.write_text(base + "\n" + table)
    return campaign_spec_of(load_scenario(path))


GOOD = """[campaign]
runs = 10
seed = 1
[campaign.dispersions]
"quadrotor.mass" = {distribution = "uniform", mode = "relative", low = -0.1, high = 0.1}
"""


@pytest.mark.parametrize("name", ["paper", "highway", "ship"])
def test_shipped_campaigns_load_and_round_trip(name, tmp_path):
    sc = load_scenario(name)
    spec = campaign_spec_of(sc)
    assert spec.runs == 300
    path = tmp_path / "again.toml"
    path.write_text(sc.to_toml())
    again = load_scenario(path)
    assert again.data == sc.data and again.campaign_table == sc.campaign_table
    assert campaign_spec_of(again).table == spec.table
    assert campaign_spec_of(again).columns() == spec.columns()


def test_the_simulation_ignores_the_table(tmp_path):
    sc = load_scenario("paper")
    # every shipped scenario has a [campaign] table: turning's file without it
    path = tmp_path / "turning.toml"
    path.write_text((SCENARIO_DIR / "turning.toml").read_text().split("\n[campaign]")[0])
    plain = load_scenario(path)
    assert plain.campaign_table is None
    assert "[campaign]" not in plain.to_toml()
    assert tomllib.loads(sc.to_toml())["campaign"]["dispersions"]["simulation.seed"] == \
        {"distribution": "seed"}
    with pytest.raises(CampaignError, match="turning has no \\[campaign\\] table"):
        campaign_spec_of(plain)


def test_a_table_the_command_ignores_does_not_block_an_override(tmp_path):
    # The ship campaign disperses the mass by +-10 %: at 10,000 kg (the range's top) its
    # draws would reach 11,000 kg. Only a campaign refuses that; loading (simulate,
    # margins, codegen) does not, and the table is written back as it was.
    sc = load_scenario("ship", ["quadrotor.mass=10000"])
    assert sc["quadrotor.mass"] == 10000.0
    with pytest.raises(ScenarioError, match="draws reach quadrotor.mass = 11000"):
        campaign_spec_of(sc)
    # a table that is wrong in itself is not the other commands' business either
    path = tmp_path / "bad.toml"
    path.write_text(PAPER + "\n[campaign]\nruns = 0\nwhen = 2019-01-01T10:00:00Z\n"
                    "[campaign.dispersions]\n\"nosuch.key\" = {distribution = \"gamma\"}\n")
    bad = load_scenario(path)
    again = tmp_path / "again.toml"
    again.write_text(bad.to_toml())
    assert load_scenario(again).campaign_table == bad.campaign_table
    with pytest.raises(ScenarioError, match="unknown key campaign.when"):
        campaign_spec_of(bad)
    path.write_text("campaign = 5\n" + PAPER)
    with pytest.raises(ScenarioError, match="\\[campaign\\] must be a table"):
        load_scenario(path)


def test_the_scenario_module_does_not_call_up_into_campaigns():
    import ast

    import quadland.scenario

    tree = ast.parse(open(quadland.scenario.__file__).read())
    names = [n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)]
    names += [a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names]
    assert not [n for n in names if n and n.startswith("quadland.campaign")]


def test_set_campaign_keys(tmp_path):
    sc = load_scenario("paper", ["campaign.runs=7", "campaign.sampling=\"sobol\""])
    spec = campaign_spec_of(sc)
    assert spec.runs == 7 and spec.sampling == "sobol"
    # every shipped scenario has a [campaign] table: turning's file without it
    path = tmp_path / "turning.toml"
    path.write_text((SCENARIO_DIR / "turning.toml").read_text().split("\n[campaign]")[0])
    with pytest.raises(ScenarioError, match="has no \\[campaign\\] table"):
        load_scenario(path, ["campaign.runs=7"])


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
    # draws that overflow, or whose values do, are refused up front (they were NaN rows)
    (GOOD.replace("uniform\", mode = \"relative\", low = -0.1, high = 0.1",
                  "normal\", std = 1e308"),
     "quadrotor.mass\".std: the draws overflow \\(they reach -inf to inf\\)"),
    (GOOD.replace("uniform\", mode = \"relative\", low = -0.1, high = 0.1",
                  "normal\", mode = \"relative\", std = 1.2e307"),
     "draws make quadrotor.mass non-finite \\(relative -9.85"),
    (GOOD.replace("low = -0.1, high = 0.1", "low = -1e308, high = 1e308"),
     "quadrotor.mass\".high: the draws overflow"),
    # a bad also is blamed on the also entry, not on the dispersion's own key
    (GOOD.replace("high = 0.1}", "high = 0.1, also = [\"quadrotor.inerta\"]}"),
     "campaign.dispersions.\"quadrotor.mass\".also: quadrotor.inerta is not a key of this "
     "scenario's schema \\(did you mean 'quadrotor.inertia'\\?\\)"),
])
def test_mistakes_are_one_line(tmp_path, table, message):
    with pytest.raises(ScenarioError, match=message) as info:
        _load(tmp_path, table)
    assert "\n" not in str(info.value)



HIGHWAY = (SCENARIO_DIR / "highway.toml").read_text().split("\n[campaign]")[0]


@pytest.mark.parametrize("key, meant", [
    ("sensors.visoin.latency", "sensors.vision.latency"),
    ("sensors.vision.latncy", "sensors.vision.latency"),
    ("estimatr.range_sigma", "estimator.range_sigma"),
])
def test_a_misspelt_sensor_key_dispersed_names_the_one_meant(tmp_path, key, meant):
    table = GOOD.replace("quadrotor.mass", key).replace("relative", "absolute")
    with pytest.raises(ScenarioError) as info:
        _load(tmp_path, table, HIGHWAY)
    assert str(info.value) == (f"campaign.dispersions.\"{key}\": not a key of this "
                               f"scenario's schema (did you mean '{meant}'?)")


def test_a_key_with_nothing_close_suggests_nothing(tmp_path):
    # before, the section's shared prefix made 'quadrotor.mass' the closest
    with pytest.raises(ScenarioError) as info:
        _load(tmp_path, GOOD.replace("quadrotor.mass", "quadrotor.xyz"))
    assert str(info.value) == ("campaign.dispersions.\"quadrotor.xyz\": not a key of this "
                               "scenario's schema")

def test_a_landing_key_in_a_paper_campaign_is_refused(tmp_path):
    with pytest.raises(ScenarioError, match="not a key of this scenario's schema"):
        _load(tmp_path, GOOD.replace("quadrotor.mass", "deck.height"))


def test_a_key_of_another_model_set_by_an_override_blames_the_override():
    # V22: a paper-only key given with --set on a landing scenario is the override's fault,
    # not the shipped file's
    with pytest.raises(ScenarioError) as info:
        load_scenario("highway", ["simulation.integrator=\"rk\""])
    assert str(info.value).startswith("override simulation.integrator: unknown key "
                                      "'simulation.integrator'")
    assert "(a key of scenario.model = \"paper\")" in str(info.value)
    with pytest.raises(ScenarioError, match="^override reference.e1d: unknown section"):
        load_scenario("ship", ["reference.e1d=[0.0, 0.0, 0.0, 0.0]"])
    # the same key written in a file is the file's fault
    path_text = (SCENARIO_DIR / "highway.toml").read_text().replace(
        "[simulation]", "[simulation]\nintegrator = \"rk\"", 1)
    import tempfile
    from pathlib import Path

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "h.toml"
        path.write_text(path_text)
        with pytest.raises(ScenarioError, match=f"^{path}: unknown key"):
            load_scenario(path)
