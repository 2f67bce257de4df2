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
import math

import casadi as ca
import numpy as np

from quadland.scenario import Scenario
from quadland_symbolic.layout import Layout

__all__ = ["ENVELOPE_FACTOR", "SLOW_CONTROL", "RK4_REAL_STABILITY", "LOOP_DIVERGED", "Envelope",
           "rk4_amplification", "rk4_steps_needed", "rk4_hint", "slow_control_hint",
           "longest_rk4_step", "loop_modes", "likely_cause", "MAX_RK_STEPS", "RK4_RESOLVE",
           "fewest_stable_steps"]

#: How far beyond its initial scale a magnitude may grow before the flight is
#: judged diverged: a stable loop never reaches it, an unstable one within a
#: few steps.
ENVELOPE_FACTOR = 1e3
#: Gain times control period beyond which a sampled loop is likely too slow
#: (the paper's loop needs 40 Hz for gains of 10 1/s: docs/margins.md).
SLOW_CONTROL = 0.25
#: RK4 is stable on lambda h inside about -2.785 on the real axis.
RK4_REAL_STABILITY = 2.785
#: ``|lambda h|`` at which RK4 resolves a mode: a local error of ``|lambda h|^5 / 120``,
#: 2e-5 per step, a few 1e-4 of phase per period of an oscillation.
RK4_RESOLVE = 0.3
#: The most RK4 steps per interval ``simulation.rk_steps_per_interval`` allows.
MAX_RK_STEPS = 1000


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
        >>> env = Envelope(PAPER_ENVELOPE, np.full(8, 10.0), ("x",) * 8)
        >>> print(env.describe(np.array([1.0, 500.0, 0, 0, 0, 0, 0, 0])))
        the speed (largest body velocity component |V1|) reached 500 m/s, beyond its
        envelope of 10 m/s
        """
        s = np.asarray(s, dtype=float)
        with np.errstate(invalid="ignore", divide="ignore"):
            ratio = np.where(np.isnan(s), np.inf, s / self.bounds)
        k = int(np.argmax(ratio))
        f = self.layout.fields[k]
        unit = "" if f.unit in ("-", "") else f" {f.unit}"
        digits = 3
        while digits < 9 and f"{s[k]:.{digits}g}" == f"{self.bounds[k]:.{digits}g}":
            digits += 1         # just past its bound: enough digits to show it
        value = "a non-finite value" if not np.isfinite(s[k]) else f"{s[k]:.{digits}g}{unit}"
        return (f"the {f.name} ({f.doc}) reached {value}, beyond its envelope of "
                f"{self.bounds[k]:.{digits}g}{unit}")


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


def fewest_stable_steps(eigenvalues: np.ndarray, interval: float) -> float:
    """The fewest RK4 steps over ``interval`` that keep every stable mode inside RK4's
    stability region, ``|R(lambda interval / n)| <= 1`` (``inf`` beyond 2**40).

    Only modes with ``Re(lambda) <= 0`` count: a growing mode grows under any
    step, and is the loop's, not the integrator's.

    Examples
    --------
    >>> fewest_stable_steps(np.array([-300.0, 5.0]), 0.01)     # -3 / 2 is inside
    2
    """
    lam = np.asarray(eigenvalues, dtype=complex).ravel()
    lam = lam[np.isfinite(lam) & (lam.real <= 0)]

    def stable(n):
        return bool(np.all(rk4_amplification(lam * interval / n) <= 1 + 1e-12))

    if stable(1):
        return 1
    lo, hi = 1, 2
    while not stable(hi):
        lo, hi = hi, 2 * hi
        if hi > 1 << 40:
            return math.inf
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (lo, mid) if stable(mid) else (mid, hi)
    return hi


def rk4_steps_needed(eigenvalues: np.ndarray, h: float, steps: int) -> float | None:
    """Steps per interval for RK4 to hold and resolve the loop's stable modes, or None
    if ``steps`` hold them.

    ``h`` is the step now (the interval over ``steps``). Where a stable mode
    lies outside RK4's stability region at ``h``, the answer is the fewest
    steps that bring every one inside (:func:`fewest_stable_steps`) and resolve
    the fastest, ``|lambda h'| <= RK4_RESOLVE`` (a step that only bounds a
    mode leaves it tens of percent wrong). It may exceed what
    ``simulation.rk_steps_per_interval`` allows (:data:`MAX_RK_STEPS`).

    Examples
    --------
    >>> rk4_steps_needed(np.array([-100.0]), 0.01, 1) is None    # z = -1: inside
    True
    >>> rk4_steps_needed(np.array([-300.0, 5.0]), 0.01, 1)       # z = -3; +5 is the loop's
    10
    """
    lam = np.asarray(eigenvalues, dtype=complex).ravel()
    lam = lam[np.isfinite(lam) & (lam.real <= 0)]
    interval = h * steps
    if lam.size == 0 or fewest_stable_steps(lam, interval) <= steps:
        return None
    resolve = math.ceil(float(np.max(np.abs(lam))) * interval / RK4_RESOLVE - 1e-9)
    return max(fewest_stable_steps(lam, interval), resolve)


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


def rk4_hint(eigenvalues, h: float, steps: int) -> str | None:
    """A hint naming ``simulation.rk_steps_per_interval`` where a stable mode of
    ``eigenvalues`` is outside RK4's stability region for the step ``h``, else None.

    The hint names the mode that sets the step (the fastest stable one outside
    the region). Where no step count up to :data:`MAX_RK_STEPS` suffices it says
    the loop is stiff there, without a value the key would refuse.
    """
    lam = np.asarray(eigenvalues, dtype=complex).ravel()
    need = rk4_steps_needed(lam, h, steps)
    if need is None:
        return None
    lam = lam[np.isfinite(lam) & (lam.real <= 0)]
    outside = lam[rk4_amplification(lam * h) > 1 + 1e-12]
    mode = outside[np.argmax(np.abs(outside))]
    text = f"{mode.real:.3g}{mode.imag:+.3g}j 1/s"
    fewest = fewest_stable_steps(lam, h * steps)
    if fewest <= MAX_RK_STEPS:
        return (f" (the RK4 step h = {h:.3g} s is outside RK4's stability region for the "
                f"loop's mode {text}: try simulation.rk_steps_per_interval="
                f"{int(min(need, MAX_RK_STEPS))})")
    return (f" (the loop's mode {text} needs an RK4 step below {h * steps / fewest:.3g} s, "
            f"shorter than simulation.rk_steps_per_interval's most ({MAX_RK_STEPS}) gives "
            "on this grid: the model is stiff there; check the parameters that set that mode)")


def loop_modes(fn: ca.Function, *args) -> np.ndarray:
    """Eigenvalues of ``fn``'s Jacobian in its first input at ``args``; empty if not finite.

    ``fn`` is a loop's ``rhs(x, w, t, p)`` or ``plant(xp, uh, w, t, pp)``
    (:class:`quadland_symbolic.loop.LoopModel`).
    """
    if not all(np.all(np.isfinite(np.asarray(a, dtype=float))) for a in args):
        return np.zeros(0, dtype=complex)
    sym = [fn.mx_in(i) for i in range(fn.n_in())]
    jac = ca.Function("modes", sym, [ca.jacobian(fn(*sym)[0] if fn.n_out() > 1 else fn(*sym),
                                                 sym[0])])
    A = np.asarray(jac(*args), dtype=float)
    return np.linalg.eigvals(A) if np.all(np.isfinite(A)) else np.zeros(0, dtype=complex)


def likely_cause(scenario: Scenario, initial: np.ndarray, last: np.ndarray,
                 gains: list[float]) -> str:
    """Why a flight left its envelope, as the tail of its failure line.

    In order: a stable mode at the initial state outside RK4's stability
    region for the run's step (:func:`rk4_hint`); a control period too long
    for the gains (:func:`slow_control_hint`); a stable mode at the last
    state recorded outside that region; else :data:`LOOP_DIVERGED`.
    ``initial`` and ``last`` are eigenvalues (:func:`loop_modes`).
    """
    h, steps = longest_rk4_step(scenario), scenario.data["simulation"]["rk_steps_per_interval"]
    first = rk4_hint(initial, h, steps)
    if first is not None:
        return first
    slow = slow_control_hint(scenario, gains)
    if slow is not None:
        return slow
    later = rk4_hint(last, h, steps)
    if later is not None and fewest_stable_steps(last, h * steps) <= MAX_RK_STEPS:
        return later
    return LOOP_DIVERGED


def longest_rk4_step(scenario: Scenario) -> float:
    """The longest RK4 step of the run: the shortest clock period over the substeps."""
    sim, ctrl = scenario.data["simulation"], scenario.data["controller"]
    clocks = [sim["output_rate_hz"], scenario.data["disturbance"]["sample_rate_hz"]]
    if ctrl["rate_hz"] > 0:
        clocks.append(ctrl["rate_hz"])
    return 1.0 / max(clocks) / sim["rk_steps_per_interval"]
