"""A finished envelope's cells: runs, successes, the exact interval, the failure modes.

:func:`cell_statistics` counts each cell of an envelope's runs.csv rows;
:func:`failure_modes` names why a run is not a success (the phrases of its
message without their numbers: ``touchdown_offset``, ``no touchdown``, a
numerical failure); :func:`envelope_files` writes ``envelope.json`` and
``envelope.png``.
"""

from __future__ import annotations

import re
from collections import Counter
from collections.abc import Mapping, Sequence

import numpy as np

from quadland.campaign.statistics import clopper_pearson
from quadland.campaign.summary import CONFIDENCE

__all__ = ["NUMERICAL_FAILURE", "INVALID_DRAW", "failure_modes", "cell_statistics",
           "envelope_files"]

#: The failure mode of a run stopped by a numerical failure (``status = failed``).
NUMERICAL_FAILURE = "numerical failure"
#: What a run whose draws made no valid scenario is counted as (not flown).
INVALID_DRAW = "invalid draw"
_DETAIL = re.compile(r"\s(?:by\b|[<>=]|[-+]?\.?\d)")


def failure_modes(status: str, success: bool, message: str) -> list[str]:
    """Why a run is not a success: one mode per missed limit (none for a success).

    ``"touchdown_offset 0.23 > 0.2 m; no touchdown by t = 40 s"`` gives
    ``["touchdown_offset", "no touchdown"]``: each phrase up to its first
    number, comparison or ``by``.

    Examples
    --------
    >>> failure_modes("ok", False, "offset 0.23 > 0.2 m; sink_rate undefined")
    ['offset', 'sink_rate undefined']
    >>> failure_modes("failed", False, "the flight left its envelope at t = 3 s")
    ['numerical failure']
    """
    if status == "invalid":
        return [INVALID_DRAW]
    if status == "failed":
        return [NUMERICAL_FAILURE]
    if success:
        return []
    modes = [_DETAIL.split(" " + p.strip())[0].strip() for p in message.split(";")]
    return [m for m in modes if m] or ["missed a limit"]


def cell_statistics(header: Sequence[str], rows: Sequence[Sequence[str]], cells: int,
                    level: float = CONFIDENCE, counted: Sequence[str] = ()) -> list[dict]:
    """Each cell's counts from an envelope's runs.csv rows.

    Returns
    -------
    list of dict
        Per cell (by index): ``runs`` (flown: ``ok`` or ``failed``),
        ``invalid``, ``successes``, ``success_rate`` (None without a run
        flown), ``interval`` (Clopper-Pearson at ``level``, None without a
        run flown) and ``failure_modes`` (mode -> runs; a run missing two
        limits counts in both); with ``counted`` (0/1 metric columns, e.g.
        ``false_touchdown``), ``counts``: column -> flown runs where it is 1.
    """
    col = {name: k for k, name in enumerate(header)}
    counts = [{"runs": 0, "invalid": 0, "successes": 0, "modes": Counter(),
               "flags": Counter()} for _ in range(cells)]
    for row in rows:
        c = counts[int(row[col["cell"]])]
        status, success = row[col["status"]], row[col["success"]] == "true"
        if status == "invalid":
            c["invalid"] += 1
        else:
            c["runs"] += 1
            c["successes"] += success
            c["flags"].update(name for name in counted if row[col[name]] in ("1", "1.0"))
        c["modes"].update(failure_modes(status, success, row[col["message"]]))
    out = []
    for c in counts:
        n, k = c["runs"], c["successes"]
        out.append({"runs": n, "invalid": c["invalid"], "successes": k,
                    "success_rate": k / n if n else None,
                    "interval": list(clopper_pearson(k, n, level)) if n else None,
                    "failure_modes": dict(sorted(c["modes"].items(),
                                                 key=lambda m: (-m[1], m[0]))),
                    **({"counts": {name: c["flags"][name] for name in counted}}
                       if counted else {})})
    return out


def envelope_files(env, header: Sequence[str], rows: Sequence[Sequence[str]],
                   session: Mapping, plots: bool = True) -> tuple[dict, dict[str, bytes]]:
    """``envelope.json`` (as a dict and as bytes) and ``envelope.png`` of a finished envelope.

    Parameters
    ----------
    env : quadland.campaign.grid.Envelope
    header, rows : the runs.csv columns and rows, sorted by index
    session : mapping
        What this command did (runs flown, wall time, where).
    plots : bool
        Draw envelope.png.
    """
    from quadland.kinds import kind_of
    from quadland.output import figure_png, strict_json
    from quadland.run import provenance

    cells = env.cells
    counted = [m.name for m in kind_of(env.base).metrics if m.counted]
    stats = cell_statistics(header, rows, len(cells), counted=counted)
    entries = []
    for c, (values, s) in enumerate(zip(cells, stats, strict=True)):
        entries.append({"cell": c, **{a.name: (int(v) if a.integer else v)
                                      for a, v in zip(env.axes, values, strict=True)}, **s})
    flown = sum(s["runs"] for s in stats)
    data = {"scenario": env.base.name, "model": env.base.model,
            "axes": [a.to_dict() for a in env.axes], "runs_per_cell": env.runs_per_cell,
            "hold": list(env.hold), "polar": env.polar,
            "runs": len(rows), "flown": flown,
            "successes": sum(s["successes"] for s in stats),
            **({"counts": {name: sum(s["counts"][name] for s in stats) for name in counted}}
               if counted else {}),
            "invalid": sum(s["invalid"] for s in stats),
            "confidence": {"level": CONFIDENCE, "method": "Clopper-Pearson (exact binomial)",
                           "contours": [0.5, 0.9, 0.99]},
            "cells": entries, "campaign": env.spec.identity(),
            "last_session": dict(session), "provenance": provenance(env.base)}
    files = {"envelope.json": strict_json(data)}
    if plots and flown:
        from quadland.plots.envelope_map import envelope_map_figure

        shape = tuple(len(a.values) for a in env.axes)
        rate, lo, hi, n, k = (np.array([np.nan if s[name] is None else
                                        (s[name][i] if i is not None else s[name])
                                        for s in stats], dtype=float).reshape(shape)
                              for name, i in (("success_rate", None), ("interval", 0),
                                              ("interval", 1), ("runs", None),
                                              ("successes", None)))
        labels = [f"{a.name} ({a.unit})" if a.unit not in ("", "-") else a.name
                  for a in env.axes]
        title = (f"{env.base.name}: success probability, {env.runs_per_cell} runs per cell "
                 f"({int(CONFIDENCE * 100)} % Clopper-Pearson intervals)")
        fig = envelope_map_figure([np.array(a.values) for a in env.axes], rate, lo, hi, k, n,
                                  labels, polar=env.polar,
                                  angle=next((i for i, a in enumerate(env.axes) if a.angle),
                                             None), title=title)
        files["envelope.png"] = figure_png(fig)
    return data, files
