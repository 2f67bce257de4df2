"""Rotations written out by hand in numpy, the tests' reference for quadland's symbolic
``Rz Ry Rx`` convention (independent of ``quadland_symbolic.kinematics``)."""

import math

import numpy as np


def Rx(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def Ry(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def Rz(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def R_zyx(eta):
    """``Rz(psi) Ry(theta) Rx(phi)`` of ``eta = (phi, theta, psi)``."""
    return Rz(eta[2]) @ Ry(eta[1]) @ Rx(eta[0])
