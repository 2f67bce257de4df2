"""The flight envelope: bounds a flight must stay within, and what leaving it means.

A diverging flight is stopped as soon as it leaves a physical envelope, not
when a value overflows. The loop's symbolic ``envelope(x, uh) -> s``
(:attr:`quadland_symbolic.loop.LoopModel.envelope`) gives magnitudes of its
state (altitude, speeds, rates, rotor forces, network weights); the
simulator compares them with the bounds of an :class:`Envelope`, derived from
the scenario by each loop (docs/simulation.md, "The flight envelope"), at
every grid point. Where a run leaves it, :func:`rk4_step_hint` tells whether
the fixed RK4 step is the likely cause, from the loop's eigenvalues and
RK4's stability region.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from quadland.scenario import Scenario
from quadland_symbolic.layout import Layout

__all__ = ["ENVELOPE_FACTOR", "SLOW_CONTROL", "RK4_REAL_STABILITY", "LOOP_DIVERGED", "Envelope",
           "rk4_amplification", "rk4_steps_needed", "rk4_hint", "slow_control_hint",
           "longest_rk4_step"]

#: How far beyond its initial scale a magnitude may grow before the flight is
#: judged diverged: a stable loop never reaches it, an unstable one within a
#: few steps.
ENVELOPE_FACTOR = 1e3
#: Gain times control period beyond which a sampled loop is likely too slow
#: (the paper's loop needs 40 Hz for gains of 10 1/s: docs/margins.md).
SLOW_CONTROL = 0.25
#: RK4 is stable on lambda h inside about -2.785 on the real axis.
RK4_REAL_STABILITY = 2.785


@dataclasses.dataclass(frozen=True)
class Envelope:
    """Bounds on a loop's envelope magnitudes, each with how it was derived.

    Attributes
    ----------
    layout : Layout
        The magnitudes (:attr:`quadland_symbolic.loop.LoopModel.envelope_layout`).
    bounds : ndarray
        One upper bound per magnitude, in its unit.
    basis : tuple of str
        How each bound follows from the scenario, one line each.
    """

    layout: Layout
    bounds: np.ndarray
    basis: tuple[str, ...]

    def __post_init__(self):
        if len(self.bounds) != self.layout.size or len(self.basis) != self.layout.size:
            raise ValueError("one bound and one basis per envelope magnitude")
        if not np.all(np.asarray(self.bounds) > 0):
            raise ValueError("envelope bounds must be positive")

    def as_dict(self) -> dict:
        """``{name: {"bound", "unit", "doc", "basis"}}``, for summaries and docs."""
        return {f.name: {"bound": float(b), "unit": f.unit, "doc": f.doc, "basis": why}
                for f, b, why in zip(self.layout.fields, self.bounds, self.basis, strict=True)}

    def describe(self, s: np.ndarray) -> str:
        """The worst magnitude of ``s`` against its bound, as one phrase.

        Examples
        --------
        >>> from quadland_symbolic.closed_loop import PAPER_ENVELOPE
        >>> env = Envelope(PAPER_ENVELOPE, np.full(6, 10.0), ("x",) * 6)
        >>> print(env.describe(np.array([1.0, 500.0, 0, 0, 0, 0])))
        the speed (largest body velocity component |V1|) reached 500 m/s, beyond its
        envelope of 10 m/s
        """
        s = np.asarray(s, dtype=float)
        with np.errstate(invalid="ignore", divide="ignore"):
            ratio = np.where(np.isnan(s), np.inf, s / self.bounds)
        k = int(np.argmax(ratio))
        f = self.layout.fields[k]
        unit = "" if f.unit in ("-", "") else f" {f.unit}"
        value = "a non-finite value" if not np.isfinite(s[k]) else f"{s[k]:.3g}{unit}"
        return (f"the {f.name} ({f.doc}) reached {value}, beyond its envelope of "
                f"{self.bounds[k]:.3g}{unit}")


def rk4_amplification(z: np.ndarray) -> np.ndarray:
    """``|R(z)|`` of the classical RK4 method, ``R(z) = 1 + z + z^2/2 + z^3/6 + z^4/24``.

    A mode ``lambda`` is integrated stably with step ``h`` when
    ``|R(lambda h)| <= 1`` (Hairer and Wanner, *Solving ODEs II*, IV.2).

    Examples
    --------
    >>> rk4_amplification(np.array([-2.785, -2.79])).round(4)   # the real-axis limit
    array([0.9996, 1.0071])
    """
    z = np.asarray(z, dtype=complex)
    return np.abs(1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24)


def rk4_steps_needed(eigenvalues: np.ndarray, h: float, steps: int) -> int | None:
    """Steps per interval that make RK4 stable on every eigenvalue, or None if ``steps`` do.

    ``h`` is the step now (the interval over ``steps``). The answer keeps
    ``|R(lambda h')| <= 1`` for the interval's new step ``h'`` on every
    eigenvalue, with a factor 2 of margin, so that the mode is damped, not
    only bounded.
    """
    lam = np.asarray(eigenvalues, dtype=complex)
    if lam.size == 0 or np.all(rk4_amplification(lam * h) <= 1 + 1e-12):
        return None
    interval = h * steps
    n = steps
    while np.any(rk4_amplification(lam * interval / n) > 1 + 1e-12) and n < 1 << 20:
        n *= 2
    return 2 * n


def slow_control_hint(scenario: Scenario, gains: list[float]) -> str | None:
    """A hint when the control period is likely too long for the gains, else None.

    A sampled loop whose gain times period exceeds :data:`SLOW_CONTROL` is
    likely unstable for that reason (the paper's loop needs 40 Hz for gains
    of 10 1/s: docs/margins.md).
    """
    rate = scenario.data["controller"]["rate_hz"]
    if gains and rate > 0 and max(gains) / rate > SLOW_CONTROL:
        need = int(np.ceil(max(gains) / SLOW_CONTROL))
        return (f" (the control period 1/{rate:g} s is likely too long for gains up to "
                f"{max(gains):g} 1/s: try controller.rate_hz={need} or more)")
    return None


#: The hint where neither the step nor the control rate is the likely cause.
LOOP_DIVERGED = (" (the loop itself left its envelope: check the gains, the disturbance, the "
                  "vehicle's drive and the initial state)")


def rk4_hint(eigenvalues, h: float, steps: int, cvodes: bool = False) -> str | None:
    """A hint naming ``simulation.rk_steps_per_interval`` where a mode of ``eigenvalues`` is
    outside RK4's stability region for the step ``h``, else None."""
    lam = np.asarray(eigenvalues, dtype=complex)
    need = rk4_steps_needed(lam, h, steps)
    if need is None:
        return None
    fastest = lam[np.argmax(np.abs(lam))]
    alternative = " or simulation.integrator=\"cvodes\"" if cvodes else ""
    return (f" (the RK4 step h = {h:.3g} s is outside RK4's stability region for the loop's "
            f"fastest mode, {fastest.real:.3g}{fastest.imag:+.3g}j 1/s: try "
            f"simulation.rk_steps_per_interval={need}{alternative})")


def longest_rk4_step(scenario: Scenario) -> float:
    """The longest RK4 step of the run: the shortest clock period over the substeps."""
    sim, ctrl = scenario.data["simulation"], scenario.data["controller"]
    clocks = [sim["output_rate_hz"], scenario.data["disturbance"]["sample_rate_hz"]]
    if ctrl["rate_hz"] > 0:
        clocks.append(ctrl["rate_hz"])
    return 1.0 / max(clocks) / sim["rk_steps_per_interval"]
