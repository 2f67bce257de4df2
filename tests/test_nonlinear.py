"""quadland.nlsys: the loop as a python-control NonlinearIOSystem, against quadland's own
simulation and linearization (issue 21)."""

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
    with pytest.raises(ScenarioError, match="sampled-data, with no continuous closed loop"):
        quadland.nlsys("highway")
    with pytest.raises(ScenarioError, match="which: must be one of closed_loop, plant"):
        quadland.nlsys("paper", "loop")
