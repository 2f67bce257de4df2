"""The attitude command filter: a second-order low-pass, stepped exactly.

``x'' = w_f^2 (c - x) - 2 zeta_f w_f x'`` per channel with the command ``c``
held over the step, integrated in closed form (a 2x2 matrix exponential), so
the landing law's filtered reference and its two derivatives are exact at
any control rate.
"""

from __future__ import annotations

import casadi as ca

__all__ = ["linear2_zoh", "command_filter", "command_filter_function"]


def _expm2(A, t):
    """exp(A t) of a 2x2 matrix in closed form.

    With ``s = tr(A) / 2`` and ``M = A - s I`` (traceless, so ``M^2 = q2 I``,
    ``q2 = -det M``): ``exp(A t) = e^(s t) (C I + t S M)``, ``C = cosh(sqrt(y))``,
    ``S = sinh(sqrt(y)) / sqrt(y)``, ``y = q2 t^2`` (cos and sin for ``y < 0``,
    their series near 0, where the damping is critical).
    """
    s = (A[0, 0] + A[1, 1]) / 2
    M = A - s * ca.SX.eye(2)
    y = -(M[0, 0] * M[1, 1] - M[0, 1] * M[1, 0]) * t * t
    r = ca.sqrt(ca.fabs(y))
    r_safe = ca.fmax(r, 1e-30)
    small = ca.fabs(y) <= 1e-3
    C = ca.if_else(small, 1 + y / 2 + y**2 / 24 + y**3 / 720,
                   ca.if_else(y > 0, ca.cosh(r), ca.cos(r)))
    S = ca.if_else(small, 1 + y / 6 + y**2 / 120 + y**3 / 5040,
                   ca.if_else(y > 0, ca.sinh(r), ca.sin(r)) / r_safe)
    return ca.exp(s * t) * (C * ca.SX.eye(2) + t * S * M)


def linear2_zoh(x, A, f, dt):
    """State after ``dt`` of ``x' = A x + f`` (2x2, ``f`` held, ``A`` invertible).

    ``x(dt) = x_eq + exp(A dt) (x - x_eq)`` with ``x_eq = -A^-1 f``.
    """
    det = A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]
    adj = ca.vertcat(ca.horzcat(A[1, 1], -A[0, 1]), ca.horzcat(-A[1, 0], A[0, 0]))
    x_eq = -(adj @ f) / det
    return x_eq + _expm2(A, dt) @ (x - x_eq)


def command_filter(x, x_dot, c, w_f, zeta_f, dt):
    """One exact step of ``x'' = w_f^2 (c - x) - 2 zeta_f w_f x'`` with ``c`` held.

    Element-wise over vectors. Returns ``(x_next, x_dot_next, x_ddot)``,
    ``x_ddot`` being the filter's acceleration at the start of the step.
    """
    A = ca.vertcat(ca.horzcat(0, 1), ca.horzcat(-w_f**2, -2 * zeta_f * w_f))
    nxt = [linear2_zoh(ca.vertcat(x[i], x_dot[i]), A, ca.vertcat(0, w_f**2 * c[i]), dt)
           for i in range(x.shape[0])]
    x_ddot = w_f**2 * (c - x) - 2 * zeta_f * w_f * x_dot
    return ca.vertcat(*[n[0] for n in nxt]), ca.vertcat(*[n[1] for n in nxt]), x_ddot


def command_filter_function(n: int = 1) -> ca.Function:
    """``command_filter(x, x_dot, c, w_f, zeta_f, dt) -> (x_next, x_dot_next, x_ddot)``."""
    x, x_dot, c = ca.SX.sym("x", n), ca.SX.sym("x_dot", n), ca.SX.sym("c", n)
    w_f, zeta_f, dt = ca.SX.sym("w_f"), ca.SX.sym("zeta_f"), ca.SX.sym("dt")
    return ca.Function("command_filter", [x, x_dot, c, w_f, zeta_f, dt],
                       list(command_filter(x, x_dot, c, w_f, zeta_f, dt)),
                       ["x", "x_dot", "c", "w_f", "zeta_f", "dt"],
                       ["x_next", "x_dot_next", "x_ddot"])
