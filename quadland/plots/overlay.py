"""Runs overlaid on one figure: each run's name in its lines' labels, one legend.

A plot function draws a run into a new figure, or (``ax=``) into the axes of
one already drawn, to compare runs. Its lines then carry the run's name
(:func:`run_tag`: ``"x_e (gain 2)"``), lines of one kind take a colour per run
(:func:`run_index`), and the legend is drawn again over everything on the
axes, an entry per label (:func:`redraw_legend`: a limit drawn once per run
shows once).
"""

from __future__ import annotations

__all__ = ["run_tag", "run_index", "redraw_legend"]


def run_tag(result, label: str | None, own: bool) -> str:
    """What a run's line labels end with: nothing for a run alone in its new figure
    without a ``label``, else `` (label)``, the label by default the scenario's name."""
    if own and label is None:
        return ""
    return f" ({result.scenario.name if label is None else label})"


def run_index(ax, gid: str) -> int:
    """How many runs the axes already show: their lines with the ``gid`` one line of
    each run carries."""
    return sum(1 for line in ax.get_lines() if line.get_gid() == gid)


def redraw_legend(ax, **kwargs) -> None:
    """The axes' legend drawn again over all their lines, one entry per label."""
    handles, labels = ax.get_legend_handles_labels()
    unique = dict(zip(labels, handles, strict=True))
    ax.legend(list(unique.values()), list(unique), **kwargs)
