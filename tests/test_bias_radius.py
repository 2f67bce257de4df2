"""The outer bias estimates held outside ``controller.bias_radius`` (issue 19, highway).

``d_hat_p' = ki_p z2_bar`` (docs/landing.md, "Integral action") learns the approach's
transient as a force when it integrates from the handover on ("The bias estimates'
slow tail"). With ``bias_radius = r > 0`` the x and y estimates integrate only while the
horizontal position error ``|z1[0:2]|`` is within ``r`` (conditional integration); z
always does; ``r = 0`` is the law of before. The step is checked here against that rule
written by hand (the estimate's exact one-period update ``d_hat + dt ki_p z2_bar``, then
the box), and the key's default against the scenarios that leave it out.
"""

import math
from pathlib import Path

import numpy as np
import pytest
from highway_before import BEFORE

import quadland
from quadland.scenario import load_scenario
from quadland_symbolic.landing.controller import (
    LANDING_MEASUREMENT,
    NETWORK_INPUT_DIM,
    landing_controller_params,
    landing_memory,
    landing_step_function,
)
from quadland_symbolic.landing.guidance import POSITION_REFERENCE
from quadland_symbolic.landing.quadrotor import ACTUATOR
from quadland_symbolic.landing.touchdown_policy import INERT_COMMANDS
from quadland_symbolic.parameters import QUADROTOR

L = 3
M1, G = 2.0, 9.8
P_QUAD = QUADROTOR.pack(dict(m1=M1, I=[0.025, 0.025, 0.045], Kt=[0.3] * 3, Kr=[0.001] * 3,
                             g=G, arm=0.25, c=0.05))
P_ACT = ACTUATOR.pack(dict(motor_time_constant=0.02, F_max=M1 * G / 2, gear_height=0.2,
                           rotor_efficiency=[1.0] * 4, cg_offset=[0.0] * 3,
                           drag_quadratic=[0.0] * 3, rotor_radius=0.0, air_density=1.225))
KI_P = np.array([2.0, 2.0, 1.0])
D_MAX_P = 4.0
DT = 0.004


def _p_ctrl(r_learn):
    return landing_controller_params(L).pack(dict(
        k1p=[1.5] * 3, k2p=[1.5] * 3, k1=[2.0] * 3, k2=[14.0] * 3, gamma1=0.05, gamma2=0.1,
        k_w=5.0, k_zeta=0.1, rho=0.1, nominal_model=1.0, w_f=10.0, zeta_f=1.0,
        tilt_max=math.radians(45), ki_p=KI_P, ki=[2.0] * 3, d_max_p=D_MAX_P, d_max=40.0,
        r_learn=r_learn, w_o=[12.0] * 3,
        centers=np.zeros((NETWORK_INPUT_DIM, L)), widths=np.full(L, 2.0)))


def _case(offset_xy):
    """At 3 m over a level deck, ``offset_xy`` (m) beside the hover point, drifting at
    0.2 m/s, the outer estimates at [0.1, -0.2, 0.3] m/s^2."""
    y = LANDING_MEASUREMENT.pack(dict(
        p_e=[*offset_xy, 3.1], v_e=[0.2, -0.2, 0.1], eta1=[0.02, -0.03, 0.0],
        Omega1=[0.0, 0.0, 0.0], eta2=[0.0, 0.0, 0.0], v2E=[13.9, 0.0, 0.0], a2E=[0.0] * 3,
        w2E=[0.0] * 3, w2E_dot=[0.0] * 3))
    ref = POSITION_REFERENCE.pack(dict(p_ref=[0.0, 0.0, 3.0], v_ref=[0.0] * 3,
                                       a_ref=[0.0] * 3, **INERT_COMMANDS))
    lay = landing_memory(L)
    mem = lay.pack({**lay.unpack(lay.zeros()), "d_hat": [0.1, -0.2, 0.3, 0.0, 0.0, 0.0],
                    "T_o": M1 * G})
    return y, ref, mem


@pytest.fixture(scope="module")
def step():
    return landing_step_function(L)


def _next_outer_bias(step, r_learn, offset_xy):
    """``d_hat_p`` after one step, and what the hand rule gives for it."""
    y, ref, mem = _case(offset_xy)
    out = dict(zip(step.name_out(), step(y, ref, mem, _p_ctrl(r_learn), P_QUAD, P_ACT, DT),
                   strict=True))
    lay = landing_memory(L)
    d_hat = lay.unpack(np.array(out["mem_next"]).ravel())["d_hat"][:3]
    # z2_bar = z2 (the compensator's xi starts at 0); z1 = p_e - p_ref
    z1, z2 = np.array(out["bs_z1"]).ravel()[:3], np.array(out["bs_z2"]).ravel()[:3]
    inside = r_learn == 0 or np.hypot(z1[0], z1[1]) <= r_learn
    gate = np.array([inside, inside, True], dtype=float)
    expected = np.clip(lay.unpack(mem)["d_hat"][:3] + DT * KI_P * gate * z2, -D_MAX_P, D_MAX_P)
    return d_hat, expected, z2


@pytest.mark.parametrize(("r_learn", "offset_xy", "learns_xy"), [
    (0.0, [1.5, -2.0], True),        # no gate: the law of before
    (0.1, [1.5, -2.0], False),       # 2.5 m off: x and y held, z learns
    (0.1, [0.06, -0.07], True),      # 0.092 m off, within 0.1 m
    (0.1, [0.08, -0.07], False),     # 0.106 m off
    (1e3, [1.5, -2.0], True),        # a radius past any error: always
])
def test_the_x_y_estimates_learn_only_within_the_radius(step, r_learn, offset_xy, learns_xy):
    d_hat, expected, z2 = _next_outer_bias(step, r_learn, offset_xy)
    assert np.all(np.abs(z2) > 0.01)                         # each channel has something to learn
    np.testing.assert_allclose(d_hat, expected, rtol=0, atol=1e-15)
    held = np.isclose(d_hat[:2], [0.1, -0.2], rtol=0, atol=0)
    assert held.tolist() == [not learns_xy] * 2
    assert d_hat[2] != 0.3                                   # z learns in every case


def test_no_radius_is_the_law_of_before_to_the_bit(step):
    """``r_learn = 0`` and a radius no error reaches give the same step, every output."""
    y, ref, mem = _case([1.5, -2.0])
    off = step(y, ref, mem, _p_ctrl(0.0), P_QUAD, P_ACT, DT)
    far = step(y, ref, mem, _p_ctrl(1e3), P_QUAD, P_ACT, DT)
    for a, b in zip(off, far, strict=True):
        np.testing.assert_array_equal(np.array(a), np.array(b))


@pytest.mark.parametrize("name", ["turning", "ship", "ship_ss5", "highway_100"])
def test_the_scenarios_that_leave_the_key_out_take_no_radius(name):
    """The key came after these files: they leave it out and fly as before (no radius)."""
    sc = load_scenario(name)
    assert "bias_radius" not in Path(sc.source).read_text()
    assert sc["controller.bias_radius"] == 0.0


#: the calm default flight: perfect sensing, no turbulence, gust or disturbance noise.
CALM = ("sensors.enabled=false", "wind.turbulence_w20=0.0", "wind.gust_amplitude=0.0",
        "disturbance.noise=false")
#: the bias estimates of x and y on, at the gain of highway's law of before.
KI_P_BEFORE = "controller.ki_p=[0.5, 0.5, 1.0]"


def _calm(*overrides):
    return quadland.simulate(load_scenario("highway", [*CALM, *BEFORE, *overrides]))


def test_held_through_the_approach_the_flight_is_the_observer_alones_until_the_radius():
    """Within the radius the estimates learn; outside they are held at 0, so the flight
    with ``ki_p = 0.5`` on x, y and a 0.1 m radius is the flight without them (highway's
    shipped ``ki_p = [0, 0, 1]``) to the bit until the horizontal error first comes within
    0.1 m, and differs after. Ungated, the same estimates learn the approach's transient
    and carry it to the contact, 33.9 / -19.1 mm from the centre
    (``tests/test_highway_observer_xyz.py``); held, 3.2 / -2.9 mm, touching down when the
    flight without them does (8.20 s, not 8.96 s)."""
    alone, held = _calm(), _calm(KI_P_BEFORE, "controller.bias_radius=0.1")
    error = np.hypot(alone["x_e"] - alone["x_ref"], alone["y_e"] - alone["y_ref"])
    first = int(np.flatnonzero(error <= 0.1)[0])
    assert alone["t"][first] > 3.0                          # the approach lasts seconds
    for name in ("x_e", "y_e", "z_e", "phi1", "theta1"):
        np.testing.assert_array_equal(held[name][:first + 1], alone[name][:first + 1])
        assert not np.array_equal(held[name], alone[name])
    k = int(np.flatnonzero(held["touched"] > 0.5)[0])
    np.testing.assert_allclose([held["x_e"][k], held["y_e"][k]], [0.00322, -0.00290],
                               atol=5e-5)
    k_alone = int(np.flatnonzero(alone["touched"] > 0.5)[0])
    assert held["t"][k] == pytest.approx(alone["t"][k_alone], abs=0.011)
    ungated = _calm(KI_P_BEFORE)
    k_ungated = int(np.flatnonzero(ungated["touched"] > 0.5)[0])
    np.testing.assert_allclose([ungated["x_e"][k_ungated], ungated["y_e"][k_ungated]],
                               [0.0339, -0.0191], atol=5e-4)
