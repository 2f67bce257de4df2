"""The deck's tilt predicted at the contact, against the flare's lean: a second commit condition.

The tilt at contact is judged between the body's z axis and the deck's normal
(``docs/contact.md``). In the flare the flight code holds the thrust axis within
``flare_tilt`` of the vertical; a quadrotor leaning into a crosswind at that limit
over a deck rolled the other way meets the deck tilted by the sum. The final descent
from the wait height lasts a fixed time (the descent profile's, :func:`descent_duration`),
so the deck's tilt at the contact can be predicted when the descent commits, as the
heave's speed is (:mod:`quadland_symbolic.landing.quiescence`).

**The deck's normal.** ``n = R2 e_z`` from the broadcast attitude ``eta2``; its rates
from the deck's angular velocity and acceleration in E, ``n' = w x n`` and
``n'' = w' x n + w x (w x n)``. Only the horizontal parts ``n_h`` (the deck's tilt
vector, ``sin`` of its tilt along the direction it leans to) are predicted.

**The frequency.** Exponential averages (``motion_time``) of ``|n_h'|^2`` and
``|n_h''|^2`` give ``omega_t = sqrt(<|n_h''|^2> / <|n_h'|^2>)``, the tilt rate's mean
zero-crossing frequency (Rice), clamped as the heave's.

**The prediction.** ``n_h(t + T) = n_h cos(omega_t T) + (n_h' / omega_t) sin(omega_t T)``,
exact for one sinusoid per component, ``T`` the profile's time from the wait height to
the touchdown height.

**The lean.** The worst lean the flare allows at the contact: ``flare_tilt`` from the
vertical, toward where the body's z axis leans on average (an exponential average of
``R1 e_z``'s horizontal part over ``motion_time``: a quadrotor holding the pad in an
airflow leans into it; the gusts' lean averages out). The predicted relative tilt is
the angle between that axis and the predicted normal; the descent commits only while its
cosine is at least ``cos(calm_tilt)`` (``calm_tilt = pi``: always, the guidance of before).

**The gust's lean.** The flare holds the thrust axis within ``flare_tilt`` of the vertical;
a quadrotor that needs more to hold the pad against a gust drifts off it in the flare, or
meets the deck at more than the flare's lean. A third average, of the lean's size ``|b_h|``
(the sine of the body z axis's angle from the vertical) over the short ``lean_time``, is
the lean the gust asks for now; the descent commits only while it is at most
``sin(calm_lean)`` (``calm_lean >= pi / 2``: always, the guidance of before).

Branch-free CasADi, generated into C with the guidance step.
"""

from __future__ import annotations

import casadi as ca

from quadland_symbolic.kinematics import rotation
from quadland_symbolic.landing.quiescence import sine_ahead, sine_frequency
from quadland_symbolic.layout import Field, Layout

__all__ = ["DECK_TILT_STATE", "TILT_CUES", "LEAN_FLOOR", "tilt_cues", "descent_duration",
           "tilt_update", "tilt_frequency", "tilt_ahead", "lean_axis", "relative_tilt_cos",
           "lean_calm"]

#: The predictor's memory: the two exponential averages of the tilt's rates.
DECK_TILT_STATE = Layout("x_tilt", (
    Field("ms_tilt_rate", 1, "1/s^2",
          "exponential average of the squared rate of the deck normal's horizontal part"),
    Field("ms_tilt_acc", 1, "1/s^4",
          "exponential average of the squared acceleration of the deck normal's horizontal "
          "part"),
    Field("lean_x", 1, "-", "exponential average of the body z axis's x component in E"),
    Field("lean_y", 1, "-", "exponential average of the body z axis's y component in E"),
    Field("lean_gust", 1, "-", "exponential average over lean_time of the body z axis's "
          "horizontal part's length (the sine of its tilt)"),
), "deck tilt predictor state")

#: What the predictor reads each step (horizontal parts in E).
TILT_CUES = Layout("c_tilt", (
    Field("n_h", 2, "-", "the deck normal's horizontal part"),
    Field("n_h_dot", 2, "1/s", "its rate"),
    Field("n_h_ddot", 2, "1/s^2", "its acceleration"),
    Field("b_h", 2, "-", "the body z axis's horizontal part (the quadrotor's lean)"),
), "deck tilt predictor inputs")

#: Length of the lean's horizontal part below which its direction is scaled down (a
#: quadrotor upright: the worst lean shrinks toward the vertical instead of dividing by 0).
LEAN_FLOOR = 1e-6


def tilt_cues(eta1, eta2, w2E, w2E_dot):
    """:data:`TILT_CUES` from the body's and the deck's attitude and the deck's rotation."""
    n = rotation(eta2)[:, 2]
    n_dot = ca.cross(w2E, n)
    n_ddot = ca.cross(w2E_dot, n) + ca.cross(w2E, n_dot)
    b = rotation(eta1)[:, 2]
    return ca.vertcat(n[0:2], n_dot[0:2], n_ddot[0:2], b[0:2])


def descent_duration(h0, descent_time, touchdown_speed, descent_speed):
    """Time the reference takes from ``h0`` above touchdown to touchdown, s.

    The rate is ``clamp(h / descent_time, touchdown_speed, descent_speed)``: at
    ``descent_speed`` down to ``descent_speed x descent_time``, then ``h' = -h /
    descent_time`` down to ``touchdown_speed x descent_time``, then the crawl.
    """
    h_fast, h_crawl = descent_speed * descent_time, touchdown_speed * descent_time
    fast = ca.fmax(h0 - h_fast, 0) / descent_speed
    mid = descent_time * ca.log(ca.fmax(ca.fmin(h0, h_fast), h_crawl) / h_crawl)
    return fast + mid + ca.fmin(h0, h_crawl) / touchdown_speed


def tilt_update(xt, n_h_dot, n_h_ddot, b_h, dt, motion_time, lean_time):
    """The averages after one step of length ``dt``, as the heave's
    (:func:`quadland_symbolic.landing.quiescence.quiescence_update`): the tilt's rates
    squared and the lean ``b_h`` over ``motion_time``, the lean's size ``|b_h|`` over
    ``lean_time``."""
    q = DECK_TILT_STATE.unpack(xt)
    k = ca.fmin(dt / motion_time, 1)
    k_gust = ca.fmin(dt / lean_time, 1)
    return ca.vertcat(q["ms_tilt_rate"] + k * (ca.dot(n_h_dot, n_h_dot) - q["ms_tilt_rate"]),
                      q["ms_tilt_acc"] + k * (ca.dot(n_h_ddot, n_h_ddot) - q["ms_tilt_acc"]),
                      q["lean_x"] + k * (b_h[0] - q["lean_x"]),
                      q["lean_y"] + k * (b_h[1] - q["lean_y"]),
                      q["lean_gust"] + k_gust * (ca.norm_2(b_h) - q["lean_gust"]))


def lean_calm(lean_gust, calm_lean):
    """Whether the gust's lean lets the descent commit: ``calm_lean >= pi / 2`` (no limit)
    or ``lean_gust <= sin(calm_lean)`` (CasADi 0/1)."""
    return ca.logic_or(calm_lean >= ca.pi / 2, lean_gust <= ca.sin(ca.fmin(calm_lean, ca.pi / 2)))


def tilt_frequency(xt):
    """``sqrt(<|n_h''|^2> / <|n_h'|^2>)`` clamped to the heave's bounds, rad/s."""
    q = DECK_TILT_STATE.unpack(xt)
    return sine_frequency(q["ms_tilt_rate"], q["ms_tilt_acc"])


def tilt_ahead(n_h, n_h_dot, omega, tau):
    """The normal's horizontal part ``tau`` ahead: ``n_h cos(w tau) + (n_h' / w) sin(w tau)``."""
    return sine_ahead(n_h, n_h_dot, omega, tau)


def lean_axis(b_h, flare_tilt):
    """The unit axis ``flare_tilt`` from the vertical toward ``b_h`` (3-vector, E)."""
    s = ca.sin(flare_tilt) * b_h / ca.fmax(ca.norm_2(b_h), LEAN_FLOOR)
    return ca.vertcat(s, ca.sqrt(ca.fmax(1 - ca.dot(s, s), 0)))


def relative_tilt_cos(b_h, d_h, flare_tilt):
    """Cosine of the angle between :func:`lean_axis` and the unit normal whose horizontal
    part is ``d_h`` (its vertical part ``sqrt(1 - |d_h|^2)``, up)."""
    d = ca.vertcat(d_h, ca.sqrt(ca.fmax(1 - ca.dot(d_h, d_h), 0)))
    return ca.dot(lean_axis(b_h, flare_tilt), d)
