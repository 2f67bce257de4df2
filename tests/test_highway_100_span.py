"""highway_100's aircraft over 30 to 100 km/h (benchmarks/highway_100_30_100.toml).

The benchmark is highway_100 with one line of its campaign table changed; its draws
are checked against the closed form of a relative dispersion and of the drive force
that holds a car's speed (docs/landing.md, "One aircraft for 30 to 100 km/h").
"""

import tomllib
from pathlib import Path

import numpy as np

from quadland.campaign.sampling import draws
from quadland.campaign.spec import campaign_spec_of
from quadland.scenario import load_scenario

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"
SPEED = "initial.velocity2"


def _load():
    return load_scenario("highway_100"), load_scenario(BENCH / "highway_100_30_100.toml")


def test_the_span_benchmark_is_highway_100_but_for_the_car_s_speed():
    """Every section but [scenario] and the campaign's speed line is highway_100's, so
    the benchmark flies the shipped aircraft, its filter and its guidance."""
    ship, span = _load()
    for section in ship.data:
        if section != "scenario":
            assert span.data[section] == ship.data[section], section
    a, b = ship.campaign_table["dispersions"], span.campaign_table["dispersions"]
    assert set(a) == set(b)
    assert {k for k in a if a[k] != b[k]} == {SPEED}
    assert (b[SPEED]["low"], b[SPEED]["high"]) == (-0.7, 0.0)
    assert b[SPEED]["common"] and b[SPEED]["also"] == ["vehicle.tau"]


def test_the_draws_span_30_to_100_km_h_with_the_drive_force_d11_v():
    """100 km/h (1 + X), X uniform on [-0.7, 0]: every draw within 30 to 100 km/h, both
    bands' ends reached by 300 draws, and the drive force d11 V (150 kg/s x speed) that
    holds each speed on the car's linear damping."""
    _, span = _load()
    spec = campaign_spec_of(load_scenario(BENCH / "highway_100_30_100.toml"))
    speeds, forces = [], []
    for run in draws(spec, range(300)):
        values = dict(item.split("=", 1) for item in run.overrides())
        speeds.append(tomllib.loads(f"v = {values[SPEED]}")["v"][0])
        forces.append(tomllib.loads(f"v = {values['vehicle.tau']}")["v"][0])
    kmh = np.array(speeds) * 3.6
    assert kmh.min() >= 30.0 - 1e-9 and kmh.max() <= 100.0 + 1e-9
    assert kmh.min() < 32.0 and kmh.max() > 98.0
    d11 = span.data["vehicle"]["d11"]
    np.testing.assert_allclose(forces, d11 * np.array(speeds), rtol=1e-12)
