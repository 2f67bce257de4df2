"""Vehicle model (eq. 4): steady state against its closed form."""

import casadi as ca
import numpy as np

from quadland_symbolic.parameters import VEHICLE
from quadland_symbolic.vehicle import vehicle_function


def test_steady_state_closed_form(values):
    """With m11 = m22 the yaw decouples: r = tau_z / d33, then
    u - (m22/d11) v r = tau_x / d11 and v + (m11/d22) u r = tau_y / d22."""
    p = VEHICLE.unpack(values.p_veh)
    tx, ty, tz = p["tau"]
    r = tz / p["d33"][0]
    a, b = p["m22"][0] / p["d11"][0] * r, p["m11"][0] / p["d22"][0] * r
    A = np.array([[1.0, -a], [b, 1.0]])
    u, v = np.linalg.solve(A, [tx / p["d11"][0], ty / p["d22"][0]])
    f = vehicle_function()
    xv = ca.SX.sym("xv", 6)
    integ = ca.integrator("veh", "cvodes", {"x": xv, "ode": f(xv, values.p_veh)}, 0, 60.0,
                          {"abstol": 1e-12, "reltol": 1e-12})
    x0 = np.array([0, 0, 0.26, 1.0, 1.0, 0.0])
    xf = np.array(integ(x0=x0)["xf"]).ravel()
    np.testing.assert_allclose(xf[3:6], [u, v, r], rtol=1e-8)
    # closed form for the paper's numbers: r = 5/80, u = (0.15 + 0.1 r)/(1 + r^2)
    np.testing.assert_allclose([u, v], [(0.15 + 0.1 * r) / (1 + r * r),
                                        (0.1 - 0.15 * r) / (1 + r * r)], rtol=1e-12)


def test_planar_kinematics(values):
    """The track moves along the heading: x2_dot = u cos psi - v sin psi."""
    f = vehicle_function()
    xdot = np.array(f([0, 0, np.pi / 2, 2.0, 0.5, 0.1], values.p_veh)).ravel()
    np.testing.assert_allclose(xdot[:3], [-0.5, 2.0, 0.1], atol=1e-15)
