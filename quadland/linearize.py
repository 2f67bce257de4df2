"""Operating points and linear models of the closed loop.

The paper's loop is broken at the virtual input u of eq. (6). The plant maps
u to the measured relative state ``y = xr = [z1, phi1, theta1, psi_e, u1,
v1, w1, p1, q1, r1]``; the controller maps y to u and carries the adaptive
states ``xc = [vec(W_hat), zeta_hat]``. The coordinates and what is left
out (planar positions, the vehicle's own dynamics) are explained in
``quadland_symbolic.linearization`` and ``docs/margins.md``.

The landing loop (``scenario.model = "landing"``) is broken at the wrench
``u = [T, M_x, M_y, M_z]`` its step sends to the mixer. The plant (6-DOF
with motor lag, in the deck frame, ``quadland_symbolic.landing.linearization``) maps
u to the quadrotor's measurements ``y = [p_e, v_e, eta1, Omega1]``; the
controller is the landing step, whose state is its memory. It is analysed
hovering ``landing.hover_height`` above the pad (:func:`equilibrium`).

A sampled controller sends its command one control period after it samples
(flight code computes during the period): :func:`sampled_models` puts
``delay_periods`` unit delays on the command.

Sign convention: ``u = K y`` is what the controller computes, so with the
loop broken at the plant input the return is ``K P``; in the negative
feedback convention of :mod:`quadland.analysis` the loop transfer is
``L = -K P`` (and ``-P K`` broken at the plant output).
"""

from __future__ import annotations

import dataclasses

import control
import numpy as np
import scipy.linalg

from quadland.constants import TILT_MIN
from quadland.exceptions import (
    MarginsError,
    OperatingPointError,
    ScenarioError,
    SingularAttitudeError,
)
from quadland.model import model_values
from quadland.scenario import Scenario
from quadland_symbolic.closed_loop import closed_loop_state
from quadland_symbolic.linearization import (
    RELATIVE_PLANT,
    VEHICLE_SPEEDS,
    controller_states,
    equilibrium_residual_function,
    linearization_function,
)
from quadland_symbolic.parameters import VEHICLE
from quadland_symbolic.quadrotor import BODY_DISTURBANCE, WRENCH
from quadland_symbolic.relative import VIRTUAL_INPUT
from quadland_symbolic.vehicle import VEHICLE_STATE

__all__ = ["check_frozen_time", "LOOP_NAMES", "INPUT_NAMES", "LANDING_LOOP_NAMES",
           "LANDING_INPUT_NAMES", "OperatingPoint", "LinearModels", "equilibrium",
           "frozen_point", "linear_models", "sampled_models"]

#: The four loops of the paper's loop, one per virtual input.
LOOP_NAMES = ("altitude", "roll", "pitch", "yaw")
#: Names of the virtual inputs u (eq. 6).
INPUT_NAMES = VIRTUAL_INPUT.element_names()
#: The four loops of the landing loop, one per entry of the wrench into the mixer.
LANDING_LOOP_NAMES = ("thrust", "roll", "pitch", "yaw")
#: Names of the landing loop's inputs: the wrench ``[T, M_x, M_y, M_z]``.
LANDING_INPUT_NAMES = WRENCH.element_names()


@dataclasses.dataclass(frozen=True)
class OperatingPoint:
    """Where the loop is linearized.

    Attributes
    ----------
    kind : str
        ``"equilibrium"`` (steady motion) or ``"frozen"`` (a simulated state).
    time : float or None
        s, the simulated time of a frozen point.
    xr : ndarray
        Plant state: the paper's relative state (10,
        ``quadland_symbolic.linearization.RELATIVE_PLANT``) or the landing plant in
        the deck frame (16, ``quadland_symbolic.landing.linearization.HOVER_PLANT``).
    xc : ndarray
        Controller state: the paper's adaptive states ``[vec(W_hat),
        zeta_hat]`` (4 l + 4) or the landing step's memory (6 l + 16,
        ``quadland_symbolic.landing.controller.landing_memory``).
    vehicle : ndarray, shape (3,)
        Vehicle surge, sway (m/s) and yaw rate r2 (rad/s).
    z2 : float
        m, deck altitude (the landing loop: the pad centre's).
    w : ndarray
        Disturbance ``[d_F (N), d_M (N m)]`` (6); the landing loop's is
        ``[v_wind (m/s, heading frame), d_F, d_M]`` (9).
    u : ndarray, shape (4,)
        Loop input at the point: the virtual input, or the landing loop's
        wrench ``[T (N), M (N m)]``.
    residual : float
        ``|d/dt [xr, xc]|`` at the point: ~0 at an equilibrium, the drift
        of a frozen point.
    iterations : int
        Newton iterations (0 for a frozen point).
    model : str
        ``"paper"`` (the 4-DOF loop) or ``"landing"`` (the 6-DOF landing loop).
    """

    kind: str
    time: float | None
    xr: np.ndarray
    xc: np.ndarray
    vehicle: np.ndarray
    z2: float
    w: np.ndarray
    u: np.ndarray
    residual: float
    iterations: int
    model: str = "paper"

    def to_dict(self) -> dict:
        """JSON-ready summary."""
        if self.model == "landing":
            from quadland_symbolic.landing.controller import landing_memory
            from quadland_symbolic.landing.linearization import HOVER_PLANT

            mem = landing_memory(_landing_nodes(self.xc.size)).unpack(self.xc)
            plant = HOVER_PLANT.element_names()
            extra = dict(zeta_hat=mem["zeta_hat"].tolist(),
                         norm_W_hat=float(np.linalg.norm(mem["W_hat"])),
                         wrench=dict(zip(LANDING_INPUT_NAMES, self.u.tolist(), strict=True)))
        else:
            plant = RELATIVE_PLANT.element_names()
            extra = dict(zeta_hat=self.xc[-4:].tolist(),
                         norm_W_hat=float(np.linalg.norm(self.xc[:-4])))
        return dict(kind=self.kind, time_s=self.time, model=self.model,
                    state={n: float(v) for n, v in zip(plant, self.xr, strict=True)},
                    **extra,
                    vehicle=dict(u2=float(self.vehicle[0]), v2=float(self.vehicle[1]),
                                 r2=float(self.vehicle[2]), z2=self.z2),
                    disturbance=self.w.tolist(), u=self.u.tolist(), residual=self.residual,
                    newton_iterations=self.iterations)


@dataclasses.dataclass(frozen=True)
class LinearModels:
    """State-space models of the loop at one operating point.

    Attributes
    ----------
    point : OperatingPoint
    plant : control.StateSpace
        P: u (4) -> y, states xr (the paper's loop: y = xr, 10; the landing
        loop: the quadrotor's measurements, 12).
    controller : control.StateSpace
        K: y -> u (4), states xc (the paper's: the adaptive states, and
        sampled with hold compensation the law's previous output
        ``u_prev``; the landing loop's: the step's memory); a sampled
        controller's last states are its computation delay.
    loop_input : control.StateSpace
        ``L_i = -K P`` (4 x 4), the loop broken at the plant input.
    loop_output : control.StateSpace
        ``L_o = -P K``, the loop broken at the plant output.
    closed_loop : control.StateSpace
        States ``[xr, xc]``; input an additive disturbance at u, output y.
    dt : float
        0 for continuous time, else the sampling period (s).
    delay_periods : int
        Control periods between sampling and commanding (0 in continuous
        time).
    loop_names : tuple of str
        One name per input: :data:`LOOP_NAMES` or :data:`LANDING_LOOP_NAMES`.
    """

    point: OperatingPoint
    plant: control.StateSpace
    controller: control.StateSpace
    loop_input: control.StateSpace
    loop_output: control.StateSpace
    closed_loop: control.StateSpace
    dt: float = 0.0
    delay_periods: int = 0
    loop_names: tuple[str, ...] = LOOP_NAMES


def _constant_disturbance(scenario: Scenario) -> np.ndarray:
    d = scenario.data["disturbance"]
    return BODY_DISTURBANCE.pack(dict(d_F=d["force_bias"], d_M=d["moment_bias"]))


def _newton(residual, xi, tol: float, max_iter: int):
    """Newton's method with step halving on ``residual(x) -> (F, dF)``; ``(x, iterations)``."""
    r, J = residual(xi)
    norm = np.linalg.norm(r)
    for it in range(1, max_iter + 1):
        try:
            step = np.linalg.solve(J, r)
        except np.linalg.LinAlgError:
            raise OperatingPointError("no equilibrium: singular Jacobian in Newton's method "
                                      f"(residual {norm:.3g})") from None
        lam = 1.0
        while lam > 1e-6:
            trial = xi - lam * step
            r_t, J_t = residual(trial)
            if np.all(np.isfinite(r_t)) and np.linalg.norm(r_t) < norm * (1 - 1e-4 * lam):
                break
            lam /= 2
        else:
            raise OperatingPointError(f"no equilibrium: Newton's method stalled at residual "
                                      f"{norm:.3g} after {it} iterations")
        xi, r, J, norm = trial, r_t, J_t, np.linalg.norm(r_t)
        if norm < tol:
            return xi, it
    raise OperatingPointError(f"no equilibrium: Newton's method did not converge in "
                              f"{max_iter} iterations (residual {norm:.3g})")


def equilibrium(scenario: Scenario, *, tol: float = 1e-9, max_iter: int = 50) -> OperatingPoint:
    """The closed loop's steady motion under the constant disturbance.

    Solves ``[xr_dot, xc_dot, vehicle speeds_dot] = 0`` by Newton's method
    with the exact symbolic Jacobian, from hover at the reference with
    zero adaptive states, halving steps that do not reduce the residual.

    For a landing scenario the point is the hover ``landing.hover_height``
    above the pad, at rest in the deck frame, with the outer position loop
    closed on that reference: the vehicle in its steady motion, the deck's
    heave, roll and pitch at zero (their mean), the wind at ``wind.mean``
    (turbulence and gust left out, the wind turned into the vehicle's
    initial heading) and the disturbance at its constant part; the step's
    memory (network, robust terms, command filter, compensator) at rest
    (``quadland_symbolic.landing.linearization.hover_equilibrium_residual_function``).

    Parameters
    ----------
    scenario : Scenario
    tol : float
        Convergence threshold on the residual's 2-norm.
    max_iter : int

    Raises
    ------
    OperatingPointError
        When Newton's method does not converge or the Jacobian is singular.
    """
    if scenario.model == "landing":
        return _hover_equilibrium(scenario, tol, max_iter)
    mv = model_values(scenario)
    l = mv.l
    F = equilibrium_residual_function(l)
    w = _constant_disturbance(scenario)
    xr0 = RELATIVE_PLANT.zeros()
    xr0[0:4] = mv.ref[0:4]                                   # hover at the reference e1d
    xr0[RELATIVE_PLANT.index("z1")] += VEHICLE.unpack(mv.p_veh)["z2"][0]
    nr, nc = RELATIVE_PLANT.size, controller_states(l).size
    xi = np.concatenate([xr0, np.zeros(nc), VEHICLE_SPEEDS.zeros()])

    def residual(x):
        r, J = F(x, w, mv.p_quad, mv.p_veh, mv.p_ctrl, mv.ref)
        return np.asarray(r, dtype=float).ravel(), np.asarray(J, dtype=float)

    xi, it = _newton(residual, xi, tol, max_iter)
    return _point(scenario, "equilibrium", None, xi[:nr], xi[nr:nr + nc], xi[nr + nc:], w, it)


def check_frozen_time(scenario: Scenario, t: float) -> None:
    """Refuse, before any work, a time :func:`frozen_point` cannot reach.

    Raises
    ------
    MarginsError
        For a landing scenario, a time out of range, or a run up to ``t``
        over the simulator's limits; the message starts with ``"at: "``.
    """
    from quadland.schema import MAX_DURATION_S, PAPER_SCHEMA
    from quadland.simulate import MAX_RK4_STEPS, MEMORY_BUDGET, check_plan, simulation_plan

    if scenario.model == "landing":
        raise MarginsError("at: the landing loop is analysed at its hover equilibrium only; "
                           "a frozen state applies to the paper's loop")
    shortest = PAPER_SCHEMA["simulation"]["duration"].lo
    if not (t == 0 or shortest <= t <= MAX_DURATION_S):
        raise MarginsError(f"at: must be 0 or in [{shortest:g}, {MAX_DURATION_S:g}] s, got {t:g}")
    if t > 0:
        upto = scenario.replace(**{"simulation.duration": float(t)})
        try:
            check_plan(upto)
        except ScenarioError:
            plan = simulation_plan(upto)
            raise MarginsError(
                f"at: reaching {t:g} s takes {plan.rows:,} output rows "
                f"({plan.memory_bytes / 2**30:.1f} GiB) and {plan.rk4_steps:.2g} RK4 steps, "
                f"over the limits ({MEMORY_BUDGET / 2**30:g} GiB, {MAX_RK4_STEPS:.0e} steps)"
            ) from None


def frozen_point(scenario: Scenario, t: float) -> OperatingPoint:
    """The simulated closed-loop state at time ``t`` (s), frozen.

    Simulates the scenario up to ``t`` (nothing at ``t = 0``). The point
    is generally not an equilibrium: the linear models then describe the
    loop's local, frozen-time behaviour. The paper's loop only.
    """
    from quadland.simulate import (
        simulate,
    )

    check_frozen_time(scenario, t)
    mv = model_values(scenario)
    if t > 0:
        res = simulate(scenario.replace(**{"simulation.duration": float(t)}))
        x = res.states[-1]
        w = np.array([res[k][-1] for k in BODY_DISTURBANCE.element_names()])
    else:
        from quadland.model import disturbance_samples
        x, w = mv.x0, disturbance_samples(scenario, np.zeros(1))[:, 0]
    xs = closed_loop_state(mv.l).unpack(x)
    xv = VEHICLE_STATE.unpack(xs["xv"])
    xr = xs["xq"].copy()
    xr[RELATIVE_PLANT.index("psi_e")] -= xv["psi2"][0]
    xc = np.concatenate([xs["W_hat"].ravel(order="F"), xs["zeta_hat"]])
    speeds = np.concatenate([xv[n] for n in VEHICLE_SPEEDS.names()])
    return _point(scenario, "frozen", float(t), xr, xc, speeds, w, 0)


def _point(scenario, kind, t, xr, xc, vehicle, w, iterations) -> OperatingPoint:
    mv = model_values(scenario)
    tilt = np.cos(xr[1]) * np.cos(xr[2])
    if abs(tilt) < TILT_MIN:
        raise SingularAttitudeError(f"operating point at cos(theta) cos(phi) = {tilt:.2e}: "
                                    "the thrust map is singular there")
    z2 = float(VEHICLE.unpack(mv.p_veh)["z2"][0])
    out = linearization_function(mv.l)(xr, xc, [z2, vehicle[2]], w, mv.p_quad, mv.p_ctrl,
                                       mv.ref)
    u, xr_dot, xc_dot = (np.asarray(v, dtype=float).ravel() for v in out[0:3])
    return OperatingPoint(kind, t, np.asarray(xr, float), np.asarray(xc, float),
                          np.asarray(vehicle, float), z2, np.asarray(w, float), u,
                          float(np.linalg.norm(np.r_[xr_dot, xc_dot])), iterations)


def _jacobians(scenario: Scenario, point: OperatingPoint):
    mv = model_values(scenario)
    out = linearization_function(mv.l)(point.xr, point.xc, [point.z2, point.vehicle[2]],
                                       point.w, mv.p_quad, mv.p_ctrl, mv.ref)
    return tuple(np.asarray(v, dtype=float) for v in out[3:9])


# ---------------------------------------------------------------- the landing loop

@dataclasses.dataclass(frozen=True)
class _HoverValues:
    """A landing scenario's vectors at its hover point (frozen deck, mean wind)."""

    l: int
    pp: np.ndarray          # plant parameters, the deck's heave, roll and pitch zeroed
    p_ctrl: np.ndarray
    ref: np.ndarray         # hover point, at rest, deck frame
    w: np.ndarray           # [v_wind (heading frame), d_F, d_M]
    speeds: np.ndarray      # the vehicle's initial [u2, v2, r2]: Newton's start
    hover_thrust: float     # N, m1 g


def _hover_values(scenario: Scenario) -> _HoverValues:
    from quadland.landing import landing_values
    from quadland_symbolic.kinematics import rotation
    from quadland_symbolic.landing.deck import DECK_PARAMS
    from quadland_symbolic.landing.guidance import POSITION_REFERENCE
    from quadland_symbolic.landing.loop import landing_loop_params
    from quadland_symbolic.landing.plant import (
        LANDING_DISTURBANCE,
        LANDING_PLANT_PARAMS,
        LANDING_PLANT_STATE,
    )

    lv = landing_values(scenario)
    pc = landing_loop_params(lv.l).unpack(lv.pc)
    pp = LANDING_PLANT_PARAMS.unpack(pc["pp"])
    deck = DECK_PARAMS.unpack(pp["p_deck"])
    for motion in ("heave", "roll", "pitch"):
        deck[f"{motion}_amp"] = np.zeros_like(deck[f"{motion}_amp"])
    pp["p_deck"] = DECK_PARAMS.pack(deck)
    d = scenario.data
    xv0 = VEHICLE_STATE.unpack(LANDING_PLANT_STATE.unpack(lv.xp0)["xv"])
    heading = np.asarray(rotation([0.0, 0.0, float(xv0["psi2"][0])]), dtype=float)
    w = LANDING_DISTURBANCE.pack(dict(v_wind=heading.T @ np.asarray(d["wind"]["mean"]),
                                      d_F=d["disturbance"]["force_bias"],
                                      d_M=d["disturbance"]["moment_bias"]))
    ref = POSITION_REFERENCE.pack(dict(p_ref=[0.0, 0.0, d["landing"]["hover_height"]],
                              v_ref=np.zeros(3), a_ref=np.zeros(3)))
    q = d["quadrotor"]
    return _HoverValues(lv.l, LANDING_PLANT_PARAMS.pack(pp), pc["p_ctrl"], ref, w,
                        np.concatenate([xv0[n] for n in VEHICLE_SPEEDS.names()]),
                        q["mass"] * q["gravity"])


def _hover_equilibrium(scenario: Scenario, tol: float, max_iter: int) -> OperatingPoint:
    from quadland_symbolic.landing.controller import landing_controller_params, landing_memory
    from quadland_symbolic.landing.linearization import (
        HOVER_PLANT,
        hover_equilibrium_residual_function,
        hover_linearization_function,
    )

    hv = _hover_values(scenario)
    F = hover_equilibrium_residual_function(hv.l)
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
    lin = hover_linearization_function(hv.l)
    ctrl = landing_controller_params(hv.l).unpack(hv.p_ctrl)
    for _ in range(3):
        mem_dot = mem_lay.unpack(np.asarray(lin(z0, mem0, hv.speeds, hv.w, hv.pp, hv.p_ctrl,
                                                    hv.ref, 0.0)[2], dtype=float).ravel())
        c = mem_lay.unpack(mem0)["eta_f"] + mem_dot["eta_f_dot"] / ctrl["w_f"] ** 2
        mem0[mem_lay.slice("eta_f")] = c
        z0[HOVER_PLANT.slice("eta1")][:2] = c
    xi = np.concatenate([z0, mem0, hv.speeds])

    def residual(x):
        r, J = F(x, hv.w, hv.pp, hv.p_ctrl, hv.ref)
        return np.asarray(r, dtype=float).ravel(), np.asarray(J, dtype=float)

    xi, it = _newton(residual, xi, tol, max_iter)
    z, mem, speeds = xi[:nz], xi[nz:nz + nm], xi[nz + nm:]
    out = lin(z, mem, speeds, hv.w, hv.pp, hv.p_ctrl, hv.ref, 0.0)
    u, z_dot, mem_dot = (np.asarray(v, dtype=float).ravel() for v in out[0:3])
    tilt = np.cos(z[HOVER_PLANT.index("phi1")]) * np.cos(z[HOVER_PLANT.index("theta1")])
    if abs(tilt) < TILT_MIN:
        raise SingularAttitudeError(f"operating point at cos(theta) cos(phi) = {tilt:.2e}: "
                                    "the attitude kinematics are singular there")
    deck = scenario.data["deck"]
    z2 = float(deck["height"] + deck["pad_offset"][2])          # the pad, the deck still
    return OperatingPoint("equilibrium", None, z, mem, speeds, z2, hv.w, u,
                          float(np.linalg.norm(np.r_[z_dot, mem_dot])), it, model="landing")


def _hover_jacobians(scenario: Scenario, point: OperatingPoint, dt: float):
    from quadland_symbolic.landing.linearization import hover_linearization_function

    hv = _hover_values(scenario)
    out = hover_linearization_function(hv.l)(point.xr, point.xc, point.vehicle, point.w, hv.pp,
                                             hv.p_ctrl, hv.ref, dt)
    return dict(zip(("A_p", "B_p", "C_p", "A_c", "B_c", "Phi_c", "Gamma_c", "C_c", "D_c"),
                    (np.asarray(v, dtype=float) for v in out[3:]), strict=True))


def _landing_nodes(memory_size: int) -> int:
    """The node count l of a landing step's memory of ``6 l + 16`` entries."""
    from quadland_symbolic.landing.controller import N_CHANNELS, landing_memory

    return (memory_size - landing_memory(1).size) // N_CHANNELS + 1


def _landing_names(l: int):
    from quadland_symbolic.landing.controller import landing_memory
    from quadland_symbolic.landing.linearization import HOVER_OUTPUT, HOVER_PLANT

    return dict(x=list(HOVER_PLANT.element_names()), y=list(HOVER_OUTPUT.element_names()),
                u=list(LANDING_INPUT_NAMES), c=list(landing_memory(l).element_names()),
                loops=LANDING_LOOP_NAMES)


def _paper_names(n_adapt: int, n_hold: int = 0):
    y = list(RELATIVE_PLANT.element_names())
    return dict(x=y, y=y, u=list(INPUT_NAMES),
                c=([f"W_hat[{k}]" for k in range(n_adapt - 4)]
                   + [f"zeta_hat[{k}]" for k in range(4)]
                   + [f"u_prev[{k}]" for k in range(n_hold)]),
                loops=LOOP_NAMES)


# ---------------------------------------------------------------- assembly

def _assemble(point, Ap, Bp, Cp, Ac, Bc, Cc, Dc, dt, names, delay_periods=0) -> LinearModels:
    n, nc = Ap.shape[0], Ac.shape[0]
    ny, m = Cp.shape[0], Bp.shape[1]
    kw = dict(dt=dt) if dt else {}
    x_names, y_names, u_names = names["x"], names["y"], names["u"]
    xc_names = names["c"] + [f"u_delay{j + 1}[{k}]" for j in range(delay_periods)
                             for k in range(m)]
    plant = control.ss(Ap, Bp, Cp, np.zeros((ny, m)), inputs=u_names, outputs=y_names,
                       states=x_names, name="plant", **kw)
    controller = control.ss(Ac, Bc, Cc, Dc, inputs=y_names, outputs=u_names,
                            states=xc_names, name="controller", **kw)
    states = x_names + xc_names
    A_i = np.block([[Ap, np.zeros((n, nc))], [Bc @ Cp, Ac]])
    loop_input = control.ss(A_i, np.vstack([Bp, np.zeros((nc, m))]), -np.hstack([Dc @ Cp, Cc]),
                            np.zeros((m, m)), inputs=u_names,
                            outputs=[f"{k}_return" for k in u_names], states=states,
                            name="loop_input", **kw)
    A_o = np.block([[Ac, np.zeros((nc, n))], [Bp @ Cc, Ap]])
    loop_output = control.ss(A_o, np.vstack([Bc, Bp @ Dc]),
                             np.hstack([np.zeros((ny, nc)), -Cp]), np.zeros((ny, ny)),
                             inputs=y_names, outputs=[f"{k}_return" for k in y_names],
                             states=xc_names + x_names, name="loop_output", **kw)
    A_cl = np.block([[Ap + Bp @ Dc @ Cp, Bp @ Cc], [Bc @ Cp, Ac]])
    closed = control.ss(A_cl, np.vstack([Bp, np.zeros((nc, m))]),
                        np.hstack([Cp, np.zeros((ny, nc))]), np.zeros((ny, m)),
                        inputs=u_names, outputs=y_names, states=states,
                        name="closed_loop", **kw)
    return LinearModels(point, plant, controller, loop_input, loop_output, closed, dt,
                        delay_periods, tuple(names["loops"]))


def linear_models(scenario: Scenario, point: OperatingPoint) -> LinearModels:
    """Continuous-time plant, controller, broken loops and closed loop at a point.

    Parameters
    ----------
    scenario : Scenario
    point : OperatingPoint
        From :func:`equilibrium` or :func:`frozen_point`.

    Returns
    -------
    LinearModels
        From the exact symbolic Jacobians of ``quadland_symbolic.linearization``.
        The landing loop's controller is its step's limit ``dt -> 0``:
        the memory's differential equations, which the step integrates
        exactly over its period (``quadland_symbolic.landing.linearization``).
    """
    if point.model == "landing":
        J = _hover_jacobians(scenario, point, 0.0)
        return _assemble(point, J["A_p"], J["B_p"], J["C_p"], J["A_c"], J["B_c"], J["C_c"],
                         J["D_c"], 0.0, _landing_names(_landing_nodes(point.xc.size)))
    Ap, Bp, Ac, Bc, Cc, Dc = _jacobians(scenario, point)
    return _assemble(point, Ap, Bp, np.eye(Ap.shape[0]), Ac, Bc, Cc, Dc, 0.0,
                     _paper_names(Ac.shape[0]))


def _zoh(A, B, dt):
    n, m = B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n], M[:n, n:] = A, B
    E = scipy.linalg.expm(M * dt)
    return E[:n, :n], E[:n, n:]


def _delayed(Phi, Gam, C, D, periods: int):
    """The controller ``(Phi, Gam, C, D)`` followed by ``periods`` unit delays on its output.

    ``d_1[k+1] = C x[k] + D y[k]``, ``d_j+1[k+1] = d_j[k]``, output ``d_periods[k]``.
    """
    if periods == 0:
        return Phi, Gam, C, D
    nc, m = Phi.shape[0], C.shape[0]
    nd = m * periods
    shift = np.eye(nd, k=-m)                     # d_j+1 <- d_j
    A = np.block([[Phi, np.zeros((nc, nd))],
                  [np.vstack([C, np.zeros((nd - m, nc))]), shift]])
    B = np.vstack([Gam, D, np.zeros((nd - m, Gam.shape[1]))])
    out = np.hstack([np.zeros((m, nc)), np.zeros((m, nd - m)), np.eye(m)])
    return A, B, out, np.zeros_like(D)


def sampled_models(scenario: Scenario, point: OperatingPoint, rate_hz: float,
                   delay_periods: int = 1) -> LinearModels:
    """Sampled-data models: zero-order hold at ``rate_hz``, with computation delay.

    The plant is discretized with its input u held (the held wrench of the
    sampled simulator, linearized). The paper's controller has its adaptive
    states integrated with the measurement held over the period, which is
    exactly how ``quadland_symbolic.control_step`` integrates eq. (22); with
    ``controller.hold_compensation = kappa > 0`` it also holds the law's
    previous output ``u_prev`` (four more states) and commands ``(1 + kappa)
    u_law - kappa u_prev``, as the control step does. The landing loop's
    controller is its step's exact Jacobians at ``dt = 1 / rate_hz``.

    Parameters
    ----------
    scenario : Scenario
    point : OperatingPoint
    rate_hz : float
        Control rate, Hz (> 0).
    delay_periods : int, optional
        Control periods from sampling to commanding (default 1): the
        command computed from the samples at ``t_k`` acts from
        ``t_(k + delay_periods)``, as flight code that computes during
        the period and sends at the next tick. Each period is a ``z^-1``
        on the command (four more controller states); 0 applies it at the
        sample, as the simulator does.
    """
    if not rate_hz > 0:
        raise ValueError(f"sampled_models: rate_hz must be > 0, got {rate_hz}")
    if isinstance(delay_periods, bool) or int(delay_periods) != delay_periods \
            or delay_periods < 0:
        raise MarginsError(f"delay_periods: must be an integer >= 0, got {delay_periods}")
    delay_periods = int(delay_periods)
    dt = 1.0 / rate_hz
    if point.model == "landing":
        J = _hover_jacobians(scenario, point, dt)
        Phi_p, Gam_p = _zoh(J["A_p"], J["B_p"], dt)
        K = _delayed(J["Phi_c"], J["Gamma_c"], J["C_c"], J["D_c"], delay_periods)
        return _assemble(point, Phi_p, Gam_p, J["C_p"], *K, dt,
                         _landing_names(_landing_nodes(point.xc.size)), delay_periods)
    Ap, Bp, Ac, Bc, Cc, Dc = _jacobians(scenario, point)
    Phi_p, Gam_p = _zoh(Ap, Bp, dt)
    Phi_c, Gam_c = _zoh(Ac, Bc, dt)
    kappa = float(scenario.data["controller"]["hold_compensation"])
    Cp = np.eye(Ap.shape[0])
    if kappa == 0:
        K = _delayed(Phi_c, Gam_c, Cc, Dc, delay_periods)
        return _assemble(point, Phi_p, Gam_p, Cp, *K, dt, _paper_names(Ac.shape[0]),
                         delay_periods)
    m, nc = Cc.shape
    Phi_k = np.block([[Phi_c, np.zeros((nc, m))], [Cc, np.zeros((m, m))]])
    Gam_k = np.vstack([Gam_c, Dc])
    C_k = np.hstack([(1 + kappa) * Cc, -kappa * np.eye(m)])
    K = _delayed(Phi_k, Gam_k, C_k, (1 + kappa) * Dc, delay_periods)
    return _assemble(point, Phi_p, Gam_p, Cp, *K, dt, _paper_names(nc, n_hold=m),
                     delay_periods)
