"""Classical and disk-based stability margins of linear feedback loops.

Every function here works on the state space, never on polynomials: the
frequency response comes from a complex Schur form ``A = Z T Z^H``
computed once per loop (:func:`~quadland.analysis.response.response_of`), so
that each frequency costs one triangular solve,
``G(s) = C Z (s I - T)^-1 Z^H B + D``. That is backward stable and fast
for loops of several hundred states, where polynomial forms (as in
``control.stability_margins``) lose every digit. Where the eigenvectors are
well conditioned, a whole grid comes from the modal form instead
(:mod:`~quadland.analysis.modal`: one product); refinements and the values
reported stay on the triangular solves.

Conventions: ``L`` is a loop transfer in the negative-feedback convention,
closed as ``u = -L u`` (the closed loop is ``(I + L)^-1``); a MIMO ``L``
is square, one channel per loop.

The package's parts: :mod:`~quadland.analysis.response` (the frequency
response from a Schur form, its adaptive grid, closed-loop poles, the
loop-at-a-time transform), :mod:`~quadland.analysis.classical` (every gain
and phase crossing, channel by channel) and :mod:`~quadland.analysis.disk`
(disk margins, loop at a time and multiloop through an upper bound of mu).
"""

from quadland.analysis.classical import Margins, allmargin
from quadland.analysis.disk import (
    DiskMargin,
    disk_gain_margin,
    disk_phase_margin,
    diskmargin,
    sensitivity_sigma,
)
from quadland.analysis.response import (
    FrequencyResponse,
    closed_loop_poles,
    freqresp,
    frequency_grid,
    loop_at_a_time,
    response_of,
)

__all__ = ["Margins", "DiskMargin", "FrequencyResponse", "response_of", "freqresp",
           "frequency_grid", "closed_loop_poles", "allmargin", "diskmargin", "sensitivity_sigma",
           "disk_gain_margin", "disk_phase_margin", "loop_at_a_time"]
