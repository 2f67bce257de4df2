"""The horizon's prediction every ``predict_every`` control periods (E6b).

The filter's horizon ``x_h``, ``P_h`` is predicted over one buffered period per step
(E6). With ``predict_every = N`` it is predicted once every ``N`` periods over their
sum: the periods leaving the input buffer are accumulated (the memory's ``acc``: their
velocity increment as a mean acceleration, their total time, the body's summed turn,
how many), and on the step the ``N``-th one joins, ``x_h`` and ``P_h`` are predicted
over the sum by the same (E6), (E6a) and ``acc`` is emptied. Between, the horizon
stays where it is and fusion goes on at it; the output predictor (E17) carries ``x_h``
through the accumulated periods, then the buffer, so the controller reads a state at
the present every period. ``N = 1`` is (E6) itself, to the bit: each step accumulates
one period into an empty ``acc`` (which keeps its values as they are) and predicts over
it.

The accumulated input is the velocity increment's mean (``sum a_k dt_k / sum dt_k``),
so the velocity's prediction is that of the ``N`` periods exactly, the position's to
first order (exact for a constant input); the body's turns add (E6a is first order in
them). The covariance is the continuous model's discretized over the sum (its ``Q`` over
``N dt``, the same as ``N`` predictions of ``dt`` for a constant ``Phi`` to rounding).
"""

from __future__ import annotations

import casadi as ca

from quadland_symbolic.kalman import select
from quadland_symbolic.landing.nav_output import output_predictor
from quadland_symbolic.landing.navigation import nav_predict
from quadland_symbolic.layout import Field

__all__ = ["ACC_ROWS", "acc_field", "carry_accumulated", "accumulate", "prediction_over",
           "prediction_due", "accumulated_prediction"]

#: The memory's ``acc``: the periods since the horizon's last prediction.
ACC_ROWS = ("acc_a_x", "acc_a_y", "acc_a_z", "acc_dt", "acc_turn_x", "acc_turn_y",
            "acc_turn_z", "acc_n")


def acc_field() -> Field:
    """The memory's ``acc`` field (zeros: empty)."""
    return Field("acc", len(ACC_ROWS), ("m/s^2",) * 3 + ("s",) + ("rad",) * 3 + ("-",),
                 "the periods left the buffer since the horizon's last prediction (E6b): "
                 "their mean acceleration input, total time, summed turn and count",
                 elements=ACC_ROWS)


def carry_accumulated(x_h, acc, omega):
    """``x_h`` carried over the accumulated periods (E17) as one of their mean input;
    ``x_h`` itself when there are none."""
    return select(acc[7] > 0, output_predictor(x_h, acc[0:4], omega), x_h)


def accumulate(acc, column):
    """``acc`` with one more period ``column`` (the buffer's rows: input, period, turn).

    Into an empty ``acc`` the column's values as they are.
    """
    a, dt, turn = column[0:3], column[3], column[4:7]
    n, t_acc = acc[7], acc[3]
    total = t_acc + dt
    mean = select(total > 0, (acc[0:3] * t_acc + a * dt) / total, a)
    return select(n > 0, ca.vertcat(mean, total, acc[4:7] + turn, n + 1),
                  ca.vertcat(a, dt, turn, 1))


def prediction_over(x, P, t_h, acc, p_est, pattern):
    """``(x_h, P_h, t_h, acc)`` predicted over the accumulated periods ``acc`` (E6), (E6a),
    ``acc`` emptied. ``P`` the full symmetric covariance, ``P_h`` its stored entries
    (``pattern``)."""
    x_p, P_p = nav_predict(x, P, acc[0:3], acc[3], p_est, pattern, acc[4:7])
    return x_p, pattern.pack(P_p), t_h + acc[3], ca.DM.zeros(acc.shape[0])


def prediction_due(acc, predict_every):
    """1 where ``acc`` holds ``predict_every`` periods or more."""
    return acc[7] >= predict_every


def accumulated_prediction(x, P, t_h, acc, p_est, pattern, predict_every):
    """``(x_h, P_h, t_h, acc)`` after this step's accumulation ``acc`` (E6b).

    :func:`prediction_over` where :func:`prediction_due`; as they are (``P`` packed) where
    not.
    """
    due = prediction_due(acc, predict_every)
    held = (x, pattern.pack(P), t_h, acc)
    return tuple(select(due, a, b) for a, b in zip(prediction_over(x, P, t_h, acc, p_est,
                                                                   pattern), held, strict=True))
