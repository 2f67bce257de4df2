"""The landing controller's disturbance observer: the outer loop's unknown acceleration, fast.

The outer loop's relative velocity obeys ``v_e' = a_T + f_p + d`` (deck frame;
docs/landing.md, "The controller"): ``a_T = R_deck^T R(eta1) e_z T / m1`` is the
thrust's acceleration, ``f_p`` the known part and ``d`` what the model does not
know (the wind's gusts through the drag, a weak rotor, a wrong mass). The bias
estimates (:mod:`quadland_symbolic.landing.bias`) learn ``d`` through the tracking
error, at the position loop's pace. This observer learns it from the velocity the
navigation filter propagates with the accelerometer, at its own bandwidth ``w_o``,
per deck-frame axis (an extended state observer, Han 2009; in the spirit of
incremental nonlinear dynamic inversion, whose acceleration feedback it replaces by
the filter's velocity):

    v_hat' = a_T + f_k + d_o + 2 w_o (v_e - v_hat)
    d_o'   =                   w_o^2 (v_e - v_hat)

with ``a_T`` from the measured attitude and the thrust the rotors are making now
(``T_o``: the commanded rotor forces through the model's motor lag), ``f_k`` the part
of ``f_p`` the law feeds forward. Its error ``e = [v_e - v_hat, d - d_o]`` obeys
``e' = A e + [0, d']`` with ``A`` of the double pole ``-w_o``, whatever the law does:
``d_o`` is ``d`` through ``w_o^2 / (s + w_o)^2``. The law subtracts
``d_o`` from its acceleration command (docs/landing.md, "The disturbance observer").

Over a period the inputs are held, so the step integrates it exactly
(:func:`~quadland_symbolic.landing.command_filter.linear2_zoh`); ``d_o`` is then
projected onto the bias estimates' box. An axis with ``w_o = 0`` has no observer:
its two states are held (at 0, where the memory starts), as a bias estimate of zero
gain is.
"""

from __future__ import annotations

import casadi as ca

from quadland_symbolic.landing.bias import bias_next
from quadland_symbolic.landing.command_filter import linear2_zoh
from quadland_symbolic.layout import Field, Layout

__all__ = ["OBSERVER_PARAMS", "OBSERVER_MEMORY", "observer_next", "thrust_next",
           "estimates_next"]

#: The observer's parameter (in the landing step's, after the bias estimates' bounds).
OBSERVER_PARAMS = Layout("p_observer", (
    Field("w_o", 3, "rad/s", "disturbance observer bandwidth, deck-frame x, y, z (0: none)",
          elements=("w_o_x", "w_o_y", "w_o_z")),
), "disturbance observer parameters")

#: The observer's memory (the landing step's last entries).
OBSERVER_MEMORY = Layout("mem_observer", (
    Field("v_hat", 3, "m/s", "disturbance observer: velocity estimate (deck frame)",
          elements=("v_hat_x", "v_hat_y", "v_hat_z")),
    Field("d_o", 3, "m/s^2", "disturbance observer: disturbance estimate (deck frame)",
          elements=("d_o_x", "d_o_y", "d_o_z")),
    Field("T_o", 1, "N", "disturbance observer: the thrust the rotors make (the model's "
          "motor lag)"),
), "disturbance observer memory")


def observer_next(v_hat, d_o, v_e, a_known, w_o, d_max, dt):
    """The observer's ``(v_hat, d_o)`` after ``dt`` with ``v_e`` and ``a_known`` held.

    Parameters
    ----------
    v_hat, d_o : casadi.SX, (3, 1)
        Its state: the velocity estimate (m/s) and the disturbance estimate (m/s^2),
        deck frame.
    v_e : casadi.SX, (3, 1)
        The measured relative velocity (the filter's), deck frame.
    a_known : casadi.SX, (3, 1)
        ``a_T + f_k``: the acceleration the model accounts for, deck frame.
    w_o : casadi.SX, (3, 1)
        Each axis's bandwidth (rad/s, the observer's double pole); 0: no observer (its
        states held).
    d_max : casadi.SX
        The box ``|d_o_i| <= d_max``.
    dt : casadi.SX
        The period, s.
    """
    v_next, d_next = [], []
    for i in range(3):
        on = w_o[i] > 0
        w = ca.if_else(on, w_o[i], 1)                    # a safe frequency where it is off
        A = ca.vertcat(ca.horzcat(-2 * w, 1), ca.horzcat(-w**2, 0))
        f = ca.vertcat(a_known[i] + 2 * w * v_e[i], w**2 * v_e[i])
        x = linear2_zoh(ca.vertcat(v_hat[i], d_o[i]), A, f, dt)
        v_next.append(ca.if_else(on, x[0], v_hat[i]))
        d_next.append(ca.if_else(on, ca.fmin(ca.fmax(x[1], -d_max), d_max), d_o[i]))
    return ca.vertcat(*v_next), ca.vertcat(*d_next)


def thrust_next(T_o, T_cmd, tau_m, dt):
    """The collective thrust after ``dt`` of the model's motor lag, ``T_cmd`` held:
    ``T_o' = (T_cmd - T_o) / tau_m``, exact."""
    return T_cmd + (T_o - T_cmd) * ca.exp(-dt / tau_m)


def estimates_next(mm, c, z2, n_clipped, v_e, axis, f_k, F_cmd, act, dt):
    """The landing step's estimates after ``dt``: the bias estimates
    (:func:`~quadland_symbolic.landing.bias.bias_next`), then the observer's
    ``v_hat, d_o, T_o``.

    ``mm``, ``c``: the step's memory and parameters, unpacked; ``z2`` the six channels'
    errors the bias estimates integrate, ``n_clipped`` the clipped rotors; ``v_e`` the
    measured relative velocity; ``axis = (b3, m1)`` the measured body z axis in the deck
    frame and the model's mass (``a_T = b3 T_o / m1``); ``f_k`` the known acceleration the law feeds
    forward; ``F_cmd`` this step's rotor commands, ``act`` the model's actuator
    (:data:`~quadland_symbolic.landing.quadrotor.ACTUATOR`, unpacked).
    """
    d_hat = bias_next(mm["d_hat"], ca.vertcat(c["ki_p"], c["ki"]), c["d_max_p"], c["d_max"],
                      z2, n_clipped, dt)
    b3, m1 = axis
    v_hat, d_o = observer_next(mm["v_hat"], mm["d_o"], v_e, b3 * mm["T_o"] / m1 + f_k, c["w_o"],
                               c["d_max_p"], dt)
    T_cmd = ca.dot(act["rotor_efficiency"], F_cmd)
    return ca.vertcat(d_hat, v_hat, d_o, thrust_next(mm["T_o"], T_cmd,
                                                     act["motor_time_constant"], dt))
