"""quadland.nlsys: the loop as a python-control NonlinearIOSystem, against quadland's own
simulation and linearization (issue 21)."""

import math
import warnings

import control
import numpy as np
import pytest

import quadland
from quadland.exceptions import ScenarioError

QUIET = ["disturbance.noise=false", "disturbance.force_bias=[0.0, 0.0, 0.0]",
         "disturbance.force_amplitude=0.0", "disturbance.moment_bias=[0.0, 0.0, 0.0]",
         "disturbance.moment_amplitude=0.0"]


def test_the_closed_loop_responds_as_quadland_simulates():
    """python-control's own integrator (SciPy's RK45 at 1e-10) on the wrapped loop against
    quadland's compiled CVODES at 1e-10, disturbance-free: the same trajectory."""
    sc = quadland.load_scenario("paper", [*QUIET, "simulation.duration=0.5",
                                          "simulation.integrator=\"cvodes\""])
    res = quadland.simulate(sc)
    sys = quadland.nlsys(sc)
    t = np.asarray(res["t"])
    resp = control.input_output_response(
        sys, t, np.zeros((sys.ninputs, len(t))), sys.x0,
        solve_ivp_kwargs=dict(rtol=1e-10, atol=1e-10))
    for name in ("z_e", "phi_e", "theta_e", "psi_e", "u_1", "lyapunov_V1"):
        got = resp.outputs[sys.output_labels.index(name)]
        np.testing.assert_allclose(got, res[name], rtol=1e-6, atol=1e-7, err_msg=name)


def test_its_linearization_is_quadlands_jacobian():
    """control.linearize (finite differences) at the initial state against the closed
    loop's Jacobian by CasADi's algorithmic differentiation."""
    from quadland.kinds.paper.values import model_values
    from quadland_symbolic.closed_loop import closed_loop_jacobian_function

    sc = quadland.load_scenario("paper", QUIET)
    sys = quadland.nlsys(sc)
    lin = control.linearize(sys, sys.x0, np.zeros(sys.ninputs), copy_names=True)
    mv = model_values(sc)
    A = np.asarray(closed_loop_jacobian_function(mv.l)(mv.x0, np.zeros(6), mv.p).full())
    scale = np.maximum(1.0, np.abs(A))
    assert np.max(np.abs(lin.A - A) / scale) < 1e-5
    assert lin.input_labels == sys.input_labels and lin.state_labels == sys.state_labels


def test_find_eqpt_holds_a_hovering_landing_plant():
    """The landing plant at its handover state (level, rotors at the weight shared by
    four): find_eqpt finds the rotor commands that rest the motors' lag, the weight
    again; there the angular accelerations vanish, as hover requires, and the vertical
    one is the ground effect's."""
    sc = quadland.load_scenario("highway", ["initial.eta1_deg=[0.0, 0.0, 0.0]",
                                            "initial.omega1_deg_s=[0.0, 0.0, 0.0]"])
    sys = quadland.nlsys(sc, "plant")
    q = sc.data["quadrotor"]
    names = sys.state_labels
    motors = [names.index(f"F_{i}") for i in range(1, 5)]
    u0 = np.zeros(sys.ninputs)
    u0[:4] = 0.8 * q["mass"] * q["gravity"] / 4
    with warnings.catch_warnings():
        # python-control counts the fixed states as constraints against the 4 free inputs
        # and warns; the result is checked below against hover's physics
        warnings.filterwarnings("ignore", "number of constraints", UserWarning)
        xeq, ueq = control.find_eqpt(sys, sys.x0, u0, iu=list(range(4, sys.ninputs)),
                                     ix=list(range(sys.nstates)), idx=motors)
    np.testing.assert_allclose(ueq[:4], q["mass"] * q["gravity"] / 4, rtol=1e-9)
    dx = sys._rhs(0.0, xeq, ueq)
    for n in ("p1", "q1", "r1"):
        assert abs(dx[names.index(n)]) < 1e-9, (n, dx[names.index(n)])
    # vertically, the ground effect 4 m above the roof is left (Cheeseman and Bennett's
    # k = 1 / (1 - (R / 4z)^2 / (1 + (V / v_i)^2)) at the car's 50 km/h through still
    # air, docs/landing.md): (k - 1) g, 1e-4 m/s^2
    R, z, V, g = sc["quadrotor.rotor_radius"], 4.0, 50 / 3.6, q["gravity"]
    v_i2 = q["mass"] * g / 4 / (2 * sc["wind.air_density"] * np.pi * R ** 2)
    k = 1 / (1 - (R / (4 * z)) ** 2 / (1 + V ** 2 / v_i2))
    assert dx[names.index("w1")] == pytest.approx((k - 1) * g, rel=1e-6)


def test_what_nlsys_refuses_is_one_line():
    with pytest.raises(ScenarioError, match="which: must be one of closed_loop, plant"):
        quadland.nlsys("paper", "loop")


# ------------------------------------------------------------ a landing's sampled loop

#: A landing on perfect sensors under a constant disturbance (its biases): the loop
#: nlsys gives, and a disturbance that holding it per control period does not change.
LANDING_QUIET = ["sensors.enabled=false", "disturbance.noise=false",
                 "disturbance.force_amplitude=0.0", "disturbance.moment_amplitude=0.0",
                 "wind.turbulence_w20=0.0", "wind.gust_amplitude=0.0"]
#: ... over a parked car, the guidance holding the hover point (align, a long dwell):
#: the loop has an equilibrium there, the one quadland margins linearizes at.
PARKED = [*LANDING_QUIET, "vehicle.tau=[0.0, 0.0, 0.0]", "initial.velocity2=[0.0, 0.0]",
          "landing.dwell_time=1000.0", "initial.position1=[0.4, -0.3]", "initial.z1=5.0"]
#: States the hover leaves where they are: the parked car's, the gear's memory (no
#: contact), the guidance's (held in align, its dwell timer a clock), the outer bias
#: estimates of x and y, whose gain is zero beside the observer there (held at 0, as
#: quadland's equilibrium pins a zero-gain bias estimate: each value would be a rest
#: with the quadrotor off its reference, docs/landing.md, "the bias estimates' slow tail").
#: (Before highway's observer on z, its v_hat_z and d_o_z were the held ones.)
HELD = ("x2", "y2", "psi2", "u2", "v2", "r2", "impulse", "t_contact", "F_peak", "phase",
        "timer", "z_ref", "aborts", "d_hat_1", "d_hat_2")


def _constant_w(sc) -> np.ndarray:
    d = sc.data["disturbance"]
    return np.r_[sc.data["wind"]["mean"], d["force_bias"], d["moment_bias"]]


def test_a_landing_closed_loop_is_the_simulated_flight_up_to_first_contact():
    """The discrete-time loop from control instant to control instant against
    quadland.simulate's rows at the instants both have (every 20 ms: 250 Hz control,
    100 Hz rows) before the first contact: the same CasADi functions and the same RK4
    steps on the same grid, so the two differ only by evaluating them compiled or on
    CasADi's virtual machine, rounding (they are bit for bit equal here)."""
    sc = quadland.load_scenario("highway", LANDING_QUIET)
    res = quadland.simulate(sc)
    sys = quadland.nlsys(sc)
    assert sys.dt == pytest.approx(1 / 250) and sys.ninputs == 9
    t_contact = float(res["t"][np.argmax(res["touched"] == 1.0)])
    assert set(res["phase"][res["t"] < t_contact]) == {0.0, 1.0, 2.0}   # approach..descend
    n = int(np.floor(t_contact / sys.dt))
    T = sys.dt * np.arange(n + 1)
    resp = control.input_output_response(sys, T, np.tile(_constant_w(sc)[:, None], n + 1),
                                         sys.x0)
    t = np.asarray(res["t"])
    rows = np.flatnonzero(np.isclose(t * 50, np.rint(t * 50), rtol=0, atol=1e-6) & (t < T[-1]))
    k = np.rint(res["t"][rows] / sys.dt).astype(int)
    np.testing.assert_allclose(T[k], res["t"][rows], rtol=0, atol=1e-12)
    # every 20 ms instant before the last control instant (touchdown near 9 s: 455 of them)
    assert len(rows) == len(np.arange(0.0, T[-1] - 1e-9, 0.02)) > 400
    for name in sys.output_labels:
        got, want = resp.outputs[sys.output_labels.index(name)][k], res[name][rows]
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12, err_msg=name)
    # the state: the plant's at the instant, the memory after that instant's step
    nxp, nxc = 25, res.states.shape[1] - 25
    np.testing.assert_allclose(resp.states[:nxp, k].T, res.states[rows, :nxp], rtol=1e-12,
                               atol=1e-12)
    np.testing.assert_allclose(resp.states[nxp:nxp + nxc, k + 1].T, res.states[rows, nxp:],
                               rtol=1e-12, atol=1e-12)
    # the queue holds the command of the step before (controller.delay_periods = 1)
    queue = [sys.state_labels.index(f"F_{i}_cmd_delay1") for i in range(1, 5)]
    commands = [sys.output_labels.index(f"F_{i}_cmd") for i in range(1, 5)]
    np.testing.assert_array_equal(resp.states[queue, 1:], resp.outputs[commands, :-1])


def test_a_landing_on_sensors_warns_that_nlsys_reads_the_true_state():
    with pytest.warns(UserWarning, match=r"nlsys: highway flies on its sensors .* true state"):
        sys = quadland.nlsys("highway")
    # the plant (25), the guidance (13: phase, timer, z_ref, aborts, the commit and arming
    # flags, the quiescent-period predictor's two averages, the deck tilt predictor's two
    # averages, the lean's two and the gust's lean), the step's memory (6 l + 29, l = 10
    # nodes), the four rotor commands of one period's delay: no filter, no sensor delay lines
    assert sys.nstates == 25 + 13 + 6 * 10 + 29 + 4 and sys.dt == pytest.approx(0.004)


def _hover(rk_steps: int = 1):
    """The parked scenario, nlsys's equilibrium at its hover by control.find_eqpt (from
    the scenario's initial state, 0.6 m off and the memory at zero), and quadland's."""
    from quadland.linearization import equilibrium

    sc = quadland.load_scenario("highway", [*PARKED, f"simulation.rk_steps_per_interval="
                                                     f"{rk_steps}"])
    sys = quadland.nlsys(sc)
    names = sys.state_labels
    x0 = sys.x0.copy()
    x0[names.index("phase")] = 1.0                  # align: the hover point, held
    ix = [names.index(n) for n in HELD]
    with warnings.catch_warnings():
        # python-control counts the outputs as constraints although no output is asked
        # for, and warns; the equations are the free states' updates, as many as they
        warnings.filterwarnings("ignore", "number of constraints", UserWarning)
        op = control.find_eqpt(sys, x0, _constant_w(sc), iu=list(range(sys.ninputs)), ix=ix,
                               idx=[i for i in range(sys.nstates) if i not in ix],
                               return_result=True)
    assert op.result.success, op.result.message
    return sc, sys, op, equilibrium(sc)


def test_find_eqpt_finds_quadlands_hover_equilibrium():
    """find_eqpt on the discrete loop (x = f(x)) against quadland's own hover
    (Newton's method on the continuous plant's and the memory's rates at rest): the
    same point, to scipy's root tolerance (1.5e-8 relative)."""
    sc, sys, op, pt = _hover()
    x = dict(zip(sys.state_labels, op.states, strict=True))
    deck = sc.data["deck"]["height"]
    from_nlsys = dict(x_e=x["x1"], y_e=x["y1"], z_e=x["z1"] - deck, psi_e=x["psi1"] - x["psi2"])
    for name, value in zip(pt.state_names, pt.xr, strict=True):
        assert from_nlsys.get(name, x.get(name)) == pytest.approx(value, abs=1e-7), name
    assert pt.xr[pt.state_names.index("z_e")] == pytest.approx(3.0)    # hover_height
    memory = sys.state_labels[38:38 + pt.xc.size]          # after the plant's 25, the guidance's 13
    np.testing.assert_allclose([x[n] for n in memory], pt.xc, rtol=1e-7, atol=1e-7)
    # the command in the queue is the step's own at the hover: the equilibrium's forces
    for i in range(1, 5):
        assert x[f"F_{i}_cmd_delay1"] == pytest.approx(x[f"F_{i}"], abs=1e-7)


def _eigenvalue_gap(sys, op, sc, pt):
    """The largest distance between the margins' sampled closed loop's eigenvalues and
    their partners (matched one to one) among control.linearize's; and the rest."""
    from scipy.optimize import linear_sum_assignment

    from quadland.linearization import sampled_models

    lin = control.linearize(sys, op.states, op.inputs, copy_names=True)
    assert lin.dt == sys.dt and lin.state_labels == sys.state_labels
    ours = np.linalg.eigvals(lin.A)
    c = sc.data["controller"]
    theirs = np.linalg.eigvals(sampled_models(sc, pt, c["rate_hz"], c["delay_periods"])
                               .closed_loop.A)
    gap = np.abs(theirs[:, None] - ours[None, :])
    rows, cols = linear_sum_assignment(gap)
    return gap[rows, cols].max(), np.sort(np.delete(ours, cols).real)


def test_linearize_at_the_hover_is_quadlands_sampled_loop():
    """control.linearize of the discrete loop (finite differences through one period)
    against ``quadland margins``' sampled-data closed loop at the same hover (the
    plant's Jacobian under an exact zero-order hold, the step's Jacobians, one period of
    delay): its eigenvalues are among the 125, within RK4's error over a 4 ms step
    (the fastest plant mode's |lambda h|^5 / 120 is 2e-6; the closed loop's eigenvalues
    carry it amplified by their conditioning: 6.55e-6 with highway's observer on z, under
    5e-6 before it). That the gap is RK4's error and nothing else is checked by its order,
    not its size: it falls sixteenfold as the steps halve (RK4 is fourth order; 17.5
    measured); the 24 others are the modes the margins' model leaves out, in closed form."""
    sc, sys, op, pt = _hover()
    gap, extra = _eigenvalue_gap(sys, op, sc, pt)
    assert gap < 1e-5
    # the parked car: its position and heading (1), its speeds' damping exp(-d/m dt); the
    # gear's memory and the guidance's phase, timer and aborts (1); z_ref, which glides
    # back onto the hover height in one step, the commit flag, set anew each step, and the
    # contact switch's arming, cleared outside the descent (0);
    # the quiescent-period predictor's two averages of the deck's motion and the deck tilt
    # predictor's four (its rates squared, the lean), 1 - dt / T_m = exp(-dt / T_m) within
    # (dt / T_m)^2 / 2 = 2e-8; the gust's lean averaged over lean_time, 1 - dt / T_l (its
    # update is that first-order step, exactly); the outer bias estimates of x and y, of zero
    # gain, held (1)
    v, dt = sc.data["vehicle"], sys.dt
    fade = math.exp(-dt / sc.data["landing"]["motion_time"])
    gust = 1 - dt / sc.data["landing"]["lean_time"]
    expected = np.sort([0.0, 0.0, 0.0, *[fade] * 6, gust,
                        *np.exp(-dt * np.array([v["d11"] / v["m11"], v["d22"] / v["m22"],
                                                v["d33"] / v["m33"]])), *[1.0] * 11])
    np.testing.assert_allclose(extra, expected, rtol=0, atol=1e-7)
    sc2, sys2, op2, pt2 = _hover(rk_steps=2)
    gap2, _ = _eigenvalue_gap(sys2, op2, sc2, pt2)
    assert 12 < gap / gap2 < 20   # 2^4 = 16
