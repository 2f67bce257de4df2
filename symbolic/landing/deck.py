"""The vehicle and its deck: eq. (4) plus prescribed heave, roll and pitch.

The vehicle's planar motion is the model of eq. (4) (:mod:`quadland_symbolic.vehicle`,
state ``xv``, driven by ``p_veh``'s ``tau``). Its deck moves in heave, roll
and pitch as prescribed sums of :data:`N_DECK` sinusoids
``s(t) = sum_i a_i sin(omega_i t + phase_i)`` (parameters :data:`DECK_PARAMS`);
a car has zero amplitudes. The first :data:`N_SINES` are a scenario's explicit
sinusoids, the other :data:`N_SEA` a sea state's wave components (drawn by the
runtime from a wave spectrum through the vessel's response,
``quadland.engine.sea``; docs/sea.md). The deck's yaw is the vehicle's heading
psi2.

Frames: E has z up. The deck frame's origin is the vehicle's reference point
``O2 = [x2, y2, deck_height + heave(t)]`` (the centre of roll and pitch) and
its attitude ``eta2 = [phi2(t), theta2(t), psi2]`` (ZYX),
``R_deck = Rz(psi2) Ry(theta2) Rx(phi2)`` maps deck vectors to E. The pad
centre is ``p2 = O2 + R_deck pad_offset``. All time derivatives are taken
symbolically along ``xv_dot = vehicle_motion(xv, t)`` (eq. 4 under its inputs plus the
drive profile's, :mod:`quadland_symbolic.landing.drive`) and the explicit time terms.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import casadi as ca
import numpy as np

from quadland_symbolic.kinematics import rotation
from quadland_symbolic.landing.drive import DRIVE_PARAMS, drive_idle, driven_vehicle_rhs
from quadland_symbolic.layout import Field, Layout
from quadland_symbolic.parameters import VEHICLE
from quadland_symbolic.vehicle import VEHICLE_STATE

__all__ = [
    "N_SINES",
    "N_SEA",
    "N_DECK",
    "DECK_PARAMS",
    "DECK_POSE",
    "DeckPose",
    "pack_deck",
    "vehicle_motion",
    "deck_motion",
    "time_derivative",
    "vee",
    "deck_pose",
    "deck_function",
]

#: A scenario's explicit sinusoids per deck motion (``[deck]``'s lists): the first slots.
N_SINES = 3
#: A sea state's wave components per deck motion: the slots after the explicit ones
#: (docs/sea.md, "How many components": the cost against the spectrum's resolution).
N_SEA = 24
#: Sinusoids per prescribed deck motion (heave, roll, pitch).
N_DECK = N_SINES + N_SEA


def _sines(name: str, unit: str, what: str) -> tuple[Field, ...]:
    idx = range(1, N_DECK + 1)
    return (
        Field(f"{name}_amp", N_DECK, unit, f"{what} amplitudes",
              elements=tuple(f"{name}_amp_{i}" for i in idx)),
        Field(f"{name}_freq", N_DECK, "rad/s", f"{what} frequencies",
              elements=tuple(f"{name}_freq_{i}" for i in idx)),
        Field(f"{name}_phase", N_DECK, "rad", f"{what} phases",
              elements=tuple(f"{name}_phase_{i}" for i in idx)),
    )


#: The deck's prescribed motion and the pad's place on it.
DECK_PARAMS = Layout("p_deck", (
    *_sines("heave", "m", "heave (along E's z)"),
    *_sines("roll", "rad", "deck roll phi2"),
    *_sines("pitch", "rad", "deck pitch theta2"),
    Field("pad_offset", 3, "m", "pad centre in the deck frame (z up) from the vehicle's "
          "reference point", elements=("pad_x", "pad_y", "pad_z")),
    Field("deck_height", 1, "m", "altitude of the vehicle's reference point at zero heave"),
    Field.nested("drive", DRIVE_PARAMS, "the vehicle's drive profile "
                 "(quadland_symbolic.landing.drive)"),
), "prescribed deck motion: sums of sinusoids (zero amplitudes for a car) and the drive")

#: Outputs of :func:`deck_function`, in order.
DECK_POSE = Layout("deck", (
    Field("p2", 3, "m", "pad centre in E", elements=("x2", "y2", "z2")),
    Field("eta2", 3, "rad", "deck attitude, ZYX", elements=("phi2", "theta2", "psi2")),
    Field("R_deck", 9, "-", "deck-to-E rotation Rz(psi2) Ry(theta2) Rx(phi2)", shape=(3, 3)),
    Field("v2E", 3, "m/s", "pad centre velocity in E", elements=("vx2", "vy2", "vz2")),
    Field("a2E", 3, "m/s^2", "pad centre acceleration in E", elements=("ax2", "ay2", "az2")),
    Field("w2E", 3, "rad/s", "deck angular velocity in E", elements=("wx2", "wy2", "wz2")),
    Field("w2E_dot", 3, "rad/s^2", "deck angular acceleration in E",
          elements=("wx2_dot", "wy2_dot", "wz2_dot")),
), "pad and deck pose in E with first and second time derivatives")


class DeckPose(NamedTuple):
    """The fields of :data:`DECK_POSE` as expressions or numbers."""

    p2: ca.SX
    eta2: ca.SX
    R_deck: ca.SX
    v2E: ca.SX
    a2E: ca.SX
    w2E: ca.SX
    w2E_dot: ca.SX


def pack_deck(values: dict):
    """``DECK_PARAMS.pack(values)`` with each sinusoid list zero-padded to :data:`N_DECK`.

    A list of fewer values fills the first slots (a scenario's explicit
    sinusoids), e.g. ``heave_amp=[0.5]``. Without ``drive`` the vehicle is not
    driven (:func:`~quadland_symbolic.landing.drive.drive_idle`).
    """
    sines = {f.name for f in DECK_PARAMS.fields if f.size == N_DECK}
    padded = {"drive": DRIVE_PARAMS.pack(drive_idle())}
    for name, v in values.items():
        if name in sines:
            flat = np.atleast_1d(np.asarray(v, dtype=float))
            v = np.concatenate([flat, np.zeros(N_DECK - flat.size)])
        padded[name] = v
    return DECK_PARAMS.pack(padded)


def vehicle_motion(xv, t, p_veh, p_deck):
    """``xv_dot``: eq. (4) driven by ``p_deck``'s profile
    (:func:`~quadland_symbolic.landing.drive.driven_vehicle_rhs`)."""
    return driven_vehicle_rhs(xv, t, p_veh, DECK_PARAMS.unpack(p_deck)["drive"])


def _sum_of_sines(amp, freq, phase, t):
    return ca.sum1(amp * ca.sin(freq * t + phase))


def deck_motion(t, p_deck):
    """Prescribed heave (m), roll phi2 and pitch theta2 (rad) at time t."""
    p = DECK_PARAMS.unpack(p_deck)
    return tuple(_sum_of_sines(p[f"{n}_amp"], p[f"{n}_freq"], p[f"{n}_phase"], t)
                 for n in ("heave", "roll", "pitch"))


def time_derivative(expr, x, x_dot, t):
    """d/dt of ``expr(x, t)`` along ``x_dot``: ``d expr/dx x_dot + d expr/dt``.

    ``x`` and ``t`` must be symbols; ``expr`` may be a matrix.
    """
    rows, cols = expr.shape
    flat = ca.reshape(expr, rows * cols, 1)
    d = ca.jtimes(flat, ca.vertcat(x, t), ca.vertcat(x_dot, 1))
    return ca.reshape(d, rows, cols)


def vee(S):
    """w from the skew-symmetric part of S (the inverse of ``skew``)."""
    A = (S - S.T) / 2
    return ca.vertcat(A[2, 1], A[0, 2], A[1, 0])


def _pose(xv, t, p_deck):
    """Pad centre p2, attitude eta2 and R_deck in E, without derivatives."""
    v, p = VEHICLE_STATE.unpack(xv), DECK_PARAMS.unpack(p_deck)
    heave, phi2, theta2 = deck_motion(t, p_deck)
    eta2 = ca.vertcat(phi2, theta2, v["psi2"])
    R_deck = rotation(eta2)
    origin = ca.vertcat(v["x2"], v["y2"], p["deck_height"] + heave)
    return origin + R_deck @ p["pad_offset"], eta2, R_deck


@functools.cache
def deck_function() -> ca.Function:
    """``deck(xv, t, p_veh, p_deck) -> (p2, eta2, R_deck, v2E, a2E, w2E, w2E_dot)``.

    Eq. (3)-(4) for the vehicle's planar motion and heading, with heave, roll
    and pitch prescribed. The derivatives are symbolic, along
    ``xv_dot = vehicle_motion(xv, t, p_veh, p_deck)`` (eq. 4 and the drive profile)
    and the explicit time terms;
    ``S(w2E) = R_deck_dot R_deck^T``. Outputs: :data:`DECK_POSE`.
    """
    xv, t = VEHICLE_STATE.sym(), ca.SX.sym("t")
    p_veh, p_deck = VEHICLE.sym(), DECK_PARAMS.sym()
    xv_dot = vehicle_motion(xv, t, p_veh, p_deck)

    def d_dt(e):
        return time_derivative(e, xv, xv_dot, t)

    p2, eta2, R_deck = _pose(xv, t, p_deck)
    v2E = d_dt(p2)
    a2E = d_dt(v2E)
    w2E = vee(d_dt(R_deck) @ R_deck.T)
    w2E_dot = d_dt(w2E)
    return ca.Function("deck", [xv, t, p_veh, p_deck],
                       [p2, eta2, R_deck, v2E, a2E, w2E, w2E_dot],
                       ["xv", "t", "p_veh", "p_deck"], list(DECK_POSE.names()))


def deck_pose(xv, t, p_veh, p_deck) -> DeckPose:
    """The deck's pose and its time derivatives (:func:`deck_function`).

    Symbolic arguments give expressions, numeric ones ``casadi.DM``.
    """
    return DeckPose(*deck_function()(xv, t, p_veh, p_deck))
