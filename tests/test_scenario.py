"""Scenario validation: every bad input gives one clear error naming the problem."""

import math

import pytest

from quadland.exceptions import ScenarioError
from quadland.scenario import SCENARIO_DIR, load_scenario


def test_paper_scenario_values(paper):
    """Table 1 and Section 4 of the paper."""
    assert paper["quadrotor.mass"] == 2.0
    assert paper["quadrotor.inertia"] == (1.2416, 1.2416, 2.4832)
    assert paper["vehicle.m33"] == 80.0
    assert paper["controller.k1"] == (3.0, 5.0, 10.0, 10.0)
    assert paper["controller.k2"] == (2.0, 4.0, 10.0, 10.0)
    assert paper["rbf.nodes"] == 100
    assert paper["initial.psi2_deg"] == 15.0
    assert paper["controller.nominal_model"] is False
    assert paper["controller.rate_hz"] == 0.0


def test_overrides_are_typed():
    sc = load_scenario("paper", ["simulation.duration=2", "controller.nominal_model=true",
                                 "quadrotor.mass=2.5", "disturbance.noise=false",
                                 "controller.k1=[1, 2, 3, 4]", "controller.backend=c"])
    assert sc["simulation.duration"] == 2.0
    assert sc["controller.nominal_model"] is True
    assert sc["quadrotor.mass"] == 2.5
    assert sc["disturbance.noise"] is False
    assert sc["controller.k1"] == (1.0, 2.0, 3.0, 4.0)
    assert sc["controller.backend"] == "c"
    assert sc.overrides[0] == "simulation.duration=2"


def test_mapping_overrides():
    assert load_scenario("paper", {"simulation.duration": 3})["simulation.duration"] == 3.0


def _write(tmp_path, text):
    path = tmp_path / "s.toml"
    path.write_text(text)
    return path


def _paper_text(**replace):
    text = (SCENARIO_DIR / "paper.toml").read_text()
    for old, new in replace.items():
        assert old in text
        text = text.replace(old, new)
    return text


BAD_OVERRIDES = [
    (["quadrotor.mass=0"], r"quadrotor\.mass: must be > 0"),
    (["quadrotor.mass=-2"], r"quadrotor\.mass: must be > 0"),
    (["quadrotor.inertia=[1.0, 0.0, 1.0]"], r"quadrotor\.inertia: must be > 0"),
    (["quadrotor.inertia=[1.0, 1.0]"], r"quadrotor\.inertia: expected a list of 3"),
    (["controller.k1=[3, 5, -1, 10]"], r"controller\.k1: must be > 0"),
    (["controller.k2=[0, 4, 10, 10]"], r"controller\.k2: must be > 0"),
    (["controller.gamma1=0"], r"controller\.gamma1: must be > 0"),
    (["rbf.width=0"], r"rbf\.width: must be > 0"),
    (["rbf.nodes=0"], r"rbf\.nodes: must be >= 1"),
    (["rbf.nodes=2.5"], r"rbf\.nodes: expected an integer"),
    (["initial.eta1_deg=[30, 90, 0]"], r"initial\.eta1_deg: .*below 90 deg"),
    (["initial.eta1_deg=[-95, 0, 0]"], r"initial\.eta1_deg: .*below 90 deg"),
    (["simulation.duration=nan"], r"simulation\.duration: must be finite"),
    (["simulation.duration=inf"], r"simulation\.duration: must be finite"),
    (["quadrotor.gravity=-inf"], r"quadrotor\.gravity: must be finite"),
    (["simulation.duration=\"long\""], r"simulation\.duration: expected a number"),
    (["simulation.duration=true"], r"simulation\.duration: expected a number"),
    (["controller.nominal_model=1"], r"controller\.nominal_model: expected true or false"),
    (["disturbance.noise=yes"], r"disturbance\.noise: expected true or false"),
    (["simulation.integrator=euler"], r"simulation\.integrator: must be one of"),
    (["controller.hold_compensation=-0.5"], r"controller\.hold_compensation: must be in \[0, 1\]"),
    (["controller.hold_compensation=2"], r"controller\.hold_compensation: must be in \[0, 1\]"),
    (["quadrotor.masss=2"], r"unknown key 'quadrotor\.masss' \(did you mean 'quadrotor\.mass'\?\)"),
    (["quadrotr.mass=2"], r"unknown section 'quadrotr' \(did you mean 'quadrotor'\?\)"),
    (["mass=2"], r"expected section\.key=value"),
    (["quadrotor.mass"], r"expected section\.key=value"),
    (["quadrotor.rotor_force_max=-600"], r"rotor_force_max"),
]


@pytest.mark.parametrize("overrides, message", BAD_OVERRIDES)
def test_bad_overrides(overrides, message):
    with pytest.raises(ScenarioError, match=message):
        load_scenario("paper", overrides)


def test_missing_file(tmp_path):
    with pytest.raises(ScenarioError, match="scenario file not found"):
        load_scenario(tmp_path / "nope.toml")


def test_unknown_scenario_name():
    with pytest.raises(ScenarioError, match=r"unknown scenario 'papr' \(did you mean 'paper'\?\)"):
        load_scenario("papr")


def test_malformed_toml(tmp_path):
    with pytest.raises(ScenarioError, match=r"s\.toml: malformed TOML"):
        load_scenario(_write(tmp_path, "[simulation\nduration = 1\n"))


def test_unknown_section_in_file(tmp_path):
    text = _paper_text() + "\n[vehicel]\nm11 = 1.0\n"
    with pytest.raises(ScenarioError, match=r"unknown section 'vehicel' \(did you mean 'vehicle'\?\)"):
        load_scenario(_write(tmp_path, text))


def test_unknown_key_in_file(tmp_path):
    text = _paper_text(**{"deck_altitude = 0.0": "deck_altitud = 0.0"})
    with pytest.raises(ScenarioError, match=r"did you mean 'vehicle\.deck_altitude'"):
        load_scenario(_write(tmp_path, text))


def test_missing_key_in_file(tmp_path):
    text = _paper_text(**{"mass = 2.0 ": "# no mass "})
    with pytest.raises(ScenarioError, match=r"missing key quadrotor\.mass"):
        load_scenario(_write(tmp_path, text))


def test_nan_in_file(tmp_path):
    text = _paper_text(**{"gamma1 = 0.05": "gamma1 = nan"})
    with pytest.raises(ScenarioError, match=r"controller\.gamma1: must be finite"):
        load_scenario(_write(tmp_path, text))


def test_wrong_type_in_file(tmp_path):
    text = _paper_text(**{"k_w = 5.0": "k_w = \"five\""})
    with pytest.raises(ScenarioError, match=r"controller\.k_w: expected a number"):
        load_scenario(_write(tmp_path, text))


def test_user_file_loads(tmp_path):
    sc = load_scenario(_write(tmp_path, _paper_text(**{'name = "paper"': 'name = "mine"'})))
    assert sc.name == "mine"
    assert math.isclose(sc["quadrotor.mass"], 2.0)


def test_error_is_one_line():
    with pytest.raises(ScenarioError) as info:
        load_scenario("paper", ["quadrotor.masss=2"])
    assert "\n" not in str(info.value)
