"""``quadland margins`` for one scenario: the review, its figures and its files.

:func:`review_scenario` validates the request, linearizes, writes
``margins.json``, ``scenario.toml`` and the figures into one output folder
(whole or not at all) and returns the report; the command line prints it and
sets the exit status.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

from quadland.margins.report import MarginReport, Requirement
from quadland.margins.review import check_request, margin_report

__all__ = ["review_scenario"]


def review_scenario(scenario, overrides, out, at, requirement: Requirement,
                    delay_periods, plots: bool = True,
                    say: Callable[[str], None] = print) -> tuple[MarginReport, Path, float]:
    """Review a scenario's margins and write them.

    Parameters
    ----------
    scenario : str or path
        A shipped scenario's name or a file.
    overrides : list of str
        ``section.key=value`` overrides.
    out : path or None
        The output folder (None: ``<scenario>-margins-<time>`` here).
    at, delay_periods
        As :func:`~quadland.margins.margin_report`'s.
    requirement : Requirement
    plots : bool
        Write the figures too.
    say : callable
        Progress lines (the command prints them).

    Returns
    -------
    report : MarginReport
    folder : Path
    elapsed : float
        s of wall time.
    """
    from threadpoolctl import threadpool_limits

    from quadland.output import figure_png, output_folder, strict_json
    from quadland.run import versions
    from quadland.scenario import load_scenario

    start = time.perf_counter()
    sc = load_scenario(scenario, overrides)
    check_request(sc, at, delay_periods)     # nothing claimed before this
    # OpenBLAS threads on matrices of a few hundred rows cost more than they
    # bring: 3-5x slower on a busy 2-core machine. threadpoolctl limits the
    # libraries loaded when it is called: SciPy's own OpenBLAS loads with
    # scipy.linalg, which the analysis imports, so load it first.
    import scipy.linalg  # noqa: F401
    with output_folder(out, sc.name, "margins") as folder, threadpool_limits(1):
        say(f"quadland: margins of {sc.name}: linearizing, then the loops' frequency "
            "responses...")
        report = margin_report(sc, at, requirement, delay_periods)
        figures = {}
        if plots:
            say(f"quadland: margins of {sc.name}: the figures...")
            from quadland.plots import margin_figures
            from quadland.plots.gc_pause import collection_paused
            from quadland.plots.text_store import texts_kept

            # the collector: 0.1 s of collections finding nothing; the texts: FreeType's
            # layouts and glyphs of the last runs, read back
            with collection_paused(), texts_kept():
                figures = {name: figure_png(fig) for name, fig in margin_figures(report).items()}
        data = dict(report.to_dict(), runtime_s=time.perf_counter() - start,
                    versions=versions())
        folder.write({"margins.json": strict_json(data),
                      "scenario.toml": sc.to_toml().encode("utf-8"), **figures})
    return report, folder.path, time.perf_counter() - start
