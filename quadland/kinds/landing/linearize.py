"""The landing loop linearized at its hover over the pad, and its linear models.

The loop is broken at the wrench ``u = [T, M_x, M_y, M_z]`` its step sends to
the mixer. The plant (6-DOF with motor lag, in the deck frame,
``quadland_symbolic.landing.linearization``) maps u to the quadrotor's
measurements ``y = [p_e, v_e, eta1, Omega1]``; the controller is the landing
step, whose state is its memory. It is analysed hovering
``landing.hover_height`` above the pad (:func:`hover_equilibrium`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from quadland.constants import TILT_MIN
from quadland.engine.function_store import stored_function
from quadland.exceptions import OperatingPointError, SingularAttitudeError
from quadland.kinds.landing.values import landing_values
from quadland.linear import (
    LinearModels,
    OperatingPoint,
    assemble,
    check_delay_periods,
    delayed,
    newton,
    zoh,
)
from quadland.scenario import Scenario
from quadland_symbolic.kinematics import rotation
from quadland_symbolic.landing.controller import (
    N_CHANNELS,
    landing_controller_params,
    landing_memory,
)
from quadland_symbolic.landing.deck import DECK_PARAMS
from quadland_symbolic.landing.guidance import POSITION_REFERENCE
from quadland_symbolic.landing.linearization import (
    HOVER_OUTPUT,
    HOVER_PLANT,
    hover_equilibrium_residual_function,
    hover_linearization_function,
)
from quadland_symbolic.landing.loop import landing_loop_params
from quadland_symbolic.landing.plant import (
    LANDING_DISTURBANCE,
    LANDING_PLANT_PARAMS,
    LANDING_PLANT_STATE,
)
from quadland_symbolic.landing.touchdown_policy import INERT_COMMANDS
from quadland_symbolic.linearization import VEHICLE_SPEEDS
from quadland_symbolic.quadrotor import WRENCH
from quadland_symbolic.vehicle import VEHICLE_STATE

__all__ = ["LANDING_LOOP_NAMES", "LANDING_INPUT_NAMES", "hover_equilibrium",
           "hover_linear_models", "hover_sampled_models", "hover_values", "hover_jacobians",
           "kept_memory"]

#: The four loops of the landing loop, one per entry of the wrench into the mixer.
LANDING_LOOP_NAMES = ("thrust", "roll", "pitch", "yaw")
#: Names of the landing loop's inputs: the wrench ``[T, M_x, M_y, M_z]``.
LANDING_INPUT_NAMES = WRENCH.element_names()


@dataclasses.dataclass(frozen=True)
class _HoverValues:
    """A landing scenario's vectors at its hover point (frozen deck, mean wind)."""

    l: int
    pp: np.ndarray          # plant parameters, the deck's heave, roll and pitch zeroed
    pm: np.ndarray          # the controller's own model of them, likewise
    p_ctrl: np.ndarray
    ref: np.ndarray         # hover point, at rest, deck frame
    w: np.ndarray           # [v_wind (heading frame), d_F, d_M]
    speeds: np.ndarray      # the vehicle's initial [u2, v2, r2]: Newton's start
    hover_thrust: float     # N, m1 g


def _hover_values(scenario: Scenario) -> _HoverValues:
    lv = landing_values(scenario)
    pc = landing_loop_params(lv.l).unpack(lv.pc)

    def frozen(params):
        """The parameters with the deck's heave, roll and pitch zeroed."""
        p = LANDING_PLANT_PARAMS.unpack(params)
        deck = DECK_PARAMS.unpack(p["p_deck"])
        for motion in ("heave", "roll", "pitch"):
            deck[f"{motion}_amp"] = np.zeros_like(deck[f"{motion}_amp"])
        p["p_deck"] = DECK_PARAMS.pack(deck)
        return LANDING_PLANT_PARAMS.pack(p)

    d = scenario.data
    xv0 = VEHICLE_STATE.unpack(LANDING_PLANT_STATE.unpack(lv.xp0)["xv"])
    heading = np.asarray(rotation([0.0, 0.0, float(xv0["psi2"][0])]), dtype=float)
    w = LANDING_DISTURBANCE.pack(dict(v_wind=heading.T @ np.asarray(d["wind"]["mean"]),
                                      d_F=d["disturbance"]["force_bias"],
                                      d_M=d["disturbance"]["moment_bias"]))
    ref = POSITION_REFERENCE.pack(dict(p_ref=[0.0, 0.0, d["landing"]["hover_height"]],
                              v_ref=np.zeros(3), a_ref=np.zeros(3), **INERT_COMMANDS))
    q = d["quadrotor"]
    return _HoverValues(lv.l, frozen(lv.pp), frozen(pc["pp"]), pc["p_ctrl"], ref, w,
                        np.concatenate([xv0[n] for n in VEHICLE_SPEEDS.names()]),
                        q["mass"] * q["gravity"])


def hover_equilibrium(scenario: Scenario, tol: float = 1e-9, max_iter: int = 50) -> OperatingPoint:
    """The landing loop's hover ``landing.hover_height`` above the pad, at rest in the deck frame.

    The outer position loop is closed on that reference: the vehicle in its
    steady motion, the deck's heave, roll and pitch at zero (their mean), the
    wind at ``wind.mean`` (turbulence and gust left out, the wind turned into
    the vehicle's initial heading) and the disturbance at its constant part;
    the step's memory (network, robust terms, command filter, compensator) at
    rest (``quadland_symbolic.landing.linearization.hover_equilibrium_residual_function``),
    found by Newton's method (:func:`quadland.linear.newton`).
    """
    hv = _hover_values(scenario)
    F = stored_function(hover_equilibrium_residual_function, hv.l)
    z0 = HOVER_PLANT.zeros()
    z0[HOVER_PLANT.slice("p_e")] = hv.ref[:3]
    z0[HOVER_PLANT.slice("V1")] = hv.speeds[:2].tolist() + [0.0]    # moving with the vehicle
    z0[HOVER_PLANT.slice("F")] = hv.hover_thrust / 4
    mem_lay = landing_memory(hv.l)
    nz, nm = HOVER_PLANT.size, mem_lay.size
    mem0 = mem_lay.zeros()
    # Start the command filter and the attitude at the commanded roll and pitch:
    # a filter far from its input commands moments that clip the rotors, where
    # Newton's method sees no slope. The filter's rate row gives its input,
    # c = eta_f + (eta_f_dot' + 2 zeta_f w_f eta_f_dot) / w_f^2, with eta_f_dot = 0.
    lin = stored_function(hover_linearization_function, hv.l)
    ctrl = landing_controller_params(hv.l).unpack(hv.p_ctrl)
    for _ in range(3):
        rates = lin(z0, mem0, hv.speeds, hv.w, hv.pp, hv.pm, hv.p_ctrl, hv.ref, 0.0)[2]
        mem_dot = mem_lay.unpack(np.asarray(rates, dtype=float).ravel())
        c = mem_lay.unpack(mem0)["eta_f"] + mem_dot["eta_f_dot"] / ctrl["w_f"] ** 2
        mem0[mem_lay.slice("eta_f")] = c
        z0[HOVER_PLANT.slice("eta1")][:2] = c
        # the body velocity of moving with the vehicle at that attitude (the drag's
        # steady tilt is 18 deg at 50 km/h: a level body's velocity would climb)
        R = np.asarray(rotation([*c, 0.0]), dtype=float)
        z0[HOVER_PLANT.slice("V1")] = R.T @ np.array([*hv.speeds[:2], 0.0])
    xi = np.concatenate([z0, mem0, hv.speeds])

    def residual_at(lam):
        """The residual with the plant ``lam`` of the way from the controller's model
        (no wind, no disturbance) to the scenario's."""
        pp, w = hv.pm + lam * (hv.pp - hv.pm), lam * hv.w

        def residual(x):
            r, J = F(x, w, pp, hv.pm, hv.p_ctrl, hv.ref)
            return np.asarray(r, dtype=float).ravel(), np.asarray(J, dtype=float)
        return residual

    try:
        xi, it = newton(residual_at(1.0), xi, tol, max_iter)
    except OperatingPointError:
        xi, it = _continuation(residual_at, xi, tol, max_iter)
    z, mem, speeds = xi[:nz], xi[nz:nz + nm], xi[nz + nm:]
    out = lin(z, mem, speeds, hv.w, hv.pp, hv.pm, hv.p_ctrl, hv.ref, 0.0)
    u, z_dot, mem_dot = (np.asarray(v, dtype=float).ravel() for v in out[0:3])
    tilt = np.cos(z[HOVER_PLANT.index("phi1")]) * np.cos(z[HOVER_PLANT.index("theta1")])
    if abs(tilt) < TILT_MIN:
        raise SingularAttitudeError(f"operating point at cos(theta) cos(phi) = {tilt:.2e}: "
                                    "the attitude kinematics are singular there")
    deck = scenario.data["deck"]
    z2 = float(deck["height"] + deck["pad_offset"][2])          # the pad, the deck still
    ms = landing_memory(hv.l).unpack(mem)
    return OperatingPoint("equilibrium", None, z, mem, speeds, z2, hv.w, u,
                          float(np.linalg.norm(np.r_[z_dot, mem_dot])), it, "landing",
                          HOVER_PLANT.element_names(),
                          dict(zeta_hat=ms["zeta_hat"].tolist(),
                               norm_W_hat=float(np.linalg.norm(ms["W_hat"])),
                               wrench=dict(zip(LANDING_INPUT_NAMES, u.tolist(), strict=True))))


def _continuation(residual_at, xi, tol: float, max_iter: int, steps: int = 64):
    """Newton's method along ``residual_at(lam)``, ``lam`` from 0 to 1.

    From a cold start Newton's method can stall where the plant differs from
    the controller's model or the wind is strong (``ship`` with a lighter
    quadrotor: the robust terms far from rest); the loop without mismatch,
    wind or disturbance (``lam = 0``) converges from it, and each step starts
    from the last point. Steps halve on a stall, at most ``steps`` of them.
    """
    xi, it = newton(residual_at(0.0), xi, tol, max_iter)
    lam, step = 0.0, 0.25
    while lam < 1.0 and steps > 0:
        steps -= 1
        trial = min(1.0, lam + step)
        try:
            xi, k = newton(residual_at(trial), xi, tol, max_iter)
        except OperatingPointError:
            step /= 2
            continue
        lam, it, step = trial, it + k, min(2 * step, 1.0)
    if lam < 1.0:
        raise OperatingPointError(f"no equilibrium: Newton's method stalled, and along the "
                                  f"way from the controller's model without wind only "
                                  f"{lam:.3g} of it")
    return xi, it


def _hover_jacobians(scenario: Scenario, point: OperatingPoint, dt: float):
    """The Jacobians at the point, without the memory's bias estimates whose gain is zero:
    constant, they are modes at rest that no measurement moves."""
    hv = _hover_values(scenario)
    lin = stored_function(hover_linearization_function, hv.l)
    out = lin(point.xr, point.xc, point.vehicle, point.w, hv.pp, hv.pm, hv.p_ctrl, hv.ref, dt)
    J = dict(zip(("A_p", "B_p", "C_p", "A_c", "B_c", "Phi_c", "Gamma_c", "C_c", "D_c"),
                 (np.asarray(v, dtype=float) for v in out[3:]), strict=True))
    keep = _kept_memory(hv.l, hv.p_ctrl)
    for name in ("A_c", "Phi_c"):
        J[name] = J[name][np.ix_(keep, keep)]
    for name in ("B_c", "Gamma_c"):
        J[name] = J[name][keep, :]
    J["C_c"] = J["C_c"][:, keep]
    return J


def _kept_memory(l: int, p_ctrl: np.ndarray) -> np.ndarray:
    """Indices of the memory the linear models keep: all but the zero-gain bias estimates
    and the observer states of the axes without one."""
    lay, c = landing_memory(l), landing_controller_params(l).unpack(p_ctrl)
    gains = dict(d_hat=np.concatenate([c["ki_p"], c["ki"]]), v_hat=c["w_o"], d_o=c["w_o"])
    pinned = np.concatenate([lay.slice(name).start + np.flatnonzero(np.asarray(g) == 0)
                             for name, g in gains.items()])
    return np.setdiff1d(np.arange(lay.size), pinned)


def _p_ctrl(scenario: Scenario) -> np.ndarray:
    return _hover_values(scenario).p_ctrl


def _landing_nodes(memory_size: int) -> int:
    """The node count l of a landing step's memory of ``6 l + 29`` entries."""
    return (memory_size - landing_memory(1).size) // N_CHANNELS + 1


def _landing_names(l: int, p_ctrl: np.ndarray):
    names = landing_memory(l).element_names()
    return dict(x=list(HOVER_PLANT.element_names()), y=list(HOVER_OUTPUT.element_names()),
                u=list(LANDING_INPUT_NAMES),
                c=[names[i] for i in _kept_memory(l, p_ctrl)], loops=LANDING_LOOP_NAMES)


def hover_linear_models(scenario: Scenario, point: OperatingPoint) -> LinearModels:
    """Continuous-time models at the hover point.

    The controller is its step's limit ``dt -> 0``: the memory's differential
    equations, which the step integrates exactly over its period
    (``quadland_symbolic.landing.linearization``).
    """
    J = _hover_jacobians(scenario, point, 0.0)
    return assemble(point, J["A_p"], J["B_p"], J["C_p"], J["A_c"], J["B_c"], J["C_c"],
                    J["D_c"], 0.0, _landing_names(_landing_nodes(point.xc.size), _p_ctrl(scenario)))


def hover_sampled_models(scenario: Scenario, point: OperatingPoint, rate_hz: float,
                         delay_periods: int = 1) -> LinearModels:
    """Sampled-data models at the hover point: the plant under a zero-order hold, the
    controller its step's exact Jacobians at ``dt = 1 / rate_hz``, ``delay_periods``
    unit delays on its command."""
    if not rate_hz > 0:
        raise ValueError(f"sampled_models: rate_hz must be > 0, got {rate_hz}")
    delay_periods = check_delay_periods(delay_periods)
    dt = 1.0 / rate_hz
    J = _hover_jacobians(scenario, point, dt)
    Phi_p, Gam_p = zoh(J["A_p"], J["B_p"], dt)
    K = delayed(J["Phi_c"], J["Gamma_c"], J["C_c"], J["D_c"], delay_periods)
    return assemble(point, Phi_p, Gam_p, J["C_p"], *K, dt,
                    _landing_names(_landing_nodes(point.xc.size), _p_ctrl(scenario)),
                    delay_periods)


def hover_values(scenario: Scenario) -> _HoverValues:
    """The scenario's vectors at its hover point: ``l``, ``pp``, ``pm`` (the deck's heave,
    roll and pitch zeroed), ``p_ctrl``, ``ref``, ``w``, ``speeds``, ``hover_thrust``."""
    return _hover_values(scenario)


def hover_jacobians(scenario: Scenario, point: OperatingPoint, dt: float) -> dict:
    """The plant's and the landing step's Jacobians at the point (:func:`hover_linear_models`'
    ``A_p`` ... ``D_c``, the zero-gain bias estimates dropped from the memory)."""
    return _hover_jacobians(scenario, point, dt)


def kept_memory(l: int, p_ctrl: np.ndarray) -> np.ndarray:
    """Indices of the step's memory the linear models keep: all but the zero-gain bias
    estimates."""
    return _kept_memory(l, p_ctrl)
