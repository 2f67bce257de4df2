"""The compiled simulators' drivers on CasADi's virtual machine.

:class:`VMLoop` runs the drivers of :class:`quadland.engine.compiled.CompiledLoop` step
for step with the loop's CasADi Functions where no C compiler is found: the same grid
(:mod:`quadland.engine.loop`), the same RK4 steps, the same event bisection and ride,
several times slower.
"""

from __future__ import annotations

import numpy as np

from quadland.engine.loop import (
    Clock,
    grid_tolerance,
    locate_event,
    merged_grid,
    ride_grid,
    rk4_span,
)
from quadland.engine.runs import (
    SIM_ENVELOPE,
    SIM_EVENT,
    SIM_GUARD,
    SIM_NONFINITE,
    SIM_OK,
    SIM_ROWS,
    Ride,
    Run,
    envelope_bounds,
    make_run,
    tick_source,
)
from quadland_symbolic.loop import LoopModel, rk4_step

__all__ = ["VMLoop"]


def _span_steps(span: float, substeps: int, h_after: float, x_ev) -> int:
    """RK4 steps over a span: ``substeps``, or after a continuing event at least
    ``ceil(span / h_after)`` (``quadland_loop``'s driver alike)."""
    if x_ev is None:
        return substeps
    return max(substeps, int(np.ceil(span / h_after - 1e-9)))


class VMLoop:
    """The drivers of :class:`CompiledLoop` on CasADi's virtual machine.

    The same algorithm, step for step (``quadland_loop.h``, mirrored by
    :mod:`quadland.engine.loop`): used where no C compiler is found.
    """

    #: Samples per call of the mapped output function.
    CHUNK = 256

    def __init__(self, model: LoopModel, part: str):
        self.model, self.part = model, part
        self._rhs = rk4_step(model.rhs) if model.rhs is not None else None
        self._plant = rk4_step(model.plant)
        self._free = rk4_step(model.free_plant) if model.free_plant is not None \
            and model.event_continues else None
        self._ride_step = rk4_step(model.ride_rhs) if model.ride_rhs is not None else None
        self._outputs = model.output_fn.map("outputs_map", "serial", self.CHUNK, [3], [])
        self._no_input = np.zeros(model.held.size)

    def _outside(self, x, uh, bound) -> np.ndarray | None:
        """The envelope's magnitudes when one is beyond its bound (or NaN), else None."""
        if self.model.envelope is None:
            return None
        s = np.asarray(self.model.envelope(x, uh), dtype=float).ravel()
        return None if np.all(s <= bound) else s

    def integrate(self, x0, clocks, W, substeps: int, p, bound=None) -> Run:
        """As :meth:`CompiledLoop.integrate`."""
        m = self.model
        bound = envelope_bounds(m, bound)
        grid, (out, dist) = merged_grid(clocks)
        x = np.asarray(x0, dtype=float)
        X, times, w_index = [], [], []
        i_w, status, t_stop, env = 0, SIM_OK, np.nan, None
        for j, t in enumerate(grid):
            if dist[j] >= 0:
                i_w = dist[j]
            env = self._outside(x, self._no_input, bound)
            if env is not None:
                status, t_stop = SIM_ENVELOPE, t
                break
            if out[j] >= 0:
                X.append(x)
                times.append(clocks[0].times()[out[j]])
                w_index.append(i_w)
            if j + 1 == len(grid):
                break
            w = W[i_w]
            x = rk4_span(lambda xx, tt, h, w=w: self._rhs(xx, w, tt, p, h), x, t,
                         grid[j + 1] - t, substeps)
            if not np.all(np.isfinite(x)):
                status, t_stop = SIM_NONFINITE, grid[j + 1]
                break
        return make_run(m, status, X, None, times, w_index, x, t_stop, env)

    def sampled(self, xp0, xc0, clocks, W, substeps: int, pp, pc, guard_min: float,
                bound=None, delay: int = 0, uh0=None, N=None, h_after: float = np.inf,
                after: float = np.inf, near: float = np.inf) -> Run:
        """As :meth:`CompiledLoop.sampled`."""
        m = self.model
        N, filled, more = tick_source(m, N)
        bound = envelope_bounds(m, bound)
        grid, (out, dist, ctrl) = merged_grid(clocks)
        xp, xc = np.asarray(xp0, dtype=float), np.asarray(xc0, dtype=float)
        uh = np.zeros(m.held.size) if uh0 is None else np.asarray(uh0, dtype=float)
        rv, first, queue = np.zeros(m.recorded.size), 1.0, []
        X, R, times, w_index = [], [], [], []
        i_w, status, t_stop, env = 0, SIM_OK, np.nan, None
        event = None if m.event is None else (lambda x, t: float(m.event(x, t, pp)))
        g_start = event(xp, grid[0]) if event is not None else None
        t_ev, x_ev, tol = np.nan, None, grid_tolerance(clocks)
        for j, t in enumerate(grid):
            if dist[j] >= 0:
                i_w = dist[j]
            if ctrl[j] >= 0:
                if m.tick_inputs is not None and ctrl[j] >= filled and more is not None:
                    filled = more(int(ctrl[j]))
                if m.tick_inputs is not None and ctrl[j] >= filled:
                    status, t_stop = SIM_ROWS, t
                    break
                extra = () if m.tick_inputs is None else (uh, W[i_w], pp, N[ctrl[j]])
                xc_n, uh_n, rv_n, guard = (np.asarray(v, dtype=float).ravel() for v in
                                           m.controller(xp, xc, pc, first, t, *extra))
                if not abs(guard[0]) >= guard_min:
                    status, t_stop = SIM_GUARD, t
                    break
                if not (np.all(np.isfinite(xc_n)) and np.all(np.isfinite(uh_n))
                        and np.all(np.isfinite(rv_n))):
                    status, t_stop = SIM_NONFINITE, t
                    break
                xc, rv, first = xc_n, rv_n, 0.0
                queue.append(uh_n)
                if len(queue) > delay:
                    uh = queue.pop(0)
            x = np.asarray(m.assemble(xp, xc), dtype=float).ravel()
            env = self._outside(x, uh, bound)
            if env is not None:
                status, t_stop = SIM_ENVELOPE, t
                break
            if out[j] >= 0:
                X.append(x)
                R.append(rv)
                times.append(clocks[0].times()[out[j]])
                w_index.append(i_w)
            if j + 1 == len(grid) or (x_ev is not None and t >= t_ev + after - tol):
                break
            w, span = W[i_w], grid[j + 1] - t

            def step(xx, tt, h, uh=uh, w=w):
                return self._plant(xx, uh, w, tt, pp, h)

            start, n_steps = xp, _span_steps(span, substeps, h_after, x_ev)
            xp, g_end = self._free_span(start, uh, w, pp, t, grid[j + 1], n_steps, near,
                                        g_start, x_ev, event)
            if xp is None:
                xp = rk4_span(step, start, t, span, n_steps)
            if not np.all(np.isfinite(xp)):
                status, t_stop = SIM_NONFINITE, grid[j + 1]
                break
            if event is not None and x_ev is None:
                g_end = event(xp, grid[j + 1]) if g_end is None else g_end
                if g_start > 0 and not g_end > 0:
                    offset, xp = locate_event(step, event, start, xp, t, span, substeps)
                    if not m.event_continues:
                        status, t_stop = SIM_EVENT, t + offset
                        break
                    t_ev, x_ev = t + offset, np.asarray(m.assemble(xp, xc), dtype=float).ravel()
                    xp = self._after_event(xp, uh, w, pp, t_ev, grid[j + 1], h_after)
                    if not np.all(np.isfinite(xp)):
                        status, t_stop = SIM_NONFINITE, grid[j + 1]
                        break
                g_start = g_end
        return make_run(m, status, X, R, times, w_index, np.concatenate([xp, xc]), t_stop, env,
                        t_ev, x_ev)

    def _free_span(self, xp, uh, w, pp, t: float, t_next: float, n_steps: int, near: float,
                   g_start, x_ev, event):
        """A span on the free plant before the first crossing, where the event function is
        above ``near`` at both ends: ``(xp, g_end)``; ``(None, None)`` where the driver
        integrates the whole plant instead."""
        if self._free is None or x_ev is not None or not g_start > near:
            return None, None
        xp = rk4_span(lambda xx, tt, h: self._free(xx, uh, w, tt, pp, h), xp, t, t_next - t,
                      n_steps)
        if not np.all(np.isfinite(xp)):
            return None, None
        g_end = event(xp, t_next)
        return (xp, g_end) if g_end > near else (None, None)

    def _after_event(self, xp, uh, w, pp, t_ev: float, t_next: float, h_after: float):
        """The rest of the span from a continuing event's state, in steps of at most
        ``h_after``."""
        if not t_next > t_ev:
            return xp

        def step(xx, tt, h):
            return self._plant(xx, uh, w, tt, pp, h)

        return rk4_span(step, xp, t_ev, t_next - t_ev,
                        max(1, int(np.ceil((t_next - t_ev) / h_after - 1e-9))))

    def ride(self, z0, a, rows: Clock, t_ev: float, t_end: float, h_max: float, pp) -> Ride:
        """As :meth:`CompiledLoop.ride` (:func:`quadland.engine.loop.ride_grid`)."""
        m = self.model
        step, z, t_prev = self._ride_step, np.asarray(z0, dtype=float), t_ev
        out = {"X": [], "Y": [], "R": []}
        times, steps = ride_grid(rows, t_ev, t_end, h_max)
        status = SIM_OK
        for t, s in zip(times, steps, strict=True):
            z = rk4_span(lambda zz, tt, h: step(zz, tt, pp, h), z, t_prev, t - t_prev, s)
            t_prev = t
            x, y, r = (np.asarray(v, dtype=float).ravel() for v in m.ride_row(z, a, t, pp))
            if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
                status = SIM_NONFINITE
                break
            for name, v in zip("XYR", (x, y, r), strict=True):
                out[name].append(v)
        k = len(out["X"])
        sizes = {"X": m.state.size, "Y": m.outputs.size, "R": m.recorded.size}
        X, Y, R = (np.array(out[n], dtype=float).reshape(-1, sizes[n]) for n in "XYR")
        return Ride(status, times[:k], X, Y, R)

    def outputs(self, X, W, T, p) -> np.ndarray:
        """As :meth:`CompiledLoop.outputs`, in chunks with ``p`` shared, not repeated."""
        n, k = X.shape[0], self.CHUNK
        Y = np.empty((n, self.model.outputs.size))
        for a in range(0, n, k):
            b = min(a + k, n)
            Xc = np.zeros((k, X.shape[1]))
            Wc = np.zeros((k, W.shape[1]))
            Tc = np.zeros((1, k))
            Xc[: b - a], Wc[: b - a], Tc[0, : b - a] = X[a:b], W[a:b], T[a:b]
            Y[a:b] = np.asarray(self._outputs(Xc.T, Wc.T, Tc, p), dtype=float).T[: b - a]
        return Y
