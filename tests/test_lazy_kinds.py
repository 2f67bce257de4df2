"""A paper scenario loads none of the landing's modules (quadland.schema.by_model).

The landing's schema and loop kind import the landing's symbolic modules, half of
the Python a cold ``simulate`` would otherwise compile. The registries keep each
model's entry by module and load it when first read; the messages of a bad
override are those of every schema, as before.
"""

import subprocess
import sys

import pytest

import quadland
from quadland.exceptions import ScenarioError
from quadland.schema.by_model import ByModel

LANDING_MODULES = ("quadland_symbolic.landing", "quadland.schema.landing",
                   "quadland.kinds.landing", "quadland_symbolic.codegen.registry")


def _loaded_after(code: str) -> list[str]:
    out = subprocess.run(
        [sys.executable, "-c", f"import sys; {code}; print('\\n'.join(sorted(sys.modules)))"],
        capture_output=True, text=True, check=True).stdout.split()
    return [m for m in out if m.startswith(LANDING_MODULES)]


def test_a_paper_scenario_and_its_kind_load_nothing_of_the_landing():
    code = ("import quadland; from quadland.kinds import kind_of; "
            "import quadland.simulation; "
            "sc = quadland.load_scenario('paper', ['simulation.duration=2', 'rbf.nodes=5']); "
            "kind = kind_of(sc); assert kind.name == 'paper'; kind.plan(sc)")
    assert _loaded_after(code) == []


def test_a_landing_scenario_loads_the_landing():
    loaded = _loaded_after("import quadland; from quadland.kinds import kind_of; "
                           "kind_of(quadland.load_scenario('highway'))")
    assert "quadland.schema.landing" in loaded
    assert "quadland.kinds.landing.kind" in loaded


def test_by_model_knows_its_keys_before_loading_and_loads_once():
    reg = ByModel({"json": ("json", "dumps"), "math": ("math", "pi")})
    assert list(reg) == ["json", "math"] and len(reg) == 2 and "math" in reg
    assert reg.loaded() == ()
    assert reg["math"] == pytest.approx(3.141592653589793)
    assert reg.loaded() == ("math",)
    import json
    assert reg["json"] is json.dumps
    assert dict(reg) == {"json": json.dumps, "math": reg["math"]}
    with pytest.raises(KeyError):
        reg["nope"]
    assert "nope" not in reg


@pytest.mark.parametrize(("overrides", "message"), [
    # a landing key on a paper scenario: accepted as an override, refused with its model
    (["sensors.vision.latency=0.1"],
     "override sensors.vision.latency: unknown section 'sensors.vision' "
     "(a section of scenario.model = \"landing\")"),
    (["sensorz.x=1"], "override sensorz.x: unknown section 'sensorz' (did you mean 'sensors'?)"),
    (["simulation.durtion=1"], "override simulation.durtion: unknown key "
                               "'simulation.durtion' (did you mean 'simulation.duration'?)"),
])
def test_a_bad_override_of_a_paper_scenario_is_checked_against_every_schema(overrides,
                                                                            message):
    with pytest.raises(ScenarioError) as err:
        quadland.load_scenario("paper", overrides)
    assert str(err.value) == message
