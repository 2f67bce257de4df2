"""Sea states: a wave spectrum through a vessel's response, as sums of sinusoids.

A ship's deck moves in heave, roll and pitch because long-crested waves pass
under it. The waves are a stationary Gaussian process with a one-sided
spectrum ``S(omega)`` (m^2 s/rad) of wave frequency ``omega``; the vessel
answers each wave component linearly, through a complex response ``H(omega)``
per motion. This module turns a sea state and a vessel into the sums of
sinusoids ``a_i sin(w_i t + phase_i)`` the deck model takes
(:mod:`quadland_symbolic.landing.deck`), in five steps:

1. **The sea state** (:data:`quadland.schema.sea_state.SEA_STATES`): WMO
   code -> significant wave height ``Hs`` and peak (modal) period ``Tp``, the
   most probable ones of Bales (1983) for the open North Atlantic.
2. **The spectrum** (:func:`wave_spectrum`): JONSWAP with peak enhancement
   ``gamma`` (DNV-RP-C205, 3.5.5); ``gamma = 1`` is the Pierson-Moskowitz
   spectrum in its two-parameter form (ITTC / Bretschneider), whose area is
   ``m0 = Hs^2 / 16`` exactly. JONSWAP is normalized to the same ``m0``.
3. **The encounter** (:func:`encounter_frequency`): a vessel making ``U``
   with the waves travelling at ``beta`` from its bow meets a component at
   ``omega_e = omega - k U cos(beta)``, ``k = omega^2 / g`` (deep water).
4. **The response** (:func:`deck_response`): the hull follows the wave
   surface averaged over its waterplane, a ``length`` by ``beam`` rectangle:
   heave is the surface's mean, pitch and roll its least-squares slopes along
   and across the hull, roll then through a damped second-order resonance at
   the natural roll period. docs/sea.md derives it and cites its sources.
5. **The components** (:func:`sea_components`): the frequency axis is cut
   into ``n`` bins of equal share of the three responses' normalized spectra
   (so each motion's energy is resolved where it lies), at each bin's
   root-mean-square frequency; each bin is one wave component with a seeded
   random phase, shared by heave, roll and pitch (one wave moves all three), of
   amplitude ``sqrt(2 * the bin's variance)`` per motion. The components'
   variance ``sum a_i^2 / 2`` is the response spectrum's area over the
   discretized band.

Units: SI, angles in rad; the deck frame has x forward, y to port, z up;
roll ``phi2`` is positive port side up, pitch ``theta2`` positive bow down
(``R = Rz Ry Rx``), as in :mod:`quadland_symbolic.landing.deck`.

References
----------
Bales, S. L. (1983). Designing ships to the natural environment. Naval
Engineers Journal 95(2), 31-40 (the open-ocean sea state table).
DNV (2010). DNV-RP-C205 Environmental conditions and environmental loads,
3.5.5 (JONSWAP).
Jensen, J. J., Mansour, A. E., Olsen, A. S. (2004). Estimation of ship
motions using closed-form expressions. Ocean Engineering 31, 61-85.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

#: The trapezoid rule: NumPy's own (``trapezoid`` from 2.0, ``trapz`` before), the same
#: sum as ``scipy.integrate.trapezoid``, without importing SciPy in a landing process.
_trapezoid = getattr(np, "trapezoid", None) or np.trapz  # noqa: NPY201 (NumPy 1.26)

__all__ = ["MOTIONS", "Vessel", "DeckComponents", "wave_spectrum", "encounter_frequency",
           "deck_response", "sea_components"]

#: The deck motions, in the order of every ``(3, n)`` array here.
MOTIONS = ("heave", "roll", "pitch")


@dataclasses.dataclass(frozen=True)
class Vessel:
    """What the deck's response depends on.

    Attributes
    ----------
    length, beam : float
        The waterplane's length and breadth, m.
    roll_period : float
        Natural roll period ``T_phi``, s.
    roll_damping : float
        Roll damping ratio ``zeta_phi`` (linearized), -.
    speed : float
        Speed through the water ``U``, m/s.
    heading : float
        ``beta``, rad: the waves' direction of travel in the deck frame, from
        the bow (x) toward port (y): pi head seas, 0 following seas, pi/2
        waves from starboard.
    """

    length: float
    beam: float
    roll_period: float
    roll_damping: float
    speed: float
    heading: float


@dataclasses.dataclass(frozen=True)
class DeckComponents:
    """A deck's motion as sums of sinusoids ``amp sin(freq t + phase)``.

    Attributes
    ----------
    freq : numpy.ndarray
        ``(n,)`` encounter frequencies ``|omega_e|``, rad/s (the same for the
        three motions).
    amp, phase : numpy.ndarray
        ``(3, n)``, rows :data:`MOTIONS`: amplitudes (m, rad, rad) and phases
        (rad, in ``[0, 2 pi)``).
    variance : numpy.ndarray
        ``(3,)`` the response spectra's areas over the whole band cut into
        the bins, ``sum amp^2 / 2`` of each row.
    band : tuple of float
        The wave frequencies discretized, rad/s.
    """

    freq: np.ndarray
    amp: np.ndarray
    phase: np.ndarray
    variance: np.ndarray
    band: tuple[float, float]


def _shape(omega: np.ndarray, omega_p: float, gamma: float) -> np.ndarray:
    """JONSWAP's shape, unnormalized: ``omega^-5 exp(-5/4 (omega_p / omega)^4) gamma^r``."""
    w = np.where(omega > 0, omega, 1.0)
    pm = np.where(omega > 0, w ** -5 * np.exp(-1.25 * (omega_p / w) ** 4), 0.0)
    if gamma == 1.0:
        return pm
    sigma = np.where(omega <= omega_p, 0.07, 0.09)
    r = np.exp(-0.5 * ((omega - omega_p) / (sigma * omega_p)) ** 2)
    return pm * gamma ** r


def wave_spectrum(omega, hs: float, tp: float, gamma: float = 1.0) -> np.ndarray:
    """The wave elevation's one-sided spectrum ``S(omega)``, m^2 s/rad.

    ``gamma = 1``: Pierson-Moskowitz, ``S = 5/16 Hs^2 omega_p^4 omega^-5
    exp(-5/4 (omega_p / omega)^4)``, ``omega_p = 2 pi / Tp``, whose area is
    ``Hs^2 / 16``. ``gamma > 1``: JONSWAP, the same times ``gamma^r``
    (``r = exp(-(omega - omega_p)^2 / (2 sigma^2 omega_p^2))``, ``sigma``
    0.07 below the peak and 0.09 above), scaled to the same area (DNV's
    ``1 - 0.287 ln(gamma)`` approximates that scale).

    Examples
    --------
    >>> w = np.linspace(0.01, 20.0, 200001)
    >>> round(float(_trapezoid(wave_spectrum(w, 2.0, 8.0), w)), 4)   # Hs^2 / 16
    0.25
    """
    omega = np.asarray(omega, dtype=float)
    omega_p = 2 * math.pi / tp
    if gamma == 1.0:
        scale = 5 / 16 * hs ** 2 * omega_p ** 4
    else:
        w = np.linspace(0.2 * omega_p, 12 * omega_p, 20001)
        area = float(_trapezoid(_shape(w, omega_p, gamma), w))
        area += 0.2 * omega_p ** -4 * (1.0 - math.exp(-1.25 / 12 ** 4))      # the PM tails
        scale = hs ** 2 / 16 / area
    return scale * _shape(omega, omega_p, gamma)


def encounter_frequency(omega, speed: float, heading: float, g: float) -> np.ndarray:
    """``omega_e = omega - omega^2 U cos(beta) / g``, rad/s (signed; deep water)."""
    omega = np.asarray(omega, dtype=float)
    return omega - omega ** 2 * speed * math.cos(heading) / g


def _mean(k, length):
    """The mean of ``exp(-i k x)`` over ``|x| <= length / 2``: ``sin(u) / u``, ``u = k L / 2``."""
    return np.sinc(np.asarray(k) * length / (2 * math.pi))


def _slope(k, length):
    """The least-squares slope of ``cos(k x)``'s odd part over the length: ``24 (sin u -
    u cos u) / (k^2 L^3)``, ``u = k L / 2`` (``k`` for a long wave)."""
    k = np.asarray(k, dtype=float)
    u = k * length / 2
    small = np.abs(u) < 1e-3
    us = np.where(small, 1.0, u)
    exact = 3 * (np.sin(us) - us * np.cos(us)) / us ** 3 * k
    return np.where(small, k * (1 - u ** 2 / 10), exact)


def deck_response(omega, vessel: Vessel, g: float) -> np.ndarray:
    """The deck's complex response to a wave of unit amplitude, ``(3, n)``.

    Rows :data:`MOTIONS`: heave (m/m), roll and pitch (rad/m). A wave
    component ``zeta(x, y, t) = a cos(k (x cos(beta) + y sin(beta)) -
    omega_e t + eps)`` at the moving hull gives the motion ``Re(a H e^(i
    psi) e^(i |omega_e| t))`` with ``psi`` the component's phase at the
    origin. With ``kx = k cos(beta)``, ``ky = k sin(beta)``, ``s`` the sign of
    ``omega_e``, ``F(k, L) = sin(u) / u`` and ``G(k, L) = 24 (sin u - u cos u)
    / (k^2 L^3)`` (``u = k L / 2``):

    * heave ``= F(kx, L) F(ky, B)``, the surface's mean over the waterplane;
    * pitch ``= i s G(kx, L) F(ky, B)``, minus the least-squares slope along x
      (positive bow down);
    * roll ``= -i s G(ky, B) F(kx, L) / (1 - r^2 + 2 i zeta r)``,
      ``r = |omega_e| T_phi / (2 pi)``: the slope across the hull drives a
      damped oscillator at the natural roll period (its static answer: the
      deck lies along the wave).

    Examples
    --------
    A wave twice the hull's length, head on, at zero speed: heave ``2 / pi``,
    pitch ``24 / (pi^2 L)`` rad/m.

    >>> v = Vessel(40.0, 8.0, 7.0, 0.1, 0.0, math.pi)
    >>> k = math.pi / 40.0
    >>> H = deck_response(math.sqrt(k * 9.81), v, 9.81)
    >>> round(float(abs(H[0, 0])), 6), round(float(abs(H[2, 0])) * 40 * math.pi ** 2 / 24, 6)
    (0.63662, 1.0)
    """
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    k = omega ** 2 / g
    kx, ky = k * math.cos(vessel.heading), k * math.sin(vessel.heading)
    w_e = encounter_frequency(omega, vessel.speed, vessel.heading, g)
    s = np.where(w_e < 0, -1.0, 1.0)
    L, B = vessel.length, vessel.beam
    r = np.abs(w_e) * vessel.roll_period / (2 * math.pi)
    heave = _mean(kx, L) * _mean(ky, B) + 0j
    pitch = 1j * s * _slope(kx, L) * _mean(ky, B)
    roll = -1j * s * _slope(ky, B) * _mean(kx, L) / (1 - r ** 2 + 2j * vessel.roll_damping * r)
    return np.vstack([heave, roll, pitch])


def _cumulative(y: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Trapezoidal cumulative integral along the last axis, starting at 0."""
    steps = (y[..., 1:] + y[..., :-1]) / 2 * np.diff(x)
    return np.concatenate([np.zeros(y.shape[:-1] + (1,)), np.cumsum(steps, axis=-1)], axis=-1)


def sea_components(hs: float, tp: float, gamma: float, vessel: Vessel, n: int,
                   rng: np.random.Generator, g: float, points: int = 8001,
                   band: tuple[float, float] = (0.5, 6.0)) -> DeckComponents:
    """``n`` wave components of a sea state, through the vessel, with random phases.

    Parameters
    ----------
    hs, tp, gamma : float
        Significant wave height (m), peak period (s), peak enhancement (-)
        of :func:`wave_spectrum`.
    vessel : Vessel
    n : int
        Components.
    rng : numpy.random.Generator
        Draws the ``n`` phases, uniform on ``[0, 2 pi)``, and nothing else.
    g : float
        Gravity, m/s^2 (the waves' dispersion).
    points : int
        The fine grid of wave frequencies the bins are cut on.
    band : tuple of float
        Its ends, in multiples of ``omega_p``: the Pierson-Moskowitz
        variance outside is ``1 - exp(-5/4 band[1]^-4) + exp(-5/4
        band[0]^-4)`` of the total (0.1 % for the default).

    Returns
    -------
    DeckComponents
        The components, in increasing wave frequency.

    Notes
    -----
    Each motion's response spectrum ``|H|^2 S`` is normalized to unit area
    on the band; the bins cut the mean ``q`` of those (of the motions that
    move) into ``n`` equal shares. A bin's amplitude per motion is
    ``sqrt(2 V)``, ``V`` the motion's variance in the bin; its wave frequency
    is the bin's root-mean-square one under ``q``, ``sqrt(int w^2 q / int
    q)`` (so the rates' variances are kept as well as the motions'), and the
    response's phase is the one there.
    """
    omega_p = 2 * math.pi / tp
    w = np.linspace(band[0] * omega_p, band[1] * omega_p, points)
    H = deck_response(w, vessel, g)
    S = np.abs(H) ** 2 * wave_spectrum(w, hs, tp, gamma)
    cum = _cumulative(S, w)
    total = cum[:, -1]
    moving = total > 1e-9 * total.max()
    density = _cumulative((S[moving] / total[moving, None]).mean(axis=0), w)
    density /= density[-1]
    edges = np.interp(np.linspace(0.0, 1.0, n + 1), density, w)
    second = _cumulative(w ** 2 * np.gradient(density, w), w)
    mids = np.sqrt(np.diff(np.interp(edges, w, second)) / np.diff(np.interp(edges, w, density)))
    bins = np.diff(np.vstack([np.interp(edges, w, c) for c in cum]), axis=1)
    amp = np.sqrt(2 * np.clip(bins, 0.0, None))
    psi = rng.uniform(0.0, 2 * math.pi, n)
    phase = np.mod(psi + np.angle(deck_response(mids, vessel, g)) + math.pi / 2, 2 * math.pi)
    freq = np.abs(encounter_frequency(mids, vessel.speed, vessel.heading, g))
    return DeckComponents(freq, amp, phase, total, (float(w[0]), float(w[-1])))
