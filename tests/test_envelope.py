"""A flight that leaves its physical envelope fails at once, with the likely cause named.

The reference for each case is independent of the simulator: RK4's
stability region in closed form, the leakage mode ``-gamma1 k_w`` of eq. (22)
read off the adaptive law, a tighter integration (cvodes, more RK4 steps)
of the same loop, and the equivalence of yaws a whole turn apart.
"""

import numpy as np
import pytest

import quadland
from quadland.engine.compiled import SIM_ENVELOPE, VMLoop
from quadland.engine.envelope import Envelope, rk4_amplification, rk4_steps_needed
from quadland.engine.loop import Clock
from quadland.exceptions import SimulationError
from quadland.kinds.landing.report import touchdown_report
from quadland.kinds.paper.simulate import paper_envelope, paper_loop_part
from quadland.kinds.paper.values import model_values
from quadland_symbolic.closed_loop import PAPER_ENVELOPE, paper_envelope_function
from quadland_symbolic.paper_loop import paper_loop

STEEP = ["controller.k1=[300.0, 5.0, 10.0, 10.0]", "controller.k2=[200.0, 4.0, 10.0, 10.0]"]


def test_rk4_stability_region_in_closed_form():
    # R(z) = 1 + z + z^2/2 + z^3/6 + z^4/24: the real-axis limit is -2.7853, the
    # imaginary-axis limit 2 sqrt(2) (Hairer and Wanner II, IV.2)
    assert rk4_amplification(np.array([-2.78]))[0] < 1 < rk4_amplification(np.array([-2.79]))[0]
    edge = 2 * np.sqrt(2)
    assert rk4_amplification(np.array([0.999 * edge * 1j]))[0] < 1
    assert rk4_amplification(np.array([1.001 * edge * 1j]))[0] > 1
    assert rk4_steps_needed(np.array([-100.0]), 0.01, 1) is None          # z = -1
    need = rk4_steps_needed(np.array([-300.0]), 0.01, 1)                  # z = -3
    assert need is not None and rk4_amplification(np.array([-300.0 * 0.01 / need]))[0] < 1


def test_steep_gains_fail_at_once_naming_the_rk4_step():
    sc = quadland.load_scenario("paper", STEEP)
    with pytest.raises(SimulationError) as info:
        quadland.simulate(sc)
    msg = str(info.value)
    assert info.value.time < 0.1                      # not when a value overflows at 10 s
    assert "beyond its envelope" in msg and "rk_steps_per_interval=" in msg and "cvodes" in msg
    partial = info.value.partial
    assert partial is not None and len(partial["t"]) >= 1
    for name in ("z_e", "F_1", "norm_W_hat"):
        assert np.all(np.isfinite(partial[name]))
    # the suggested step count, and cvodes, fly the same loop without leaving the envelope
    need = int(msg.split("rk_steps_per_interval=")[1].split()[0])
    fine = quadland.simulate(quadland.load_scenario(
        "paper", [*STEEP, f"simulation.rk_steps_per_interval={need}"]))
    reference = quadland.simulate(quadland.load_scenario(
        "paper", [*STEEP, 'simulation.integrator="cvodes"']))
    assert abs(fine["z_e"][-1] - reference["z_e"][-1]) < 1e-4
    assert abs(reference["z_e"][-1]) < 1e-2


def test_the_physical_flight_stays_well_inside_its_envelope():
    """cvodes' trajectory of the steep loop never comes near the bounds that stop RK4's."""
    sc = quadland.load_scenario("paper", [*STEEP, 'simulation.integrator="cvodes"'])
    mv = model_values(sc)
    env = paper_envelope(sc, mv)
    res = quadland.simulate(sc)
    S = np.asarray(paper_envelope_function(mv.l).map(len(res["t"]))(
        res.states.T, np.zeros((4, len(res["t"])))), dtype=float).T
    assert np.max(S / env.bounds) < 0.5


def test_a_stiff_adaptive_law_names_its_leakage_mode():
    """W' = Gamma1 (Psi z2^T - k_w W): a mode at -gamma1 k_w = -5e6 1/s, far outside RK4's
    region at h = 0.01 s; the line names the weights and that mode."""
    sc = quadland.load_scenario("paper", ["controller.gamma1=1e6", "simulation.duration=1"])
    with pytest.raises(SimulationError) as info:
        quadland.simulate(sc)
    msg = str(info.value)
    assert "weight" in msg and "rk_steps_per_interval" in msg
    fastest = complex(msg.split("fastest mode, ")[1].split()[0].rstrip(":"))
    assert fastest == pytest.approx(-1e6 * sc["controller.k_w"], rel=1e-3)


def test_a_landing_spun_up_by_its_disturbance_stops_with_honest_rows():
    sc = quadland.load_scenario("ship", ["disturbance.moment_amplitude=10000"])
    with pytest.raises(SimulationError) as info:
        quadland.simulate(sc)
    partial = info.value.partial
    t = partial["t"]
    assert np.all(np.diff(t) > 0) and t[-1] <= info.value.time
    # every row holds a real state: no row of zeros written after the failure
    assert not np.any(np.all(partial.states == 0, axis=1))
    assert "disturbance" in str(info.value)         # named among the loop's suspects


def test_a_vehicle_driven_away_leaves_the_distance_envelope():
    sc = quadland.load_scenario("turning", ["vehicle.tau=[1e8, 1e8, 1e8]"])
    with pytest.raises(SimulationError) as info:
        quadland.simulate(sc)
    assert "the distance" in str(info.value) and info.value.time < 1.0


@pytest.mark.parametrize("yaw", [3600.0, -3600.0, 1800.0])
def test_a_yaw_whole_turns_away_is_the_same_landing(yaw):
    base = touchdown_report(quadland.simulate(quadland.load_scenario("highway")))
    turned = touchdown_report(quadland.simulate(quadland.load_scenario(
        "highway", [f"initial.eta1_deg=[0.0, 0.0, {yaw}]"])))
    assert turned.success and turned.time == pytest.approx(base.time, abs=1e-9)
    assert turned.offset == pytest.approx(base.offset, abs=1e-6)


def test_compiled_and_vm_drivers_stop_at_the_same_point():
    sc = quadland.load_scenario("paper", [*STEEP, "rbf.nodes=4", "simulation.duration=0.2"])
    mv = model_values(sc)
    env = paper_envelope(sc, mv)
    clocks = (Clock(100.0, 0.0, 0.2, True), Clock(100.0, 0.0, 0.2, True))
    W = np.zeros((21, 6))
    runs = [loop.integrate(mv.x0, clocks, W, 1, mv.p, env.bounds) for loop in (
        paper_loop_part(4, "continuous"), VMLoop(paper_loop(4),
                                               "continuous"))]
    for run in runs:
        assert run.status == SIM_ENVELOPE and run.rows >= 1
    assert runs[0].t_stop == runs[1].t_stop and runs[0].rows == runs[1].rows
    np.testing.assert_allclose(runs[0].envelope, runs[1].envelope, rtol=1e-9)
    np.testing.assert_allclose(runs[0].X, runs[1].X, rtol=1e-12, atol=1e-12)


def test_envelope_describes_its_worst_magnitude():
    env = Envelope(PAPER_ENVELOPE, np.array([10.0, 10, 10, 10, 10, 10]), ("why",) * 6)
    text = env.describe(np.array([5.0, 20.0, np.nan, 0, 0, 0]))
    assert text.startswith("the rate") and "non-finite" in text
    with pytest.raises(ValueError):
        Envelope(PAPER_ENVELOPE, np.ones(5), ("why",) * 5)
