"""A paper scenario as the symbolic model's numeric vectors."""

from __future__ import annotations

import dataclasses

import numpy as np

from quadland.scenario import Scenario, require_model
from quadland_symbolic.backstepping import PAPER_REFERENCE
from quadland_symbolic.closed_loop import POSITION1, closed_loop_params, closed_loop_state
from quadland_symbolic.parameters import QUADROTOR, VEHICLE, controller_layout
from quadland_symbolic.quadrotor import QUAD_STATE
from quadland_symbolic.rbf import default_centers
from quadland_symbolic.vehicle import VEHICLE_STATE

__all__ = ["ModelValues", "model_values"]


@dataclasses.dataclass(frozen=True)
class ModelValues:
    """Parameter and initial-state vectors of one scenario.

    Attributes
    ----------
    l : int
        RBF node count.
    p_quad, p_veh, p_ctrl, ref : ndarray
        The parameter groups of ``quadland_symbolic.parameters`` and the reference
        ``[e1d, e1d_dot, e1d_ddot]``.
    p : ndarray
        Their concatenation, the closed loop's parameter vector.
    x0 : ndarray
        Initial closed-loop state (adaptive states start at zero).
    rotor_limits : tuple of float
        (min, max) rotor force, N.
    hold : float
        Hold compensation of the sampled control step, periods.
    """

    l: int
    p_quad: np.ndarray
    p_veh: np.ndarray
    p_ctrl: np.ndarray
    ref: np.ndarray
    p: np.ndarray
    x0: np.ndarray
    rotor_limits: tuple[float, float]
    hold: float


def model_values(scenario: Scenario) -> ModelValues:
    """Translate a validated scenario into the symbolic model's vectors.

    The paper's 4-DOF loop only: a landing scenario is refused in one line
    (its vectors are ``quadland.kinds.landing.values.landing_values``).
    """
    require_model(scenario, "paper", "the 4-DOF loop (simulation, codegen, margins)")
    q, v, c, r = (scenario.data[k] for k in ("quadrotor", "vehicle", "controller", "rbf"))
    l = r["nodes"]
    p_quad = QUADROTOR.pack(dict(
        m1=q["mass"], I=q["inertia"], Kt=q["drag_translational"], Kr=q["drag_rotational"],
        g=q["gravity"], arm=q["arm_length"], c=q["rotor_drag_factor"]))
    p_veh = VEHICLE.pack(dict(
        m11=v["m11"], m22=v["m22"], m33=v["m33"], d11=v["d11"], d22=v["d22"], d33=v["d33"],
        tau=v["tau"], z2=v["deck_altitude"]))
    p_ctrl = controller_layout(l).pack(dict(
        k1=c["k1"], k2=c["k2"], gamma1=c["gamma1"], gamma2=c["gamma2"], k_w=c["k_w"],
        k_zeta=c["k_zeta"], rho=c["rho"], nominal_model=float(c["nominal_model"]),
        centers=default_centers(l, r["center_min"], r["center_max"]),
        widths=np.full(l, r["width"])))
    ref = PAPER_REFERENCE.pack(dict(e1d=scenario.data["reference"]["e1d"], e1d_dot=np.zeros(4),
                              e1d_ddot=np.zeros(4)))
    init = scenario.data["initial"]
    deg = np.pi / 180
    xq = QUAD_STATE.pack(dict(z1=init["z1"], eta1=np.multiply(init["eta1_deg"], deg),
                              V1=init["velocity1"], Omega1=np.multiply(init["omega1_deg_s"], deg)))
    (x2, y2), (u2, v2) = init["position2"], init["velocity2"]
    xv = VEHICLE_STATE.pack(dict(x2=x2, y2=y2, psi2=init["psi2_deg"] * deg, u2=u2, v2=v2,
                                 r2=init["r2_deg_s"] * deg))
    x0 = closed_loop_state(l).pack(dict(
        xq=xq, xv=xv, W_hat=np.zeros((l, 4)), zeta_hat=np.zeros(4),
        pos1=POSITION1.pack(dict(x1=x2, y1=y2))))   # the quadrotor starts above the vehicle
    p = closed_loop_params(l).pack(dict(p_quad=p_quad, p_veh=p_veh, p_ctrl=p_ctrl, ref=ref))
    return ModelValues(l, p_quad, p_veh, p_ctrl, ref, p, x0,
                       (q["rotor_force_min"], q["rotor_force_max"]), c["hold_compensation"])
