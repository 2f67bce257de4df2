"""Margin review of a scenario's closed loop, as typed results.

:func:`margin_report` linearizes the closed loop at an operating point (the
equilibrium, or the simulated state at time ``at``), breaks it at the plant
input u, and reports per loop (altitude, roll, pitch, yaw; for a landing
scenario thrust, roll, pitch, yaw at the wrench into the mixer) the
classical margins with the other loops closed, the loop-at-a-time and
multiloop disk margins, the closed-loop poles, and pass or fail against a
:class:`Requirement`. With ``controller.rate_hz > 0`` (always for a landing
scenario) the sampled-data loop, with its computation delay, is reported
beside the continuous one. :meth:`MarginReport.to_dict` is the
content of ``margins.json``; :func:`format_report` the table that
``quadland margins`` prints.

The package's parts: :mod:`~quadland.margins.report` (the typed results),
:mod:`~quadland.margins.review` (building one) and
:mod:`~quadland.margins.text` (the printed table). The figures need
matplotlib and are in :mod:`quadland.plots.margins`.

The margin mathematics (:mod:`quadland.analysis`) and the loop kinds'
linearization (:mod:`quadland.kinds`) are imported when a report is built, so
that the command line can read :class:`Requirement`'s defaults without loading
python-control.
"""

from quadland.margins.report import (
    LoopMargins,
    LoopReport,
    MarginReport,
    MultiloopDiskMargin,
    Pole,
    PoleSummary,
    Requirement,
)
from quadland.margins.review import MAX_LOOP_STATES, check_request, loop_states, margin_report
from quadland.margins.text import format_report

__all__ = ["MAX_LOOP_STATES", "loop_states", "check_request", "Requirement", "LoopMargins",
           "MultiloopDiskMargin", "Pole", "PoleSummary", "LoopReport", "MarginReport",
           "margin_report", "format_report"]
