"""Parameter vectors of the model and the controller.

Every builder in ``symbolic`` takes its constants as symbolic parameter
vectors, never as Python numbers, so that the same expressions serve the
simulator, the linearization and generated C code whose gains and physical
constants are tuned at run time without regeneration.

There are three groups, each a :class:`quadland_symbolic.layout.Layout`:

* ``QUADROTOR``: physical constants of the quadrotor (Table 1, eq. 2);
* ``VEHICLE``: constants and inputs of the ground vehicle (Table 1, eq. 4);
* ``controller_layout(l)``: gains, adaptation constants and RBF network
  (eq. 14, 16, 20, 22); its length depends on the node count ``l``.
"""

from __future__ import annotations

import functools

from quadland_symbolic.layout import Field, Layout

__all__ = [
    "RBF_INPUT_DIM",
    "QUADROTOR",
    "VEHICLE",
    "controller_layout",
]

#: Dimension of the RBF input vartheta (Section 3.2): four velocities and
#: their six pairwise products.
RBF_INPUT_DIM = 10


QUADROTOR = Layout(
    "p_quad",
    (
        Field("m1", 1, "kg", "quadrotor mass"),
        Field("I", 3, "kg m^2", "principal inertias Ix, Iy, Iz"),
        Field("Kt", 3, "N s/m", "translational drag Kt1..Kt3 (body axes)"),
        Field("Kr", 3, "N m s/rad", "rotational drag Kr1..Kr3 (body axes)"),
        Field("g", 1, "m/s^2", "gravitational acceleration"),
        Field("arm", 1, "m", "distance d from the centre to a rotor axis"),
        Field("c", 1, "m", "rotor drag factor c (yaw moment per unit thrust)"),
    ),
)

VEHICLE = Layout(
    "p_veh",
    (
        Field("m11", 1, "kg", "surge mass"),
        Field("m22", 1, "kg", "sway mass"),
        Field("m33", 1, "kg m^2", "yaw inertia"),
        Field("d11", 1, "kg/s", "surge damping"),
        Field("d22", 1, "kg/s", "sway damping"),
        Field("d33", 1, "kg m^2/s", "yaw damping"),
        Field("tau", 3, "N, N, N m", "inputs tau_x, tau_y, tau_z (eq. 4)"),
        Field("z2", 1, "m", "deck altitude (heave is neglected)"),
    ),
)


@functools.cache
def controller_layout(l: int) -> Layout:
    """Layout of the controller parameters for an ``l``-node network.

    Parameters
    ----------
    l : int
        Number of RBF nodes (eq. 8).
    """
    if l < 1:
        raise ValueError(f"RBF node count l must be >= 1, got {l}")
    return Layout(
        "p_ctrl",
        (
            Field("k1", 4, "1/s", "diagonal of k1 (eq. 14)"),
            Field("k2", 4, "1/s", "diagonal of k2 (eq. 20)"),
            Field("gamma1", 1, "-", "Gamma1 = gamma1 I_l (eq. 22)"),
            Field("gamma2", 1, "-", "Gamma2 = gamma2 I_4 (eq. 22)"),
            Field("k_w", 1, "-", "leakage of W_hat (eq. 22)"),
            Field("k_zeta", 1, "-", "leakage of zeta_hat (eq. 22)"),
            Field("rho", 1, "-", "tanh smoothing width varrho (eq. 20)"),
            Field("nominal_model", 1, "0 or 1",
                       "1 feeds forward the quadrotor's known dynamics"),
            Field("centers", RBF_INPUT_DIM * l, "-",
                       "RBF centres mu_i as the columns of a 10 x l matrix",
                       shape=(RBF_INPUT_DIM, l)),
            Field("widths", l, "-", "RBF widths epsilon_i"),
        ),
    )
