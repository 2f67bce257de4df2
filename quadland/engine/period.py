"""One control period of a sampled-data loop, as a discrete-time map.

A sampled-data loop (:class:`quadland_symbolic.loop.LoopModel` without a
continuous ``rhs``) flown by the simulator carries from one control tick to
the next: the plant's state ``xp``, the controller's memory ``xc`` and the
commands computed but not yet applied (``delay`` control periods of them,
the queue of :class:`quadland.engine.vm.VMLoop`). :class:`SampledPeriod`
steps that state over one period with the loop's CasADi functions on the
virtual machine, the way the simulator's driver does (``quadland_loop.h``,
mirrored by :mod:`quadland.engine.vm`): the controller at the tick, the
held command the oldest of the queue, the plant by the same RK4 steps
(:func:`quadland_symbolic.loop.rk4_step`) on the same grid, the period split
where the output and disturbance clocks tick (:mod:`quadland.engine.loop`),
``substeps`` steps per piece. ``quadland.nlsys`` wraps it for python-control.

What the driver does besides is left out: the envelope and the guard are not
checked, and a continuing event (a landing's first contact) is neither
located nor followed by its shorter steps, so the map equals the flight
before such an event only. The disturbance is held over the whole period
(the driver holds it from each tick of its own clock).
"""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np

from quadland.engine.loop import GRID_TOL, rk4_span
from quadland_symbolic.loop import LoopModel, rk4_step

__all__ = ["SampledPeriod"]


def _vector(value) -> np.ndarray:
    return np.asarray(value, dtype=float).ravel()


@dataclasses.dataclass(frozen=True)
class SampledPeriod:
    """One control period of a sampled-data loop (see the module docstring).

    Attributes
    ----------
    model : LoopModel
        A sampled-data loop without per-tick inputs (``tick_inputs`` None).
    pc, pp : ndarray
        The controller's and the plant's parameters.
    dt : float
        s, the control period.
    delay : int
        Control periods between a command's computation and its application.
    substeps : int
        RK4 steps per piece of the grid (``simulation.rk_steps_per_interval``).
    break_rates : tuple of float
        Hz, the other clocks (phase 0) whose ticks split a period: the output
        rows' and the disturbance samples'.

    The state is ``[xp, xc, q]``, ``q`` the ``delay`` queued commands, the
    oldest first (:meth:`state_names`).
    """

    model: LoopModel
    pc: np.ndarray
    pp: np.ndarray
    dt: float
    delay: int
    substeps: int
    break_rates: tuple[float, ...]

    def __post_init__(self):
        m = self.model
        if m.tick_inputs is not None:
            raise ValueError(f"{m.name}: a loop with per-tick inputs has no one-period map")
        first = m.controller.name_in().index("first")
        if any(m.controller.sparsity_jac(first, j).nnz() for j in range(m.controller.n_out())):
            raise ValueError(f"{m.name}: its controller's first step differs from the others")

    @functools.cached_property
    def _plant_step(self):
        return rk4_step(self.model.plant)

    @property
    def _tol(self) -> float:
        """The grid's merge tolerance (:func:`quadland.engine.loop.grid_tolerance`)."""
        return GRID_TOL * min([self.dt, *(1.0 / r for r in self.break_rates)])

    def state_names(self) -> list[str]:
        """``xp``'s, ``xc``'s and the queue's names (``F_1_cmd_delay1``: the command
        one period old)."""
        m = self.model
        queue = [f"{n}_delay{self.delay - j}" for j in range(self.delay)
                 for n in m.held.element_names()]
        return [*m.plant_state.element_names(), *m.controller_state.element_names(), *queue]

    def output_names(self) -> list[str]:
        """The loop's output signals, then what its controller records."""
        return [*self.model.outputs.element_names(), *self.model.recorded.element_names()]

    def initial_state(self, xp0, xc0, uh0) -> np.ndarray:
        """``[xp0, xc0]`` and a queue full of ``uh0`` (the driver's held input until
        the first command is applied)."""
        return np.concatenate([_vector(xp0), _vector(xc0), np.tile(_vector(uh0), self.delay)])

    def _split(self, x):
        nxp, nxc = self.model.plant_state.size, self.model.controller_state.size
        x = _vector(x)
        return x[:nxp], x[nxp:nxp + nxc], x[nxp + nxc:]

    def _control(self, xp, xc, t):
        """``(xc_next, uh, rec)`` of the controller's step at ``t``."""
        out = self.model.controller(xp, xc, self.pc, 0.0, t)
        return tuple(_vector(v) for v in out[:3])

    def grid(self, t: float) -> np.ndarray:
        """The period's grid from the tick ``t`` to the next: the other clocks' ticks
        between them, those within the tolerance of another taken as one."""
        tol = self._tol
        k = round(t / self.dt)
        t_end = self.dt * (k + 1) if abs(self.dt * k - t) <= tol else t + self.dt
        points = []
        for rate in self.break_rates:
            h = 1.0 / rate
            i = np.arange(math.floor(t / h), math.ceil(t_end / h) + 1)
            ticks = h * i
            points.extend(ticks[(ticks > t + tol) & (ticks < t_end - tol)])
        grid = [t]
        for p in sorted(points):
            if p > grid[-1] + tol:
                grid.append(p)
        return np.array([*grid, t_end])

    def update(self, t: float, x, w) -> np.ndarray:
        """The state one period after the tick ``t`` under the held disturbance ``w``."""
        xp, xc, queue = self._split(x)
        xc_next, uh_new, _ = self._control(xp, xc, t)
        m = self.model.held.size
        held = queue[:m] if self.delay else uh_new
        w = _vector(w)

        def step(xx, tt, h):
            return self._plant_step(xx, held, w, tt, self.pp, h)

        grid = self.grid(t)
        for a, b in zip(grid[:-1], grid[1:], strict=True):
            xp = rk4_span(step, xp, a, b - a, self.substeps)
        return np.concatenate([xp, xc_next, queue[m:], uh_new if self.delay else []])

    def output(self, t: float, x, w) -> np.ndarray:
        """The row the simulator records at the tick ``t``: the outputs of the plant's
        state and the memory after the step, then the step's recorded signals."""
        xp, xc, _ = self._split(x)
        xc_next, _, rec = self._control(xp, xc, t)
        x_row = self.model.assemble(xp, xc_next)
        return np.concatenate([_vector(self.model.output_fn(x_row, _vector(w), t, self.pp)),
                               rec])
