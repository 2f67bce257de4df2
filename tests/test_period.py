"""SampledPeriod: one control period of a sampled loop on the simulator's grid."""

import numpy as np
import pytest

from quadland.engine.loop import Clock, merged_grid
from quadland.engine.period import SampledPeriod
from quadland.kinds import kind_of
from quadland.scenario import load_scenario
from quadland_symbolic.landing.loop import landing_loop


def _period(rate, breaks, delay=1):
    sc = load_scenario("highway", ["rbf.nodes=2"])
    v = kind_of(sc).io_values(sc)
    s = v["sampled"]
    return SampledPeriod(landing_loop(2), s["pc"], v["pp"], 1.0 / rate, delay, 1, breaks)


@pytest.mark.parametrize("rate, breaks", [(250.0, (100.0, 100.0)), (250.0, (100.0, 30.0)),
                                          (50.0, (100.0, 100.0)), (100.0, (100.0, 100.0))])
def test_a_period_s_grid_is_the_simulator_s(rate, breaks):
    """Between two control ticks, the points of the simulator's merged grid of the output,
    disturbance and control clocks (quadland.engine.loop.merged_grid, the C driver's
    mirror): the same instants, as many."""
    T = 1.0
    grid, (*_, ctrl) = merged_grid([Clock(breaks[0], 0.0, T, True),
                                    Clock(breaks[1], 0.0, T, True), Clock(rate, 0.0, T, False)])
    ticks = np.flatnonzero(ctrl >= 0)
    period = _period(rate, breaks)
    for a, b in zip(ticks[:-1], ticks[1:], strict=True):
        np.testing.assert_allclose(period.grid(grid[a]), grid[a:b + 1], rtol=0, atol=1e-15)


def test_names_and_the_initial_queue():
    p = _period(250.0, (100.0, 100.0), delay=2)
    names = p.state_names()
    assert names[-8:] == [f"F_{i}_cmd_delay{d}" for d in (2, 1) for i in range(1, 5)]
    x0 = p.initial_state(np.zeros(25), np.zeros(p.model.controller_state.size), [1, 2, 3, 4])
    assert len(x0) == len(names) and x0[-8:].tolist() == [1, 2, 3, 4] * 2
    assert p.output_names()[-13:] == list(p.model.recorded.element_names())


def test_a_loop_with_per_tick_inputs_has_no_one_period_map():
    from quadland_symbolic.landing.sensed_loop import landing_sensed_loop

    sc = load_scenario("highway", ["rbf.nodes=2"])
    v = kind_of(sc).io_values(sc)
    with pytest.raises(ValueError, match="per-tick inputs"):
        SampledPeriod(landing_sensed_loop(2), v["sampled"]["pc"], v["pp"], 0.004, 1, 1, ())
