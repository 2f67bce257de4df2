"""Figures of a campaign: metric CDFs against their limits, failures against a parameter.

Like the other figures they are made without pyplot
(:mod:`quadland.plots`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
from matplotlib.figure import Figure

__all__ = ["metrics_cdf_figure", "failures_figure"]


def _ecdf(x: np.ndarray, total: int) -> tuple[np.ndarray, np.ndarray]:
    """Step points of the empirical CDF over ``total`` runs (undefined ones never reached)."""
    x = np.sort(x[np.isfinite(x)])
    return x, np.arange(1, x.size + 1) / total


def metrics_cdf_figure(values: Mapping[str, np.ndarray], limits: Mapping[str, float],
                       units: Mapping[str, str] | None = None) -> Figure:
    """Empirical CDF of each metric over the runs, with its limit.

    Parameters
    ----------
    values : mapping of str to ndarray
        Each metric over the runs flown; NaN where undefined (no touchdown,
        never settled, a numerical failure): such runs count in the total,
        so the curve stops below 1.
    limits : mapping of str to float
        Upper limits, drawn as vertical lines.
    units : mapping of str to str, optional

    Returns
    -------
    matplotlib.figure.Figure
    """
    names = list(values)
    cols = min(2, len(names))
    rows = math.ceil(len(names) / cols)
    fig = Figure(figsize=(5.2 * cols, 3.4 * rows), layout="constrained")
    axes = fig.subplots(rows, cols, squeeze=False).ravel()
    for ax, name in zip(axes, names, strict=False):
        x = np.asarray(values[name], dtype=float)
        xs, ps = _ecdf(x, x.size)
        if xs.size:
            ax.step(np.concatenate([[xs[0]], xs]), np.concatenate([[0.0], ps]), where="post",
                    color="C0", label="runs")
        limit = limits.get(name)
        unit = (units or {}).get(name, "-")
        if limit is not None:
            within = int(np.sum(x <= limit))
            ax.axvline(limit, color="C3", ls="--",
                       label=f"limit {limit:g}: {within} of {x.size} within")
        ax.set_xlabel(name + ("" if unit == "-" else f" ({unit})"))
        ax.set_ylabel("fraction of runs")
        ax.set_ylim(0, 1.02)
        ax.grid(alpha=0.3)
        ax.legend(loc="lower right", fontsize="small")
    for ax in axes[len(names):]:
        ax.set_visible(False)
    fig.suptitle(f"Campaign metrics over {len(next(iter(values.values()), []))} runs")
    return fig


def failures_figure(parameter: np.ndarray, severity: np.ndarray, failed: np.ndarray,
                    name: str, title: str = "") -> Figure:
    """The runs against one dispersed parameter: severity, and the parameter's CDFs.

    Parameters
    ----------
    parameter : ndarray
        The parameter's value in each run.
    severity : ndarray
        Each run's largest metric / limit (> 1: a limit missed; inf: no
        touchdown or a numerical failure, drawn at the top edge).
    failed : ndarray of bool
    name : str
        The parameter's column in runs.csv.
    title : str
        The figure's title (default: "Failures against <name>").

    Returns
    -------
    matplotlib.figure.Figure
        Without a failure the right panel says "no failures" instead of
        comparing the parameter's distributions (there is nothing to
        separate), and the default title claims no correlation.
    """
    x = np.asarray(parameter, dtype=float)
    s = np.asarray(severity, dtype=float)
    failed = np.asarray(failed, dtype=bool)
    finite = np.isfinite(s)
    top = max(1.5, float(np.max(s[finite])) * 1.1) if finite.any() else 1.5
    shown = np.where(finite, s, top)
    fig = Figure(figsize=(10.4, 3.8), layout="constrained")
    left, right = fig.subplots(1, 2)
    left.scatter(x[~failed], shown[~failed], s=12, color="0.5", label="success")
    if failed.any():
        left.scatter(x[failed], shown[failed], s=22, color="C3", marker="x", label="failure")
    left.axhline(1.0, color="C3", ls="--", lw=1, label="limit")
    if not finite.all():
        left.axhline(top, color="0.3", ls=":", lw=1,
                     label="no value (the run did not reach it, or failed numerically)")
    left.set_xlabel(name)
    left.set_ylabel("largest metric / limit")
    left.grid(alpha=0.3)
    left.legend(fontsize="small")
    if not failed.any():                        # no failure: nothing to separate
        right.text(0.5, 0.5, f"no failures\n({x.size} of {x.size} runs succeeded)",
                   ha="center", va="center", fontsize="large", transform=right.transAxes)
        right.set_xticks([])
        right.set_yticks([])
        fig.suptitle(title or f"No failures: the runs against {name}")
        left.set_xlabel(name)
        return fig
    for group, color, text in ((~failed, "0.4", "successes"), (failed, "C3", "failures")):
        if group.any():
            xs, ps = _ecdf(x[group], int(group.sum()))
            right.step(np.concatenate([[xs[0]], xs]), np.concatenate([[0.0], ps]),
                       where="post", color=color, label=f"{text} ({int(group.sum())})")
    right.set_xlabel(name)
    right.set_ylabel("fraction of the group")
    right.grid(alpha=0.3)
    right.legend(fontsize="small")
    fig.suptitle(title or f"Failures against {name}")
    return fig
