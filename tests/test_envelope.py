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
from quadland.engine.envelope import (
    MAX_RK_STEPS,
    Envelope,
    fewest_stable_steps,
    rk4_amplification,
    rk4_hint,
    rk4_steps_needed,
)
from quadland.engine.loop import Clock
from quadland.exceptions import SimulationError
from quadland.kinds.landing.report import touchdown_report
from quadland.kinds.paper.simulate import paper_envelope, paper_loop_part
from quadland.kinds.paper.values import model_values
from quadland_symbolic.closed_loop import (
    PAPER_ENVELOPE,
    closed_loop_state,
    paper_envelope_function,
)
from quadland_symbolic.paper_loop import paper_loop
from quadland_symbolic.quadrotor import QUAD_STATE

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
    # z = -3 / 2 is inside the region, so 2 steps hold the mode; resolving it,
    # |lambda h| <= 0.3, takes 3 / 0.3 = 10
    assert fewest_stable_steps(np.array([-300.0]), 0.01) == 2 and need == 10
    # a growing mode grows under any step: it is the loop's, and names no step count
    assert rk4_steps_needed(np.array([5.0]), 0.01, 1) is None
    assert rk4_steps_needed(np.array([-300.0, 5.0]), 0.01, 1) == 10


def test_a_hint_never_names_a_value_the_key_refuses():
    """-5e6 1/s at h = 0.01 s needs ~18,000 steps: beyond the key's 1000, the line says
    the model is stiff and names no step count."""
    assert fewest_stable_steps(np.array([-5e6]), 0.01) > MAX_RK_STEPS
    text = rk4_hint(np.array([-5e6, -1.0]), 0.01, 1)
    assert "stiff" in text and "rk_steps_per_interval=" not in text
    assert "-5e+06" in text                                       # the mode that sets it
    assert rk4_hint(np.array([3.0, -1.0]), 0.01, 1) is None       # only a growing mode


@pytest.mark.slow
def test_steep_gains_fail_at_once_naming_the_rk4_step():
    sc = quadland.load_scenario("paper", STEEP)
    with pytest.raises(SimulationError) as info:
        quadland.simulate(sc)
    msg = str(info.value)
    # within a few dozen steps, not when a value overflows at 10 s (the speed envelope
    # is 1000 x the 450 m/s the law commands for the initial 1.5 m offset, k1_z = 300)
    assert info.value.time < 0.5
    assert "beyond its envelope" in msg and "rk_steps_per_interval=" in msg
    assert "mode -300+0j" in msg                      # k1_z: z1' = -k1 z1 (eq. 9)
    partial = info.value.partial
    assert partial is not None and len(partial["t"]) >= 1
    for name in ("z_e", "F_1", "norm_W_hat"):
        assert np.all(np.isfinite(partial[name]))
    # the suggested step count, and cvodes, fly the same loop without leaving the envelope
    need = int(msg.split("rk_steps_per_interval=")[1].rstrip(")"))
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


@pytest.mark.slow
def test_a_stiff_adaptive_law_names_its_leakage_mode():
    """W' = Gamma1 (Psi z2^T - k_w W): a mode at -gamma1 k_w = -5e6 1/s, far outside RK4's
    region at h = 0.01 s; the line names the weights and that mode."""
    sc = quadland.load_scenario("paper", ["controller.gamma1=1e6", "simulation.duration=1"])
    with pytest.raises(SimulationError) as info:
        quadland.simulate(sc)
    msg = str(info.value)
    assert "weight" in msg and "stiff" in msg
    fastest = complex(msg.split("mode ")[1].split()[0])
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
    env = Envelope(PAPER_ENVELOPE, np.full(8, 10.0), ("why",) * 8)
    text = env.describe(np.array([5.0, 20.0, np.nan, 0, 0, 0, 0, 0]))
    assert text.startswith("the rate") and "non-finite" in text
    # just past its bound, the value shows enough digits to differ from it
    text = env.describe(np.array([0, 0, 0, 0, 0, 0, 10.0004, 0]))
    assert "reached 10.0004 rad" in text and "envelope of 10 rad" in text
    with pytest.raises(ValueError):
        Envelope(PAPER_ENVELOPE, np.ones(5), ("why",) * 5)


@pytest.mark.parametrize("case", [
    ["initial.eta1_deg=[30, 30, 3600]"],                              # ten turns of yaw
    ["controller.gamma1=1e6", "controller.k_w=1e-6", "simulation.duration=2"],
    # the sampled loop: the plant's drag mode -b/m = -500 1/s, at h = 0.01 s
    ["quadrotor.drag_translational=[1e3, 1e3, 1e3]", "controller.rate_hz=100",
     "simulation.duration=1"],
], ids=["yaw-turns", "fast-adaptation", "sampled-drag"])
@pytest.mark.slow
def test_the_named_step_count_flies_the_loop(case):
    """Following the hint flies the flight, and its step count is converged: twice as many
    steps change the trajectory by less than the flight's own scale."""
    with pytest.raises(SimulationError) as info:
        quadland.simulate(quadland.load_scenario("paper", case))
    need = int(str(info.value).split("rk_steps_per_interval=")[1].rstrip(")"))
    assert need <= MAX_RK_STEPS
    runs = [quadland.simulate(quadland.load_scenario(
        "paper", [*case, f"simulation.rk_steps_per_interval={n}"])) for n in (need, 2 * need)]
    for name in ("z_e", "phi_e", "psi_e"):
        scale = max(1e-3, np.abs(runs[1][name]).max())
        assert np.abs(runs[0][name] - runs[1][name]).max() < 1e-2 * scale, name


def test_an_offset_the_law_commands_fast_is_flown():
    """z1 = 1000 m: k1_z = 3 commands ~3,000 m/s at first, a speed the loop reaches
    and recovers from; the flight converges to the reference (e1 -> e1d, eq. 9)."""
    for case, target in ((["initial.z1=1000", "simulation.duration=5"], 0.0),
                         (["reference.e1d=[2000, 0, 0, 0]"], 2000.0)):
        res = quadland.simulate(quadland.load_scenario("paper", case))
        # from 1000-2000 m away to within 1e-4 of that offset
        assert abs(res["z_e"][-1] - target) < 0.1


@pytest.mark.slow
def test_a_tilt_past_90_degrees_between_samples_fails_there():
    """A 10 Hz control of 10 1/s gains tumbles slowly; the flight fails at the first grid
    point past the thrust map's singularity, found independently from the same loop run
    with the tilt bound lifted (cos phi cos theta changes sign there)."""
    sc = quadland.load_scenario("paper", ["controller.rate_hz=10", "simulation.duration=10"])
    with pytest.raises(SimulationError) as info:
        quadland.simulate(sc)
    msg = str(info.value)
    assert "the tilt" in msg and "controller.rate_hz=" in msg
    mv = model_values(sc)
    env = paper_envelope(sc, mv)
    bounds = env.bounds.copy()
    bounds[PAPER_ENVELOPE.index("tilt")] = np.inf
    from quadland.kinds.paper import simulate as paper_simulate

    run, _ = paper_simulate._sampled_run(
        paper_loop_part(mv.l, "sampled"), sc, mv,
        paper_simulate.disturbance_samples(sc, paper_simulate.run_clocks(sc)[1].times()),
        Envelope(env.layout, bounds, env.basis))
    eta = QUAD_STATE.unpack(closed_loop_state(mv.l).unpack(run.X.T)["xq"])["eta1"]
    c = np.cos(eta[0]) * np.cos(eta[1])
    assert c[0] > 0 and np.any(c < 0)
    crossing = run.times[int(np.argmax(c < 0))]
    assert info.value.time <= crossing + 1e-9
    partial = info.value.partial
    tilt = np.cos(partial["phi1"]) * np.cos(partial["theta1"])
    assert np.all(tilt > 0)                               # honest rows: all before it


@pytest.mark.slow
def test_a_vehicle_driven_without_drag_leaves_its_speed_envelope():
    sc = quadland.load_scenario("paper", [
        "vehicle.d11=0", "vehicle.d22=0", "vehicle.m11=0.001", "vehicle.m22=0.001",
        "vehicle.tau=[1e8, 1e8, 5]", "simulation.duration=2"])
    with pytest.raises(SimulationError) as info:
        quadland.simulate(sc)
    assert "the vehicle_speed" in str(info.value)


@pytest.mark.slow
def test_a_cvodes_failure_keeps_its_rows_and_names_rk4():
    """cvodes' Adams method gives up on a body spun at 10,000 deg/s; the rows before
    the failing interval are kept and equal a one-call cvodes run that stops there."""
    case = ["initial.omega1_deg_s=[1e4, 1e4, 1e4]", 'simulation.integrator="cvodes"']
    with pytest.raises(SimulationError) as info:
        quadland.simulate(quadland.load_scenario("paper", [*case, "simulation.duration=5"]))
    msg = str(info.value)
    assert "CV_TOO_MUCH_WORK" in msg and 'simulation.integrator="rk"' in msg
    partial = info.value.partial
    assert partial is not None and partial["t"][-1] < info.value.time + 1e-12
    n = len(partial["t"])
    if partial["t"][-1] >= 0.01:
        short = quadland.simulate(quadland.load_scenario(
            "paper", [*case, f"simulation.duration={partial['t'][-1]:.12g}"]))
        np.testing.assert_allclose(partial.states, short.states[:n], rtol=1e-6, atol=1e-6)


def test_a_landing_too_slow_for_its_gains_names_the_control_rate():
    sc = quadland.load_scenario("highway", ["controller.k1=[1e3, 1e3, 1e3]",
                                            "controller.k2=[1e3, 1e3, 1e3]"])
    with pytest.raises(SimulationError) as info:
        quadland.simulate(sc)
    assert "controller.rate_hz=" in str(info.value)
    assert "rk_steps_per_interval" not in str(info.value)


def test_a_vehicle_that_outruns_the_quadrotor_is_not_a_divergence():
    """150 m/s and accelerating: the quadrotor flies at its tilt limit and falls behind
    at the vehicle's pace; after 300 s it has not landed, and the flight is judged so."""
    sc = quadland.load_scenario("highway", [
        "initial.velocity2=[150, 0]", "vehicle.tau=[22500, 0, 0]",
        "simulation.duration=300", "simulation.output_rate_hz=10", "sensors.enabled=false"])
    res = quadland.simulate(sc)
    assert not touchdown_report(res).touchdown
