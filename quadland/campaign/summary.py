"""A finished campaign's summary and figures, from its runs.csv rows.

:func:`summarize_campaign` gives the success rate with its exact 95 %
interval, the order statistics of every metric, the worst runs with the
command that replays each (:func:`replay_command`) and the dispersed column
that best separates failures; :func:`campaign_figures` draws them.
"""

from __future__ import annotations

import math
import shlex
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path

import numpy as np

from quadland.campaign.sampling import format_value
from quadland.campaign.spec import campaign_spec_of
from quadland.campaign.statistics import (
    clopper_pearson,
    lower_confidence_bound,
    order_statistic,
    separation,
)
from quadland.kinds import kind_of
from quadland.scenario import Scenario

__all__ = ["CONFIDENCE", "QUANTILES", "WORST_RUNS", "CAMPAIGN_FIGURES", "summarize_campaign",
           "campaign_figures", "replay_command", "summary_counts", "counted_text"]

#: Confidence level of the success rate's interval and bound.
CONFIDENCE = 0.95


#: The order statistics summary.json gives of every metric.
QUANTILES = {"p50": 0.5, "p90": 0.9, "p99": 0.99, "max": 1.0}


#: Runs listed in summary.json's ``worst_runs``.
WORST_RUNS = 5


#: The figures of a finished campaign.
CAMPAIGN_FIGURES = ("metrics_cdf.png", "failures.png")


def replay_command(scenario_arg: str, overrides: Sequence[str], draw_overrides: Sequence[str]
                   ) -> str:
    """The ``quadland simulate`` command that flies one run of a campaign again."""
    words = ["quadland", "simulate", "--scenario", scenario_arg]
    for text in (*overrides, *draw_overrides):
        words += ["--set", text]
    return shlex.join(words)


def _parse(rows: Sequence[Sequence[str]], header: Sequence[str]) -> dict[str, list[str]]:
    return {name: [r[k] for r in rows] for k, name in enumerate(header)}


def _floats(texts: Iterable[str]) -> np.ndarray:
    return np.array([float(t) if t != "" else np.nan for t in texts])


def _severity(cols: Mapping[str, list[str]], limits: Mapping[str, float], n: int) -> np.ndarray:
    """Each run's largest metric / limit ratio (inf when undefined or not flown to the end)."""
    out = np.zeros(n)
    ok = np.array([s == "ok" for s in cols["status"]])
    for name, limit in limits.items():
        ratio = _floats(cols[name]) / limit
        out = np.maximum(out, np.where(np.isnan(ratio), np.inf, ratio))
    return np.where(ok, out, np.inf)


def _dispersed_numbers(spec, cols: Mapping[str, list[str]]) -> dict[str, np.ndarray]:
    """Each varying dispersed column as numbers (a choice as its position in ``values``)."""
    out = {}
    for disp in spec.dispersions:
        if disp.distribution == "seed":
            continue
        for col in disp.columns():
            if disp.distribution == "choice":
                texts = [format_value(v) for v in disp.values]
                out[col] = np.array([texts.index(t) if t in texts else -1 for t in cols[col]],
                                    dtype=float)
            else:
                out[col] = _floats(cols[col])
    return out


def summarize_campaign(base: Scenario, header: Sequence[str], rows: Sequence[Sequence[str]],
                       scenario_arg: str | None = None, overrides: Sequence[str] = ()
                       ) -> dict:
    """summary.json of a finished campaign, from its runs.csv rows (sorted by index).

    Success rate with its exact (Clopper-Pearson) 95 % interval and
    one-sided lower bound over the runs flown (``ok`` or ``failed``; an
    ``invalid`` run is counted apart); p50, p90, p99 and max (order
    statistics) of every metric; the worst runs with the command that
    replays each; the dispersed column that best separates failures.
    Without a flown run (every draw invalid) the rate, its interval and the
    separation are null and ``note`` says so; without a failure (or a
    success) ``separation`` is null and ``most_correlated`` names the column
    the severity follows most.
    """
    spec, model = campaign_spec_of(base), base.model
    cols = _parse(rows, header)
    n_all = len(rows)
    status = np.array(cols["status"])
    success = np.array([s == "true" for s in cols["success"]])
    flown = status != "invalid"
    n, k = int(flown.sum()), int((success & flown).sum())
    limits = kind_of(base).limits(base, spec.limits)
    summary: dict = {"scenario": base.name, "model": model, "runs": n_all, "flown": n,
                     "invalid": int((~flown).sum()), "successes": k, "failures": n - k,
                     "numerical_failures": int((status == "failed").sum())}
    summary["success_rate"] = summary["confidence"] = None
    if n:
        lo, hi = clopper_pearson(k, n, CONFIDENCE)
        summary["success_rate"] = k / n
        summary["confidence"] = {
            "level": CONFIDENCE, "method": "Clopper-Pearson (exact binomial)",
            "interval": [lo, hi],
            "lower_bound_one_sided": lower_confidence_bound(k, n, CONFIDENCE)}
    else:
        summary["note"] = (f"no run was flown: the draws of all {n_all} were invalid (each "
                           "row's message says why); no success rate, no figures")
    summary["metrics"] = {m.name: _metric_entry(m, cols[m.name], limits, n)
                          for m in kind_of(model).metrics}
    severity = _severity(cols, limits, n_all)
    order = sorted((i for i in range(n_all) if flown[i]),
                   key=lambda i: (status[i] != "failed", -severity[i], i))
    worst = []
    arg = scenario_arg or Path(base.source).stem
    draw_cols = spec.columns()
    for i in order[:WORST_RUNS]:
        values = _row_values(spec, cols, i)
        worst.append({
            "index": i, "seed": int(cols["seed"][i]), "status": status[i],
            "success": bool(success[i]), "message": cols["message"][i],
            "severity": severity[i],
            "metrics": {m.name: (None if cols[m.name][i] == "" else float(cols[m.name][i]))
                        for m in kind_of(model).metrics},
            "dispersed": {c: cols[c][i] for c in draw_cols},
            "command": replay_command(arg, overrides, values)})
    summary["worst_runs"] = worst
    numbers = _dispersed_numbers(spec, cols)
    fail = ~success[flown]
    sep = separation({c: v[flown] for c, v in numbers.items()}, fail) if n else None
    summary["separation"] = None if sep is None else {
        "parameter": sep.parameter, "ks_statistic": sep.statistic,
        "failures": int(fail.sum()), "successes": int((~fail).sum())}
    if sep is None and numbers and n:
        name, rho = _most_correlated({c: v[flown] for c, v in numbers.items()},
                                     severity[flown])
        summary["most_correlated"] = {"parameter": name, "spearman_rho": rho}
    summary["campaign"] = {**spec.identity(), "runs": n_all}
    summary["severity_definition"] = "largest metric / limit of a run; > 1 misses a limit"
    return summary


def summary_counts(summary: Mapping) -> dict[str, int]:
    """The ``count`` of every counted 0/1 flag in a campaign's summary.json, by metric."""
    return {name: e["count"] for name, e in summary["metrics"].items() if "count" in e}


def counted_text(model: str, counts: Mapping[str, int]) -> str:
    """``"; false touchdowns 0, tipped over 2"``: counted flags by their labels (the last
    line a campaign or an envelope prints), or ``""`` when the model counts none."""
    labels = [(m.counted, counts[m.name]) for m in kind_of(model).metrics
              if m.counted and m.name in counts]
    return "; " + ", ".join(f"{label} {n}" for label, n in labels) if labels else ""


def _metric_entry(m, column: list[str], limits: Mapping[str, float], flown: int) -> dict:
    """One metric's entry of summary.json: its order statistics over the runs that define
    it, the runs within its limit, and for a 0/1 flag the runs where it is 1."""
    x = _floats(column)
    x = x[~np.isnan(x)]
    entry = {"unit": m.unit, "doc": m.doc, "limit": limits.get(m.name), "n": int(x.size),
             "undefined": int(flown - x.size)}
    if m.name in limits:
        entry["within_limit"] = int(np.sum(x <= limits[m.name]))
    if m.counted:
        entry["count"] = int(np.sum(x == 1.0))
    for label, q in QUANTILES.items():
        entry[label] = order_statistic(x, q) if x.size else None
    return entry


def _row_values(spec, cols: Mapping[str, list[str]], i: int) -> list[str]:
    """Run ``i``'s dispersed values as ``--set`` texts, from its runs.csv row."""
    out = []
    for disp in spec.dispersions:
        if disp.distribution in ("seed", "choice"):
            out.append(f"{disp.key}={cols[disp.key][i]}")
            continue
        for target in disp.targets:
            texts = [cols[c][i] for c in target.columns()]
            value = texts[0] if target.scalar else "[" + ", ".join(texts) + "]"
            out.append(f"{target.key}={value}")
    return out


def campaign_figures(base: Scenario, header, rows, summary) -> dict[str, bytes]:
    from quadland.output import figure_png
    from quadland.plots.campaign import failures_figure, metrics_cdf_figure

    spec = campaign_spec_of(base)
    cols = _parse(rows, header)
    limits = kind_of(base).limits(base, spec.limits)
    success = np.array([s == "true" for s in cols["success"]])
    flown = np.array([s != "invalid" for s in cols["status"]])
    if not flown.any():
        return {}                               # nothing to draw: summary.json's note says so
    metric_values = {m.name: _floats(cols[m.name])[flown] for m in kind_of(base).metrics
                     if m.name in limits}
    units = {m.name: m.unit for m in kind_of(base).metrics}
    files = {}
    if metric_values:
        files["metrics_cdf.png"] = figure_png(metrics_cdf_figure(metric_values, limits, units))
    numbers = {c: v[flown] for c, v in _dispersed_numbers(spec, cols).items()}
    severity = _severity(cols, limits, len(rows))[flown]
    if summary["separation"] is not None:
        sep = summary["separation"]
        name, title = sep["parameter"], (f"Failures against {sep['parameter']}, the parameter "
                                         f"that best separates them (KS D = "
                                         f"{sep['ks_statistic']:.2f})")
    elif "most_correlated" in summary:
        corr = summary["most_correlated"]
        name = corr["parameter"]
        rho = corr["spearman_rho"]
        if success[flown].all():                # nothing failed: no correlation to point at
            title = f"No failures in {int(flown.sum())} runs: the severity against {name}"
        else:
            title = ("No success: the runs against "
                     + (f"{name}, the parameter the severity follows most (Spearman rho = "
                        f"{rho:.2f})" if rho is not None
                        else f"{name} (the severity is constant)"))
    else:
        return files
    files["failures.png"] = figure_png(failures_figure(numbers[name], severity,
                                                       ~success[flown], name, title))
    return files


def _most_correlated(numbers: Mapping[str, np.ndarray], severity: np.ndarray
                     ) -> tuple[str, float | None]:
    """The column whose ranks follow the severity's most closely, and its Spearman rho."""
    from scipy.stats import rankdata

    s = rankdata(np.where(np.isfinite(severity), severity, np.inf))
    best, best_r = next(iter(numbers)), None
    for name, x in numbers.items():
        if np.ptp(x) == 0 or np.ptp(s) == 0:
            continue
        r = float(np.corrcoef(rankdata(x), s)[0, 1])
        if math.isfinite(r) and (best_r is None or abs(r) > abs(best_r)):
            best, best_r = name, r
    return best, best_r
