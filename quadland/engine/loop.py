"""The loop algorithm's clocks and grid, mirrored from ``quadland_loop.h``.

The compiled simulators and the pure-C examples run the loop algorithm of
``symbolic/templates/quadland_loop.h.jinja``; this module is its one Python
mirror, used by the fallback on CasADi's virtual machine
(:class:`quadland.engine.vm.VMLoop`) and wherever Python needs a run's grid
(cvodes' output times, the rows' disturbance samples). The rule, in both:

* a :class:`Clock` ticks at ``phase + k / rate`` while below the duration
  ``T``; a *closing* clock also ticks at ``T`` itself, unless its last
  regular tick already lies there (``numpy.isclose``'s tolerance);
* the merged grid's next point is the earliest pending tick of all clocks,
  and every clock whose next tick lies within :data:`GRID_TOL` of the
  shortest clock period after it ticks there too.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from quadland_symbolic.loop import RIDE_TOL

__all__ = ["GRID_TOL", "EVENT_TOL", "EVENT_ITERATIONS", "RIDE_TOL", "Clock", "grid_tolerance",
           "merged_grid", "rk4_span", "locate_event", "ride_grid"]

#: Clock times closer than this fraction of the shortest period are one grid point.
GRID_TOL = 1e-6
#: An event is located to this fraction of its span.
EVENT_TOL = 1e-12
#: Most bisection halvings (2^-60 of a span is below EVENT_TOL).
EVENT_ITERATIONS = 60


@dataclasses.dataclass(frozen=True)
class Clock:
    """Ticks at ``phase + k / rate`` below ``T``, and at ``T`` when ``closing``.

    Examples
    --------
    >>> Clock(4.0, 0.0, 1.0, closing=True).times()
    array([0.  , 0.25, 0.5 , 0.75, 1.  ])
    >>> Clock(4.0, 0.0, 1.1, closing=False).times()
    array([0.  , 0.25, 0.5 , 0.75, 1.  ])
    >>> Clock(4.0, 0.0, 1.1, closing=True).times()[-1]
    np.float64(1.1)
    """

    rate: float
    phase: float
    T: float
    closing: bool

    @property
    def h(self) -> float:
        """The period, s."""
        return 1.0 / self.rate

    def _counts(self) -> tuple[int, int]:
        span = self.T - self.phase
        if span < 0:
            return 0, 0
        regular = int(math.floor(span / self.h + 1e-9)) + 1
        last = self.phase + self.h * (regular - 1)
        if abs(last - self.T) <= 1e-8 + 1e-5 * abs(self.T):
            return regular, regular if self.closing else regular - 1
        return regular, regular + (1 if self.closing else 0)

    def count(self) -> int:
        """How many ticks: ``len(self.times())``, without them."""
        return self._counts()[1]

    def times(self) -> np.ndarray:
        """Every tick's time, s (``quadland_loop.h``'s ``qll_clock_time``); read-only, computed
        once per clock (a landing's run reads its 4,001 disturbance ticks five times)."""
        kept = self.__dict__.get("_times")
        if kept is None:
            regular, count = self._counts()
            k = np.arange(count)
            kept = np.where(k < regular, self.phase + self.h * k, self.T)
            kept.flags.writeable = False
            object.__setattr__(self, "_times", kept)
        return kept

    def table(self) -> tuple[float, float, float]:
        """``(rate, phase, closing)``: the row of the C drivers' clock table."""
        return (float(self.rate), float(self.phase), 1.0 if self.closing else 0.0)


def grid_tolerance(clocks) -> float:
    """The merge tolerance: :data:`GRID_TOL` of the shortest period of a clock that ticks twice."""
    periods = [c.h for c in clocks if c.count() > 1]
    return GRID_TOL * (min(periods) if periods else 1.0)


def merged_grid(clocks) -> tuple[np.ndarray, list[np.ndarray]]:
    """The merged grid of ``clocks`` and, per clock, each grid point's tick index or -1.

    Returns
    -------
    grid : ndarray
        The grid points, s, increasing.
    ticks : list of ndarray of int
        For each clock, per grid point, the index of the tick it takes there
        (``qll_tick``), or -1.

    Examples
    --------
    >>> grid, (a, b) = merged_grid([Clock(2.0, 0.0, 1.0, True), Clock(3.0, 0.0, 1.0, True)])
    >>> grid.round(4).tolist(), a.tolist(), b.tolist()
    ([0.0, 0.3333, 0.5, 0.6667, 1.0], [0, -1, 1, -1, 2], [0, 1, -1, 2, 3])
    """
    times = [c.times() for c in clocks]
    tol = grid_tolerance(clocks)
    nxt = [0] * len(clocks)
    grid, ticks = [], [[] for _ in clocks]
    while True:
        pending = [ts[k] for ts, k in zip(times, nxt, strict=True) if k < len(ts)]
        if not pending:
            break
        t = min(pending)
        grid.append(t)
        for i, ts in enumerate(times):
            if nxt[i] < len(ts) and ts[nxt[i]] <= t + tol:
                ticks[i].append(nxt[i])
                nxt[i] += 1
            else:
                ticks[i].append(-1)
    return np.array(grid, dtype=float), [np.array(k, dtype=np.int_) for k in ticks]


def rk4_span(step, x: np.ndarray, t0: float, span: float, m: int) -> np.ndarray:
    """``x`` over ``span`` from ``t0`` in ``m`` classical RK4 steps (``qll_rk4_span``).

    ``step(x, t, h) -> x_next`` is one RK4 step of length ``h`` from time ``t``
    (``quadland_symbolic.loop.rk4_step``'s function with the held inputs bound).
    """
    h = span / m
    for s in range(int(m)):
        x = np.asarray(step(x, t0 + s * h, h), dtype=float).ravel()
    return x


def locate_event(step, g, x_start: np.ndarray, x_end: np.ndarray, t0: float, span: float,
                 m: int) -> tuple[float, np.ndarray]:
    """The event's offset within a span and the state then (``qll_locate``).

    ``g(x, t)`` is positive at ``x_start`` and not at ``x_end``; bisection on the
    RK4 solution from ``x_start`` to :data:`EVENT_TOL` of the span.
    """
    lo, hi, x = 0.0, span, x_end
    for _ in range(EVENT_ITERATIONS):
        if not hi - lo > EVENT_TOL * span:
            break
        mid = (lo + hi) / 2
        trial = rk4_span(step, x_start, t0, mid, m)
        if g(trial, t0 + mid) > 0:
            lo = mid
        else:
            hi, x = mid, trial
    return hi, x


def ride_grid(rows: Clock, t_ev: float, t_end: float, h_max: float
              ) -> tuple[np.ndarray, np.ndarray]:
    """The ride's rows after an event and the RK4 steps before each (``qll_ride``).

    A row at each tick of ``rows`` after ``t_ev`` and before ``t_end`` (beyond
    :data:`quadland_symbolic.loop.RIDE_TOL`, the C's ``QLL_RIDE_TOL``), then at
    ``t_end`` (none when ``t_end`` is ``t_ev``); the span to each row from the
    last is taken in ``ceil(span / h_max)`` steps.

    Examples
    --------
    >>> times, steps = ride_grid(Clock(10.0, 0.0, 2.0, True), 0.95, 1.25, 0.04)
    >>> times.round(6).tolist(), steps.tolist()
    ([1.0, 1.1, 1.2, 1.25], [2, 3, 3, 2])
    """
    ticks = rows.times()
    times = ticks[(ticks > t_ev + RIDE_TOL) & (ticks < t_end - RIDE_TOL)]
    if t_end > t_ev + RIDE_TOL:
        times = np.append(times, t_end)
    before = np.concatenate([[t_ev], times[:-1]])
    steps = np.maximum(1, np.ceil((times - before) / h_max - 1e-9)).astype(np.int_)
    return times, steps
