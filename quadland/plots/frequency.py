"""What the margin figures share: the loops' responses, one phase convention, the regions.

A margin figure draws each loop broken at its input with the others closed,
``l_i = 1 / [(I + L)^-1]_ii - 1`` (:func:`quadland.analysis.loop_at_a_time`),
of the continuous loop and, when the report has them, of the sampled-data loop
(zero-order hold and computation delay) and of the sampled loop with the
navigation filter in it, up to the Nyquist frequency.
"""

from __future__ import annotations

import dataclasses
import math
from typing import TYPE_CHECKING

import numpy as np
from threadpoolctl import threadpool_limits

from quadland.analysis import frequency_grid, loop_at_a_time, response_of

if TYPE_CHECKING:       # a figure draws a report it is given; it never builds one
    from quadland.margins import MarginReport

__all__ = ["POINTS_PER_DECADE", "DECADES_BELOW", "LoopCurves", "loop_curves", "figure_floor",
           "phase_deg", "crossing_phase",
           "exclusion_circle", "m_circle"]

#: Grid density of the figures, points per decade (the margins use a finer one).
POINTS_PER_DECADE = 30


@dataclasses.dataclass(frozen=True)
class LoopCurves:
    """One controller's loop-at-a-time responses and margins, ready to draw.

    Attributes
    ----------
    label : str
        ``"continuous"``, ``"sampled"`` or ``"filtered"`` (the filter in the loop).
    omega : ndarray
        rad/s (a sampled loop's stop below its Nyquist frequency).
    loops : ndarray, shape (len(omega), m)
        ``l_i(j omega)``.
    margins : tuple of LoopMargins
        The report's margins of each loop, in the same order.
    style : str
        Line style: ``"-"`` continuous, ``"--"`` sampled, ``":"`` filtered.
    color : str
    """

    label: str
    omega: np.ndarray
    loops: np.ndarray
    margins: tuple
    style: str
    color: str

    def phase(self, i: int) -> np.ndarray:
        """deg, loop ``i``'s phase in the figures' convention (:func:`phase_deg`)."""
        return phase_deg(self.loops[:, i], self.omega, self.margins[i].crossover_frequency)


def loop_curves(report: MarginReport) -> tuple[LoopCurves, ...]:
    """The continuous loop's curves, then the sampled loop's and the filtered loop's if
    the report has them.

    Evaluated on one BLAS thread: on matrices of a few hundred rows more
    threads cost more than they bring (``quadland margins`` does the same).
    """
    with threadpool_limits(1):
        return _loop_curves(report)


def _loop_curves(report: MarginReport) -> tuple[LoopCurves, ...]:
    resp = response_of(report.models.realizations["loop_input"])
    omega = frequency_grid(resp, points_per_decade=POINTS_PER_DECADE, extra_poles=report.poles)
    floor = figure_floor(report)
    out = [LoopCurves("continuous", *_above(resp, omega, floor, math.inf),
                      report.continuous.loops, "-", "C0")]
    if report.sampled_models is not None and report.sampled is not None:
        discrete = response_of(report.sampled_models.realizations["loop_input"])
        out.append(LoopCurves("sampled", *_above(discrete, omega, floor,
                                                   math.pi / report.sampled_models.dt),
                              report.sampled.loops, "--", "C1"))
    if report.filtered_models is not None and report.filtered is not None:
        flown = response_of(report.filtered_models.realizations["loop_input"])
        out.append(LoopCurves("filtered", *_above(flown, omega, floor,
                                                    math.pi / report.filtered_models.dt),
                              report.filtered.loops, ":", "C2"))
    return tuple(out)


def _above(resp, omega: np.ndarray, floor: float, nyquist: float
           ) -> tuple[np.ndarray, np.ndarray]:
    """``(w, l(j w))``: ``w`` the grid's frequencies from ``floor`` up to under ``nyquist``
    (rad/s; ``inf`` for a continuous loop), ``l`` the loop-at-a-time responses there.

    The response is evaluated on the whole grid up to the Nyquist frequency, which the
    singular value figure reads too (:func:`quadland.plots.sensitivity.sigma_plot`): the
    response keeps its grids (:class:`~quadland.analysis.FrequencyResponse`), so the
    two figures evaluate it once (each frequency's value is its own, whatever the grid).
    """
    below = omega[omega < nyquist]
    keep = below >= floor
    return below[keep], loop_at_a_time(resp(below)[keep])


#: The figures start this many decades below the lowest frequency a margin is read at.
DECADES_BELOW = 2


def figure_floor(report: MarginReport) -> float:
    """rad/s, the lowest frequency the loop figures draw: :data:`DECADES_BELOW` decades
    under the lowest gain or phase crossover of any loop (0 if none has one).

    Below it a loop's response says nothing a review reads, and the sampled loop's is
    evaluated where ``z - 1`` is ``omega dt``: its integrators' cancellation costs
    ``eps / (omega dt)^k``, 59 dB at 1e-6 rad/s and 250 Hz on highway's roll, 0.01 dB three
    decades under its crossovers, invisible at two.
    """
    freqs = [f for lm in report.continuous.loops
             for f in (lm.crossover_frequency, lm.gain_margin_up_frequency,
                       lm.gain_margin_down_frequency)
             if f is not None and math.isfinite(f) and f > 0]
    return min(freqs) * 10.0 ** -DECADES_BELOW if freqs else 0.0


def phase_deg(values: np.ndarray, omega: np.ndarray, crossover: float | None) -> np.ndarray:
    """Unwrapped phase, deg, turned by whole turns so the crossover's lies in [-360, 0).

    Parameters
    ----------
    values : ndarray of complex
        A loop's response on the grid ``omega``.
    omega : ndarray
        rad/s, increasing.
    crossover : float or None
        rad/s, the gain crossover of the loop's phase margin; None (no
        crossing) refers to the grid's first frequency instead.

    Returns
    -------
    ndarray
        deg. At the crossover the phase is ``-180 + PM``, so every loop's
        margin is read against the same -180 deg line, whatever the
        number of integrators or right-half-plane poles of the loop.
    """
    raw = np.degrees(np.unwrap(np.angle(values)))
    if crossover is None or not math.isfinite(crossover):
        ref = raw[0]
    else:
        ref = np.interp(math.log(crossover), np.log(omega), raw)
    return raw - 360.0 * math.floor((ref + 360.0) / 360.0)


def crossing_phase(curves: LoopCurves, i: int, frequency: float) -> float:
    """deg, loop ``i``'s drawn phase at ``frequency`` (interpolated in log frequency)."""
    return float(np.interp(math.log(frequency), np.log(curves.omega), curves.phase(i)))


def exclusion_circle(alpha: float) -> tuple[float, float, bool]:
    """The values of ``l`` that a balanced disk margin ``alpha`` excludes.

    Parameters
    ----------
    alpha : float
        Disk margin (skew 0): the loop tolerates every factor ``f`` in the
        disk ``(1 + alpha/2 d) / (1 - alpha/2 d)``, ``|d| < 1``.

    Returns
    -------
    centre, radius, inside : float, float, bool
        The circle of the critical points ``l = -1/f`` of the disk's
        boundary: centre ``-(1 + h^2) / (1 - h^2)`` on the real axis and
        radius ``2 h / |1 - h^2|``, ``h = alpha / 2``. ``inside`` says whether
        the excluded region is the disk (``alpha < 2``; it contains -1) or
        the plane outside it (``alpha > 2``). At ``alpha = 2`` it is the left
        half-plane: centre ``-inf``.
    """
    h = alpha / 2.0
    if abs(1.0 - h * h) < 1e-12:
        return -math.inf, math.inf, True
    return -(1.0 + h * h) / (1.0 - h * h), 2.0 * h / abs(1.0 - h * h), h < 1.0


def m_circle(m_db: float, n: int = 721) -> tuple[np.ndarray, np.ndarray]:
    """A Nichols chart's M-circle: where ``|l / (1 + l)| = M``, as (phase deg, gain dB).

    Parameters
    ----------
    m_db : float
        ``20 log10 M``, nonzero.
    n : int
        Points.

    Returns
    -------
    phase, gain : ndarray
        In the l-plane the locus is the circle of centre ``-M^2 / (M^2 - 1)``
        and radius ``M / |M^2 - 1|``; its points in Nichols coordinates, the
        phase in ``[-360, 0]`` deg and sorted along the curve. M > 1 closes
        around -1 (a loop inside it is amplified by more than M); M < 1 is
        an open curve from -360 to 0 deg.
    """
    M = 10.0 ** (m_db / 20.0)
    centre, radius = -M * M / (M * M - 1.0), M / abs(M * M - 1.0)
    t = np.linspace(0.0, 2.0 * np.pi, n)
    z = centre + radius * np.exp(1j * t)       # never 0: |centre| != radius
    phase = np.degrees(np.angle(z))             # (-180, 180]
    phase = np.where(phase > 0, phase - 360.0, phase)
    # M > 1: the circle stays in Re l < 0 and its phase is continuous around -180 in
    # the order of t; M < 1: it encloses 0 and is cut where it crosses Re l > 0
    order = np.arange(t.size) if M > 1 else np.argsort(phase)
    return phase[order], 20.0 * np.log10(np.abs(z[order]))
