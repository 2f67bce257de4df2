"""``extends``: a scenario file that gives only what differs from another (issue 21).

Each file built on a base is checked against the same scenario reached
independently: the base loaded with the differing keys as ``--set``
overrides.
"""

import subprocess
import sys
import tomllib

import pytest

from quadland.exceptions import ScenarioError
from quadland.extends import merge_scenarios
from quadland.scenario import load_scenario


def _write(path, text):
    path.write_text(text, encoding="utf-8")
    return path


def _same_but_the_name(a, b):
    """Equal data but ``scenario.name`` and ``scenario.description``."""
    strip = {"name", "description"}
    for section in set(a.data) | set(b.data):
        ta, tb = dict(a.data[section]), dict(b.data[section])
        if section == "scenario":
            ta = {k: v for k, v in ta.items() if k not in strip}
            tb = {k: v for k, v in tb.items() if k not in strip}
        assert ta == tb, section


def test_a_file_gives_only_what_differs(tmp_path):
    path = _write(tmp_path / "gusty.toml",
                  'extends = "highway"\n\n[wind]\nmean = [4.0, 0.0, 0.0]\n'
                  '\n[simulation]\nseed = 7\n')
    sc = load_scenario(path)
    reference = load_scenario("highway", ["wind.mean=[4.0, 0.0, 0.0]", "simulation.seed=7"])
    _same_but_the_name(sc, reference)
    assert sc.model == "landing"
    assert sc.name == "gusty"                     # named after its own file, not the base
    assert sc["scenario.description"] == ""
    assert sc.campaign_table == reference.campaign_table    # the base's [campaign] too


def test_resolved_copy_has_no_extends_and_repeats_the_scenario(tmp_path):
    sc = load_scenario(_write(tmp_path / "a.toml",
                              'extends = "paper"\n[rbf]\nnodes = 7\n'), ["controller.rate_hz=50"])
    text = sc.to_toml()
    assert "extends" not in tomllib.loads(text)
    again = load_scenario(_write(tmp_path / "resolved.toml", text))
    assert again.data == sc.data
    assert again["rbf.nodes"] == 7 and again["controller.rate_hz"] == 50.0


def test_a_chain_of_bases_relative_to_each_file(tmp_path):
    (tmp_path / "bases").mkdir()
    _write(tmp_path / "bases" / "base.toml",
           'extends = "paper"\n[scenario]\nname = "base"\n[rbf]\nnodes = 5\n'
           '[simulation]\nduration = 3.0\n')
    _write(tmp_path / "bases" / "middle.toml",
           'extends = "base.toml"\n[simulation]\nduration = 2.0\n')
    top = _write(tmp_path / "top.toml",
                 'extends = "bases/middle.toml"\n[scenario]\nname = "mine"\n'
                 '[controller]\nrate_hz = 100.0\n')
    sc = load_scenario(top)
    reference = load_scenario("paper", ["rbf.nodes=5", "simulation.duration=2.0",
                                        "controller.rate_hz=100.0"])
    _same_but_the_name(sc, reference)
    assert sc.name == "mine"


def test_overrides_apply_after_the_bases(tmp_path):
    path = _write(tmp_path / "a.toml", 'extends = "paper"\n[rbf]\nnodes = 7\n')
    assert load_scenario(path, ["rbf.nodes=9"])["rbf.nodes"] == 9


@pytest.mark.parametrize("files, top, message", [
    ({"a.toml": 'extends = "b.toml"\n', "b.toml": 'extends = "a.toml"\n'}, "a.toml",
     "{d}/a.toml: extends cycle: a.toml -> b.toml -> a.toml"),
    ({"a.toml": 'extends = "a.toml"\n'}, "a.toml", "{d}/a.toml: extends cycle: a.toml -> a.toml"),
    ({"a.toml": 'extends = "hihgway"\n'}, "a.toml",
     "{d}/a.toml: extends: unknown scenario 'hihgway' (did you mean 'highway'?)"),
    ({"a.toml": 'extends = "gone.toml"\n'}, "a.toml",
     "{d}/a.toml: extends 'gone.toml': scenario file not found ({d}/gone.toml)"),
    ({"a.toml": 'extends = "b.toml"\n', "b.toml": 'extends = "nowhere/c.toml"\n'}, "a.toml",
     "{d}/b.toml: extends 'nowhere/c.toml': scenario file not found ({d}/nowhere/c.toml)"),
    ({"a.toml": "extends = 3\n"}, "a.toml",
     "{d}/a.toml: extends must be a shipped scenario's name or a file path (a string), got 3"),
    ({"a.toml": 'extends = "b.toml"\n', "b.toml": "[simulation\n"}, "a.toml",
     "{d}/b.toml: malformed TOML at line 1, column 12: "),
])
def test_a_bad_base_is_one_line(tmp_path, files, top, message):
    for name, text in files.items():
        _write(tmp_path / name, text)
    with pytest.raises(ScenarioError) as info:
        load_scenario(tmp_path / top)
    text = str(info.value)
    assert "\n" not in text
    assert text.startswith(message.format(d=tmp_path))


def test_the_extending_file_is_blamed_for_its_own_unknown_key(tmp_path):
    path = _write(tmp_path / "a.toml", 'extends = "paper"\n[rbf]\nnodse = 7\n')
    with pytest.raises(ScenarioError, match=r"a\.toml: unknown key 'rbf\.nodse' "
                                            r"\(did you mean 'rbf\.nodes'\?\)"):
        load_scenario(path)


def test_merge_replaces_a_key_whole():
    base = {"campaign": {"runs": 10, "dispersions": {"a": 1, "b": 2}}, "rbf": {"nodes": 5}}
    child = {"campaign": {"dispersions": {"c": 3}}}
    assert merge_scenarios(base, child) == {"campaign": {"runs": 10, "dispersions": {"c": 3}},
                                            "rbf": {"nodes": 5}}
    assert base["campaign"]["dispersions"] == {"a": 1, "b": 2}     # the base untouched


def test_command_line_bad_base_exit_2_nothing_written(tmp_path):
    bad = _write(tmp_path / "bad.toml", 'extends = "hihgway"\n')
    proc = subprocess.run([sys.executable, "-m", "quadland", "simulate", "--scenario",
                           str(bad)], capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert proc.returncode == 2
    assert proc.stderr == (f"quadland: error: {bad}: extends: unknown scenario 'hihgway' "
                           "(did you mean 'highway'?)\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml"]
