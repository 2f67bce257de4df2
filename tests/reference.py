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
