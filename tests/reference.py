"""Independent NumPy expressions of the paper's kinematics, for the tests."""

import numpy as np


def euler_rate_matrix(phi, theta):
    """Rr of eq. (1), written out from the printed matrix."""
    return np.array([[1, np.tan(theta) * np.sin(phi), np.tan(theta) * np.cos(phi)],
                     [0, np.cos(phi), -np.sin(phi)],
                     [0, np.sin(phi) / np.cos(theta), np.cos(phi) / np.cos(theta)]])


def error_rate_matrix(phi, theta):
    """R = diag(1, Rr) of eq. (10)."""
    R = np.eye(4)
    R[1:, 1:] = euler_rate_matrix(phi, theta)
    return R


def rotation(eta):
    """Rz(psi) Ry(theta) Rx(phi) (body to E), multiplied out by hand."""
    phi, th, psi = eta
    cf, sf, ct, st = np.cos(phi), np.sin(phi), np.cos(th), np.sin(th)
    cp, sp = np.cos(psi), np.sin(psi)
    return np.array([[cp * ct, cp * st * sf - sp * cf, cp * st * cf + sp * sf],
                     [sp * ct, sp * st * sf + cp * cf, sp * st * cf - cp * sf],
                     [-st, ct * sf, ct * cf]])


def have_compiler() -> bool:
    """Whether quadland finds a C compiler (tests of generated C skip without one)."""
    from quadland.build import have_compiler as found

    return found()
